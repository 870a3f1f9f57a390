"""Albedo smoothness of Eq. 11: a Gaussian scale mixture on 5x5 log-RGB differences.

``E = lam * sum_x sum_{y in N(x)} g(r2)``,  ``r2 = d^T Sigma^-1 d``,
``d = A(x) - A(y)``, where ``N(x)`` holds the other pixels of the
``(2 radius + 1)^2`` window around ``x`` inside the image (24 for the paper's
5x5) and ``g(r2) = -log sum_m alpha_m N(d; 0, sigma_m Sigma)`` (minus its
value at 0).  All 40 components share ``Sigma``, so ``g`` depends on ``r2``
only and is read from a 1-D table (:mod:`ivkernels.priors`): the grid is
uniform in ``sqrt(r2)``, ``r2_i = (i sqrt(r2_max) / (n-1))^2``, so the cell is
found in O(1) and ``g``, ``g'`` are interpolated linearly in ``r2`` inside it;
beyond ``r2_max`` ``g`` continues linearly with the last slope.

Gradient.  The double sum visits every unordered pair ``{x, y}`` twice
(``y in N(x)`` and ``x in N(y)``), and ``d/dA(x) g(r2) = 2 g'(r2) Sigma^-1 d``
for ``d = A(x) - A(y)`` (the other ordering has ``-d`` and the same ``r2``), so

    dE/dA(x) = 4 lam sum_{y in N(x)} g'(r2(x, y)) Sigma^-1 (A(x) - A(y)),

a gather: one thread per image row, each pixel visiting its window once for
both the energy and the gradient.

Whitening.  With ``L`` upper triangular, ``L^T L = Sigma^-1`` (Cholesky), a
first pass stores ``B(x) = L A(x)`` per pixel in a scratch buffer (cached per
(device, shape, calling thread)); then ``r2 = |B(x) - B(y)|^2`` and

    dE/dA(x) = 4 lam L^T sum_{y in N(x)} g'(r2) (B(x) - B(y)),

so a neighbour costs a 3-vector difference, a dot product, a square root and
two table reads, and the 3x3 products are once per pixel.
"""
from __future__ import annotations

import math
import threading

import warp as wp

from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.warp._checks import check_array, check_float, check_int

wp.set_module_options({"enable_backward": False})


@wp.func
def gsm_lookup(r2: float, table_g: wp.array(dtype=float), table_dg: wp.array(dtype=float),
               r2_max: float, cells_per_root: float):
    """``(g, g')`` at ``r2`` from the tables; ``cells_per_root = (n - 1) / sqrt(r2_max)``."""
    n = table_g.shape[0]
    u = wp.sqrt(r2) * cells_per_root
    g = float(0.0)
    dg = float(0.0)
    if u < float(n - 1):
        i = int(u)
        fi = float(i)
        f = (u - fi) * (u + fi) / (2.0 * fi + 1.0)     # linear in r2 inside the cell
        g = (1.0 - f) * table_g[i] + f * table_g[i + 1]
        dg = (1.0 - f) * table_dg[i] + f * table_dg[i + 1]
    else:
        dg = table_dg[n - 1]
        g = table_g[n - 1] + dg * (r2 - r2_max)
    return g, dg


@wp.func
def load_vec3(a: wp.array4d(dtype=float), t: int, y: int, x: int):
    return wp.vec3(a[t, y, x, 0], a[t, y, x, 1], a[t, y, x, 2])


@wp.func
def precision_factor(sigma_inv: wp.array2d(dtype=float)):
    """Upper-triangular ``L`` with ``L^T L = Sigma^-1`` (Cholesky of the symmetric
    part of ``sigma_inv``, which must be positive definite)."""
    p01 = 0.5 * (sigma_inv[0, 1] + sigma_inv[1, 0])
    p02 = 0.5 * (sigma_inv[0, 2] + sigma_inv[2, 0])
    p12 = 0.5 * (sigma_inv[1, 2] + sigma_inv[2, 1])
    l00 = wp.sqrt(sigma_inv[0, 0])
    l01 = p01 / l00
    l02 = p02 / l00
    l11 = wp.sqrt(sigma_inv[1, 1] - l01 * l01)
    l12 = (p12 - l01 * l02) / l11
    l22 = wp.sqrt(sigma_inv[2, 2] - l02 * l02 - l12 * l12)
    return wp.mat33(l00, l01, l02,
                    0.0, l11, l12,
                    0.0, 0.0, l22)


@wp.kernel
def whiten_rows(row_begin: int, A: wp.array4d(dtype=float), sigma_inv: wp.array2d(dtype=float),
                B: wp.array2d(dtype=wp.vec3)):
    """``B(x) = L A(x)``: then ``r2 = d^T Sigma^-1 d = |B(x) - B(y)|^2``."""
    r = row_begin + wp.tid()
    height = A.shape[1]
    t = r // height
    y = r - t * height
    L = precision_factor(sigma_inv)
    for x in range(A.shape[2]):
        B[r, x] = L * load_vec3(A, t, y, x)


