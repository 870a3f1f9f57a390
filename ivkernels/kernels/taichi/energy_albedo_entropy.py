"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_albedo_entropy` (Eq. 12): same host
functions, same signatures, NumPy arrays passed as ``ti.types.ndarray()``.

See the Warp module for the algorithm (trilinear splat of the whitened albedo,
separable Gaussian blur skipping empty rows, ``<hist, blurred>``, sliced
gradient) and the normalisation.  Outermost loops run in parallel over image
rows or histogram rows; ``+=`` on an ndarray inside them is atomic.
Inputs that are not C-contiguous are copied; outputs must be C-contiguous.
"""
import math
import sys

import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import EntropyScratch, allocate_entropy_scratch_with, run_entropy_steps
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_albedo_entropy import FAMILY

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd4_i32 = ti.types.ndarray(dtype=ti.i32, ndim=4)


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@ti.func
def bin_coordinate(v, lo, h, bins):
    """``(i0, f, inside)`` of whitened coordinate ``v`` (see the Warp module)."""
    c = (v - lo) / h
    cc = 0.0
    inside = 0.0
    if c >= 0.0:
        cc = c
        inside = 1.0
    if cc > ti.cast(bins - 1, ti.f32):
        cc = ti.cast(bins - 1, ti.f32)
        inside = 0.0
    i0 = ti.min(ti.cast(cc, ti.i32), bins - 2)
    return i0, cc - ti.cast(i0, ti.f32), inside


@ti.func
def load_mat33(m: ti.template()):
    return ti.Matrix([[m[0, 0], m[0, 1], m[0, 2]], [m[1, 0], m[1, 1], m[1, 2]],
                      [m[2, 0], m[2, 1], m[2, 2]]])


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@ti.kernel
def _splat_whitened_rows(A: nd4, whiten: nd2, lo: ti.f32, h: ti.f32, hist: nd4, row_flags: nd4_i32):
    for t, y in ti.ndrange(A.shape[0], A.shape[1]):
        bins = hist.shape[1]
        Wm = load_mat33(whiten)
        for x in range(A.shape[2]):
            u = Wm @ ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
            i0, fi, ini = bin_coordinate(u[0], lo, h, bins)
            j0, fj, inj = bin_coordinate(u[1], lo, h, bins)
            k0, fk, ink = bin_coordinate(u[2], lo, h, bins)
            for a in ti.static(range(2)):
                wa = (1.0 - fi) if a == 0 else fi
                for b in ti.static(range(2)):
                    wab = wa * ((1.0 - fj) if b == 0 else fj)
                    row_flags[0, t, i0 + a, j0 + b] = 1
                    hist[t, i0 + a, j0 + b, k0] += wab * (1.0 - fk)
                    hist[t, i0 + a, j0 + b, k0 + 1] += wab * fk


@ti.kernel
def _blur_along_rows(src: nd4, taps: nd1, row_flags: nd4_i32, dst: nd4):
    for t, i, j in ti.ndrange(src.shape[0], src.shape[1], src.shape[2]):
        bins = src.shape[1]
        radius = (taps.shape[0] - 1) // 2
        if row_flags[0, t, i, j] == 0:
            for k in range(bins):
                dst[t, i, j, k] = 0.0
        else:
            for k in range(bins):
                acc = 0.0
                for o in range(ti.max(-radius, -k), ti.min(radius, bins - 1 - k) + 1):
                    acc += taps[o + radius] * src[t, i, j, k + o]
                dst[t, i, j, k] = acc


@ti.kernel
def _blur_across_rows(src: nd4, taps: nd1, axis: ti.i32, flag_in: ti.i32, flag_out: ti.i32,
                      row_flags: nd4_i32, dst: nd4):
    for t, i, j in ti.ndrange(src.shape[0], src.shape[1], src.shape[2]):
        bins = src.shape[1]
        radius = (taps.shape[0] - 1) // 2
        di = 1 if axis == 1 else 0
        dj = 1 - di
        p = di * i + dj * j
        for k in range(bins):
            dst[t, i, j, k] = 0.0
        touched = 0
        for o in range(ti.max(-radius, -p), ti.min(radius, bins - 1 - p) + 1):
            si = i + o * di
            sj = j + o * dj
            if row_flags[flag_in, t, si, sj] != 0:
                touched = 1
                w = taps[o + radius]
                for k in range(bins):
                    dst[t, i, j, k] += w * src[t, si, sj, k]
        if flag_out >= 0:
            row_flags[flag_out, t, i, j] = touched


@ti.kernel
def _frame_dot_rows(hist: nd4, blurred: nd4, dots: nd1_f64):
    for t, i, j in ti.ndrange(hist.shape[0], hist.shape[1], hist.shape[2]):
        acc = ti.cast(0.0, ti.f64)
        for k in range(hist.shape[3]):
            acc += ti.cast(hist[t, i, j, k] * blurred[t, i, j, k], ti.f64)
        dots[t] += acc


@ti.kernel
def _slice_gradient_rows(A: nd4, whiten: nd2, lo: ti.f32, h: ti.f32, blurred: nd4, dots: nd1_f64,
                         lam: ti.f32, gA: nd4):
    for t, y in ti.ndrange(A.shape[0], A.shape[1]):
        bins = blurred.shape[1]
        Wm = load_mat33(whiten)
        scale = ti.cast(ti.cast(-2.0 * lam, ti.f64) / dots[t], ti.f32) / h
        for x in range(A.shape[2]):
            u = Wm @ ti.Vector([A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2]])
            i0, fi, ini = bin_coordinate(u[0], lo, h, bins)
            j0, fj, inj = bin_coordinate(u[1], lo, h, bins)
            k0, fk, ink = bin_coordinate(u[2], lo, h, bins)
            v000 = blurred[t, i0, j0, k0]
            v001 = blurred[t, i0, j0, k0 + 1]
            v010 = blurred[t, i0, j0 + 1, k0]
            v011 = blurred[t, i0, j0 + 1, k0 + 1]
            v100 = blurred[t, i0 + 1, j0, k0]
            v101 = blurred[t, i0 + 1, j0, k0 + 1]
            v110 = blurred[t, i0 + 1, j0 + 1, k0]
            v111 = blurred[t, i0 + 1, j0 + 1, k0 + 1]
            gi = ((1.0 - fj) * ((1.0 - fk) * (v100 - v000) + fk * (v101 - v001))
                  + fj * ((1.0 - fk) * (v110 - v010) + fk * (v111 - v011)))
            gj = ((1.0 - fi) * ((1.0 - fk) * (v010 - v000) + fk * (v011 - v001))
                  + fi * ((1.0 - fk) * (v110 - v100) + fk * (v111 - v101)))
            gk = ((1.0 - fi) * ((1.0 - fj) * (v001 - v000) + fj * (v011 - v010))
                  + fi * ((1.0 - fj) * (v101 - v100) + fj * (v111 - v110)))
            g = Wm.transpose() @ ti.Vector([gi * ini, gj * inj, gk * ink]) * scale
            for c in ti.static(range(3)):
                gA[t, y, x, c] += g[c]


@ti.kernel
def _entropy_energy_frames(dots: nd1_f64, log_norm: ti.f64, lam: ti.f32, rows_per_frame: ti.i32,
                           energy_rows: nd1_f64):
    for t in range(dots.shape[0]):
        energy_rows[t * rows_per_frame] -= ti.cast(lam, ti.f64) * (ti.log(dots[t]) + log_norm)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def allocate_entropy_scratch(n_frames: int, bins: int, device="cpu") -> EntropyScratch:
    """Allocate :class:`EntropyScratch` for ``n_frames`` frames and a ``bins^3`` cube."""
    if device != "cpu":
        raise ValueError(f"the taichi backend runs on device='cpu' only, got {device!r}")
    return allocate_entropy_scratch_with(np.empty, n_frames, bins)


@host("entropy_histogram")
def entropy_histogram(A, whiten, lo: float, h: float, hist, row_flags) -> None:
    """Overwrite ``hist`` (T, B, B, B) with the trilinear splat of ``W A(x)``; flag touched rows
    in ``row_flags[0]`` (see the Warp module)."""
    T, H, W, _ = A.shape
    hist.fill(0.0)
    row_flags.fill(0)
    if T * H and W:
        _splat_whitened_rows(A, whiten, lo, h, hist, row_flags)


@host("entropy_blur")
def entropy_blur(hist, taps, row_flags, tmp, blurred) -> None:
    """``blurred = G * hist`` per frame with the separable 1-D ``taps`` (see the Warp module)."""
    _blur_along_rows(hist, taps, row_flags, blurred)
    _blur_across_rows(blurred, taps, 2, 0, 1, row_flags, tmp)
    _blur_across_rows(tmp, taps, 1, 1, -1, row_flags, blurred)


@host("entropy_dot")
def entropy_dot(hist, blurred, dots) -> None:
    """Overwrite ``dots`` (float64 (T,)) with ``<hist_t, blurred_t>`` per frame."""
    dots.fill(0.0)
    _frame_dot_rows(hist, blurred, dots)


@host("entropy_slice_gradient")
def entropy_slice_gradient(A, whiten, lo: float, h: float, blurred, dots, gA, lam: float) -> None:
    """Add ``-2 lam W^T grad V(W A(x)) / dots[t]`` into ``gA`` (see the Warp module)."""
    T, H, W, _ = A.shape
    if T * H and W:
        _slice_gradient_rows(A, whiten, lo, h, blurred, dots, lam, gA)


@host("entropy_energy")
def entropy_energy(dots, sigma_p: float, n_pixels: int, energy_rows, lam: float) -> None:
    """Add ``E_t = -lam log(dots[t] / (n_pixels^2 sqrt(4 pi sigma_p^2)))`` into
    ``energy_rows[t * (len(energy_rows) // T)]``."""
    T = dots.shape[0]
    log_norm = -2.0 * math.log(n_pixels) - 0.5 * math.log(4.0 * math.pi * sigma_p ** 2)
    _entropy_energy_frames(dots, log_norm, lam, energy_rows.shape[0] // T, energy_rows)


@host("entropy_term")
def entropy_term(A, whiten, lo: float, h: float, taps, sigma_p: float, scratch: EntropyScratch,
                 gA, energy_rows, lam: float) -> None:
    """Add Eq. 12's energy (row ``t*H``) and gradient for every frame (see the Warp module)."""
    run_entropy_steps(sys.modules[__name__], A, whiten, lo, h, taps, sigma_p, scratch, gA, energy_rows, lam)
