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


def temporal_terms(A, S, flow, occ, gA, gS, energy_rows, lam_albedo: float, lam_shading: float,
                   alpha: float = 5.0, *, workspace=None) -> None:
    """Add both temporal terms (Eq. 4 on A (T, H, W, 3), Eq. 8 on S (T, H, W)) and their gradients."""
    check_workspace(workspace)
    arrays(A=A, S=S, flow=flow, occ=occ)
    why = "the gradients are scattered while A and S are read"
    for grad_name, grad in (("gA", gA), ("gS", gS)):
        check_disjoint(grad_name, grad, "A", A, why)
        check_disjoint(grad_name, grad, "S", S, why)
    arrays(np.float64, energy_rows=energy_rows)
    rows, grad_albedo, grad_shading = ref.temporal_terms(A, S, flow, occ, float(lam_albedo), float(lam_shading),
                                                         check_positive("alpha", alpha))
    add("gA", gA, grad_albedo)
    add("gS", gS, grad_shading)
    add("energy_rows", energy_rows, rows)
