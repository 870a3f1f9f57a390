"""``energy_temporal``: the declared contract of its host functions, and the NumPy references (Eq. 4, 5, 8), float64."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Array, Family, Positive, Real, Workspace

FAMILY = Family("energy_temporal", "The temporal terms (Eq. 4, 8).")

_WHY = "the gradients are scattered while A and S are read"

FAMILY.declare("temporal_term(X, flow, occ, gX, energy_rows, lam, alpha=5.0, *, workspace=None)",
               "Add the Tukey temporal term of X (with or without a channel axis) and its gradient.",
               X=Array("T H W [C]", layout="(T, H, W, C) or (T, H, W)"), flow="T-1 H W 2", occ="T-1 H W",
               gX=Acc("T H W [C]", layout="(T, H, W, C) like X"), energy_rows=Acc("T*H", "float64"),
               lam=Real, alpha=Positive, workspace=Workspace(),
               separate=(("gX", "X", "the gradient is scattered into gX while X is read"),))
FAMILY.declare("temporal_terms(A, S, flow, occ, gA, gS, energy_rows, lam_albedo, lam_shading, alpha=5.0, *, "
               "workspace=None)", "Both temporal terms at once, sharing flow, occ and alpha.",
               A="T H W 3", S=Array("T H W", layout="(T, H, W) like A"), flow="T-1 H W 2", occ="T-1 H W",
               gA=Acc("T H W 3", layout="(T, H, W, 3) like A"), gS=Acc("T H W", layout="(T, H, W) like S"),
               energy_rows=Acc("T*H", "float64"), lam_albedo=Real, lam_shading=Real,
               alpha=Positive, workspace=Workspace(),
               separate=(("gA", "A", _WHY), ("gA", "S", _WHY), ("gS", "A", _WHY), ("gS", "S", _WHY)))


def tukey(z, alpha: float = 5.0):
    """Continuous Tukey penalty: ``z^2/a^2 - z^4/a^4 + z^6/(3 a^6)`` inside ``|z| <= a``, 1/3 outside."""
    q = (np.asarray(z, np.float64) / alpha) ** 2
    return np.where(q <= 1.0, q - q * q + q * q * q / 3.0, 1.0 / 3.0)


def tukey_derivative(z, alpha: float = 5.0):
    """``(2/a^2) z (1 - z^2/a^2)^2`` inside ``|z| <= a``, 0 outside."""
    z = np.asarray(z, np.float64)
    q = (z / alpha) ** 2
    return np.where(q <= 1.0, 2.0 / alpha**2 * z * (1.0 - q) ** 2, 0.0)


def bilinear_corners(flow, h: int, w: int):
    """The four clamped corners and weights of ``x + flow`` for every pixel.

    Returns a list of ``(yi, xi, weight)`` arrays of shape ``flow.shape[:-1]``.
    Corner indices ``floor(p)``, ``floor(p) + 1`` are clamped to the image; the
    weights come from the unclamped fractional position.
    """
    flow = np.asarray(flow, np.float64)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    px = xx + flow[..., 0]
    py = yy + flow[..., 1]
    fx0, fy0 = np.floor(px), np.floor(py)
    fx, fy = px - fx0, py - fy0
    x0 = np.clip(fx0.astype(np.int64), 0, w - 1)
    x1 = np.clip(fx0.astype(np.int64) + 1, 0, w - 1)
    y0 = np.clip(fy0.astype(np.int64), 0, h - 1)
    y1 = np.clip(fy0.astype(np.int64) + 1, 0, h - 1)
    return [(y0, x0, (1 - fx) * (1 - fy)), (y0, x1, fx * (1 - fy)),
            (y1, x0, (1 - fx) * fy), (y1, x1, fx * fy)]


def temporal_term(X, flow, occ, lam: float, alpha: float = 5.0):
    """Temporal term of Eq. 4 / Eq. 8 and its gradient.

    ``E = lam * sum_{t<T-1} sum_{x,c} occ_t(x) rho(X_{t+1}(x + u_t(x), c) - X_t(x, c))``
    with ``rho`` the continuous Tukey and ``X_{t+1}(x + u)`` bilinear with
    clamped corners.

    Parameters
    ----------
    X : (T, H, W, C) or (T, H, W).
    flow : (T-1, H, W, 2).  occ : (T-1, H, W).

    Returns ``(energy_rows (T*H,), gX (shape of X))``, float64; the energy of
    the pair ``(t, t+1)`` goes to the rows of frame ``t``.
    """
    X = np.asarray(X, np.float64)
    squeeze = X.ndim == 3
    if squeeze:
        X = X[..., None]
    t, h, w, c = X.shape
    energy = np.zeros((t, h))
    grad = np.zeros_like(X)
    for k in range(t - 1):
        corners = bilinear_corners(flow[k], h, w)
        warped = sum(wt[..., None] * X[k + 1][yi, xi] for yi, xi, wt in corners)
        d = warped - X[k]
        o = np.asarray(occ[k], np.float64)[..., None]
        energy[k] = lam * (o * tukey(d, alpha)).sum(axis=(1, 2))
        g = lam * o * tukey_derivative(d, alpha)
        grad[k] -= g
        for yi, xi, wt in corners:
            np.add.at(grad[k + 1], (yi, xi), wt[..., None] * g)
    if squeeze:
        grad = grad[..., 0]
    return energy.reshape(t * h), grad


def temporal_terms(A, S, flow, occ, lam_albedo: float, lam_shading: float, alpha: float = 5.0):
    """Both temporal terms, Eq. 4 on ``A`` (T, H, W, 3) and Eq. 8 on ``S`` (T, H, W).

    Returns ``(energy_rows (T*H,), gA, gS)``, float64: the sum of
    :func:`temporal_term` on each with its own weight and the shared ``alpha``.
    """
    rows_albedo, gA = temporal_term(A, flow, occ, lam_albedo, alpha)
    rows_shading, gS = temporal_term(S, flow, occ, lam_shading, alpha)
    return rows_albedo + rows_shading, gA, gS
