"""``energy_data``: the declared contract of its host functions, and their NumPy references
(Eq. 3), float64."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Family, Out, Real

FAMILY = Family("energy_data", "The data term (Eq. 3) and the constraint ``A = I - S``.")

FAMILY.declare("data_term(I, A, S, w_lum, gA, gS, energy_rows, lam=10.0, eps=0.001)",
               "Add Eq. 3 and its gradient (into gA, gS) and its energy per row (into energy_rows).",
               I="T H W 3", A="T H W 3", S="T H W", w_lum="T H W", gA=Acc("T H W 3"), gS=Acc("T H W"),
               energy_rows=Acc("T*H", "float64"), lam=Real, eps=Real)
FAMILY.declare("constrained_albedo(I, S, A)", "``A = I - S``.",
               I="T H W 3", S="T H W", A=Out("T H W 3"),
               separate=(("A", "I", "constrained_albedo writes A while reading I"),))
FAMILY.declare("constrained_gradient(gA, gS, out)", "``out = gS - sum_c gA`` (``out`` may be ``gS``).",
               gA="T H W 3", gS="T H W", out=Out("T H W"))


def data_term(I, A, S, w_lum, lam: float = 10.0, eps: float = 0.001):
    """Data term of Eq. 3 and its gradient.

    ``E = lam * sum_{t,y,x,c} sqrt(z^2 + eps^2)`` with
    ``z = w_lum * (I - A - S)`` (log domain).

    Parameters
    ----------
    I, A : (T, H, W, 3) log input and log albedo.
    S : (T, H, W) log shading.
    w_lum : (T, H, W) luminance weight.

    Returns
    -------
    energy_rows : (T*H,) float64, the energy of row ``t*H + y``.
    gA : (T, H, W, 3) float64, dE/dA.
    gS : (T, H, W) float64, dE/dS.
    """
    I, A, S, w = (np.asarray(a, np.float64) for a in (I, A, S, w_lum))
    t, h, wd, _ = I.shape
    z = w[..., None] * (I - A - S[..., None])
    rho = np.sqrt(z * z + eps * eps)
    energy_rows = lam * rho.sum(axis=(2, 3)).reshape(t * h)
    gA = -lam * w[..., None] * z / rho
    gS = gA.sum(axis=-1)
    return energy_rows, gA, gS


def constrained_albedo(I, S):
    """``A = I - S`` (T, H, W, 3), float64: Eq. 3 taken as a constraint."""
    return np.asarray(I, np.float64) - np.asarray(S, np.float64)[..., None]


def constrained_gradient(gA, gS):
    """Chain rule of ``A = I - S``: ``gS - sum_c gA`` (T, H, W), float64."""
    return np.asarray(gS, np.float64) - np.asarray(gA, np.float64).sum(axis=-1)
