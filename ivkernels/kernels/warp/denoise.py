"""Edge-preserving smoothing of the solved layers at the input's noise level.

:func:`range_sigma` turns the noise level function read at each pixel (a
step of ``log(i + offset)``) into the noise's step in ``log i``;
:func:`bilateral` smooths a log layer (the albedo, the shading) with a
bilateral filter whose range at each pixel is that step, so that the noise
averages out while steps much larger than the noise (albedo edges, cast
shadows) keep their sides apart.  See :mod:`ivkernels.solver.denoise` for
where the solver uses them.

One thread per tile of a row (one tile per row on the CPU, one pixel on a
GPU); each output pixel visits its ``(2 radius + 1)^2`` window once, its
one to three channels (the shading, the albedo) and the weights' sum in
registers.  Runs once per window on the outputs, not in the
solver's loop, so no CPU row loop is written for it.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.denoise import DARK_FRACTION, FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import frame_row, row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.kernel
def range_sigma_rows(row_begin: int, tiles: int, offset_image: wp.array4d(dtype=float),
                     level: wp.array4d(dtype=float), out: wp.array3d(dtype=float), scale: float,
                     offset: float, dark: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, out.shape[2])
    t, y = frame_row(r, out.shape[1])
    for x in range(x_begin, x_end):
        e = wp.exp((offset_image[t, y, x, 0] + offset_image[t, y, x, 1] + offset_image[t, y, x, 2]) / 3.0)
        brightness = wp.max(e - offset, dark * offset)
        out[t, y, x] = scale * level[t, y, x, 0] * e / brightness


@wp.func
def pixel_channels(src: wp.array4d(dtype=float), t: int, y: int, x: int, channels: int):
    """The pixel's 1 to 3 channels as a vector, the missing ones 0."""
    green = float(0.0)
    blue = float(0.0)
    if channels > 1:
        green = src[t, y, x, 1]
    if channels > 2:
        blue = src[t, y, x, 2]
    return wp.vec3(src[t, y, x, 0], green, blue)


@wp.kernel
def bilateral_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float), rs: wp.array3d(dtype=float),
                   out: wp.array4d(dtype=float), radius: int, inv_space: float):
    height = src.shape[1]
    width = src.shape[2]
    channels = src.shape[3]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t, y = frame_row(r, height)
    for x in range(x_begin, x_end):
        centre = pixel_channels(src, t, y, x, channels)
        sigma = rs[t, y, x]
        total = centre
        if sigma > 0.0:                    # else (0, negative or NaN) the pixel keeps its value
            inv_range = 1.0 / (2.0 * sigma * sigma * float(channels))
            num = wp.vec3(0.0)
            den = float(0.0)
            for dy in range(wp.max(-radius, -y), wp.min(radius, height - 1 - y) + 1):
                for dx in range(wp.max(-radius, -x), wp.min(radius, width - 1 - x) + 1):
                    value = pixel_channels(src, t, y + dy, x + dx, channels)
                    d = value - centre
                    w = wp.exp(-float(dy * dy + dx * dx) * inv_space - wp.dot(d, d) * inv_range)
                    den += w
                    num += w * value
            total = num / den
        for c in range(channels):
            out[t, y, x, c] = total[c]


@host("range_sigma")
def range_sigma(offset_image, level, out, scale: float, offset: float) -> None:
    """The noise's log-luminance step in units of ``log i``, times ``scale``.

    offset_image : wp.array float32 (T, H, W, 3), ``log(i + offset)``.
    level : wp.array float32 (T, H, W, 2), the noise level function read at each pixel
        (``step_evidence.cap_at_level``); channel 0, the log-luminance step, is read.
    out : wp.array float32 (T, H, W), ``scale * level[..., 0] * e / max(e - offset, offset / 10)``
        with ``e = exp(mean_c offset_image)``.
    scale : >= 0; offset : > 0, the offset of ``offset_image``.
    """
    t, h, w = out.shape
    tiles = row_tiles(w, out.device)
    launch_rows(range_sigma_rows, t * h * tiles,
                [tiles, offset_image, level, out, float(scale), float(offset), DARK_FRACTION], device=out.device)


@host("bilateral")
def bilateral(src, range_sigma, out, radius: int, sigma_space: float) -> None:
    """Bilateral filter of a log layer with a per-pixel range.

    src : wp.array float32 (T, H, W, C), 1 <= C <= 3: log albedo (C = 3) or log shading (C = 1).
    range_sigma : wp.array float32 (T, H, W), the range at each centre pixel, log units
        (:func:`range_sigma`); where it is not positive the pixel keeps its value.
    out : wp.array float32 (T, H, W, C), ``sum_y w src(y) / sum_y w`` over the window inside the
        frame, ``w = exp(-|y - x|^2 / (2 sigma_space^2) - mean_c (src(y) - src(x))^2 / (2 range^2))``;
        may not alias ``src``.
    radius : >= 0, the window's half width in pixels; sigma_space : > 0, pixels.
    """
    t, h, w, _ = src.shape
    tiles = row_tiles(w, src.device)
    launch_rows(bilateral_rows, t * h * tiles,
                [tiles, src, range_sigma, out, int(radius), 1.0 / (2.0 * float(sigma_space) ** 2)],
                device=src.device)
