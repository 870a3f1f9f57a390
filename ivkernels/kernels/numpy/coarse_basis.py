"""``coarse_basis`` on the NumPy backend: :mod:`ivkernels.kernels.reference.coarse_basis` written into the outputs."""
from __future__ import annotations

from ivkernels.kernels.checks import check_int, check_positive
from ivkernels.kernels.host import grid_shape
from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint, write
from ivkernels.kernels.reference import coarse_basis as ref


def coarse_weights(A, weights, spacing: int, sigma: float) -> None:
    """Weights (T, H, W, 16) of the edge-aware coarse basis guided by ``A`` (T, H, W, C)."""
    arrays(A=A)
    check_disjoint("weights", weights, "A", A, "the weights are written while A is read at the nodes")
    spacing = check_int("spacing", spacing, 1)
    sigma = check_positive("sigma", sigma)
    write("weights", weights, ref.coarse_weights(A, spacing, sigma))


def _grid(z_name: str, z, weights, spacing: int) -> int:
    arrays(weights=weights)
    spacing = check_int("spacing", spacing, 1)
    if weights.ndim != 4 or weights.shape[3] != 16:
        raise ValueError(f"weights must have shape (T, H, W, 16), got {weights.shape}")
    t, h, w, _ = weights.shape
    want = (t, *grid_shape(h, w, spacing))
    if z.shape != want:
        raise ValueError(f"{z_name} must have shape (T, Hc, Wc) = {want} for spacing {spacing}, got {z.shape}")
    return spacing


def prolong_add(z, weights, out, spacing: int) -> None:
    """``out += P z``: z (T, Hc, Wc), weights (T, H, W, 16), out (T, H, W)."""
    arrays(z=z)
    spacing = _grid("z", z, weights, spacing)
    check_disjoint("out", out, "z", z, "each pixel reads 16 nodes of z")
    add("out", out, ref.prolong(z, weights, spacing))


def restrict_add(values, weights, out, spacing: int) -> None:
    """``out += P^T values``: values (T, H, W), weights (T, H, W, 16), out (T, Hc, Wc)."""
    arrays(values=values, out=out)
    spacing = _grid("out", out, weights, spacing)
    check_disjoint("out", out, "values", values, "each node sums values over 4 x 4 node spacings")
    add("out", out, ref.restrict(values, weights, spacing))
