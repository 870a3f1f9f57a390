"""``flow_classic`` on the NumPy backend: :mod:`ivkernels.kernels.reference.flow_classic` written into the outputs."""
from __future__ import annotations

from ivkernels.kernels.host import GREY_WEIGHTS  # noqa: F401  (rgb2gray weights, part of the family)
from ivkernels.kernels.numpy._adapt import arrays, check_disjoint, write
from ivkernels.kernels.reference import flow_classic as ref


def srgb_grey(rgb, out) -> None:
    """Grey level in [0, 255] (T, H, W) of sRGB-encoded linear ``rgb`` (T, H, W, 3)."""
    arrays(rgb=rgb)
    write("out", out, ref.srgb_grey(rgb))


def log_grey(rgb, out, floor: float = 0.001) -> None:
    """``log(max(grey(rgb), floor))`` (T, H, W) of linear ``rgb`` (T, H, W, 3)."""
    arrays(rgb=rgb)
    if not floor > 0.0:
        raise ValueError(f"floor must be > 0, got {floor!r}")
    write("out", out, ref.log_grey(rgb, float(floor)))


def row_min_max(src, out) -> None:
    """Per row and channel (min, max) (T*H, C, 2) of ``src`` (T, H, W, C)."""
    arrays(src=src)
    if src.ndim != 4 or src.shape[2] < 1:
        raise ValueError(f"src must be (T, H, W, C) with at least one column, got shape {src.shape}")
    write("out", out, ref.row_min_max(src))


def scale_shift(src, out, scale, shift) -> None:
    """``out = src * scale[c] + shift[c]``, (T, H, W, C); ``out`` may be ``src``."""
    arrays(src=src, scale=scale, shift=shift)
    write("out", out, ref.scale_shift(src, scale, shift))


def rof_dual_step(img, p_in, p_out, theta: float, delta: float) -> None:
    """One Chambolle step: ``img`` (T, H, W), ``p_in``, ``p_out`` (T, H, W, 2) separate."""
    arrays(img=img, p_in=p_in)
    check_disjoint("p_in", p_in, "p_out", p_out, "the step reads neighbours of p_in")
    write("p_out", p_out, ref.rof_dual_step(img, p_in, float(theta), float(delta)))


def rof_texture(img, p, out, theta: float, alpha: float) -> None:
    """``out = img - alpha (img + theta div p)`` (T, H, W); ``out`` may be ``img``."""
    arrays(img=img, p=p)
    write("out", out, ref.rof_texture(img, p, float(theta), float(alpha)))


def pack_image_gradient(img, gx, gy, out) -> None:
    """``out = (img, gx, gy)`` (T, H, W, 3)."""
    arrays(img=img, gx=gx, gy=gy)
    write("out", out, ref.pack_image_gradient(img, gx, gy))


def pack_gradient(gx, gy, out) -> None:
    """``out = (gx, gy)`` (T, H, W, 2) of ``gx``, ``gy`` (T, H, W)."""
    arrays(gx=gx, gy=gy)
    write("out", out, ref.pack_gradient(gx, gy))


def data_coefficients(i1, i1x, i1y, warped, inside, du, out, blend: float = 0.5, a: float = 0.45,
                      eps: float = 0.001, quad_frac: float = 0.0, quad_weight: float = 2000000.0) -> None:
    """IRLS data coefficients (T, H, W, 5) of the linearised brightness constancy."""
    arrays(i1=i1, i1x=i1x, i1y=i1y, warped=warped, inside=inside, du=du)
    write("out", out, ref.data_coefficients(i1, i1x, i1y, warped, inside, du, float(blend), float(a), float(eps),
                                            float(quad_frac), float(quad_weight)))


def soft_census(img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
    """Soft census (T, H, W, (2r+1)^2 - 1) of ``img`` (T, H, W)."""
    arrays(img=img)
    radius = int(radius)
    if radius < 1:
        raise ValueError(f"radius must be >= 1, got {radius}")
    if not eps > 0.0:
        raise ValueError(f"eps must be > 0, got {eps!r}")
    write("out", out, ref.soft_census(img, radius, float(eps), float(scale)))


def pack_channels_gradient(feat, gx, gy, out) -> None:
    """Interleave ``feat``, ``gx``, ``gy`` (T, H, W, C) into ``out`` (T, H, W, 3C)."""
    arrays(feat=feat, gx=gx, gy=gy)
    write("out", out, ref.pack_channels_gradient(feat, gx, gy))


def data_coefficients_channels(first, warped, inside, du, weights, out, blend: float = 0.5,
                               a: float = 0.45, eps: float = 0.001, quad_frac: float = 0.0,
                               quad_weight: float = 2000000.0) -> None:
    """IRLS data coefficients (T, H, W, 5) of C feature channels (``first``, ``warped`` (T, H, W, 3C))."""
    arrays(first=first, warped=warped, inside=inside, du=du, weights=weights)
    write("out", out, ref.data_coefficients_channels(first, warped, inside, du, weights, float(blend), float(a),
                                                     float(eps), float(quad_frac), float(quad_weight)))


def smoothness_weights(flow, du, out, a: float = 0.45, eps: float = 0.001, quad_frac: float = 0.0,
                       quad_weight: float = 2000000.0) -> None:
    """IRLS smoothness weights (T, H, W, 4) of ``flow + du``."""
    arrays(flow=flow, du=du)
    write("out", out, ref.smoothness_weights(flow, du, float(a), float(eps), float(quad_frac), float(quad_weight)))


def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """Per-pixel 2x2 system (T, H, W, 5) from ``data`` (T, H, W, 5) and ``smooth`` (T, H, W, 4)."""
    arrays(flow=flow, data=data, smooth=smooth)
    write("out", out, ref.assemble_system(flow, data, smooth, float(lam)))


def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """Red-black SOR half sweep on ``du`` (T, H, W, 2), in place."""
    arrays(du=du, system=system, smooth=smooth)
    if parity not in (0, 1):
        raise ValueError(f"parity must be 0 or 1, got {parity!r}")
    write("du", du, ref.sor_sweep(du, system, smooth, float(lam), float(omega), int(parity)))


def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """``out = flow + clip(du, -limit, limit)`` (T, H, W, 2); ``out`` may alias an input."""
    arrays(flow=flow, du=du)
    write("out", out, ref.apply_update(flow, du, float(limit)))


def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """``out = mask >= 0.5 ? inside_mask : outside_mask`` (T, H, W, C)."""
    arrays(mask=mask, inside_mask=inside_mask, outside_mask=outside_mask)
    write("out", out, ref.select_masked(mask, inside_mask, outside_mask))


def flow_sobel_components(flow, out, row_energy) -> None:
    """Sobel derivatives (T, H, W, 4) of both flow components and their per-row energy (T*H, 2)."""
    arrays(flow=flow)
    sobel, energy = ref.flow_sobel_components(flow)
    write("out", out, sobel)
    write("row_energy", row_energy, energy)


def thin_edges(sobel, cutoff, out) -> None:
    """Thinned edges (T, H, W) 0/1 of ``sobel`` (T, H, W, 4) above ``cutoff`` (T, 2)."""
    arrays(sobel=sobel, cutoff=cutoff)
    write("out", out, ref.thin_edges(sobel, cutoff))
