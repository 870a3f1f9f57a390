"""Warping frames by a flow (bilinear, bicubic) and the bilinear splat, its adjoint.

The temporal terms of the paper (Eq. 4 and 8) compare ``A_t(x)`` with the next
frame warped back by the forward flow, ``A_{t+1}(x + u_t(x))``.  The warp is a
gather (:func:`warp_bilinear`); the derivative of a term in the warped image
lands on the four bilinear corners of ``x + u``, which is a scatter with atomic
adds (:func:`splat_bilinear`, the exact transpose of the warp).

Sampling convention: pixel centres sit at integer coordinates; the sample
point ``(px, py) = (x + u, y + v)`` mixes the corners ``floor(p)`` and
``floor(p) + 1``, each index clamped to the image (replicate border).  The
``inside`` map is 1 where the sample point lies in ``[0, W-1] x [0, H-1]``
(the "x + u stays inside the image" of Eq. 6), else 0.

The ``@wp.func`` helpers (:func:`clamped_corners`, :func:`bilinear_at`,
:func:`inside_image`, :func:`bicubic_at`) are shared by the occlusion maps and
the resizing kernels.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.sampling import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def clamped_corners(p: float, n: int):
    """Corners of a sample at coordinate ``p`` along an axis of ``n`` pixels.

    Returns ``(i0, i1, f)``: ``i0 = floor(p)``, ``i1 = i0 + 1``, both clamped
    to ``[0, n-1]``, and ``f = p - floor(p)`` the weight of ``i1``.  ``p`` is
    first clamped to ``[-2, n+1]``; this changes no sample (every tap beyond the
    border reads the border pixel anyway) but keeps huge flows from
    overflowing the float-to-int conversion.
    """
    q = wp.clamp(p, -2.0, float(n) + 1.0)
    f = wp.floor(q)
    i0 = int(f)
    return wp.clamp(i0, 0, n - 1), wp.clamp(i0 + 1, 0, n - 1), q - f


@wp.func
def bilinear_at(src: wp.array4d(dtype=float), t: int, c: int,
                x0: int, x1: int, fx: float, y0: int, y1: int, fy: float):
    """Bilinear mix of channel ``c`` of ``src[t]`` at corners from :func:`clamped_corners`."""
    top = (1.0 - fx) * src[t, y0, x0, c] + fx * src[t, y0, x1, c]
    bottom = (1.0 - fx) * src[t, y1, x0, c] + fx * src[t, y1, x1, c]
    return (1.0 - fy) * top + fy * bottom


@wp.func
def inside_image(px: float, py: float, height: int, width: int):
    """1.0 if ``(px, py)`` lies in ``[0, width-1] x [0, height-1]``, else 0.0."""
    result = 0.0
    if px >= 0.0 and px <= float(width - 1) and py >= 0.0 and py <= float(height - 1):
        result = 1.0
    return result


@wp.func
def keys_cubic(s: float):
    """Keys' cubic convolution kernel with a = -0.5 at distance ``s``."""
    a = -0.5
    s = wp.abs(s)
    w = 0.0
    if s <= 1.0:
        w = ((a + 2.0) * s - (a + 3.0)) * s * s + 1.0
    elif s < 2.0:
        w = ((a * s - 5.0 * a) * s + 8.0 * a) * s - 4.0 * a
    return w


@wp.func
def bicubic_at(src: wp.array4d(dtype=float), t: int, c: int, px: float, py: float):
    """Bicubic (Keys, a = -0.5) sample of channel ``c`` of ``src[t]`` at ``(px, py)``,
    every tap index clamped to the image."""
    height = src.shape[1]
    width = src.shape[2]
    qx = wp.clamp(px, -2.0, float(width) + 1.0)
    qy = wp.clamp(py, -2.0, float(height) + 1.0)
    bx = wp.floor(qx)
    by = wp.floor(qy)
    fx = qx - bx
    fy = qy - by
    ix = int(bx)
    iy = int(by)
    acc = 0.0
    for j in range(4):
        yj = wp.clamp(iy + j - 1, 0, height - 1)
        wy = keys_cubic(fy - float(j - 1))
        row = 0.0
        for i in range(4):
            xi = wp.clamp(ix + i - 1, 0, width - 1)
            row += keys_cubic(fx - float(i - 1)) * src[t, yj, xi, c]
        acc += wy * row
    return acc


# ----------------------------------------------------------------------------
# Kernels: one thread per tile of an image row (row = t * H + y; one tile per
# row on the CPU, one pixel per tile on a GPU), looping over x
# ----------------------------------------------------------------------------

