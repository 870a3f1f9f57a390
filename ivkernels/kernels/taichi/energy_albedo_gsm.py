"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_albedo_gsm` (Eq. 11): same host
function, same signature, NumPy arrays passed as ``ti.types.ndarray()``.

See the Warp module for the energy, the table grid and the gradient; the
kernels here follow the same whitening pass, per-cell coefficient pass and
two pair passes, the image passes each with its outermost loop over the
``T * H`` image rows in parallel (a row is one thread's, so the gradient
needs no atomics) and each row's energy summed in float64:

1. whitening: ``B(x) = L A(x)`` (``L^T L = Sigma^-1``), so ``r2 = |B(x) - B(y)|^2``;
2. cell coefficients: one thread per table entry turns ``table_g``,
   ``table_dg`` into ``(a, b, c, d)`` with ``g = a + b r2``, ``g' = c + d r2``
   inside cell ``i`` (the linear-in-r2 interpolation; the last entry holds the
   extrapolation beyond ``r2_max``), in float64, recomputed on every call;
3. forward pairs: each pixel visits its forward half-window (``dy > 0``, or
   ``dy = 0`` and ``dx > 0``: 12 of the 5x5 window's 24 neighbours), looks
   each pair ``{x, x + o_k}`` up once (cell
   ``i = int(min(sqrt(r2) (n-1) / sqrt(r2_max), n-1))``, its four
   coefficients and two multiply-adds), stores ``(g, g')`` as pair ``k`` of
   ``x``, and starts its gradient sum ``sum_k g' (B(x) - B(x + o_k))`` and
   its row's energy;
4. backward pairs: each pixel gathers the pairs it closes (``x - o_k``) from
   the stored values, adds their ``g`` to its own row's energy and adds its
   gradient ``4 lam L^T acc`` to ``gA``.

Every unordered pair thus counts twice in the energy (once in each of its
pixels' rows), exactly as a full-window visit would give.

Scratch buffers (float32, from the caller's workspace or allocated for the
call, as in the Warp module) have the Warp
module's layouts, ``B`` and the forward sums ``(T*H, W, 3)`` and the pairs
``(T*H, W, K, 2)`` with ``K = radius + radius (2 radius + 1)`` and the cell
coefficients ``(n, 4)``, but are passed flat and indexed by pixel
``p = (t H + y) W + x``: ``B[3 p + c]``, ``pairs[2 (K p + k) + j]``,
``coef[4 i + j]``.  With stores to the pairs in the inner loop, flat
indexing saves reloading every ndarray's shape at each access (the forward
pass runs ~15% faster than with 4-D indexing).  The pair passes take the
window radius as a ``ti.template()`` (one compiled kernel per radius), so
the offsets are unrolled as in the Warp module: 1.45x faster than with a
runtime radius (640x480, 8 frames, radius 2, 2 threads, alternated in one
process: 275 against 399 ms; gradients agree to 1.2e-4, float32 rounding).
"""
import math

import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_albedo_gsm import FAMILY
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)


@ti.kernel
def _cell_coefficients(table_g: nd1, table_dg: nd1, r2_max: ti.f32, cells_per_root: ti.f32, coef: nd1):
    """Per table cell ``i``, ``(a, b, c, d)`` at ``coef[4 i : 4 i + 4]`` with
    ``g = a + b r2`` and ``g' = c + d r2`` inside it (the linear-in-r2
    interpolation of the table); the last entry holds the linear extrapolation
    beyond ``r2_max``.  Float64 arithmetic."""
    for i in range(table_g.shape[0]):
        n = table_g.shape[0]
        if i < n - 1:
            root_lo = ti.cast(i, ti.f64) / ti.cast(cells_per_root, ti.f64)
            root_hi = ti.cast(i + 1, ti.f64) / ti.cast(cells_per_root, ti.f64)
            r2_lo = root_lo * root_lo
            inv_width = ti.cast(1.0, ti.f64) / (root_hi * root_hi - r2_lo)
            slope_g = (ti.cast(table_g[i + 1], ti.f64) - ti.cast(table_g[i], ti.f64)) * inv_width
            slope_dg = (ti.cast(table_dg[i + 1], ti.f64) - ti.cast(table_dg[i], ti.f64)) * inv_width
            coef[4 * i] = ti.cast(ti.cast(table_g[i], ti.f64) - slope_g * r2_lo, ti.f32)
            coef[4 * i + 1] = ti.cast(slope_g, ti.f32)
            coef[4 * i + 2] = ti.cast(ti.cast(table_dg[i], ti.f64) - slope_dg * r2_lo, ti.f32)
            coef[4 * i + 3] = ti.cast(slope_dg, ti.f32)
        else:
            last_dg = ti.cast(table_dg[n - 1], ti.f64)
            coef[4 * i] = ti.cast(ti.cast(table_g[n - 1], ti.f64) - last_dg * ti.cast(r2_max, ti.f64), ti.f32)
            coef[4 * i + 1] = ti.cast(last_dg, ti.f32)
            coef[4 * i + 2] = ti.cast(last_dg, ti.f32)
            coef[4 * i + 3] = 0.0


@ti.func
def gsm_lookup(r2, coef: ti.template(), cells_per_root):
    """``(g, g')`` at ``r2``: the cell ``floor(sqrt(r2) (n-1) / sqrt(r2_max))``,
    or the extrapolation entry beyond the table, then one multiply-add each."""
    last = coef.shape[0] // 4 - 1
    i = 4 * ti.cast(ti.min(ti.sqrt(r2) * cells_per_root, ti.cast(last, ti.f32)), ti.i32)
    return coef[i] + coef[i + 1] * r2, coef[i + 2] + coef[i + 3] * r2


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
def load3(a: ti.template(), i):
    """The 3-vector ``a[i : i + 3]`` of a flat buffer."""
    return ti.Vector([a[i], a[i + 1], a[i + 2]])


@ti.kernel
def _whiten_rows(A: nd4, sigma_inv: nd2, B: nd1):
    """``B(p) = L A(t, y, x)`` at ``B[3 p : 3 p + 3]``, ``p = (t H + y) W + x``,
    so that ``r2 = |B(x) - B(y)|^2``."""
    for r in range(A.shape[0] * A.shape[1]):
        height = A.shape[1]
        width = A.shape[2]
        t = r // height
        y = r - t * height
        L = precision_factor(sigma_inv)
        for x in range(width):
            b = L @ ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
            i = 3 * (r * width + x)
            for c in ti.static(range(3)):
                B[i + c] = b[c]


@ti.kernel
def _gsm_forward_pairs_rows(B: nd1, coef: nd1, cells_per_root: ti.f32, lam: ti.f32, radius: ti.template(),
                            height: ti.i32, width: ti.i32, pairs: nd1, acc_out: nd1, energy_rows: nd1_f64):
    """Pass 1: every unordered pair once, from its first pixel in scan order.

    For the forward offsets ``o_k = (dy, dx)`` of pixel ``p`` (``dy > 0``, or
    ``dy = 0`` and ``dx > 0``; ``k = dy (2 radius + 1) + dx - 1``) inside the
    image, stores ``(g, g')`` at ``pairs[2 (K p + k) :][:2]`` and starts the
    gradient sum ``acc_out(p) = sum_k g' (B(p) - B(p + o_k))`` and the row energy.
    ``radius`` is a compile-time constant: the offsets are unrolled.
    """
    for r in range(energy_rows.shape[0]):
        t = r // height
        y = r - t * height
        span = 2 * radius + 1
        n_forward = radius + radius * span
        e = ti.cast(0.0, ti.f64)
        for x in range(width):
            p = r * width + x
            b = load3(B, 3 * p)
            acc = ti.Vector([0.0, 0.0, 0.0])
            e_x = 0.0
            for dy in ti.static(range(radius + 1)):
                for dx in ti.static(range(-radius, radius + 1)):
                    if ti.static(dy > 0 or dx > 0):
                        if y + dy < height and x + dx >= 0 and x + dx < width:
                            d = b - load3(B, 3 * (p + dy * width + dx))
                            g, dg = gsm_lookup(d.dot(d), coef, cells_per_root)
                            q = 2 * (n_forward * p + dy * span + dx - 1)
                            pairs[q] = g
                            pairs[q + 1] = dg
                            acc += dg * d
                            e_x += g
            for c in ti.static(range(3)):
                acc_out[3 * p + c] = acc[c]
            e += ti.cast(e_x, ti.f64)
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@ti.kernel
def _gsm_backward_pairs_rows(B: nd1, sigma_inv: nd2, pairs: nd1, acc_in: nd1, lam: ti.f32,
                             radius: ti.template(), height: ti.i32, width: ti.i32, gA: nd4,
                             energy_rows: nd1_f64):
    """Pass 2: each pixel gathers the pairs in which it is the second pixel,
    ``(g, g')`` read from ``pairs`` of the first (``p - o_k``), and adds its
    gradient ``4 lam L^T (acc_in(p) + sum_k g' (B(p) - B(p - o_k)))``.
    ``radius`` is a compile-time constant: the offsets are unrolled."""
    for r in range(energy_rows.shape[0]):
        t = r // height
        y = r - t * height
        span = 2 * radius + 1
        n_forward = radius + radius * span
        Lt = precision_factor(sigma_inv).transpose()
        e = ti.cast(0.0, ti.f64)
        for x in range(width):
            p = r * width + x
            b = load3(B, 3 * p)
            acc = load3(acc_in, 3 * p)
            e_x = 0.0
            for dy in ti.static(range(radius + 1)):
                for dx in ti.static(range(-radius, radius + 1)):
                    if ti.static(dy > 0 or dx > 0):
                        if y - dy >= 0 and x - dx >= 0 and x - dx < width:
                            p0 = p - dy * width - dx
                            q = 2 * (n_forward * p0 + dy * span + dx - 1)
                            acc += pairs[q + 1] * (b - load3(B, 3 * p0))
                            e_x += pairs[q]
            grad = (4.0 * lam) * (Lt @ acc)
            for c in ti.static(range(3)):
                gA[t, y, x, c] += grad[c]
            e += ti.cast(e_x, ti.f64)
        energy_rows[r] += ti.cast(lam, ti.f64) * e


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
    n_forward = radius + radius * (2 * radius + 1)      # 12 for the 5x5 window
    if T * H * W * n_forward * 2 > 2**31 - 1:
        raise ValueError(f"A of shape {A.shape} with radius {radius} needs {T * H * W * n_forward * 2} "
                         f"pair entries, more than the 2**31 - 1 that 32-bit indices address; "
                         f"pass fewer frames per call or a smaller radius")
    B = _scratch(workspace, "whitened", (T * H * W * 3,))
    pairs = _scratch(workspace, "pairs", (T * H * W * n_forward * 2,))
    acc = _scratch(workspace, "forward_sum", (T * H * W * 3,))
    coef = _scratch(workspace, "cell_coefficients", (4 * n,))
    cells_per_root = (n - 1) / math.sqrt(r2_max)
    _whiten_rows(A, sigma_inv, B)
    _cell_coefficients(table_g, table_dg, float(r2_max), float(cells_per_root), coef)
    _gsm_forward_pairs_rows(B, coef, float(cells_per_root), float(lam), int(radius), int(H), int(W), pairs,
                            acc, energy_rows)
    _gsm_backward_pairs_rows(B, sigma_inv, pairs, acc, float(lam), int(radius), int(H), int(W), gA,
                             energy_rows)
