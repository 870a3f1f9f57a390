"""Albedo global sparsity of Eq. 12: quadratic entropy of whitened albedo, by histogram.

Eq. 12, per frame ``t`` with ``N = H W`` pixels and ``u(x) = W A_t(x)``::

    E_t = -lam log[ 1 / (N^2 sqrt(4 pi sigma_p^2)) sum_x sum_y exp(-|u(x) - u(y)|^2 / (4 sigma_p^2)) ]

The double sum is never formed.  Per frame (cost O(pixels + bins)):

1. :func:`entropy_histogram` splats every ``u(x)`` into a histogram
   ``(T, B, B, B)`` over the cube of bin centres ``lo + (i, j, k) h`` with
   trilinear weights (atomic adds).  Axis 1 of the histogram is ``u[0]``,
   axis 2 ``u[1]``, axis 3 ``u[2]``.  A coordinate outside the cube is
   clamped onto its face (choose the cube to hold the data:
   ``AlbedoPrior.hist_lo/hist_hi``).
2. :func:`entropy_blur` convolves it with the separable, *unnormalised*
   Gaussian ``exp(-|delta|^2 / (4 sigma_p^2))`` (variance ``2 sigma_p^2`` per
   axis, peak 1), sampled on the bins: the 1-D ``taps`` of
   :func:`ivkernels.priors.entropy_blur_weights`, which by default shrink the
   variance by the ``h^2 / 3`` that trilinear splat + slice add back.
3. :func:`entropy_dot` forms ``D_t = <hist_t, blurred_t>``, which
   approximates the double sum itself (each pair weighted by the Gaussian,
   the ``x = y`` pairs included), so
   ``E_t = -lam (log D_t - 2 log N - log sqrt(4 pi sigma_p^2))``
   (:func:`entropy_energy`); the error against the direct sum shrinks with
   ``h`` (tests/test_kernels_energy_albedo_entropy.py).
4. :func:`entropy_slice_gradient`: ``D_t = sum_x V(u(x))`` with ``V`` the
   trilinear interpolant of the blurred histogram, and the blur is symmetric,
   so ``dE_t/dA(x) = -2 lam W^T grad V(u(x)) / D_t``.  ``grad V`` is the exact
   gradient of the trilinear interpolant (per axis: the bin-to-bin difference
   of ``blurred`` across the cell / h, mixed bilinearly over the other two
   axes; 0 along an axis where the coordinate was clamped), so the gradient
   is exactly that of the discretised energy: line searches see a
   consistent pair.  (A gradient grid by central differences, sampled
   trilinearly, is smoother per pixel but biased low by 5-20% along descent
   directions at ``h = 0.04-0.08``, and inconsistent with the energy.)

:func:`entropy_term` runs all steps on preallocated scratch
(:func:`allocate_entropy_scratch`).  ``row_flags`` mark the histogram rows
that hold mass, so the blur skips the empty part of the cube.  The splat
scatters, so its launch is split only at frame boundaries (``align=H``); the
dot accumulates per frame and is split at histogram-frame boundaries.
"""
from __future__ import annotations

import math
import sys

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import EntropyScratch, allocate_entropy_scratch_with, run_entropy_steps
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.energy_albedo_entropy import FAMILY
from ivkernels.kernels.warp._checks import FRONT

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def bin_coordinate(v: float, lo: float, h: float, bins: int):
    """Cell of whitened coordinate ``v``: ``(i0, f, inside)``.

    ``c = (v - lo) / h`` is clamped to ``[0, bins - 1]`` (NaN goes to 0);
    ``i0 = min(floor(c), bins - 2)``, ``f = c - i0`` the weight of ``i0 + 1``;
    ``inside`` is 1.0 if no clamping happened, else 0.0.
    """
    c = (v - lo) / h
    cc = float(0.0)
    inside = float(0.0)
    if c >= 0.0:
        cc = c
        inside = 1.0
    if cc > float(bins - 1):
        cc = float(bins - 1)
        inside = 0.0
    i0 = wp.min(int(cc), bins - 2)
    return i0, cc - float(i0), inside


@wp.func
def load_mat33(m: wp.array2d(dtype=float)):
    return wp.mat33(m[0, 0], m[0, 1], m[0, 2], m[1, 0], m[1, 1], m[1, 2], m[2, 0], m[2, 1], m[2, 2])