@wp.kernel
def bilinear_warp_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                       out: wp.array4d(dtype=float), inside: wp.array3d(dtype=float)):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        px = float(x) + flow[t, y, x, 0]
        py = float(y) + flow[t, y, x, 1]
        x0, x1, fx = clamped_corners(px, width)
        y0, y1, fy = clamped_corners(py, height)
        for c in range(src.shape[3]):
            out[t, y, x, c] = bilinear_at(src, t, c, x0, x1, fx, y0, y1, fy)
        inside[t, y, x] = inside_image(px, py, height, width)


@wp.kernel
def bilinear_splat_rows(row_begin: int, tiles: int, values: wp.array4d(dtype=float),
                        flow: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        px = float(x) + flow[t, y, x, 0]
        py = float(y) + flow[t, y, x, 1]
        x0, x1, fx = clamped_corners(px, width)
        y0, y1, fy = clamped_corners(py, height)
        w00 = (1.0 - fx) * (1.0 - fy)
        w01 = fx * (1.0 - fy)
        w10 = (1.0 - fx) * fy
        w11 = fx * fy
        for c in range(values.shape[3]):
            v = values[t, y, x, c]
            wp.atomic_add(out, t, y0, x0, c, w00 * v)
            wp.atomic_add(out, t, y0, x1, c, w01 * v)
            wp.atomic_add(out, t, y1, x0, c, w10 * v)
            wp.atomic_add(out, t, y1, x1, c, w11 * v)


@wp.kernel
def bicubic_warp_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                      out: wp.array4d(dtype=float), inside: wp.array3d(dtype=float)):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        px = float(x) + flow[t, y, x, 0]
        py = float(y) + flow[t, y, x, 1]
        for c in range(src.shape[3]):
            out[t, y, x, c] = bicubic_at(src, t, c, px, py)
        inside[t, y, x] = inside_image(px, py, height, width)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("warp_bilinear")
def warp_bilinear(src, flow, out, inside) -> None:
    """Warp ``src`` by ``flow`` with bilinear interpolation: ``out = src[t](x + u)``.

    The ``A_{t+1}(x + u_t(x))`` of Eq. 4 and 8 (pass ``src = A[1:]``, the next
    frames, with the forward flows).

    Parameters
    ----------
    src : wp.array float32 (T, H, W, C), any C >= 1 (a (T, H, W) image goes in
        as a ``reshape((T, H, W, 1))`` view).
    flow : wp.array float32 (T, H, W, 2), pixels, (dx, dy).
    out : wp.array float32 (T, H, W, C), written: ``out[t, y, x, c]`` is the
        bilinear sample of ``src[t, :, :, c]`` at ``(x + dx, y + dy)``, corner
        indices clamped to the image (replicate border).  Must not overlap src.
    inside : wp.array float32 (T, H, W), written: 1.0 where the sample point
        lies within ``[0, W-1] x [0, H-1]``, else 0.0.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = src.shape[0], src.shape[1], src.shape[2]
    tiles = row_tiles(w, src.device)
    launch_rows(bilinear_warp_rows, t * h * tiles, [tiles, src, flow, out, inside], device=src.device)


@host("splat_bilinear")
def splat_bilinear(values, flow, out) -> None:
    """Add the transpose of :func:`warp_bilinear` applied to ``values`` into ``out``.

    Each ``values[t, y, x, c]`` is distributed over the four clamped bilinear
    corners of ``(x + dx, y + dy)`` in ``out[t]`` with the warp's weights, so
    ``<warp(a), b> == <a, splat(b)>`` for every ``a`` and ``b``.  This is how the
    gradient of a term in ``A_{t+1}(x + u)`` (Eq. 4, 8) reaches ``A_{t+1}``.

    Parameters
    ----------
    values : wp.array float32 (T, H, W, C).
    flow : wp.array float32 (T, H, W, 2), pixels.
    out : wp.array float32 (T, H, W, C), accumulated (``out += W^T values``);
        zero it first for the plain transpose.  Must not overlap ``values``.

    Atomic adds; the rows are split between CPU threads only at frame
    boundaries (``align=H``) so the two halves never write the same frame.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, c = values.shape
    tiles = row_tiles(w, values.device)
    launch_rows(bilinear_splat_rows, t * h * tiles, [tiles, values, flow, out], device=values.device,
                align=h * tiles)


@host("warp_bicubic")
def warp_bicubic(src, flow, out, inside) -> None:
    """Warp ``src`` by ``flow`` with bicubic interpolation (Keys, a = -0.5).

    Same contract as :func:`warp_bilinear` (shapes, clamped tap indices,
    ``inside`` map); the 4 x 4 taps around ``floor(p)`` are each clamped to the
    image.  Used by the optical flow's warping step (Classic+NL warps bicubically).

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = src.shape[0], src.shape[1], src.shape[2]
    tiles = row_tiles(w, src.device)
    launch_rows(bicubic_warp_rows, t * h * tiles, [tiles, src, flow, out, inside], device=src.device)
