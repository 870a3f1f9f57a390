"""Albedo smoothness of Eq. 11: a Gaussian scale mixture on 5x5 log-RGB differences.

``E = lam * sum_x sum_{y in N(x)} g(r2)``,  ``r2 = d^T Sigma^-1 d``,
``d = A(x) - A(y)``, where ``N(x)`` holds the other pixels of the
``(2 radius + 1)^2`` window around ``x`` inside the image (24 for the paper's
5x5) and ``g(r2) = -log sum_m alpha_m N(d; 0, sigma_m Sigma)`` (minus its
value at 0).  All 40 components share ``Sigma``, so ``g`` depends on ``r2``
only and is read from a 1-D table (:mod:`ivkernels.priors`): the grid is
uniform in ``sqrt(r2)``, ``r2_i = (i sqrt(r2_max) / (n-1))^2``, so the cell is
found in O(1) and ``g``, ``g'`` are interpolated linearly in ``r2`` inside it;
beyond ``r2_max`` ``g`` continues linearly with the last slope.  Each call
first turns the table into per-cell coefficients, ``g = a + b r2`` and
``g' = c + d r2`` (one ``vec4`` per cell, the extrapolation as the last), so a
look-up is a square root, one ``vec4`` read and two multiply-adds.

Gradient.  The double sum visits every unordered pair ``{x, y}`` twice
(``y in N(x)`` and ``x in N(y)``), and ``d/dA(x) g(r2) = 2 g'(r2) Sigma^-1 d``
for ``d = A(x) - A(y)`` (the other ordering has ``-d`` and the same ``r2``), so

    dE/dA(x) = 4 lam sum_{y in N(x)} g'(r2(x, y)) Sigma^-1 (A(x) - A(y)),

computed in two gather passes, one thread per image row, so that each
unordered pair is looked up once (12 table reads per pixel instead of 24):
the first pass visits the pairs from their first pixel in scan order (the
forward half of the window), stores ``(g, g')`` per pair and starts each
pixel's sum; the second lets each pixel gather the pairs it closes (the
backward half) from the stored values.  Each row's energy is the same as a
single full-window visit would give.  The two passes are compiled per window
radius (:func:`_pair_kernels_for`), so their offset loops are unrolled.

Whitening.  With ``L`` upper triangular, ``L^T L = Sigma^-1`` (Cholesky), a
whitening pass stores ``B(x) = L A(x)`` per pixel in a scratch buffer (the
scratch buffers, ~120 bytes per pixel, come from the caller's workspace,
:mod:`ivkernels.kernels.workspace`); then
``r2 = |B(x) - B(y)|^2`` and

    dE/dA(x) = 4 lam L^T sum_{y in N(x)} g'(r2) (B(x) - B(y)),

so a pair costs a 3-vector difference, a dot product, a square root and one
coefficient read, and the 3x3 products are once per pixel.
"""
from __future__ import annotations

import functools
import math

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.energy_albedo_gsm import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.kernel
def cell_coefficients(table_g: wp.array(dtype=float), table_dg: wp.array(dtype=float), r2_max: float,
                      cells_per_root: float, coef: wp.array(dtype=wp.vec4)):
    """Per table cell ``i``, ``(a, b, c, d)`` with ``g = a + b r2`` and ``g' = c + d r2``
    inside it (the linear-in-r2 interpolation of the table); the last entry
    holds the linear extrapolation beyond ``r2_max``.  Float64 arithmetic."""
    i = wp.tid()
    n = table_g.shape[0]
    if i < n - 1:
        root_lo = wp.float64(i) / wp.float64(cells_per_root)
        root_hi = wp.float64(i + 1) / wp.float64(cells_per_root)
        r2_lo = root_lo * root_lo
        inv_width = wp.float64(1.0) / (root_hi * root_hi - r2_lo)
        slope_g = (wp.float64(table_g[i + 1]) - wp.float64(table_g[i])) * inv_width
        slope_dg = (wp.float64(table_dg[i + 1]) - wp.float64(table_dg[i])) * inv_width
        coef[i] = wp.vec4(float(wp.float64(table_g[i]) - slope_g * r2_lo), float(slope_g),
                          float(wp.float64(table_dg[i]) - slope_dg * r2_lo), float(slope_dg))
    else:
        last_dg = wp.float64(table_dg[n - 1])
        coef[i] = wp.vec4(float(wp.float64(table_g[n - 1]) - last_dg * wp.float64(r2_max)), float(last_dg),
                          float(last_dg), 0.0)


