"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_albedo_gsm` (Eq. 11): same host
function, same signature, NumPy arrays passed as ``ti.types.ndarray()``.

See the Warp module for the energy, the table grid, the gradient and the
band pass; the kernels here follow the same two steps:

1. cell coefficients: one thread per table entry turns ``table_g``,
   ``table_dg`` into ``(a, b, c, d)`` with ``g = a + b r2``, ``g' = c + d r2``
   inside cell ``i`` (the linear-in-r2 interpolation; the last cell holds the
   extrapolation beyond ``r2_max``), in float64, as four planes of ``n``;
2. the band pass: the outermost loop, over bands of rows, runs in parallel
   (one band is one thread's, so nothing needs atomics); a band walks its
   rows in order (and the ``radius`` rows above it in its frame) with a ring
   of ``radius + 1`` row slots holding the whitened rows ``B = L A``
   (``L^T L = Sigma^-1``) and each pixel's running sums
   ``(sum g' (B(x) - B(y)), sum g)``.  Each pixel of a row visits its
   forward half-window (``dy > 0``, or ``dy = 0`` and ``dx > 0``), looks each
   pair up once (cell ``i = int(min(sqrt(r2) (n-1) / sqrt(r2_max), n-1))``,
   its four coefficients, two multiply-adds), keeps its own sums in registers
   and adds the other halves to the pixels ahead; a finished row gets its
   gradient ``4 lam L^T sum`` and its energy (float64), and its slot is
   cleared for the row ``radius + 1`` below.

The buffers (float32, from the caller's workspace or allocated for the call)
are flat and hold planes of ``W`` floats: three per slot for ``B``, four per
slot for the sums.  The window radius is a ``ti.template()``, so the offset
loops are unrolled.  The sums are updated by plain assignments (Taichi makes
``+=`` on an ndarray atomic, which cost 4x here).  Unlike the Warp module the
pair loop runs pixel by pixel rather than offset by offset along the row:
Taichi does not vectorise either, and the pixel order keeps a pixel's own
sums out of memory (1 frame of 640x480 on 1 thread, alternated in one
process: 44 ms pixel by pixel, 56 offset by offset, 60 for the two passes
of the previous version).
"""
import math

import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_albedo_gsm import FAMILY
from ivkernels.kernels.thread_count import get_threads
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)


@ti.kernel
def _cell_coefficients(table_g: nd1, table_dg: nd1, r2_max: ti.f32, cells_per_root: ti.f32, coef: nd1):
    """Per table cell ``i``, ``(a, b, c, d)`` at ``coef[i], coef[n + i], coef[2n + i],
    coef[3n + i]`` with ``g = a + b r2`` and ``g' = c + d r2`` inside it (the
    linear-in-r2 interpolation of the table); the last cell holds the linear
    extrapolation beyond ``r2_max``.  Float64 arithmetic."""
    for i in range(table_g.shape[0]):
        n = table_g.shape[0]
        if i < n - 1:
            root_lo = ti.cast(i, ti.f64) / ti.cast(cells_per_root, ti.f64)
            root_hi = ti.cast(i + 1, ti.f64) / ti.cast(cells_per_root, ti.f64)
            r2_lo = root_lo * root_lo
            inv_width = ti.cast(1.0, ti.f64) / (root_hi * root_hi - r2_lo)
            slope_g = (ti.cast(table_g[i + 1], ti.f64) - ti.cast(table_g[i], ti.f64)) * inv_width
            slope_dg = (ti.cast(table_dg[i + 1], ti.f64) - ti.cast(table_dg[i], ti.f64)) * inv_width
            coef[i] = ti.cast(ti.cast(table_g[i], ti.f64) - slope_g * r2_lo, ti.f32)
            coef[n + i] = ti.cast(slope_g, ti.f32)
            coef[2 * n + i] = ti.cast(ti.cast(table_dg[i], ti.f64) - slope_dg * r2_lo, ti.f32)
            coef[3 * n + i] = ti.cast(slope_dg, ti.f32)
        else:
            last_dg = ti.cast(table_dg[n - 1], ti.f64)
            coef[i] = ti.cast(ti.cast(table_g[n - 1], ti.f64) - last_dg * ti.cast(r2_max, ti.f64), ti.f32)
            coef[n + i] = ti.cast(last_dg, ti.f32)
            coef[2 * n + i] = ti.cast(last_dg, ti.f32)
            coef[3 * n + i] = 0.0


@ti.func
def precision_factor(sigma_inv: ti.template()):
    """Upper-triangular ``L`` with ``L^T L = Sigma^-1`` (Cholesky of the symmetric part)."""
    p01 = 0.5 * (sigma_inv[0, 1] + sigma_inv[1, 0])
    p02 = 0.5 * (sigma_inv[0, 2] + sigma_inv[2, 0])
    p12 = 0.5 * (sigma_inv[1, 2] + sigma_inv[2, 1])
    l00 = ti.sqrt(sigma_inv[0, 0])
    l01 = p01 / l00
    l02 = p02 / l00
    l11 = ti.sqrt(sigma_inv[1, 1] - l01 * l01)
    l12 = (p12 - l01 * l02) / l11
    l22 = ti.sqrt(sigma_inv[2, 2] - l02 * l02 - l12 * l12)
    return ti.Matrix([[l00, l01, l02], [0.0, l11, l12], [0.0, 0.0, l22]])


@ti.func
def whiten_row(A: ti.template(), t, y, L, whitened: ti.template(), slot, width):
    """Slot ``slot`` of ``whitened`` (three planes of ``width``) gets ``B = L A(t, y, x)``."""
    o = slot * 3 * width
    for x in range(width):
        b = L @ ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
        for c in ti.static(range(3)):
            whitened[o + c * width + x] = b[c]


@ti.kernel
def _gsm_bands(A: nd4, sigma_inv: nd2, coef: nd1, cells_per_root: ti.f32, lam: ti.f32, radius: ti.template(),
               band_rows: ti.i32, n_bands: ti.i32, whitened: nd1, sums: nd1, gA: nd4,
               energy_rows: nd1_f64):
    """One thread per band of rows ``[r0, r1)`` (``r0 = band * band_rows``) with its
    ring of ``radius + 1`` slots (slot ``band (radius + 1) + r mod (radius + 1)``):
    the rows ``max(r0 - radius, frame start) .. r1 - 1`` are walked in order, each
    one's forward pairs added to both pixels; rows from ``r0`` on then get their
    gradient and energy.  ``radius`` is a compile-time constant."""
    ti.loop_config(block_dim=1)
    for band in range(n_bands):
        height = A.shape[1]
        width = A.shape[2]
        n_rows = A.shape[0] * height
        S = radius + 1
        r0 = band * band_rows
        r1 = ti.min(r0 + band_rows, n_rows)
        start = ti.max(r0 - radius, (r0 // height) * height)
        base = band * S
        L = precision_factor(sigma_inv)
        Lt = L.transpose()
        scale = 4.0 * lam
        for i in range(base * 4 * width, (base + S) * 4 * width):
            sums[i] = 0.0
        for r in range(start, ti.min(start + radius, n_rows)):
            t = r // height
            whiten_row(A, t, r - t * height, L, whitened, base + r % S, width)
        for r in range(start, r1):
            t = r // height
            y = r - t * height
            ahead = r + radius
            if ahead < n_rows:
                ta = ahead // height
                whiten_row(A, ta, ahead - ta * height, L, whitened, base + ahead % S, width)
            own = base + r % S
            n_cells = coef.shape[0] // 4
            last = ti.cast(n_cells - 1, ti.f32)
            ob = own * 3 * width
            os = own * 4 * width
            for x in range(width):
                # the forward half of x's window, each pair added to both pixels
                b0 = whitened[ob + x]
                b1 = whitened[ob + width + x]
                b2 = whitened[ob + 2 * width + x]
                a0 = 0.0
                a1 = 0.0
                a2 = 0.0
                ae = 0.0
                for dy in ti.static(range(radius + 1)):
                    qb = (base + (r + dy) % S) * 3 * width
                    qs = (base + (r + dy) % S) * 4 * width
                    for dx in ti.static(range(-radius, radius + 1)):
                        if ti.static(dy > 0 or dx > 0):
                            # a row above the band only serves the pairs that reach into it
                            if y + dy < height and r + dy >= r0 and x + dx >= 0 and x + dx < width:
                                d0 = b0 - whitened[qb + x + dx]
                                d1 = b1 - whitened[qb + width + x + dx]
                                d2 = b2 - whitened[qb + 2 * width + x + dx]
                                r2 = d0 * d0 + d1 * d1 + d2 * d2
                                i = ti.cast(ti.min(ti.sqrt(r2) * cells_per_root, last), ti.i32)
                                g = coef[i] + coef[n_cells + i] * r2
                                dg = coef[2 * n_cells + i] + coef[3 * n_cells + i] * r2
                                a0 += dg * d0
                                a1 += dg * d1
                                a2 += dg * d2
                                ae += g
                                q = qs + x + dx
                                sums[q] = sums[q] - dg * d0
                                sums[q + width] = sums[q + width] - dg * d1
                                sums[q + 2 * width] = sums[q + 2 * width] - dg * d2
                                sums[q + 3 * width] = sums[q + 3 * width] + g
                sums[os + x] = sums[os + x] + a0
                sums[os + width + x] = sums[os + width + x] + a1
                sums[os + 2 * width + x] = sums[os + 2 * width + x] + a2
                sums[os + 3 * width + x] = sums[os + 3 * width + x] + ae
            o = own * 4 * width
            if r >= r0:
                # row r has all its pairs (rows above the band only served the band's first rows)
                e = ti.cast(0.0, ti.f64)
                for x in range(width):
                    grad = scale * (Lt @ ti.Vector([sums[o + x], sums[o + width + x], sums[o + 2 * width + x]]))
                    for c in ti.static(range(3)):
                        gA[t, y, x, c] = gA[t, y, x, c] + grad[c]
                    e += ti.cast(sums[o + 3 * width + x], ti.f64)
                energy_rows[r] = energy_rows[r] + ti.cast(lam, ti.f64) * e
            for i in range(o, o + 4 * width):
                sums[i] = 0.0


def _scratch(workspace, name: str, shape: tuple) -> np.ndarray:
    """Float32 scratch buffer ``name`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, np.float32,
                          lambda: np.empty(shape, np.float32))


@host("gsm_smoothness")
def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows,
                   lam: float, radius: int = 2, *, workspace=None) -> None:
    """Add Eq. 11's GSM smoothness energy and gradient (see the Warp module).

    ``A`` (T, H, W, 3) float32 log albedo; ``sigma_inv`` (3, 3) float32;
    ``table_g``, ``table_dg`` (n,) float32 (inputs copied if not C-contiguous);
    ``gA`` (T, H, W, 3) float32 (not overlapping ``A``) and ``energy_rows``
    (T*H,) float64 accumulated (C-contiguous); ``workspace`` an optional
    :class:`ivkernels.kernels.workspace.Workspace` keeping the scratch buffers.
    """
    T, H, W, _ = A.shape
    n = table_g.shape[0]
    if T * H == 0 or W == 0:
        return
    band_rows = band_rows_for(T * H)
    n_bands = -(-T * H // band_rows)
    slots = n_bands * (radius + 1)
    if slots * 4 * W > 2**31 - 1:
        raise ValueError(f"A of shape {A.shape} with radius {radius} needs {slots * 4 * W} scratch entries, "
                         f"more than the 2**31 - 1 that 32-bit indices address; pass fewer frames per call "
                         f"or a smaller radius")
    coef = _scratch(workspace, "cell_coefficients", (4 * n,))
    whitened = _scratch(workspace, "whitened_rows", (slots * 3 * W,))
    sums = _scratch(workspace, "pixel_sums", (slots * 4 * W,))
    cells_per_root = (n - 1) / math.sqrt(r2_max)
    _cell_coefficients(table_g, table_dg, float(r2_max), float(cells_per_root), coef)
    _gsm_bands(A, sigma_inv, coef, float(cells_per_root), float(lam), int(radius), int(band_rows), int(n_bands),
               whitened, sums, gA, energy_rows)


def band_rows_for(n_rows: int) -> int:
    """Rows per band: about :data:`BANDS_PER_THREAD` bands per thread (the
    launch thread count, which Taichi is initialised with), at least
    :data:`MIN_BAND_ROWS` rows each, as in the Warp module."""
    return max(MIN_BAND_ROWS, -(-n_rows // (BANDS_PER_THREAD * get_threads())))


#: Bands per thread: enough that a thread held up by another process leaves its share to the others.
BANDS_PER_THREAD = 16

#: Fewest rows of a band.
MIN_BAND_ROWS = 32
