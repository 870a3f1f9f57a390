"""``energy_albedo_gsm`` on the NumPy backend: :mod:`ivkernels.kernels.reference.energy_albedo_gsm` into the outputs."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.checks import check_float, check_int
from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint
from ivkernels.kernels.reference import energy_albedo_gsm as ref
from ivkernels.kernels.workspace import check_workspace


def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows, lam: float,
                   radius: int = 2, *, workspace=None) -> None:
    """Add Eq. 11's GSM smoothness of A (T, H, W, 3) and its gradient into gA (T, H, W, 3)."""
    check_workspace(workspace)
    arrays(A=A, sigma_inv=sigma_inv, table_g=table_g, table_dg=table_dg)
    check_disjoint("gA", gA, "A", A, "the gradient is scattered into gA while A is read")
    arrays(np.float64, energy_rows=energy_rows)
    rows, grad = ref.gsm_smoothness(A, sigma_inv, table_g, table_dg, check_float("r2_max", r2_max, positive=True),
                                    check_float("lam", lam), check_int("radius", radius, 1))
    add("gA", gA, grad)
    add("energy_rows", energy_rows, rows)