@wp.func
def whitened(A: wp.array4d(dtype=float), Wm: wp.mat33, t: int, y: int, x: int):
    return Wm * wp.vec3(A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2])


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@wp.kernel
def splat_whitened_rows(row_begin: int, A: wp.array4d(dtype=float), whiten: wp.array2d(dtype=float),
                        lo: float, h: float, hist: wp.array4d(dtype=float),
                        row_flags: wp.array4d(dtype=wp.int32)):
    """One thread per image row: trilinear splat of ``W A(x)`` into ``hist[t]`` (atomic adds);
    marks the touched histogram rows in ``row_flags[0]``."""
    r = row_begin + wp.tid()
    height = A.shape[1]
    t = r // height
    y = r - t * height
    bins = hist.shape[1]
    Wm = load_mat33(whiten)
    for x in range(A.shape[2]):
        u = whitened(A, Wm, t, y, x)
        i0, fi, ini = bin_coordinate(u[0], lo, h, bins)
        j0, fj, inj = bin_coordinate(u[1], lo, h, bins)
        k0, fk, ink = bin_coordinate(u[2], lo, h, bins)
        for a in range(2):
            wa = wp.where(a == 0, 1.0 - fi, fi)
            for b in range(2):
                wab = wa * wp.where(b == 0, 1.0 - fj, fj)
                row_flags[0, t, i0 + a, j0 + b] = 1
                wp.atomic_add(hist, t, i0 + a, j0 + b, k0, wab * (1.0 - fk))
                wp.atomic_add(hist, t, i0 + a, j0 + b, k0 + 1, wab * fk)


@wp.func
def histogram_row(r: int, bins: int):
    """``(t, i, j)`` of histogram row ``r = (t * B + i) * B + j``."""
    t = r // (bins * bins)
    rem = r - t * bins * bins
    i = rem // bins
    return t, i, rem - i * bins


@wp.kernel
def blur_along_rows(row_begin: int, src: wp.array4d(dtype=float), taps: wp.array(dtype=float),
                    row_flags: wp.array4d(dtype=wp.int32), dst: wp.array4d(dtype=float)):
    """One thread per histogram row ``(t, i, j)``: blur along the contiguous axis ``k``.

    Rows not flagged in ``row_flags[0]`` are all zero in ``src``: write zeros.
    """
    bins = src.shape[1]
    t, i, j = histogram_row(row_begin + wp.tid(), bins)
    radius = (taps.shape[0] - 1) // 2
    if row_flags[0, t, i, j] == 0:
        for k in range(bins):
            dst[t, i, j, k] = 0.0
    else:
        for k in range(bins):
            o_lo = wp.max(-radius, -k)
            o_hi = wp.min(radius, bins - 1 - k)
            acc = float(0.0)
            for o in range(o_lo, o_hi + 1):
                acc += taps[o + radius] * src[t, i, j, k + o]
            dst[t, i, j, k] = acc


@wp.kernel
def blur_across_rows(row_begin: int, src: wp.array4d(dtype=float), taps: wp.array(dtype=float),
                     axis: int, flag_in: int, flag_out: int, row_flags: wp.array4d(dtype=wp.int32),
                     dst: wp.array4d(dtype=float)):
    """One thread per histogram row ``(t, i, j)``: blur along ``axis`` 1 (``i``) or 2 (``j``).

    The row is a weighted sum of whole source rows (reads run along the
    contiguous axis), skipping source rows not flagged in
    ``row_flags[flag_in]`` (all zero).  If ``flag_out >= 0`` the row's own
    flag in ``row_flags[flag_out]`` records whether any source was non-zero.
    """
    bins = src.shape[1]
    t, i, j = histogram_row(row_begin + wp.tid(), bins)
    radius = (taps.shape[0] - 1) // 2
    di = wp.where(axis == 1, 1, 0)
    dj = 1 - di
    p = di * i + dj * j
    for k in range(bins):
        dst[t, i, j, k] = 0.0
    touched = int(0)
    for o in range(wp.max(-radius, -p), wp.min(radius, bins - 1 - p) + 1):
        si = i + o * di
        sj = j + o * dj
        if row_flags[flag_in, t, si, sj] != 0:
            touched = 1
            w = taps[o + radius]
            for k in range(bins):
                dst[t, i, j, k] = dst[t, i, j, k] + w * src[t, si, sj, k]
    if flag_out >= 0:
        row_flags[flag_out, t, i, j] = touched


