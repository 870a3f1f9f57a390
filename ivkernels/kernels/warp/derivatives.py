"""Spatial derivatives of images and flow fields.

* :func:`image_gradient`: the optical flow's derivative filter
  ``[1 -8 0 8 -1] / 12`` along x and y (Classic+NL).
* :func:`flow_sobel_magnitude`: edge strength of a flow field, the input of
  the motion-boundary map ``w_bnd`` (Section 3.3).
* :func:`divergence_negative`: the one-sided (compression only) divergence
  ``d`` of the occlusion detector (Eq. 7).

Every neighbour index is clamped to the image (replicate border).  One kernel
thread per tile of an image row: one tile per row on the CPU, one pixel per
tile on a GPU (:func:`ivkernels.kernels.launch.row_tiles`).
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.derivatives import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Kernels (one thread per tile of a row = t * H + y)
# ----------------------------------------------------------------------------

@wp.kernel
def five_point_gradient_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float),
                             gx: wp.array4d(dtype=float), gy: wp.array4d(dtype=float)):
    height = src.shape[1]
    width = src.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    ym2 = wp.max(y - 2, 0)
    ym1 = wp.max(y - 1, 0)
    yp1 = wp.min(y + 1, height - 1)
    yp2 = wp.min(y + 2, height - 1)
    for x in range(x_begin, x_end):
        xm2 = wp.max(x - 2, 0)
        xm1 = wp.max(x - 1, 0)
        xp1 = wp.min(x + 1, width - 1)
        xp2 = wp.min(x + 2, width - 1)
        for c in range(src.shape[3]):
            gx[t, y, x, c] = (src[t, y, xm2, c] - 8.0 * src[t, y, xm1, c]
                              + 8.0 * src[t, y, xp1, c] - src[t, y, xp2, c]) / 12.0
            gy[t, y, x, c] = (src[t, ym2, x, c] - 8.0 * src[t, ym1, x, c]
                              + 8.0 * src[t, yp1, x, c] - src[t, yp2, x, c]) / 12.0


@wp.kernel
def flow_sobel_magnitude_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                              out: wp.array3d(dtype=float)):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    for x in range(x_begin, x_end):
        xm = wp.max(x - 1, 0)
        xp = wp.min(x + 1, width - 1)
        total = 0.0
        for c in range(2):
            sx = ((flow[t, ym, xp, c] - flow[t, ym, xm, c])
                  + 2.0 * (flow[t, y, xp, c] - flow[t, y, xm, c])
                  + (flow[t, yp, xp, c] - flow[t, yp, xm, c])) / 8.0
            sy = ((flow[t, yp, xm, c] - flow[t, ym, xm, c])
                  + 2.0 * (flow[t, yp, x, c] - flow[t, ym, x, c])
                  + (flow[t, yp, xp, c] - flow[t, ym, xp, c])) / 8.0
            total += sx * sx + sy * sy
        out[t, y, x] = wp.sqrt(total)


@wp.kernel
def divergence_negative_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                             out: wp.array3d(dtype=float)):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    for x in range(x_begin, x_end):
        xm = wp.max(x - 1, 0)
        xp = wp.min(x + 1, width - 1)
        div = 0.5 * (flow[t, y, xp, 0] - flow[t, y, xm, 0]) + 0.5 * (flow[t, yp, x, 1] - flow[t, ym, x, 1])
        out[t, y, x] = wp.min(div, 0.0)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("image_gradient")
def image_gradient(src, gx, gy) -> None:
    """x and y derivatives with the 5-point filter ``[1 -8 0 8 -1] / 12``.

    ``gx[t, y, x] = (src[x-2] - 8 src[x-1] + 8 src[x+1] - src[x+2]) / 12`` (the
    derivative of a linear ramp is its slope), likewise along y; neighbour
    indices clamped (replicate border).

    Parameters
    ----------
    src : wp.array float32 (T, H, W, C), any C >= 1.
    gx, gy : wp.array float32 (T, H, W, C), written (must not overlap src).

    On a GPU one pixel per thread (row tiles).
    """
    tiles = row_tiles(src.shape[2], src.device)
    launch_rows(five_point_gradient_rows, src.shape[0] * src.shape[1] * tiles, [tiles, src, gx, gy],
                device=src.device)


@host("flow_sobel_magnitude")
def flow_sobel_magnitude(flow, out) -> None:
    """Sobel edge magnitude of a flow field, ``sqrt(sum_c Sx(u_c)^2 + Sy(u_c)^2)``.

    Sobel kernels ``[[-1 0 1], [-2 0 2], [-1 0 1]] / 8`` and its transpose (a unit
    ramp gives 1), replicate border.  Thresholded and dilated by
    :func:`ivkernels.kernels.warp.maps.motion_boundary` into ``w_bnd`` (Sec. 3.3).

    Parameters
    ----------
    flow : wp.array float32 (T, H, W, 2), pixels.
    out : wp.array float32 (T, H, W), written, pixels per pixel.

    On a GPU one pixel per thread (row tiles).
    """
    tiles = row_tiles(flow.shape[2], flow.device)
    launch_rows(flow_sobel_magnitude_rows, flow.shape[0] * flow.shape[1] * tiles, [tiles, flow, out],
                device=flow.device)


@host("divergence_negative")
def divergence_negative(flow, out) -> None:
    """One-sided divergence ``d = min(du/dx + dv/dy, 0)`` of Eq. 7.

    Central differences ``(u[x+1] - u[x-1]) / 2`` with replicate border; only
    compression (negative divergence, where surfaces get occluded) is kept.

    Parameters
    ----------
    flow : wp.array float32 (T, H, W, 2), pixels.
    out : wp.array float32 (T, H, W), written, <= 0.

    On a GPU one pixel per thread (row tiles).
    """
    tiles = row_tiles(flow.shape[2], flow.device)
    launch_rows(divergence_negative_rows, flow.shape[0] * flow.shape[1] * tiles, [tiles, flow, out],
                device=flow.device)