@wp.kernel
def gsm_smoothness_rows(row_begin: int, B: wp.array2d(dtype=wp.vec3), sigma_inv: wp.array2d(dtype=float),
                        table_g: wp.array(dtype=float), table_dg: wp.array(dtype=float),
                        r2_max: float, cells_per_root: float, lam: float, radius: int,
                        gA: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64)):
    r = row_begin + wp.tid()
    height = gA.shape[1]
    width = gA.shape[2]
    t = r // height
    y = r - t * height
    row0 = t * height
    Lt = wp.transpose(precision_factor(sigma_inv))
    y_lo = wp.max(y - radius, 0)
    y_hi = wp.min(y + radius, height - 1)
    e = wp.float64(0.0)
    for x in range(width):
        b = B[r, x]
        x_lo = wp.max(x - radius, 0)
        x_hi = wp.min(x + radius, width - 1)
        e_x = float(0.0)
        acc = wp.vec3(0.0, 0.0, 0.0)
        for yy in range(y_lo, y_hi + 1):
            for xx in range(x_lo, x_hi + 1):
                if yy != y or xx != x:
                    d = b - B[row0 + yy, xx]
                    g, dg = gsm_lookup(wp.dot(d, d), table_g, table_dg, r2_max, cells_per_root)
                    e_x += g
                    acc += dg * d
        grad = (4.0 * lam) * (Lt * acc)
        gA[t, y, x, 0] = gA[t, y, x, 0] + grad[0]
        gA[t, y, x, 1] = gA[t, y, x, 1] + grad[1]
        gA[t, y, x, 2] = gA[t, y, x, 2] + grad[2]
        e += wp.float64(e_x)
    energy_rows[r] = energy_rows[r] + wp.float64(lam) * e


_scratch_cache: dict = {}
_scratch_lock = threading.Lock()


def _scratch(rows: int, width: int, device):
    """A (rows, width) vec3 buffer cached per (device, shape, calling thread)."""
    key = (str(device), rows, width, threading.get_ident())
    with _scratch_lock:
        buf = _scratch_cache.get(key)
        if buf is None:
            buf = wp.empty((rows, width), dtype=wp.vec3, device=device)
            _scratch_cache[key] = buf
    return buf


def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows,
                   lam: float, radius: int = 2) -> None:
    """Add Eq. 11's GSM smoothness energy and gradient.

    Parameters
    ----------
    A : wp.array float32 (T, H, W, 3), log albedo (natural log, linear RGB).
    sigma_inv : wp.array float32 (3, 3), ``Sigma^-1`` (``AlbedoPrior.sigma_inv``),
        symmetric positive definite.
    table_g, table_dg : wp.array float32 (n,), n >= 2: ``g`` and ``g' = dg/dr2``
        on the grid ``r2_i = (i sqrt(r2_max) / (n-1))^2`` (``AlbedoPrior.table_g``,
        ``.table_dg``).
    r2_max : float > 0, the last grid point.
    gA : wp.array float32 (T, H, W, 3), accumulated: ``gA += dE/dA``
        ``= 4 lam sum_y g'(r2) Sigma^-1 (A(x) - A(y))``.  Must not overlap ``A``.
    energy_rows : wp.array float64 (T*H,), accumulated: row ``t*H + y`` gets
        ``lam * sum_{x in row} sum_{y in N(x)} g(r2)``.
    lam : Eq. 11's ``lambda_As``.
    radius : window radius (2: the paper's 5x5 window, 24 neighbours).
    """
    check_array("A", A, (None, None, None, 3), "(T, H, W, 3)")
    T, H, W, _ = A.shape
    dev = A.device
    check_array("sigma_inv", sigma_inv, (3, 3), "(3, 3)", dev)
    check_array("table_g", table_g, (None,), "(n,)", dev)
    n = table_g.shape[0]
    if n < 2:
        raise ValueError(f"table_g must hold at least 2 entries, got {n}")
    check_array("table_dg", table_dg, (n,), "(n,) like table_g", dev)
    check_array("gA", gA, (T, H, W, 3), "(T, H, W, 3)", dev)
    check_array("energy_rows", energy_rows, (T * H,), "(T*H,)", dev, dtype=wp.float64)
    r2_max = check_float("r2_max", r2_max, positive=True)
    lam = check_float("lam", lam)
    radius = check_int("radius", radius, 1, " (2 for the paper's 5x5 window)")
    cells_per_root = (n - 1) / math.sqrt(r2_max)
    B = _scratch(T * H, W, dev)
    launch_rows(whiten_rows, T * H, [A, sigma_inv, B], device=dev)
    launch_rows(gsm_smoothness_rows, T * H,
                [B, sigma_inv, table_g, table_dg, float(r2_max), float(cells_per_root), float(lam),
                 int(radius), gA, energy_rows], device=dev)
