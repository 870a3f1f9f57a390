"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_albedo_gsm` (Eq. 11): same host
function, same signature, NumPy arrays passed as ``ti.types.ndarray()``.

See the Warp module for the energy, the table grid and the gradient.  The
kernel's outermost loop runs over the ``T * H`` image rows in parallel; each
row loops over ``x`` and the window (a gather: no atomics).
"""
import math

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


@ti.kernel
def _gsm_smoothness_rows(A: nd4, sigma_inv: nd2, table_g: nd1, table_dg: nd1, r2_max: ti.f32,
                         cells_per_root: ti.f32, lam: ti.f32, radius: ti.i32, gA: nd4,
                         energy_rows: nd1_f64):
    for t, y in ti.ndrange(A.shape[0], A.shape[1]):
        height = A.shape[1]
        width = A.shape[2]
        P = ti.Matrix([[sigma_inv[0, 0], sigma_inv[0, 1], sigma_inv[0, 2]],
                       [sigma_inv[1, 0], sigma_inv[1, 1], sigma_inv[1, 2]],
                       [sigma_inv[2, 0], sigma_inv[2, 1], sigma_inv[2, 2]]])
        y_lo = ti.max(y - radius, 0)
        y_hi = ti.min(y + radius, height - 1)
        e = ti.cast(0.0, ti.f64)
        for x in range(width):
            a = ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
            x_lo = ti.max(x - radius, 0)
            x_hi = ti.min(x + radius, width - 1)
            e_x = 0.0
            grad = ti.Vector([0.0, 0.0, 0.0])
            for yy in range(y_lo, y_hi + 1):
                for xx in range(x_lo, x_hi + 1):
                    if yy != y or xx != x:
                        d = a - ti.Vector([A[t, yy, xx, 0], A[t, yy, xx, 1], A[t, yy, xx, 2]])
                        q = P @ d
                        g, dg = gsm_lookup(d.dot(q), table_g, table_dg, r2_max, cells_per_root)
                        e_x += g
                        grad += dg * q
            s = 4.0 * lam
            for c in ti.static(range(3)):
                gA[t, y, x, c] += s * grad[c]
            e += ti.cast(e_x, ti.f64)
        energy_rows[t * height + y] += ti.cast(lam, ti.f64) * e


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
    _gsm_smoothness_rows(A, sigma_inv, table_g, table_dg, float(r2_max),
                         float((n - 1) / math.sqrt(r2_max)), float(lam), int(radius), gA, energy_rows)
