"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_albedo_gsm` (Eq. 11): same host
function, same signature, NumPy arrays passed as ``ti.types.ndarray()``.

See the Warp module for the energy, the table grid and the gradient.  The
kernel's outermost loop runs over the ``T * H`` image rows in parallel; each
row loops over ``x`` and the window (a gather: no atomics), on the whitened
albedo ``B = L A`` (``L^T L = Sigma^-1``) that a first kernel writes into a
scratch buffer cached per (shape, calling thread).
"""
import math
import threading

import numpy as np
import taichi as ti

from ivkernels.kernels.taichi._checks import check_array, check_float, check_int

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)


@ti.func
def gsm_lookup(r2, table_g: ti.template(), table_dg: ti.template(), r2_max, cells_per_root):
    """``(g, g')`` at ``r2``; ``cells_per_root = (n - 1) / sqrt(r2_max)``."""
    n = table_g.shape[0]
    u = ti.sqrt(r2) * cells_per_root
    g = 0.0
    dg = 0.0
    if u < ti.cast(n - 1, ti.f32):
        i = ti.cast(u, ti.i32)
        fi = ti.cast(i, ti.f32)
        f = (u - fi) * (u + fi) / (2.0 * fi + 1.0)     # linear in r2 inside the cell
        g = (1.0 - f) * table_g[i] + f * table_g[i + 1]
        dg = (1.0 - f) * table_dg[i] + f * table_dg[i + 1]
    else:
        dg = table_dg[n - 1]
        g = table_g[n - 1] + dg * (r2 - r2_max)
    return g, dg


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


@ti.kernel
def _whiten_rows(A: nd4, sigma_inv: nd2, B: nd4):
    """``B(x) = L A(x)``, so that ``r2 = |B(x) - B(y)|^2``."""
    for t, y in ti.ndrange(A.shape[0], A.shape[1]):
        L = precision_factor(sigma_inv)
        for x in range(A.shape[2]):
            b = L @ ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
            for c in ti.static(range(3)):
                B[t, y, x, c] = b[c]


@ti.kernel
def _gsm_smoothness_rows(B: nd4, sigma_inv: nd2, table_g: nd1, table_dg: nd1, r2_max: ti.f32,
                         cells_per_root: ti.f32, lam: ti.f32, radius: ti.i32, gA: nd4,
                         energy_rows: nd1_f64):
    for t, y in ti.ndrange(B.shape[0], B.shape[1]):
        height = B.shape[1]
        width = B.shape[2]
        Lt = precision_factor(sigma_inv).transpose()
        y_lo = ti.max(y - radius, 0)
        y_hi = ti.min(y + radius, height - 1)
        e = ti.cast(0.0, ti.f64)
        for x in range(width):
            b = ti.Vector([B[t, y, x, 0], B[t, y, x, 1], B[t, y, x, 2]])
            x_lo = ti.max(x - radius, 0)
            x_hi = ti.min(x + radius, width - 1)
            e_x = 0.0
            acc = ti.Vector([0.0, 0.0, 0.0])
            for yy in range(y_lo, y_hi + 1):
                for xx in range(x_lo, x_hi + 1):
                    if yy != y or xx != x:
                        d = b - ti.Vector([B[t, yy, xx, 0], B[t, yy, xx, 1], B[t, yy, xx, 2]])
                        g, dg = gsm_lookup(d.dot(d), table_g, table_dg, r2_max, cells_per_root)
                        e_x += g
                        acc += dg * d
            grad = (4.0 * lam) * (Lt @ acc)
            for c in ti.static(range(3)):
                gA[t, y, x, c] += grad[c]
            e += ti.cast(e_x, ti.f64)
        energy_rows[t * height + y] += ti.cast(lam, ti.f64) * e


_scratch_cache: dict = {}
_scratch_lock = threading.Lock()


def _scratch(shape: tuple) -> np.ndarray:
    """A float32 buffer of ``shape`` cached per (shape, calling thread)."""
    key = (shape, threading.get_ident())
    with _scratch_lock:
        buf = _scratch_cache.get(key)
        if buf is None:
            buf = np.empty(shape, np.float32)
            _scratch_cache[key] = buf
    return buf


def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows,
                   lam: float, radius: int = 2) -> None:
    """Add Eq. 11's GSM smoothness energy and gradient (see the Warp module).

    ``A`` (T, H, W, 3) float32 log albedo; ``sigma_inv`` (3, 3) float32;
    ``table_g``, ``table_dg`` (n,) float32; ``gA`` (T, H, W, 3) float32 and
    ``energy_rows`` (T*H,) float64 accumulated.
    """
    check_array("A", A, (None, None, None, 3), "(T, H, W, 3)", copy=False)
    T, H, W, _ = A.shape
    check_array("sigma_inv", sigma_inv, (3, 3), "(3, 3)", copy=False)
    check_array("table_g", table_g, (None,), "(n,)", copy=False)
    n = table_g.shape[0]
    if n < 2:
        raise ValueError(f"table_g must hold at least 2 entries, got {n}")
    check_array("table_dg", table_dg, (n,), "(n,) like table_g", copy=False)
    check_array("gA", gA, (T, H, W, 3), "(T, H, W, 3)", copy=False)
    check_array("energy_rows", energy_rows, (T * H,), "(T*H,)", dtype=np.float64, copy=False)
    r2_max = check_float("r2_max", r2_max, positive=True)
    lam = check_float("lam", lam)
    radius = check_int("radius", radius, 1, " (2 for the paper's 5x5 window)")
    if T * H == 0 or W == 0:
        return
    B = _scratch((T, H, W, 3))
    _whiten_rows(A, sigma_inv, B)
    _gsm_smoothness_rows(B, sigma_inv, table_g, table_dg, float(r2_max),
                         float((n - 1) / math.sqrt(r2_max)), float(lam), int(radius), gA, energy_rows)
