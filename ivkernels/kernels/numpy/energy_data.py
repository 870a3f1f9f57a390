"""``energy_data`` on the NumPy backend: :mod:`ivkernels.kernels.reference.energy_data` into the outputs."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint, write
from ivkernels.kernels.reference import energy_data as ref


def data_term(I, A, S, w_lum, gA, gS, energy_rows, lam: float = 10.0, eps: float = 0.001) -> None:
    """Add Eq. 3 into ``energy_rows`` (T*H,) float64 and its gradient into gA (T, H, W, 3), gS (T, H, W)."""
    arrays(I=I, A=A, S=S, w_lum=w_lum)
    rows, dA, dS = ref.data_term(I, A, S, w_lum, float(lam), float(eps))
    add("gA", gA, dA)
    add("gS", gS, dS)
    arrays(np.float64, energy_rows=energy_rows)
    add("energy_rows", energy_rows, rows)


def constrained_albedo(I, S, A) -> None:
    """``A = I - S``: I, A (T, H, W, 3), S (T, H, W)."""
    arrays(I=I, S=S, A=A)
    check_disjoint("A", A, "I", I, "constrained_albedo writes A while reading I")
    write("A", A, ref.constrained_albedo(I, S))


def constrained_gradient(gA, gS, out) -> None:
    """``out = gS - sum_c gA``: gA (T, H, W, 3), gS, out (T, H, W); ``out`` may be ``gS``."""
    arrays(gA=gA, gS=gS)
    write("out", out, ref.constrained_gradient(gA, gS))
