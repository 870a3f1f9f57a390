"""Edges of a flow field: Sobel derivatives of both components and their thinning.

MATLAB's ``edge(u, 'sobel')`` of u OR of v, as the public Classic+NL code
finds the flow's motion boundaries: :func:`flow_sobel_components` gives the
derivatives and the per-row energy the host turns into a cutoff,
:func:`thin_edges` keeps the local maxima above it.  Part of
:mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

__all__ = ["flow_sobel_components", "thin_edges"]

wp.set_module_options({"enable_backward": False})


@wp.func
def sobel_at(flow: wp.array4d(dtype=float), t: int, y: int, x: int, c: int):
    """Sobel derivatives ``(gx, gy)`` of flow component ``c``, kernels / 8, replicate border."""
    height = flow.shape[1]
    width = flow.shape[2]
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    xm = wp.max(x - 1, 0)
    xp = wp.min(x + 1, width - 1)
    gx = (flow[t, ym, xp, c] + 2.0 * flow[t, y, xp, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, y, xm, c] - flow[t, yp, xm, c]) / 8.0
    gy = (flow[t, yp, xm, c] + 2.0 * flow[t, yp, x, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, ym, x, c] - flow[t, ym, xp, c]) / 8.0
    return gx, gy


@wp.kernel
def flow_sobel_components_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                               out: wp.array4d(dtype=float), row_energy: wp.array2d(dtype=float)):
    """The Sobel derivatives of one tile of a row; with one tile per row also the
    row's energy (else :func:`sobel_row_energy_rows` sums it afterwards)."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    sum_u = float(0.0)
    sum_v = float(0.0)
    for x in range(x_begin, x_end):
        gxu, gyu = sobel_at(flow, t, y, x, 0)
        gxv, gyv = sobel_at(flow, t, y, x, 1)
        out[t, y, x, 0] = gxu
        out[t, y, x, 1] = gyu
        out[t, y, x, 2] = gxv
        out[t, y, x, 3] = gyv
        sum_u += gxu * gxu + gyu * gyu
        sum_v += gxv * gxv + gyv * gyv
    if tiles == 1:
        row_energy[r, 0] = sum_u
        row_energy[r, 1] = sum_v


@wp.kernel
def sobel_row_energy_rows(row_begin: int, sobel: wp.array4d(dtype=float), row_energy: wp.array2d(dtype=float)):
    """``sum_x |grad u|^2`` and ``sum_x |grad v|^2`` of a row of :func:`flow_sobel_components_rows`'
    output, added in the order and with the operations of its one-tile loop (the same bits)."""
    r = row_begin + wp.tid()
    height = sobel.shape[1]
    t = r // height
    y = r - t * height
    sum_u = float(0.0)
    sum_v = float(0.0)
    for x in range(sobel.shape[2]):
        gxu = sobel[t, y, x, 0]
        gyu = sobel[t, y, x, 1]
        gxv = sobel[t, y, x, 2]
        gyv = sobel[t, y, x, 3]
        sum_u += gxu * gxu + gyu * gyu
        sum_v += gxv * gxv + gyv * gyv
    row_energy[r, 0] = sum_u
    row_energy[r, 1] = sum_v


@wp.func
def sobel_energy(sobel: wp.array4d(dtype=float), t: int, y: int, x: int, c: int):
    gx = sobel[t, y, x, 2 * c]
    gy = sobel[t, y, x, 2 * c + 1]
    return gx * gx + gy * gy


@wp.kernel
def thin_edges_rows(row_begin: int, tiles: int, sobel: wp.array4d(dtype=float), cutoff: wp.array2d(dtype=float),
                    out: wp.array3d(dtype=float)):
    height = sobel.shape[1]
    width = sobel.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    for x in range(x_begin, x_end):
        xm = wp.max(x - 1, 0)
        xp = wp.min(x + 1, width - 1)
        edge = float(0.0)
        for c in range(2):
            b = sobel_energy(sobel, t, y, x, c)
            if b > cutoff[t, c]:
                ax = wp.abs(sobel[t, y, x, 2 * c])
                ay = wp.abs(sobel[t, y, x, 2 * c + 1])
                if ax >= ay and b > sobel_energy(sobel, t, y, xm, c) and b >= sobel_energy(sobel, t, y, xp, c):
                    edge = 1.0
                if ay >= ax and b > sobel_energy(sobel, t, ym, x, c) and b >= sobel_energy(sobel, t, yp, x, c):
                    edge = 1.0
        out[t, y, x] = edge


@host("flow_sobel_components")
def flow_sobel_components(flow, out, row_energy) -> None:
    """Sobel derivatives of both flow components and their per-row energy.

    Kernels ``[[-1 0 1], [-2 0 2], [-1 0 1]] / 8`` and its transpose, replicate
    border (MATLAB's ``edge(u, 'sobel')`` gradients).

    flow : (T, H, W, 2) float32.
    out : (T, H, W, 4) float32 ``(du/dx, du/dy, dv/dx, dv/dy)``.
    row_energy : (T*H, 2) float32, ``sum_x |grad u|^2`` and ``sum_x |grad v|^2``
        of each row (the host averages them into the edge thresholds).

    On a GPU one pixel per thread (row tiles), then one thread per row sums the
    row energies from ``out`` in the CPU's order (no atomics: the same bits).
    """
    t, h, w, _ = flow.shape
    dev = flow.device
    tiles = row_tiles(w, dev)
    launch_rows(flow_sobel_components_rows, t * h * tiles, [tiles, flow, out, row_energy], dev)
    if tiles > 1:
        launch_rows(sobel_row_energy_rows, t * h, [out, row_energy], dev)


@host("thin_edges")
def thin_edges(sobel, cutoff, out) -> None:
    """Thinned Sobel edges of a flow field (MATLAB ``edge(., 'sobel')`` of u OR of v).

    A pixel is an edge of component ``c`` where ``b = gx^2 + gy^2`` exceeds
    ``cutoff[t, c]`` and is a local maximum across the edge: along x where
    ``|gx| >= |gy|`` (``b > b(x-1)`` and ``b >= b(x+1)``), along y where
    ``|gy| >= |gx|``; neighbour indices clamped.  The public code takes
    ``cutoff = 4 * mean(b)`` per frame and component.

    sobel : (T, H, W, 4) float32 from :func:`flow_sobel_components`.
    cutoff : (T, 2) float32 squared-magnitude thresholds (pixels^2 / pixel^2).
    out : (T, H, W) float32, 1 on an edge of u or v, else 0.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = sobel.shape
    tiles = row_tiles(w, sobel.device)
    launch_rows(thin_edges_rows, t * h * tiles, [tiles, sobel, cutoff, out], sobel.device)
