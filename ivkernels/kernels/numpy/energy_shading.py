"""``energy_shading`` on the NumPy backend: :mod:`ivkernels.kernels.reference.energy_shading` into the outputs."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint
from ivkernels.kernels.reference import energy_shading as ref


def shading_smoothness(S, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add Eq. 9's 3x3 Charbonnier smoothness of S (T, H, W) and its gradient into gS (T, H, W)."""
    _local_term(S, None, gS, energy_rows, lam, eps)


def shading_smoothness_gated(S, gate, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add Eq. 9's smoothness of S (T, H, W) with pair weights ``(gate(x) + gate(y)) / 2``, gate (T, H, W)."""
    _local_term(S, gate, gS, energy_rows, lam, eps)


def _local_term(S, gate, gS, energy_rows, lam: float, eps: float) -> None:
    """Checks and reference of Eq. 9's local term, gated unless ``gate`` is None."""
    arrays(S=S)
    if gate is not None:
        arrays(gate=gate)
        if gate.shape != S.shape:
            raise ValueError(f"gate must have shape {S.shape} (T, H, W), got {gate.shape}")
    check_disjoint("gS", gS, "S", S, "the gradient is scattered into gS while S is read")
    if gate is not None:
        check_disjoint("gS", gS, "gate", gate, "the gradient is scattered into gS while gate is read")
    arrays(np.float64, energy_rows=energy_rows)
    if gate is None:
        rows, grad = ref.shading_smoothness(S, float(lam), float(eps))
    else:
        rows, grad = ref.shading_smoothness_gated(S, gate, float(lam), float(eps))
    add("gS", gS, grad)
    add("energy_rows", energy_rows, rows)


def coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
    """Add ``lam w_bnd (S - S~)^2``: S, S_tilde, gS (T, H, W), w_bnd (T', H, W), T' <= T."""
    arrays(S=S, S_tilde=S_tilde, w_bnd=w_bnd)
    arrays(np.float64, energy_rows=energy_rows)
    rows, grad = ref.coupling_term(S, S_tilde, w_bnd, float(lam))
    add("gS", gS, grad)
    add("energy_rows", energy_rows, rows)
