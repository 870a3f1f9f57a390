"""The flow's input: the grey level of the frames, and its normalisation.

Classic+NL works on MATLAB's ``rgb2gray`` of the 8-bit sRGB image
(:func:`srgb_grey`), or here on the log of the linear grey level
(:func:`log_grey`, where the shading of ``i = a * s`` is additive);
:func:`row_min_max` and :func:`scale_shift` let the host rescale images the
way the public code does.  Part of :mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import GREY_WEIGHTS
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

__all__ = ["srgb_grey", "log_grey", "row_min_max", "scale_shift"]

wp.set_module_options({"enable_backward": False})


@wp.func
def srgb_encode(c: float):
    """sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1]."""
    c = wp.clamp(c, 0.0, 1.0)
    result = 12.92 * c
    if c > 0.0031308:
        result = 1.055 * wp.pow(c, 1.0 / 2.4) - 0.055
    return result


@wp.kernel
def srgb_grey_rows(row_begin: int, tiles: int, rgb: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                   wr: float, wg: float, wb: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, out.shape[2])
    height = out.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        g = wr * srgb_encode(rgb[t, y, x, 0]) + wg * srgb_encode(rgb[t, y, x, 1]) \
            + wb * srgb_encode(rgb[t, y, x, 2])
        out[t, y, x] = 255.0 * g


@wp.kernel
def log_grey_rows(row_begin: int, tiles: int, rgb: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                  wr: float, wg: float, wb: float, floor: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, out.shape[2])
    height = out.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        g = wr * rgb[t, y, x, 0] + wg * rgb[t, y, x, 1] + wb * rgb[t, y, x, 2]
        out[t, y, x] = wp.log(wp.max(g, floor))


@wp.kernel
def min_max_rows(row_begin: int, src: wp.array4d(dtype=float), out: wp.array3d(dtype=float)):
    r = row_begin + wp.tid()
    height = src.shape[1]
    t = r // height
    y = r - t * height
    for c in range(src.shape[3]):
        lo = src[t, y, 0, c]
        hi = lo
        for x in range(1, src.shape[2]):
            v = src[t, y, x, c]
            lo = wp.min(lo, v)
            hi = wp.max(hi, v)
        out[r, c, 0] = lo
        out[r, c, 1] = hi


@wp.kernel
def scale_shift_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float), out: wp.array4d(dtype=float),
                     scale: wp.array(dtype=float), shift: wp.array(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, src.shape[2])
    height = src.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        for c in range(src.shape[3]):
            out[t, y, x, c] = src[t, y, x, c] * scale[c] + shift[c]


@host("srgb_grey")
def srgb_grey(rgb, out) -> None:
    """Grey level of linear RGB frames, sRGB-encoded and scaled to [0, 255].

    ``out = 255 * (0.2989 R' + 0.5870 G' + 0.1140 B')`` with ``X'`` the
    sRGB encoding of the linear value clamped to [0, 1] (MATLAB's ``rgb2gray``
    of the 8-bit image, the input of the public Classic+NL code).

    rgb : (T, H, W, 3) float32, linear RGB in [0, 1].
    out : (T, H, W) float32, grey in [0, 255] (gamma-encoded, not linear).

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = rgb.shape
    tiles = row_tiles(w, rgb.device)
    launch_rows(srgb_grey_rows, t * h * tiles, [tiles, rgb, out, *GREY_WEIGHTS], rgb.device)


@host("log_grey")
def log_grey(rgb, out, floor: float = 1e-3) -> None:
    """Natural log of the linear grey level: ``out = log(max(0.2989 R + 0.5870 G + 0.1140 B, floor))``.

    Under the image model ``i = a * s`` the log turns the shading into an
    additive term, which the ROF structure part then absorbs where it is smooth.

    rgb : (T, H, W, 3) float32, linear RGB.
    out : (T, H, W) float32, log grey (<= 0 for input in [0, 1]).

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = rgb.shape
    tiles = row_tiles(w, rgb.device)
    launch_rows(log_grey_rows, t * h * tiles, [tiles, rgb, out, *GREY_WEIGHTS, float(floor)], rgb.device)


@host("row_min_max")
def row_min_max(src, out) -> None:
    """Minimum and maximum of every image row and channel.

    src : (T, H, W, C) float32.
    out : (T*H, C, 2) float32; ``out[t*H + y, c] = (min, max)`` of ``src[t, y, :, c]``.
    The host finishes the reduction over rows (``out.min(0)``, ``out.max(0)``).
    """
    t, h, w, c = src.shape
    launch_rows(min_max_rows, t * h, [src, out], src.device)


@host("scale_shift")
def scale_shift(src, out, scale, shift) -> None:
    """Per-channel affine map ``out[..., c] = src[..., c] * scale[c] + shift[c]``.

    src, out : (T, H, W, C) float32 (may be the same array).
    scale, shift : (C,) float32 arrays on the same device.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, c = src.shape
    tiles = row_tiles(w, src.device)
    launch_rows(scale_shift_rows, t * h * tiles, [tiles, src, out, scale, shift], src.device)
