"""The backend contract, declared: one ``typing.Protocol`` per kernel family,
and one for the backend object.

A backend is an object satisfying :class:`BackendProtocol`; its attribute
named after a family (``be.sampling``) is a module whose host functions have
exactly the names, parameter names, kinds and defaults declared here
(:data:`FAMILY_PROTOCOLS`).  ``tests/test_backend_contract.py`` checks every
registered backend's every family module against these declarations with
:func:`inspect.signature`, so a signature that drifts in one backend fails
the tests.

The methods below are declarations (``self`` aside, they are the module
functions' signatures).  Shapes follow the array convention of
:mod:`ivkernels.kernels`: float32 backend arrays, images ``(T, H, W[, C])``,
flow ``(T, H, W, 2)`` in pixels (x then y), energies added per row into a
float64 ``energy_rows`` of length ``T*H``; outputs are passed in and
written (or added into where said); functions return ``None`` unless a
return type is declared.  The full documentation of each function is in
:mod:`ivkernels.kernels.warp`.
"""
from __future__ import annotations

from typing import Protocol

import numpy as np


class ColourFamily(Protocol):
    """``colour``: transfer curves, log, Lab and luminance, element-wise."""

    def srgb_to_linear(self, src, out) -> None:
        """sRGB-encoded -> linear, any shape; ``out`` like ``src``."""

    def linear_to_srgb(self, src, out) -> None:
        """Linear -> sRGB-encoded, any shape; ``out`` like ``src``."""

    def log_floor(self, src, out, floor: float) -> None:
        """``out = log(max(src, floor))``, any shape; ``floor > 0``."""

    def linear_rgb_to_lab(self, rgb, out) -> None:
        """Linear RGB (T, H, W, 3) -> CIE Lab (T, H, W, 3), D65 white."""

    def luminance(self, rgb, out) -> None:
        """Linear RGB (T, H, W, 3) -> Rec. 709 luminance (T, H, W)."""


class SamplingFamily(Protocol):
    """``sampling``: warping frames by a flow, and its adjoint."""

    def warp_bilinear(self, src, flow, out, inside) -> None:
        """``out = src[t](x + u)`` bilinear: src, out (T, H, W, C), flow (T, H, W, 2), inside (T, H, W) 0/1."""

    def splat_bilinear(self, values, flow, out) -> None:
        """Add the transpose of :meth:`warp_bilinear` of values (T, H, W, C) into out (T, H, W, C)."""

    def warp_bicubic(self, src, flow, out, inside) -> None:
        """``out = src[t](x + u)`` bicubic (Keys): shapes as :meth:`warp_bilinear`."""


class DerivativesFamily(Protocol):
    """``derivatives``: image gradients, flow Sobel magnitude, divergence."""

    def image_gradient(self, src, gx, gy) -> None:
        """5-point x and y derivatives of src (T, H, W, C) into gx, gy (T, H, W, C)."""

    def flow_sobel_magnitude(self, flow, out) -> None:
        """Sobel magnitude of flow (T, H, W, 2) into out (T, H, W)."""

    def divergence_negative(self, flow, out) -> None:
        """``min(div u, 0)`` of flow (T, H, W, 2) into out (T, H, W) (Eq. 7)."""