@wp.func
def gsm_lookup(r2: float, coef: wp.array(dtype=wp.vec4), cells_per_root: float):
    """``(g, g')`` at ``r2``: the cell ``floor(sqrt(r2) (n-1) / sqrt(r2_max))``,
    or the extrapolation entry beyond the table, then one multiply-add each."""
    last = coef.shape[0] - 1
    i = int(wp.min(wp.sqrt(r2) * cells_per_root, float(last)))
    c = coef[i]
    return c[0] + c[1] * r2, c[2] + c[3] * r2


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


@functools.lru_cache(maxsize=None)
def _pair_kernels_for(radius: int):
    """The two pair passes with the window radius compiled in.

    With ``radius`` a compile-time constant (``wp.static``) the offset loops
    are unrolled and the test that picks the forward half is resolved at
    compile time: 1.7x faster than a loop over a runtime radius on the CPU
    (640x480, 8 frames, radius 2, both alternated in one process: 129
    against 223 ms on 2 threads), with bitwise the same results.  Pixels whose
    half window lies inside the image take a branch without the bounds tests
    (the same sums in the same order, so bitwise the same again): the call
    goes from 230 to 202 ms at 640x480, 8 frames, 2 threads.  One module
    per radius, built on first use and kept (``functools.lru_cache``).
    """
    R = int(radius)

    @wp.kernel(module="unique")
    def gsm_forward_pairs_rows(row_begin: int, B: wp.array2d(dtype=wp.vec3), coef: wp.array(dtype=wp.vec4),
                               cells_per_root: float, lam: float, height: int,
                               pairs: wp.array3d(dtype=wp.vec2), acc_out: wp.array2d(dtype=wp.vec3),
                               energy_rows: wp.array(dtype=wp.float64)):
        """Pass 1: every unordered pair once, from its first pixel in scan order.

        For the forward offsets ``k`` of pixel ``x`` (``dy > 0``, or ``dy = 0`` and
        ``dx > 0``) stores ``pairs[r, x, k] = (g, g')`` and starts the gradient
        sum ``acc_out(x) = sum_k g' (B(x) - B(x + o_k))`` and the row energy.
        """
        r = row_begin + wp.tid()
        width = B.shape[1]
        t = r // height
        y = r - t * height
        row0 = t * height
        e = wp.float64(0.0)
        inside_rows = y + R < height
        for x in range(width):
            b = B[r, x]
            acc = wp.vec3(0.0, 0.0, 0.0)
            e_x = float(0.0)
            k = int(0)
            if inside_rows and x >= R and x + R < width:
                # the whole forward half lies in the image: no bounds tests
                for dy in range(wp.static(R + 1)):
                    for dx in range(wp.static(-R), wp.static(R + 1)):
                        if wp.static(dy > 0 or dx > 0):
                            d = b - B[r + dy, x + dx]
                            g, dg = gsm_lookup(wp.dot(d, d), coef, cells_per_root)
                            pairs[r, x, k] = wp.vec2(g, dg)
                            acc += dg * d
                            e_x += g
                            k += 1
            else:
                for dy in range(wp.static(R + 1)):
                    yy = y + dy
                    for dx in range(wp.static(-R), wp.static(R + 1)):
                        if dy > 0 or dx > 0:
                            xx = x + dx
                            if yy < height and xx >= 0 and xx < width:
                                d = b - B[row0 + yy, xx]
                                g, dg = gsm_lookup(wp.dot(d, d), coef, cells_per_root)
                                pairs[r, x, k] = wp.vec2(g, dg)
                                acc += dg * d
                                e_x += g
                            k += 1
            acc_out[r, x] = acc
            e += wp.float64(e_x)
        energy_rows[r] = energy_rows[r] + wp.float64(lam) * e

    @wp.kernel(module="unique")
    def gsm_backward_pairs_rows(row_begin: int, B: wp.array2d(dtype=wp.vec3), sigma_inv: wp.array2d(dtype=float),
                                pairs: wp.array3d(dtype=wp.vec2), acc_in: wp.array2d(dtype=wp.vec3),
                                lam: float, height: int,
                                gA: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64)):
        """Pass 2: each pixel gathers the pairs in which it is the second pixel,
        ``(g, g')`` read from ``pairs`` of the first, and writes its gradient
        ``4 lam L^T (acc_in(x) + sum g' (B(x) - B(x - o_k)))``."""
        r = row_begin + wp.tid()
        width = B.shape[1]
        t = r // height
        y = r - t * height
        row0 = t * height
        Lt = wp.transpose(precision_factor(sigma_inv))
        e = wp.float64(0.0)
        inside_rows = y >= R
        for x in range(width):
            b = B[r, x]
            acc = acc_in[r, x]
            e_x = float(0.0)
            k = int(0)
            if inside_rows and x >= R and x + R < width:
                # the whole backward half lies in the image: no bounds tests
                for dy in range(wp.static(R + 1)):
                    for dx in range(wp.static(-R), wp.static(R + 1)):
                        if wp.static(dy > 0 or dx > 0):
                            p = pairs[r - dy, x - dx, k]
                            acc += p[1] * (b - B[r - dy, x - dx])
                            e_x += p[0]
                            k += 1
            else:
                for dy in range(wp.static(R + 1)):
                    yy = y - dy
                    for dx in range(wp.static(-R), wp.static(R + 1)):
                        if dy > 0 or dx > 0:
                            xx = x - dx
                            if yy >= 0 and xx >= 0 and xx < width:
                                p = pairs[row0 + yy, xx, k]
                                acc += p[1] * (b - B[row0 + yy, xx])
                                e_x += p[0]
                            k += 1
            grad = (4.0 * lam) * (Lt * acc)
            gA[t, y, x, 0] = gA[t, y, x, 0] + grad[0]
            gA[t, y, x, 1] = gA[t, y, x, 1] + grad[1]
            gA[t, y, x, 2] = gA[t, y, x, 2] + grad[2]
            e += wp.float64(e_x)
        energy_rows[r] = energy_rows[r] + wp.float64(lam) * e

    return gsm_forward_pairs_rows, gsm_backward_pairs_rows


