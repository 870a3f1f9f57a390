"""``median`` on the NumPy backend: :mod:`ivkernels.kernels.reference.median` (brute force) written into ``out``.

The weighted medians visit each selected pixel's window in Python: use on
small images.  ``workspace`` is checked for the contract and not used.
"""
from __future__ import annotations

from ivkernels.kernels.checks import check_int, check_positive
from ivkernels.kernels.host import flow_scratch_shape, shading_scratch_shape  # noqa: F401  (part of the family)
from ivkernels.kernels.numpy._adapt import arrays, check_disjoint, write
from ivkernels.kernels.reference import median as ref
from ivkernels.kernels.workspace import check_workspace


def median5x5(src, out) -> None:
    """5x5 median of every channel of ``src`` (T, H, W, C), replicate border."""
    arrays(src=src)
    check_disjoint("out", out, "src", src, "the median reads a window of src around each pixel")
    write("out", out, ref.median5x5(src))


def weighted_median_shading(S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                            lam: float = 0.001, *, workspace=None) -> None:
    """S~ update of Eq. 13: S, out (T, H, W), flow (T', H, W, 2), w_bnd (T', H, W), T' <= T."""
    check_workspace(workspace)
    arrays(S=S, flow=flow, w_bnd=w_bnd)
    check_disjoint("out", out, "S", S, "the median reads a window of S around each pixel")
    if flow.shape[0] > S.shape[0]:
        raise ValueError(f"flow has {flow.shape[0]} frames but S only {S.shape[0]}; expected T' <= T")
    lam = float(lam)
    if not lam >= 0.0:
        raise ValueError(f"lam must be >= 0, got {lam!r}")
    write("out", out, ref.weighted_median_shading(S, flow, w_bnd, check_int("radius", radius, 0),
                                                  check_positive("sigma_s", sigma_s), lam))


def weighted_median_flow(flow, lab, occ, mask, out, radius: int = 7, sigma_x: float = 7.0,
                         sigma_i: float = 7.0, *, workspace=None) -> None:
    """Classic+NL's weighted flow median: flow, out (T, H, W, 2), lab (T, H, W, 3), occ, mask (T, H, W)."""
    check_workspace(workspace)
    arrays(flow=flow, lab=lab, occ=occ, mask=mask)
    check_disjoint("out", out, "flow", flow, "the median reads a window of flow around each pixel")
    write("out", out, ref.weighted_median_flow(flow, lab, occ, mask, check_int("radius", radius, 0),
                                               check_positive("sigma_x", sigma_x),
                                               check_positive("sigma_i", sigma_i)))