@wp.kernel
def frame_dot_rows(row_begin: int, hist: wp.array4d(dtype=float), blurred: wp.array4d(dtype=float),
                   dots: wp.array(dtype=wp.float64)):
    """One thread per histogram row: ``dots[t] += sum_k hist * blurred`` (atomic, float64)."""
    bins = hist.shape[1]
    t, i, j = histogram_row(row_begin + wp.tid(), bins)
    acc = wp.float64(0.0)
    for k in range(bins):
        acc += wp.float64(hist[t, i, j, k] * blurred[t, i, j, k])
    wp.atomic_add(dots, t, acc)


@wp.kernel
def slice_gradient_rows(row_begin: int, A: wp.array4d(dtype=float), whiten: wp.array2d(dtype=float),
                        lo: float, h: float, blurred: wp.array4d(dtype=float),
                        dots: wp.array(dtype=wp.float64), lam: float, gA: wp.array4d(dtype=float)):
    """One thread per image row: ``gA += -2 lam W^T grad V(W A(x)) / dots[t]``."""
    r = row_begin + wp.tid()
    height = A.shape[1]
    t = r // height
    y = r - t * height
    bins = blurred.shape[1]
    Wm = load_mat33(whiten)
    scale = float(wp.float64(-2.0 * lam) / dots[t]) / h
    for x in range(A.shape[2]):
        u = whitened(A, Wm, t, y, x)
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
        g = wp.transpose(Wm) * wp.vec3(gi * ini, gj * inj, gk * ink) * scale
        gA[t, y, x, 0] = gA[t, y, x, 0] + g[0]
        gA[t, y, x, 1] = gA[t, y, x, 1] + g[1]
        gA[t, y, x, 2] = gA[t, y, x, 2] + g[2]


@wp.kernel
def entropy_energy_frames(row_begin: int, dots: wp.array(dtype=wp.float64), log_norm: wp.float64,
                          lam: float, rows_per_frame: int, energy_rows: wp.array(dtype=wp.float64)):
    """One thread per frame: ``energy_rows[t * rows_per_frame] += -lam (log dots[t] + log_norm)``."""
    t = row_begin + wp.tid()
    r = t * rows_per_frame
    energy_rows[r] = energy_rows[r] - wp.float64(lam) * (wp.log(dots[t]) + log_norm)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def allocate_entropy_scratch(n_frames: int, bins: int, device="cpu") -> EntropyScratch:
    """Allocate :class:`EntropyScratch` for ``n_frames`` frames and a ``bins^3`` cube on ``device``."""
    def empty(shape, dtype):
        return wp.empty(shape, dtype=wp.dtype_from_numpy(dtype), device=device)

    return allocate_entropy_scratch_with(empty, n_frames, bins)


@host("entropy_histogram")
def entropy_histogram(A, whiten, lo: float, h: float, hist, row_flags) -> None:
    """Overwrite ``hist`` with the trilinear splat of the whitened albedo ``W A(x)`` (Eq. 12).

    Parameters
    ----------
    A : wp.array float32 (T, H, W, 3), log albedo.
    whiten : wp.array float32 (3, 3), ``W`` (``AlbedoPrior.whiten``).
    lo : whitened coordinate of the centre of bin 0 on every axis.
    h : bin width (whitened units), > 0.
    hist : wp.array float32 (T, B, B, B), written: bin ``(i, j, k)`` centred at
        ``lo + (i, j, k) h`` holds the summed trilinear weights (each pixel
        adds mass 1); coordinates outside the cube are clamped onto it.
    row_flags : wp.array int32 (2, T, B, B), written: ``row_flags[0, t, i, j]``
        is 1 where the row ``hist[t, i, j, :]`` received mass, else 0 (plane
        1 is zeroed; :func:`entropy_blur` uses both to skip empty rows).
    """
    T, H, W, _ = A.shape
    dev = A.device
    hist.zero_()
    row_flags.zero_()
    launch_rows(splat_whitened_rows, T * H, [A, whiten, lo, h, hist, row_flags], device=dev, align=H)


