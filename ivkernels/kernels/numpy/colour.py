"""``colour`` on the NumPy backend: :mod:`ivkernels.kernels.reference.colour` written into ``out``."""
from __future__ import annotations

from ivkernels.kernels.checks import check_positive
from ivkernels.kernels.numpy._adapt import arrays, write
from ivkernels.kernels.reference import colour as ref


def srgb_to_linear(src, out) -> None:
    """sRGB-encoded -> linear, any shape."""
    arrays(src=src)
    write("out", out, ref.srgb_to_linear(src))


def linear_to_srgb(src, out) -> None:
    """Linear -> sRGB-encoded, any shape."""
    arrays(src=src)
    write("out", out, ref.linear_to_srgb(src))


def log_floor(src, out, floor: float) -> None:
    """``out = log(max(src, floor))``, any shape."""
    arrays(src=src)
    write("out", out, ref.log_floor(src, check_positive("floor", floor)))


def linear_rgb_to_lab(rgb, out) -> None:
    """Linear RGB (T, H, W, 3) -> CIE Lab (T, H, W, 3)."""
    arrays(rgb=rgb)
    write("out", out, ref.linear_rgb_to_lab(rgb))


def luminance(rgb, out) -> None:
    """Linear RGB (T, H, W, 3) -> Rec. 709 luminance (T, H, W)."""
    arrays(rgb=rgb)
    write("out", out, ref.luminance(rgb))
