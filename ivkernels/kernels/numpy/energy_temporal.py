"""``energy_temporal`` on the NumPy backend: :mod:`ivkernels.kernels.reference.energy_temporal` into the outputs."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.checks import check_positive
from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint
from ivkernels.kernels.reference import energy_temporal as ref
from ivkernels.kernels.workspace import check_workspace


def temporal_term(X, flow, occ, gX, energy_rows, lam: float, alpha: float = 5.0, *,
                  workspace=None) -> None:
    """Add the Tukey temporal term of Eq. 4 / 8: X, gX (T, H, W, C), flow (T-1, H, W, 2), occ (T-1, H, W)."""
    check_workspace(workspace)
    arrays(X=X, flow=flow, occ=occ)
    check_disjoint("gX", gX, "X", X, "the gradient is scattered into gX while X is read")
    arrays(np.float64, energy_rows=energy_rows)
    rows, grad = ref.temporal_term(X, flow, occ, float(lam), check_positive("alpha", alpha))
    add("gX", gX, grad)
    add("energy_rows", energy_rows, rows)