class MapsFamily(Protocol):
    """``maps``: occlusion, warp reliability, motion boundaries and the shading gate."""

    def occlusion_soft(self, lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3) -> None:
        """Eq. 7's likelihood: lab (T+1, H, W, 3), flow (T, H, W, 2), div_neg, out (T, H, W)."""

    def occlusion_binary(self, lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3,
                         threshold: float = 0.5) -> None:
        """Eq. 6's ``w_occ`` (0/1): shapes as :meth:`occlusion_soft`."""

    def warp_reliability(self, log_image, flow, occ, max_spread: float) -> None:
        """Clear occ (T, H, W) where the warp of log_image (T+1, H, W, C) by flow straddles an edge."""

    def chroma_consistency(self, log_image, flow, occ, max_change: float) -> None:
        """Clear occ (T, H, W) where the log chromaticity of log_image (T+1, H, W, 3) changes along flow."""

    def shading_gate(self, log_image, flow, gate, tau: float, tau_chroma: float = 0.0) -> None:
        """Gate (T, H, W) of Eq. 9's local term: log_image (T, H, W, 3), flow (T-1, H, W, 2), tau > 0."""

    def motion_boundary(self, sobel_mag, out, threshold: float, radius: int, *, workspace=None) -> None:
        """``w_bnd`` (T, H, W): sobel_mag (T, H, W) above threshold, dilated by radius pixels."""


class PyramidFamily(Protocol):
    """``pyramid``: Gaussian blur and bilinear resizing of frames and flows."""

    def gaussian_kernel(self, sigma: float) -> np.ndarray:
        """Normalised 1-D Gaussian taps, float32 (2r+1,), r = max(1, ceil(3 sigma))."""

    def gaussian_blur(self, src, out, scratch, sigma: float) -> None:
        """Separable blur of src (T, H, W, C) into out; scratch (T, H, W, C) separate."""

    def resize_bilinear(self, src, out) -> None:
        """Resize src (T, h, w, C) to out (T, H, W, C), pixel-centre mapping."""

    def resize_flow(self, src, out) -> None:
        """Resize flow (T, h, w, 2) to out (T, H, W, 2), vectors rescaled."""


class VecopsFamily(Protocol):
    """``vecops``: BLAS-1 on 1-D float32 vectors (n,) and (k, n) bases."""

    def dot(self, a, b) -> float:
        """``sum(a * b)`` of two (n,) vectors, accumulated in float64."""

    def norm_inf(self, x) -> float:
        """``max |x|`` of an (n,) vector."""

    def axpy(self, alpha: float, x, y) -> None:
        """``y += alpha * x``, (n,) vectors."""

    def scale(self, alpha: float, x) -> None:
        """``x *= alpha``, (n,) vector."""

    def lincomb(self, out, a: float, x, b: float, y) -> None:
        """``out = a x + b y``, (n,) vectors; out may be x or y."""

    def copy(self, src, dst) -> None:
        """``dst[:] = src``, (n,) vectors."""

    def fill(self, x, value: float) -> None:
        """``x[:] = value``, (n,) vector."""

    def dots(self, basis, x, rows=None) -> np.ndarray:
        """float64 (len(rows),) dot products of x (n,) with rows of basis (k, n)."""

    def combine(self, out, basis, rows, coeffs) -> None:
        """``out = sum_r coeffs[r] basis[rows[r]]``, out (n,), basis (k, n)."""


class MedianFamily(Protocol):
    """``median``: the flow's 5x5 median and the weighted medians (Eq. 10, 13)."""

    def shading_scratch_shape(self, S_shape: tuple, radius: int) -> tuple:
        """Shape ``(T*H, 2*(2r+1)^2)`` of :meth:`weighted_median_shading`'s scratch."""

    def flow_scratch_shape(self, flow_shape: tuple, radius: int) -> tuple:
        """Shape ``(T*H, 3*(2r+1)^2)`` of :meth:`weighted_median_flow`'s scratch."""

    def median5x5(self, src, out) -> None:
        """5x5 median of every channel of src (T, H, W, C) into out, replicate border."""

    def weighted_median_shading(self, S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                                lam: float = 0.001, *, workspace=None) -> None:
        """S~ update of Eq. 13: S, out (T, H, W), flow (T', H, W, 2), w_bnd (T', H, W), T' <= T."""

    def weighted_median_flow(self, flow, lab, occ, mask, out, radius: int = 7, sigma_x: float = 7.0,
                             sigma_i: float = 7.0, *, workspace=None) -> None:
        """Classic+NL's weighted flow median: flow, out (T, H, W, 2), lab (T, H, W, 3), occ, mask (T, H, W)."""


