"""``pyramid`` on the NumPy backend: :mod:`ivkernels.kernels.reference.pyramid` written into ``out``."""
from __future__ import annotations

import math

from ivkernels.kernels.host import gaussian_kernel  # noqa: F401  (part of the family)
from ivkernels.kernels.numpy._adapt import arrays, check_disjoint, write
from ivkernels.kernels.reference import pyramid as ref


def gaussian_blur(src, out, scratch, sigma: float) -> None:
    """Separable blur of ``src`` (T, H, W, C) into ``out`` (may be ``src``); ``scratch`` is not needed
    here but must be a separate (T, H, W, C) array as on every backend; ``sigma <= 0`` copies."""
    arrays(src=src, scratch=scratch)
    check_disjoint("scratch", scratch, "src", src, "it holds the x-blurred image")
    check_disjoint("scratch", scratch, "out", out, "it holds the x-blurred image")
    sigma = float(sigma)
    if not math.isfinite(sigma):
        raise ValueError(f"sigma must be finite, got {sigma}")
    write("out", out, ref.gaussian_blur(src, sigma))


def resize_bilinear(src, out) -> None:
    """Resize ``src`` (T, h, w, C) to ``out``'s (T, H, W, C), pixel-centre mapping."""
    arrays(src=src)
    write("out", out, ref.resize_bilinear(src, _size(src, out)))


def resize_flow(src, out) -> None:
    """Resize a flow ``src`` (T, h, w, 2) to ``out``'s (T, H, W, 2), vectors rescaled."""
    arrays(src=src)
    write("out", out, ref.resize_flow(src, _size(src, out)))


def _size(src, out) -> tuple:
    """``(H, W)`` of ``out``, checked to be a 4-D array of at least one pixel like ``src``."""
    arrays(out=out)
    if src.ndim != 4 or out.ndim != 4 or min(src.shape[1:3] + out.shape[1:3]) < 1:
        raise ValueError(f"src and out must be (T, H, W, C) of at least one pixel, got {src.shape}, {out.shape}")
    return out.shape[1], out.shape[2]
