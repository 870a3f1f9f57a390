"""The IRLS step's linear system and its solve: red-black SOR, then the flow update.

:func:`assemble_system` folds the data coefficients, the smoothness weights
and the current flow into each pixel's 2x2 block and right-hand side, so a
sweep of :func:`sor_sweep` reads only ``du``: pixels with
``(x + y) % 2 == parity`` read only neighbours of the other colour, so a
half sweep is race-free and can be split into row bands anywhere;
:func:`sor_full_sweep` does both half sweeps in one pass over each band.
:func:`apply_update` adds the clipped increment; :func:`select_masked`
chooses between two fields per pixel.  Part of
:mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import functools

import numpy as np
import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import get_threads, gpu_layout, launch_rows, min_band_rows, row_bands, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

__all__ = ["assemble_system", "sor_sweep", "sor_full_sweep", "apply_update", "select_masked"]

wp.set_module_options({"enable_backward": False})


@wp.kernel
def assemble_system_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                         data: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float),
                         out: wp.array4d(dtype=float), lam: float):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        u = flow[t, y, x, 0]
        v = flow[t, y, x, 1]
        diag_u = float(0.0)
        diag_v = float(0.0)
        rhs_u = -data[t, y, x, 3]
        rhs_v = -data[t, y, x, 4]
        if x < width - 1:
            wu = lam * smooth[t, y, x, 0]
            wv = lam * smooth[t, y, x, 2]
            diag_u += wu
            diag_v += wv
            rhs_u += wu * (flow[t, y, x + 1, 0] - u)
            rhs_v += wv * (flow[t, y, x + 1, 1] - v)
        if x > 0:
            wu = lam * smooth[t, y, x - 1, 0]
            wv = lam * smooth[t, y, x - 1, 2]
            diag_u += wu
            diag_v += wv
            rhs_u += wu * (flow[t, y, x - 1, 0] - u)
            rhs_v += wv * (flow[t, y, x - 1, 1] - v)
        if y < height - 1:
            wu = lam * smooth[t, y, x, 1]
            wv = lam * smooth[t, y, x, 3]
            diag_u += wu
            diag_v += wv
            rhs_u += wu * (flow[t, y + 1, x, 0] - u)
            rhs_v += wv * (flow[t, y + 1, x, 1] - v)
        if y > 0:
            wu = lam * smooth[t, y - 1, x, 1]
            wv = lam * smooth[t, y - 1, x, 3]
            diag_u += wu
            diag_v += wv
            rhs_u += wu * (flow[t, y - 1, x, 0] - u)
            rhs_v += wv * (flow[t, y - 1, x, 1] - v)
        out[t, y, x, 0] = data[t, y, x, 0] + diag_u
        out[t, y, x, 1] = data[t, y, x, 1]
        out[t, y, x, 2] = data[t, y, x, 2] + diag_v
        out[t, y, x, 3] = rhs_u
        out[t, y, x, 4] = rhs_v


@wp.func
def sor_relax(du: wp.array4d(dtype=float), system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float),
              lam: float, omega: float, t: int, y: int, x: int):
    """Relaxes pixel ``(t, y, x)``: solves its 2x2 block with the neighbours fixed."""
    height = du.shape[1]
    width = du.shape[2]
    rhs_u = system[t, y, x, 3]
    rhs_v = system[t, y, x, 4]
    if x < width - 1:
        rhs_u += lam * smooth[t, y, x, 0] * du[t, y, x + 1, 0]
        rhs_v += lam * smooth[t, y, x, 2] * du[t, y, x + 1, 1]
    if x > 0:
        rhs_u += lam * smooth[t, y, x - 1, 0] * du[t, y, x - 1, 0]
        rhs_v += lam * smooth[t, y, x - 1, 2] * du[t, y, x - 1, 1]
    if y < height - 1:
        rhs_u += lam * smooth[t, y, x, 1] * du[t, y + 1, x, 0]
        rhs_v += lam * smooth[t, y, x, 3] * du[t, y + 1, x, 1]
    if y > 0:
        rhs_u += lam * smooth[t, y - 1, x, 1] * du[t, y - 1, x, 0]
        rhs_v += lam * smooth[t, y - 1, x, 3] * du[t, y - 1, x, 1]
    a11 = system[t, y, x, 0]
    a12 = system[t, y, x, 1]
    a22 = system[t, y, x, 2]
    det = a11 * a22 - a12 * a12
    if det > 1.0e-20 * (a11 * a22 + 1.0e-30):
        new_u = (a22 * rhs_u - a12 * rhs_v) / det
        new_v = (a11 * rhs_v - a12 * rhs_u) / det
        du[t, y, x, 0] = (1.0 - omega) * du[t, y, x, 0] + omega * new_u
        du[t, y, x, 1] = (1.0 - omega) * du[t, y, x, 1] + omega * new_v


@wp.func
def sor_relax_row(du: wp.array4d(dtype=float), system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float),
                  lam: float, omega: float, r: int, parity: int):
    """Relaxes the pixels of colour ``parity`` in stack row ``r`` (frame ``r // H``, row ``r % H``), left to right."""
    height = du.shape[1]
    t = r // height
    y = r - t * height
    x = (parity + y) % 2
    while x < du.shape[2]:
        sor_relax(du, system, smooth, lam, omega, t, y, x)
        x += 2


@wp.kernel
def sor_sweep_rows(row_begin: int, tiles: int, du: wp.array4d(dtype=float), system: wp.array4d(dtype=float),
                   smooth: wp.array4d(dtype=float), lam: float, omega: float, parity: int):
    """The pixels of colour ``parity`` in one tile of a stack row (the whole row
    with one tile per row: :func:`sor_relax_row`'s order), left to right."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, du.shape[2])
    height = du.shape[1]
    t = r // height
    y = r - t * height
    x = x_begin + (parity + y + x_begin) % 2
    while x < x_end:
        sor_relax(du, system, smooth, lam, omega, t, y, x)
        x += 2


@wp.kernel
def sor_full_sweep_bands(band_begin: int, bounds: wp.array(dtype=int), du: wp.array4d(dtype=float),
                         system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float), lam: float,
                         omega: float):
    """Band ``j = band_begin + tid`` covers rows ``[bounds[j], bounds[j + 1])``: red of row r, then black
    of row r - 1; the black pixels of the band's first and last rows are left to :func:`sor_edge_rows`."""
    j = band_begin + wp.tid()
    first = bounds[j]
    last = bounds[j + 1] - 1
    for r in range(first, last + 1):
        sor_relax_row(du, system, smooth, lam, omega, r, 0)
        b = r - 1
        # the black of row b reads the red of rows b - 1, b and b + 1, all final here when inside the band
        if b > first and b < last:
            sor_relax_row(du, system, smooth, lam, omega, b, 1)


@wp.kernel
def sor_edge_rows(row_begin: int, bounds: wp.array(dtype=int), du: wp.array4d(dtype=float),
                  system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float), lam: float, omega: float):
    """Thread ``2 j`` relaxes the black of band j's first row, thread ``2 j + 1`` that of its last row
    (when the band has more than one row)."""
    i = row_begin + wp.tid()
    j = i // 2
    first = bounds[j]
    last = bounds[j + 1] - 1
    if i % 2 == 0:
        sor_relax_row(du, system, smooth, lam, omega, first, 1)
    elif last > first:
        sor_relax_row(du, system, smooth, lam, omega, last, 1)