@host("entropy_blur")
def entropy_blur(hist, taps, row_flags, tmp, blurred) -> None:
    """``blurred = G * hist`` per frame, ``G`` separable with 1-D ``taps`` (zero outside the cube).

    Parameters
    ----------
    hist : wp.array float32 (T, B, B, B), unchanged.
    taps : wp.array float32 (2 r + 1,), odd length, centred
        (:func:`ivkernels.priors.entropy_blur_weights`).
    row_flags : wp.array int32 (2, T, B, B): plane 0 from
        :func:`entropy_histogram` (read), plane 1 scratch (written).
    tmp : wp.array float32 (T, B, B, B), scratch.  Must not overlap ``hist``.
    blurred : wp.array float32 (T, B, B, B), written.  Must not overlap ``hist``.

    Three passes (along k, j, i); rows whose sources are all empty cost only
    a flag check, so the cost follows the occupied part of the cube.
    """
    dev = hist.device
    B = hist.shape[1]
    T = hist.shape[0]
    n = T * B * B
    launch_rows(blur_along_rows, n, [hist, taps, row_flags, blurred], device=dev)
    launch_rows(blur_across_rows, n, [blurred, taps, 2, 0, 1, row_flags, tmp], device=dev)
    launch_rows(blur_across_rows, n, [tmp, taps, 1, 1, -1, row_flags, blurred], device=dev)


@host("entropy_dot")
def entropy_dot(hist, blurred, dots) -> None:
    """Overwrite ``dots`` (wp.array float64 (T,)) with ``<hist_t, blurred_t>`` per frame."""
    dev = hist.device
    B = hist.shape[1]
    T = hist.shape[0]
    dots.zero_()
    launch_rows(frame_dot_rows, T * B * B, [hist, blurred, dots], device=dev, align=B * B)


@host("entropy_slice_gradient")
def entropy_slice_gradient(A, whiten, lo: float, h: float, blurred, dots, gA, lam: float) -> None:
    """Add Eq. 12's gradient ``-2 lam W^T grad V(W A(x)) / dots[t]`` into ``gA``.

    ``V`` is the trilinear interpolant of ``blurred`` (same ``lo``, ``h`` as
    the histogram), ``dots`` from :func:`entropy_dot`.  ``gA`` float32
    (T, H, W, 3) is accumulated; it must not overlap ``A``.
    """
    T, H, W, _ = A.shape
    dev = A.device
    launch_rows(slice_gradient_rows, T * H, [A, whiten, lo, h, blurred, dots, lam, gA], device=dev)


@host("entropy_energy")
def entropy_energy(dots, sigma_p: float, n_pixels: int, energy_rows, lam: float) -> None:
    """Add ``E_t = -lam log(dots[t] / (n_pixels^2 sqrt(4 pi sigma_p^2)))`` into
    ``energy_rows[t * (len(energy_rows) // T)]`` (the first row of frame ``t``)."""
    dev = dots.device
    T = dots.shape[0]
    log_norm = -2.0 * math.log(n_pixels) - 0.5 * math.log(4.0 * math.pi * sigma_p ** 2)
    launch_rows(entropy_energy_frames, T,
                [dots, wp.float64(log_norm), lam, energy_rows.shape[0] // T, energy_rows], device=dev)


@host("entropy_term")
def entropy_term(A, whiten, lo: float, h: float, taps, sigma_p: float, scratch: EntropyScratch,
                 gA, energy_rows, lam: float) -> None:
    """Add Eq. 12's energy and gradient for every frame of ``A``, in O(pixels + bins).

    Parameters
    ----------
    A : wp.array float32 (T, H, W, 3), log albedo.
    whiten : wp.array float32 (3, 3), ``W`` (``AlbedoPrior.whiten``).
    lo, h : histogram cube (bin centres ``lo + i h``, ``i < B``), whitened
        units (``AlbedoPrior.hist_lo``, ``.hist_bin_width``).
    taps : wp.array float32 (2r+1,), blur taps for ``sigma_p`` and ``h``
        (:func:`ivkernels.priors.entropy_blur_weights`).
    sigma_p : Eq. 12's ``sigma_p`` (whitened units), for the normalisation.
    scratch : :class:`EntropyScratch` for T frames (overwritten; afterwards
        ``hist``, ``blurred`` and ``dots`` hold the histogram, its blur and
        ``<hist, blurred>``).
    gA : wp.array float32 (T, H, W, 3), accumulated ``+= dE/dA``.  Must not overlap ``A``.
    energy_rows : wp.array float64 (T*H,), row ``t*H`` accumulates ``E_t``.
    lam : Eq. 12's ``lambda_Ap``.
    """
    run_entropy_steps(sys.modules[__name__], A, whiten, lo, h, taps, sigma_p, scratch, gA, energy_rows, lam)
