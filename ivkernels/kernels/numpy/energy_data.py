"""``energy_data`` on the NumPy backend: :mod:`ivkernels.kernels.reference.energy_data` into the outputs."""
from __future__ import annotations

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.numpy._adapt import add, write
from ivkernels.kernels.reference import energy_data as ref

host = implements(ref.FAMILY, FRONT)


@host("data_term")
def data_term(I, A, S, w_lum, gA, gS, energy_rows, lam: float = 10.0, eps: float = 0.001) -> None:
    """Add Eq. 3 into ``energy_rows`` (T*H,) float64 and its gradient into gA (T, H, W, 3), gS (T, H, W)."""
    rows, dA, dS = ref.data_term(I, A, S, w_lum, float(lam), float(eps))
    add("gA", gA, dA)
    add("gS", gS, dS)
    add("energy_rows", energy_rows, rows)


@host("constrained_albedo")
def constrained_albedo(I, S, A) -> None:
    """``A = I - S``: I, A (T, H, W, 3), S (T, H, W)."""
    write("A", A, ref.constrained_albedo(I, S))


@host("constrained_gradient")
def constrained_gradient(gA, gS, out) -> None:
    """``out = gS - sum_c gA``: gA (T, H, W, 3), gS, out (T, H, W); ``out`` may be ``gS``."""
    write("out", out, ref.constrained_gradient(gA, gS))