@wp.kernel
def apply_update_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), du: wp.array4d(dtype=float),
                      out: wp.array4d(dtype=float), limit: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        for c in range(2):
            d = du[t, y, x, c]
            if limit > 0.0:
                d = wp.clamp(d, -limit, limit)
            out[t, y, x, c] = flow[t, y, x, c] + d


@wp.kernel
def select_masked_rows(row_begin: int, tiles: int, mask: wp.array3d(dtype=float),
                       inside_mask: wp.array4d(dtype=float), outside_mask: wp.array4d(dtype=float),
                       out: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, mask.shape[2])
    height = mask.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        for c in range(out.shape[3]):
            if mask[t, y, x] >= 0.5:
                out[t, y, x, c] = inside_mask[t, y, x, c]
            else:
                out[t, y, x, c] = outside_mask[t, y, x, c]


@host("assemble_system")
def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """The 2x2 block and right-hand side of every pixel's IRLS equations.

    ``out = (a11, a12, a22, b_u, b_v)`` with ``a11 = psi_D Ix^2 + lam sum_n w^u_n``,
    ``a12 = psi_D Ix Iy``, ``a22 = psi_D Iy^2 + lam sum_n w^v_n`` and
    ``b_u = -psi_D Ix It + lam sum_n w^u_n (u_n - u)`` (likewise ``b_v``), so
    that the equations read ``A_p du_p - lam sum_n w_n du_n = b_p``.

    flow : (T, H, W, 2) float32, flow ``u`` the increment is added to.
    data : (T, H, W, 5) float32 from :func:`data_coefficients`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights`.
    out : (T, H, W, 5) float32.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = flow.shape
    dev = flow.device
    tiles = row_tiles(w, dev)
    launch_rows(assemble_system_rows, t * h * tiles, [tiles, flow, data, smooth, out, float(lam)], dev)


@host("sor_sweep")
def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """One half-sweep of red-black block SOR on the IRLS system, in place on ``du``.

    Updates the pixels with ``(x + y) % 2 == parity``: solves their 2x2 block
    ``A_p du_p = b_p + lam sum_n w_n du_n`` with the neighbours fixed, and
    relaxes by ``omega`` (1 = Gauss-Seidel).  Call with parity 0 then 1 for a
    full sweep.

    du : (T, H, W, 2) float32, increment, read and written.
    system : (T, H, W, 5) float32 from :func:`assemble_system`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights` (the same
        ``lam`` as given to :func:`assemble_system`).
    """
    t, h, w, _ = du.shape
    dev = du.device
    tiles = row_tiles(w, dev, pixels_per_tile=2)        # on a GPU one pixel of the colour per thread
    launch_rows(sor_sweep_rows, t * h * tiles, [tiles, du, system, smooth, float(lam), float(omega), int(parity)],
                dev)


@host("sor_full_sweep")
def sor_full_sweep(du, system, smooth, lam: float, omega: float) -> None:
    """One full sweep of red-black block SOR, in place on ``du``: bitwise the
    result of :func:`sor_sweep` with parity 0 then 1, in one pass over memory.

    The ``T * H`` rows are cut into the row bands :func:`launch_rows` would
    use; in each band, one thread updates the red pixels of row ``r`` and then
    the black pixels of row ``r - 1``, whose four neighbours (all red) are then
    final, so each row's coefficients are read while still in cache.  The
    black pixels of a band's first and last rows read red pixels of the
    neighbouring bands and are updated by a second, small launch after all
    bands.  Every pixel sees the same neighbour values as in the two half
    sweeps, so every bit of the result is theirs.  On CUDA it is the two
    half-sweep launches.

    du : (T, H, W, 2) float32, increment, read and written.
    system : (T, H, W, 5) float32 from :func:`assemble_system`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights` (the same
        ``lam`` as given to :func:`assemble_system`).
    """
    t, h, w, _ = du.shape
    dev = du.device
    if gpu_layout(dev):
        sor_sweep(du, system, smooth, lam, omega, 0)
        sor_sweep(du, system, smooth, lam, omega, 1)
        return
    n_rows = t * h
    inputs = [du, system, smooth, float(lam), float(omega)]
    bands = row_bands(n_rows, get_threads(), 1, min_band_rows(n_rows, inputs))
    bounds = _band_bounds(tuple(b for b, _ in bands) + (n_rows,), str(dev))
    # one band per thread: launch_rows splits these len(bands) units one per band
    launch_rows(sor_full_sweep_bands, len(bands), [bounds, *inputs], dev)
    wp.launch(sor_edge_rows, dim=2 * len(bands), inputs=[0, bounds, *inputs], device=dev)


@functools.lru_cache(maxsize=64)
def _band_bounds(bounds: tuple[int, ...], device: str):
    """The band boundaries ``(b_0 = 0, b_1, ..., b_k = T * H)`` as a Warp int array, made once per split."""
    return wp.array(np.asarray(bounds, np.int32), dtype=int, device=device)


@host("apply_update")
def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """``out = flow + clip(du, -limit, limit)`` (no clipping when ``limit <= 0``).

    flow, du, out : (T, H, W, 2) float32; ``out`` may be ``flow``.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = flow.shape
    tiles = row_tiles(w, flow.device)
    launch_rows(apply_update_rows, t * h * tiles, [tiles, flow, du, out, float(limit)], flow.device)


@host("select_masked")
def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """``out = inside_mask`` where ``mask >= 0.5``, else ``outside_mask``.

    mask : (T, H, W) float32; inside_mask, outside_mask, out : (T, H, W, C) float32
    (``out`` may alias either input).  On a GPU one pixel per thread (row tiles).
    """
    t, h, w = mask.shape
    tiles = row_tiles(w, mask.device)
    launch_rows(select_masked_rows, t * h * tiles, [tiles, mask, inside_mask, outside_mask, out], mask.device)