class EnergyDataFamily(Protocol):
    """``energy_data``: the data term (Eq. 3) and the constraint ``A = I - S``."""

    def data_term(self, I, A, S, w_lum, gA, gS, energy_rows, lam: float = 10.0, eps: float = 0.001) -> None:
        """Add Eq. 3 and its gradient: I, A, gA (T, H, W, 3); S, w_lum, gS (T, H, W)."""

    def constrained_albedo(self, I, S, A) -> None:
        """``A = I - S``: I, A (T, H, W, 3) separate, S (T, H, W)."""

    def constrained_gradient(self, gA, gS, out) -> None:
        """``out = gS - sum_c gA``: gA (T, H, W, 3), gS, out (T, H, W)."""


class EnergyTemporalFamily(Protocol):
    """``energy_temporal``: the temporal terms (Eq. 4, 8)."""

    def temporal_term(self, X, flow, occ, gX, energy_rows, lam: float, alpha: float = 5.0, *,
                      workspace=None) -> None:
        """Add the Tukey temporal term: X, gX (T, H, W, C), flow (T-1, H, W, 2), occ (T-1, H, W)."""

    def temporal_terms(self, A, S, flow, occ, gA, gS, energy_rows, lam_albedo: float, lam_shading: float,
                       alpha: float = 5.0, *, workspace=None) -> None:
        """Both temporal terms at once: A, gA (T, H, W, 3), S, gS (T, H, W), shared flow, occ and alpha."""


