"""``maps`` on the NumPy backend: :mod:`ivkernels.kernels.reference.maps` written into the outputs."""
from __future__ import annotations

from ivkernels.kernels.checks import check_int, check_non_negative, check_positive
from ivkernels.kernels.numpy._adapt import arrays, check_disjoint, write
from ivkernels.kernels.reference import maps as ref
from ivkernels.kernels.workspace import check_workspace


def occlusion_soft(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3) -> None:
    """Eq. 7's likelihood (T, H, W): lab (T+1, H, W, 3), flow (T, H, W, 2), div_neg (T, H, W)."""
    arrays(lab=lab, flow=flow, div_neg=div_neg)
    write("out", out, ref.occlusion_soft(lab, flow, div_neg, check_positive("sigma_e", sigma_e),
                                         check_positive("sigma_d", sigma_d)))


def occlusion_binary(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3,
                     threshold: float = 0.5) -> None:
    """Eq. 6's ``w_occ`` (0/1), shapes as :func:`occlusion_soft`."""
    arrays(lab=lab, flow=flow, div_neg=div_neg)
    write("out", out, ref.occlusion_binary(lab, flow, div_neg, check_positive("sigma_e", sigma_e),
                                           check_positive("sigma_d", sigma_d), float(threshold)))


def _check_rgb_log_image(log_image) -> None:
    """The reference reads three channels of ``log_image``: refuse any other shape."""
    if log_image.ndim != 4 or log_image.shape[3] != 3:
        raise ValueError(f"log_image must have shape (T, H, W, 3), got {log_image.shape}")


def warp_reliability(log_image, flow, occ, max_spread: float) -> None:
    """Clear ``occ`` (T, H, W) in place where the warp of ``log_image`` (T+1, H, W, C) straddles an edge."""
    arrays(log_image=log_image, flow=flow, occ=occ)
    write("occ", occ, ref.warp_reliability(log_image, flow, occ, float(max_spread)))


def chroma_consistency(log_image, flow, occ, max_change: float) -> None:
    """Clear ``occ`` (T, H, W) in place where the log chromaticity of ``log_image`` (T+1, H, W, 3)
    changes along ``flow`` by ``max_change`` or more."""
    arrays(log_image=log_image, flow=flow, occ=occ)
    _check_rgb_log_image(log_image)
    write("occ", occ, ref.chroma_consistency(log_image, flow, occ, check_positive("max_change", max_change)))


def shading_gate(log_image, flow, gate, tau: float, tau_chroma: float = 0.0) -> None:
    """The gate (T, H, W) of Eq. 9's local term from log_image (T, H, W, 3) and flow (T-1, H, W, 2)."""
    arrays(log_image=log_image, flow=flow)
    _check_rgb_log_image(log_image)
    t, h, w, _ = log_image.shape
    if flow.shape != (max(t - 1, 0), h, w, 2):
        raise ValueError(f"flow must have shape {(max(t - 1, 0), h, w, 2)} (T-1, H, W, 2), got {flow.shape}")
    check_disjoint("gate", gate, "log_image", log_image, "the gate is written while log_image is read")
    check_disjoint("gate", gate, "flow", flow, "the gate is written while flow is read")
    write("gate", gate, ref.shading_gate(log_image, flow, check_positive("tau", tau),
                                         check_non_negative("tau_chroma", tau_chroma)))


def motion_boundary(sobel_mag, out, threshold: float, radius: int, *, workspace=None) -> None:
    """``w_bnd`` (T, H, W): ``sobel_mag`` above ``threshold``, dilated by ``radius`` pixels."""
    check_workspace(workspace)
    radius = check_int("radius", radius, 0)
    arrays(sobel_mag=sobel_mag)
    if radius:
        check_disjoint("out", out, "sobel_mag", sobel_mag, "the dilation reads neighbours of sobel_mag")
    write("out", out, ref.motion_boundary(sobel_mag, float(threshold), radius))