def _scratch(workspace, name: str, shape: tuple, dtype, device):
    """Scratch buffer ``name`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, dtype,
                          lambda: wp.empty(shape, dtype=dtype, device=device), device)


@host("gsm_smoothness")
def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows,
                   lam: float, radius: int = 2, *, workspace=None) -> None:
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
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the scratch buffers (``B`` and the forward sums, 12 bytes per
        pixel each; the pairs, ``8 K`` bytes per pixel with
        ``K = radius + radius (2 radius + 1)``; the cell coefficients, 16 bytes
        per table entry) between calls; without one they are allocated for
        this call.
    """
    T, H, W, _ = A.shape
    dev = A.device
    n = table_g.shape[0]
    cells_per_root = (n - 1) / math.sqrt(r2_max)
    n_forward = radius + radius * (2 * radius + 1)      # 12 for the 5x5 window
    B = _scratch(workspace, "whitened", (T * H, W), wp.vec3, dev)
    pairs = _scratch(workspace, "pairs", (T * H, W, n_forward), wp.vec2, dev)
    acc = _scratch(workspace, "forward_sum", (T * H, W), wp.vec3, dev)
    launch_rows(whiten_rows, T * H, [A, sigma_inv, B], device=dev)
    coef = _scratch(workspace, "cell_coefficients", (n,), wp.vec4, dev)
    wp.launch(cell_coefficients, dim=n, inputs=[table_g, table_dg, float(r2_max), float(cells_per_root), coef],
              device=dev)
    forward_pairs, backward_pairs = _pair_kernels_for(radius)
    launch_rows(forward_pairs, T * H,
                [B, coef, float(cells_per_root), float(lam), H, pairs, acc, energy_rows], device=dev)
    launch_rows(backward_pairs, T * H,
                [B, sigma_inv, pairs, acc, float(lam), H, gA, energy_rows], device=dev)