class EnergyShadingFamily(Protocol):
    """``energy_shading``: local smoothness and coupling of the shading (Eq. 9, 13)."""

    def shading_smoothness(self, S, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
        """Add the 3x3 Charbonnier smoothness of S (T, H, W) and its gradient gS (T, H, W)."""

    def shading_smoothness_gated(self, S, gate, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
        """The same with pair weights ``(gate(x) + gate(y)) / 2``: S, gate, gS (T, H, W)."""

    def coupling_term(self, S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
        """Add ``lam w_bnd (S - S~)^2``: S, S_tilde, gS (T, H, W), w_bnd (T', H, W), T' <= T."""


class EnergyAlbedoGsmFamily(Protocol):
    """``energy_albedo_gsm``: the albedo's GSM smoothness (Eq. 11)."""

    def gsm_smoothness(self, A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows, lam: float,
                       radius: int = 2, *, workspace=None) -> None:
        """Add Eq. 11: A, gA (T, H, W, 3), sigma_inv (3, 3), tables (n,) over r2 in [0, r2_max]."""


class EnergyAlbedoEntropyFamily(Protocol):
    """``energy_albedo_entropy``: the albedo's global sparsity (Eq. 12)."""

    def allocate_entropy_scratch(self, n_frames: int, bins: int, device="cpu"):
        """:class:`ivkernels.kernels.host.EntropyScratch` of backend arrays for T frames, B^3 bins."""

    def entropy_histogram(self, A, whiten, lo: float, h: float, hist, row_flags) -> None:
        """Splat of ``W A`` (A (T, H, W, 3), whiten (3, 3)) into hist (T, B, B, B), flags (2, T, B, B)."""

    def entropy_blur(self, hist, taps, row_flags, tmp, blurred) -> None:
        """``blurred = G * hist`` per frame: hist, tmp, blurred (T, B, B, B), taps (k,)."""

    def entropy_dot(self, hist, blurred, dots) -> None:
        """``dots[t] = <hist_t, blurred_t>``: dots float64 (T,)."""

    def entropy_slice_gradient(self, A, whiten, lo: float, h: float, blurred, dots, gA, lam: float) -> None:
        """Add Eq. 12's gradient into gA (T, H, W, 3)."""

    def entropy_energy(self, dots, sigma_p: float, n_pixels: int, energy_rows, lam: float) -> None:
        """Add Eq. 12's energy of each frame into energy_rows (T*H,)."""

    def entropy_term(self, A, whiten, lo: float, h: float, taps, sigma_p: float, scratch, gA, energy_rows,
                     lam: float) -> None:
        """Add Eq. 12's energy and gradient (the five steps above): A, gA (T, H, W, 3)."""


class FlowClassicFamily(Protocol):
    """``flow_classic``: the Classic+NL optical flow's per-pixel steps."""

    def srgb_grey(self, rgb, out) -> None:
        """Grey level of sRGB-encoded rgb (T, H, W, 3) in [0, 255] into out (T, H, W)."""

    def log_grey(self, rgb, out, floor: float = 0.001) -> None:
        """``log(max(grey(rgb), floor))``: rgb (T, H, W, 3), out (T, H, W)."""

    def row_min_max(self, src, out) -> None:
        """Per row and channel (min, max) of src (T, H, W, C) into out (T*H, C, 2)."""

    def scale_shift(self, src, out, scale, shift) -> None:
        """``out = src * scale[c] + shift[c]``: src, out (T, H, W, C), scale, shift (C,)."""

    def rof_dual_step(self, img, p_in, p_out, theta: float, delta: float) -> None:
        """One Chambolle step: img (T, H, W), p_in, p_out (T, H, W, 2) separate."""

    def rof_texture(self, img, p, out, theta: float, alpha: float) -> None:
        """``out = img - alpha (img + theta div p)``: img, out (T, H, W), p (T, H, W, 2)."""

    def pack_image_gradient(self, img, gx, gy, out) -> None:
        """``out = (img, gx, gy)``: inputs (T, H, W), out (T, H, W, 3)."""

    def pack_gradient(self, gx, gy, out) -> None:
        """``out = (gx, gy)``: inputs (T, H, W), out (T, H, W, 2)."""

    def data_coefficients(self, i1, i1x, i1y, warped, inside, du, out, blend: float = 0.5, a: float = 0.45,
                          eps: float = 0.001, quad_frac: float = 0.0, quad_weight: float = 2000000.0) -> None:
        """IRLS data coefficients (T, H, W, 5) of brightness constancy; warped (T, H, W, 3), du (T, H, W, 2)."""

    def soft_census(self, img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
        """Soft census of img (T, H, W) into out (T, H, W, (2r+1)^2 - 1)."""

    def pack_channels_gradient(self, feat, gx, gy, out) -> None:
        """Interleave feat, gx, gy (T, H, W, C) into out (T, H, W, 3C)."""

    def data_coefficients_channels(self, first, warped, inside, du, weights, out, blend: float = 0.5,
                                   a: float = 0.45, eps: float = 0.001, quad_frac: float = 0.0,
                                   quad_weight: float = 2000000.0) -> None:
        """IRLS data coefficients (T, H, W, 5) of C feature channels: first, warped (T, H, W, 3C), weights (C,)."""

    def smoothness_weights(self, flow, du, out, a: float = 0.45, eps: float = 0.001, quad_frac: float = 0.0,
                           quad_weight: float = 2000000.0) -> None:
        """IRLS smoothness weights (T, H, W, 4) of flow + du, both (T, H, W, 2)."""

    def assemble_system(self, flow, data, smooth, lam: float, out) -> None:
        """Per-pixel 2x2 system (T, H, W, 5) from data (T, H, W, 5) and smooth (T, H, W, 4)."""

    def sor_sweep(self, du, system, smooth, lam: float, omega: float, parity: int) -> None:
        """Red-black SOR half sweep on du (T, H, W, 2) in place; parity 0 or 1."""

    def apply_update(self, flow, du, out, limit: float = 1.0) -> None:
        """``out = flow + clip(du, -limit, limit)``, all (T, H, W, 2)."""

    def select_masked(self, mask, inside_mask, outside_mask, out) -> None:
        """``out = mask >= 0.5 ? inside_mask : outside_mask``: mask (T, H, W), others (T, H, W, C)."""

    def flow_sobel_components(self, flow, out, row_energy) -> None:
        """Sobel x, y of both components (T, H, W, 4) and per-row energy (T*H, 2) of flow (T, H, W, 2)."""

    def thin_edges(self, sobel, cutoff, out) -> None:
        """Thinned edges (T, H, W) 0/1 of sobel (T, H, W, 4) above cutoff (T, 2)."""


class CoarseBasisFamily(Protocol):
    """``coarse_basis``: the solver's edge-aware coarse basis (nodes every ``spacing`` pixels)."""

    def coarse_weights(self, A, weights, spacing: int, sigma: float) -> None:
        """16 tap weights (T, H, W, 16) per pixel from the guide A (T, H, W, C)."""

    def prolong_add(self, z, weights, out, spacing: int) -> None:
        """``out += P z``: z (T, Hc, Wc), weights (T, H, W, 16), out (T, H, W)."""

    def restrict_add(self, values, weights, out, spacing: int) -> None:
        """``out += P^T values``: values (T, H, W), weights (T, H, W, 16), out (T, Hc, Wc)."""


#: Family name -> its protocol; the families every backend provides.
FAMILY_PROTOCOLS: dict[str, type] = {
    "colour": ColourFamily,
    "sampling": SamplingFamily,
    "derivatives": DerivativesFamily,
    "maps": MapsFamily,
    "pyramid": PyramidFamily,
    "vecops": VecopsFamily,
    "median": MedianFamily,
    "energy_data": EnergyDataFamily,
    "energy_temporal": EnergyTemporalFamily,
    "energy_shading": EnergyShadingFamily,
    "energy_albedo_gsm": EnergyAlbedoGsmFamily,
    "energy_albedo_entropy": EnergyAlbedoEntropyFamily,
    "flow_classic": FlowClassicFamily,
    "coarse_basis": CoarseBasisFamily,
}
FAMILIES = tuple(FAMILY_PROTOCOLS)


class BackendProtocol(Protocol):
    """The object the solver and the flow hold: arrays, and the families as attributes.

    ``name`` is the name it is registered under (:func:`ivkernels.backends.register_backend`),
    ``device`` the device it runs on ("cpu", "cuda:0").  Backend arrays are
    whatever its family modules take (``wp.array``, ``numpy.ndarray``); the
    methods below are the only way host code makes or reads them.
    """

    name: str
    device: str
    colour: ColourFamily
    sampling: SamplingFamily
    derivatives: DerivativesFamily
    maps: MapsFamily
    pyramid: PyramidFamily
    vecops: VecopsFamily
    median: MedianFamily
    energy_data: EnergyDataFamily
    energy_temporal: EnergyTemporalFamily
    energy_shading: EnergyShadingFamily
    energy_albedo_gsm: EnergyAlbedoGsmFamily
    energy_albedo_entropy: EnergyAlbedoEntropyFamily
    flow_classic: FlowClassicFamily
    coarse_basis: CoarseBasisFamily

    def asarray(self, a: np.ndarray):
        """A backend array holding ``a`` (a view where the backend can, else a copy)."""

    def empty(self, shape, dtype=np.float32):
        """An uninitialised backend array of ``shape`` (int or tuple) and NumPy ``dtype``."""

    def zeros(self, shape, dtype=np.float32):
        """A zero-filled backend array of ``shape`` and ``dtype``."""

    def zero(self, a) -> None:
        """Set every element of backend array ``a`` (any shape) to 0, in place."""

    def numpy(self, a) -> np.ndarray:
        """A NumPy view (CPU) or copy (other devices) of backend array ``a``, after synchronising."""

    def synchronize(self) -> None:
        """Wait until all work launched on ``device`` has finished."""
