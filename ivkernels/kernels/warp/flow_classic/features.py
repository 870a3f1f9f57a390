"""Feature channels of the data term: an image with its derivatives, and a soft census.

Each data term compares channels of the two frames: the grey level
(brightness constancy), its derivatives (gradient constancy) or the
:func:`soft_census` of the window.  The ``pack_*`` functions interleave
channels and their x and y derivatives in the layout
:func:`ivkernels.kernels.warp.flow_classic.irls.data_coefficients_channels`
reads.  Part of :mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

__all__ = ["pack_image_gradient", "pack_gradient", "soft_census", "pack_channels_gradient"]

wp.set_module_options({"enable_backward": False})


@wp.kernel
def pack_image_gradient_rows(row_begin: int, tiles: int, img: wp.array3d(dtype=float),
                             gx: wp.array3d(dtype=float), gy: wp.array3d(dtype=float),
                             out: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, img.shape[2])
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        out[t, y, x, 0] = img[t, y, x]
        out[t, y, x, 1] = gx[t, y, x]
        out[t, y, x, 2] = gy[t, y, x]


@wp.kernel
def pack_gradient_rows(row_begin: int, tiles: int, gx: wp.array3d(dtype=float), gy: wp.array3d(dtype=float),
                       out: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gx.shape[2])
    height = gx.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        out[t, y, x, 0] = gx[t, y, x]
        out[t, y, x, 1] = gy[t, y, x]


@wp.kernel
def soft_census_rows(row_begin: int, tiles: int, img: wp.array3d(dtype=float), out: wp.array4d(dtype=float),
                     radius: int, eps: float, scale: float):
    height = img.shape[1]
    width = img.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        centre = img[t, y, x]
        k = int(0)
        for dy in range(-radius, radius + 1):
            yy = wp.clamp(y + dy, 0, height - 1)
            for dx in range(-radius, radius + 1):
                if dy != 0 or dx != 0:
                    d = img[t, yy, wp.clamp(x + dx, 0, width - 1)] - centre
                    out[t, y, x, k] = scale * d / wp.sqrt(d * d + eps * eps)
                    k += 1


@wp.kernel
def pack_channels_gradient_rows(row_begin: int, tiles: int, feat: wp.array4d(dtype=float),
                                gx: wp.array4d(dtype=float), gy: wp.array4d(dtype=float),
                                out: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, feat.shape[2])
    height = feat.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        for c in range(feat.shape[3]):
            out[t, y, x, 3 * c] = feat[t, y, x, c]
            out[t, y, x, 3 * c + 1] = gx[t, y, x, c]
            out[t, y, x, 3 * c + 2] = gy[t, y, x, c]


@host("pack_image_gradient")
def pack_image_gradient(img, gx, gy, out) -> None:
    """Stack an image and its two derivatives as channels: ``out = (img, gx, gy)``.

    img, gx, gy : (T, H, W) float32; out : (T, H, W, 3) float32.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = img.shape
    tiles = row_tiles(w, img.device)
    launch_rows(pack_image_gradient_rows, t * h * tiles, [tiles, img, gx, gy, out], img.device)


@host("pack_gradient")
def pack_gradient(gx, gy, out) -> None:
    """Stack two derivatives as channels: ``out = (gx, gy)``, the feature of a gradient-constancy term.

    gx, gy : (T, H, W) float32 (e.g. from
    :func:`ivkernels.kernels.warp.derivatives.image_gradient`); out : (T, H, W, 2) float32.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = gx.shape
    tiles = row_tiles(w, gx.device)
    launch_rows(pack_gradient_rows, t * h * tiles, [tiles, gx, gy, out], gx.device)


@host("soft_census")
def soft_census(img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
    """Soft ternary (census) transform: one channel per neighbour of a window.

    ``out[t, y, x, k] = scale * d_k / sqrt(d_k^2 + eps^2)`` with
    ``d_k = img(y + dy_k, x + dx_k) - img(y, x)`` over the ``(2 radius + 1)^2 - 1``
    offsets of the window in row-major order, the centre left out; neighbour
    indices clamped (replicate border).  A smooth stand-in for the ternary
    census of Stein (2004) / Zabih & Woodfill (1994): it keeps the sign of each
    local difference and saturates its size, so it is unchanged by a gain or
    an offset of the image that is constant over the window.

    img : (T, H, W) float32.
    out : (T, H, W, C) float32, ``C = (2 radius + 1)^2 - 1``.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = img.shape
    tiles = row_tiles(w, img.device)
    launch_rows(soft_census_rows, t * h * tiles, [tiles, img, out, radius, float(eps), float(scale)], img.device)


@host("pack_channels_gradient")
def pack_channels_gradient(feat, gx, gy, out) -> None:
    """Interleave C channels with their derivatives: ``out[..., 3c : 3c + 3] = (feat_c, gx_c, gy_c)``.

    feat, gx, gy : (T, H, W, C) float32; out : (T, H, W, 3C) float32.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, c = feat.shape
    tiles = row_tiles(w, feat.device)
    launch_rows(pack_channels_gradient_rows, t * h * tiles, [tiles, feat, gx, gy, out], feat.device)
