"""Median filters: the flow's 5x5 median, the weighted (non-local) medians of
Classic+NL's flow and of the shading coupling variable (Eq. 9, 10, 13).

Weighted medians are computed per pixel inside the kernel: one kernel thread
owns one image row and, for each pixel, writes the window's entries into its
own row of a *scratch* buffer, seen as vectors (the shading's (value, weight)
pairs as ``vec2``, the flow's (u, v, weight) triples as ``vec3``), then
selects the minimiser from there in expected linear time
(:func:`l1_quadratic_select`, a weighted quickselect whose passes are free of
data-dependent branches, starting from the previous pixel's answer).  The
225 weights of a 15x15 window are never stored per pixel: the spatial factor
is one shared (2r+1)^2 table (the shading's ``exp(-d^2 / 2 sigma^2)``, the
flow's exponent ``d^2 / 2 sigma^2``, so that its weights come out bit for bit
as if computed per pixel).  The shading median's 2-means of the window's
flow vectors is a kernel of its own (:func:`surface_centres`, run on a copy
of the vectors and skipped where their bounding box is too small to split):
it depends on the flow alone, so the solver finds the centres once per level
and the median of every alternation reads them (in the default solve at
640x480 the 2-means was more than half the median's time).  The 5x5 median runs a branch-free compare-exchange network
(:func:`median_network`) written out as straight-line code on 25 scalars
(:func:`median25`); on the CPU the same network runs as a native loop over
a row's pixels, which the compiler vectorises (:func:`median5x5_row`: 8 frames
at 640x480, two channels, 2 threads: 204 -> 29 ms, bit for bit the same).

Scratch convention: the weighted medians take ``workspace=None``, a
:class:`ivkernels.kernels.workspace.Workspace` that keeps their float32
scratch (:func:`shading_scratch_shape`, :func:`flow_scratch_shape`) between
calls; without one the buffer is allocated for the call.  The spatial tables
depend on (radius, sigma) only and are shared through the bounded table cache
of :mod:`ivkernels.kernels.cache`.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from ivkernels.kernels.cache import cached
from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import (KMEANS_ITERATIONS, MIN_SEPARATION, flow_scratch_shape,  # noqa: F401
                                    median_network, shading_scratch_shape, spatial_weights)
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.median import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows
from ivkernels.kernels.warp.row_tiles import frame_row, row_span
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def keep_side(buf: wp.array2d(dtype=Any), row: int, n: int, vc: int, pivot: float, above: int, whole: int):
    """Move the entries ``buf[row, i]``, ``i < n``, whose component ``vc`` lies above
    ``pivot`` (``above = 1``) or below it (``above = 0``) to the front and return how
    many there are.  Branch-free: each entry is written at the next free slot, which
    only advances when the entry is kept.  ``whole = 0`` overwrites the others;
    ``whole = 1`` swaps instead (a Lomuto partition), so all ``n`` entries remain."""
    kept = int(0)
    for i in range(n):
        e = buf[row, i]
        if whole == 1:
            buf[row, i] = buf[row, kept]
        buf[row, kept] = e
        if above == 1:
            kept += wp.where(e[vc] > pivot, 1, 0)
        else:
            kept += wp.where(e[vc] < pivot, 1, 0)
    return kept


@wp.func
def l1_quadratic_select(buf: wp.array2d(dtype=Any), row: int, n: int, vc: int, wc: int, whole: int,
                        s: float, lam: float, guess: float, use_guess: int):
    """``argmin_u sum_i w_i |u - v_i| + lam (u - s)^2`` over the ``n`` entries ``e_i = buf[row, i]``,
    value ``v_i = e_i[vc]``, weight ``w_i = e_i[wc] > 0`` (``buf`` of vectors: (value, weight)
    pairs, or (u, v, weight) triples of a flow).

    Weighted quickselect on the subgradient ``g(u) = 2 lam (u - s) + W(< u) - W(> u)``,
    which is non-decreasing in ``u``.  Each round takes a pivot ``p`` (``guess`` in
    the first round if ``use_guess = 1``, e.g. the answer at the previous pixel,
    else the median of the first, middle and last active values) and sums the
    active weights below, at and above ``p`` (one branch-free pass, no data
    moved); if ``g(p-) < 0 <= g(p+)`` the answer is ``p``, else only the active
    entries on the side holding the zero crossing stay active
    (:func:`keep_side`), the others' weight joins the weight known to lie below
    or above.  When no entry remains the minimiser lies strictly between two
    values, where ``g`` is linear: ``u = s + (W_above - W_below) / (2 lam)``
    (Li & Osher's median formula gives the same point).  ``lam = 0`` returns the
    lower weighted median (smallest ``v`` with ``W(<= v) >= W / 2``); ``n = 0``
    returns ``s``.  The entries are reordered and, unless ``whole = 1``, partly
    overwritten.

    The answer depends only on the multiset of pairs (not on their order, the
    guess or the pivots) up to the rounding of the float32 weight sums.
    """
    hi = int(n)
    w_below = float(0.0)
    w_above = float(0.0)
    result = float(s)
    found = int(0)
    first = use_guess
    while hi > 0 and found == 0:
        a = buf[row, 0][vc]
        b = buf[row, hi // 2][vc]
        c = buf[row, hi - 1][vc]
        pivot = wp.max(wp.min(a, b), wp.min(wp.max(a, b), c))
        if first == 1:
            pivot = guess
            first = 0
        # the active weights below, at and above the pivot, two entries a step
        # (two sets of sums, so consecutive additions do not wait on each other)
        w_lt = float(0.0)
        w_eq = float(0.0)
        w_gt = float(0.0)
        w_lt2 = float(0.0)
        w_eq2 = float(0.0)
        w_gt2 = float(0.0)
        i = int(0)
        while i + 1 < hi:
            e = buf[row, i]
            v = e[vc]
            w = e[wc]
            w_lt += wp.where(v < pivot, w, 0.0)
            w_eq += wp.where(v == pivot, w, 0.0)
            w_gt += wp.where(v > pivot, w, 0.0)
            e2 = buf[row, i + 1]
            v2 = e2[vc]
            w2 = e2[wc]
            w_lt2 += wp.where(v2 < pivot, w2, 0.0)
            w_eq2 += wp.where(v2 == pivot, w2, 0.0)
            w_gt2 += wp.where(v2 > pivot, w2, 0.0)
            i += 2
        if i < hi:
            e = buf[row, i]
            v = e[vc]
            w = e[wc]
            w_lt += wp.where(v < pivot, w, 0.0)
            w_eq += wp.where(v == pivot, w, 0.0)
            w_gt += wp.where(v > pivot, w, 0.0)
        w_lt += w_lt2
        w_eq += w_eq2
        w_gt += w_gt2
        below = w_below + w_lt
        above = w_above + w_gt
        g_lo = 2.0 * lam * (pivot - s) + below - above - w_eq
        g_hi = g_lo + 2.0 * w_eq
        if g_lo < 0.0 and g_hi >= 0.0:
            result = pivot
            found = 1
        elif g_hi < 0.0:
            w_below = below + w_eq
            hi = keep_side(buf, row, hi, vc, pivot, 1, whole)
        else:
            w_above = above + w_eq
            hi = keep_side(buf, row, hi, vc, pivot, 0, whole)
    if found == 0 and lam > 0.0 and n > 0:
        result = s + (w_above - w_below) / (2.0 * lam)
    return result


@wp.func
def sort2(a: float, b: float):
    """``(min(a, b), max(a, b))``: one compare-exchange."""
    return wp.min(a, b), wp.max(a, b)


@wp.func
def median25(v0: float, v1: float, v2: float, v3: float, v4: float, v5: float, v6: float, v7: float, v8: float,
             v9: float, v10: float, v11: float, v12: float, v13: float, v14: float, v15: float, v16: float,
             v17: float, v18: float, v19: float, v20: float, v21: float, v22: float, v23: float, v24: float):
    """Median of 25 values: the 113 compare-exchanges of ``median_network(25)``
    as straight-line code on scalars (wire ``k`` is ``v<k>``; the median ends on wire 12)."""
    v0, v1 = sort2(v0, v1)
    v2, v3 = sort2(v2, v3)
    v4, v5 = sort2(v4, v5)
    v6, v7 = sort2(v6, v7)
    v8, v9 = sort2(v8, v9)
    v10, v11 = sort2(v10, v11)
    v12, v13 = sort2(v12, v13)
    v14, v15 = sort2(v14, v15)
    v16, v17 = sort2(v16, v17)
    v18, v19 = sort2(v18, v19)
    v20, v21 = sort2(v20, v21)
    v22, v23 = sort2(v22, v23)
    v0, v2 = sort2(v0, v2)
    v1, v3 = sort2(v1, v3)
    v4, v6 = sort2(v4, v6)
    v5, v7 = sort2(v5, v7)
    v8, v10 = sort2(v8, v10)
    v9, v11 = sort2(v9, v11)
    v12, v14 = sort2(v12, v14)
    v13, v15 = sort2(v13, v15)
    v16, v18 = sort2(v16, v18)
    v17, v19 = sort2(v17, v19)
    v20, v22 = sort2(v20, v22)
    v21, v23 = sort2(v21, v23)
    v1, v2 = sort2(v1, v2)
    v5, v6 = sort2(v5, v6)
    v9, v10 = sort2(v9, v10)
    v13, v14 = sort2(v13, v14)
    v17, v18 = sort2(v17, v18)
    v21, v22 = sort2(v21, v22)
    v0, v4 = sort2(v0, v4)
    v1, v5 = sort2(v1, v5)
    v2, v6 = sort2(v2, v6)
    v3, v7 = sort2(v3, v7)
    v8, v12 = sort2(v8, v12)
    v9, v13 = sort2(v9, v13)
    v10, v14 = sort2(v10, v14)
    v11, v15 = sort2(v11, v15)
    v16, v20 = sort2(v16, v20)
    v17, v21 = sort2(v17, v21)
    v18, v22 = sort2(v18, v22)
    v19, v23 = sort2(v19, v23)
    v2, v4 = sort2(v2, v4)
    v3, v5 = sort2(v3, v5)
    v10, v12 = sort2(v10, v12)
    v11, v13 = sort2(v11, v13)
    v18, v20 = sort2(v18, v20)
    v19, v21 = sort2(v19, v21)
    v1, v2 = sort2(v1, v2)
    v3, v4 = sort2(v3, v4)
    v5, v6 = sort2(v5, v6)
    v9, v10 = sort2(v9, v10)
    v11, v12 = sort2(v11, v12)
    v13, v14 = sort2(v13, v14)
    v17, v18 = sort2(v17, v18)
    v19, v20 = sort2(v19, v20)
    v21, v22 = sort2(v21, v22)
    v0, v8 = sort2(v0, v8)
    v1, v9 = sort2(v1, v9)
    v2, v10 = sort2(v2, v10)
    v3, v11 = sort2(v3, v11)
    v4, v12 = sort2(v4, v12)
    v5, v13 = sort2(v5, v13)
    v6, v14 = sort2(v6, v14)
    v7, v15 = sort2(v7, v15)
    v16, v24 = sort2(v16, v24)
    v4, v8 = sort2(v4, v8)
    v5, v9 = sort2(v5, v9)
    v6, v10 = sort2(v6, v10)
    v7, v11 = sort2(v7, v11)
    v20, v24 = sort2(v20, v24)
    v2, v4 = sort2(v2, v4)
    v3, v5 = sort2(v3, v5)
    v6, v8 = sort2(v6, v8)
    v7, v9 = sort2(v7, v9)
    v10, v12 = sort2(v10, v12)
    v11, v13 = sort2(v11, v13)
    v18, v20 = sort2(v18, v20)
    v19, v21 = sort2(v19, v21)
    v22, v24 = sort2(v22, v24)
    v1, v2 = sort2(v1, v2)
    v3, v4 = sort2(v3, v4)
    v5, v6 = sort2(v5, v6)
    v7, v8 = sort2(v7, v8)
    v9, v10 = sort2(v9, v10)
    v11, v12 = sort2(v11, v12)
    v13, v14 = sort2(v13, v14)
    v17, v18 = sort2(v17, v18)
    v19, v20 = sort2(v19, v20)
    v21, v22 = sort2(v21, v22)
    v23, v24 = sort2(v23, v24)
    v0, v16 = sort2(v0, v16)
    v1, v17 = sort2(v1, v17)
    v2, v18 = sort2(v2, v18)
    v3, v19 = sort2(v3, v19)
    v4, v20 = sort2(v4, v20)
    v5, v21 = sort2(v5, v21)
    v6, v22 = sort2(v6, v22)
    v7, v23 = sort2(v7, v23)
    v8, v24 = sort2(v8, v24)
    v8, v16 = sort2(v8, v16)
    v9, v17 = sort2(v9, v17)
    v10, v18 = sort2(v10, v18)
    v11, v19 = sort2(v11, v19)
    v12, v20 = sort2(v12, v20)
    v13, v21 = sort2(v13, v21)
    v6, v10 = sort2(v6, v10)
    v7, v11 = sort2(v7, v11)
    v12, v16 = sort2(v12, v16)
    v13, v17 = sort2(v13, v17)
    v10, v12 = sort2(v10, v12)
    v11, v13 = sort2(v11, v13)
    v11, v12 = sort2(v11, v12)
    return v12


@wp.func
def window_bounds(y: int, x: int, radius: int, height: int, width: int):
    """Rows ``[y_lo, y_hi)`` and columns ``[x_lo, x_hi)`` of the ``(2 radius + 1)^2`` window
    around ``(y, x)`` that lie inside a ``height x width`` frame."""
    return (wp.max(y - radius, 0), wp.min(y + radius + 1, height), wp.max(x - radius, 0),
            wp.min(x + radius + 1, width))


@wp.func
def nearer_second(fx: float, fy: float, c0x: float, c0y: float, c1x: float, c1y: float):
    """True if ``(fx, fy)`` is strictly nearer to centre 1 than to centre 0."""
    d0 = (fx - c0x) * (fx - c0x) + (fy - c0y) * (fy - c0y)
    d1 = (fx - c1x) * (fx - c1x) + (fy - c1y) * (fy - c1y)
    return d1 < d0


# ----------------------------------------------------------------------------
# Kernels: one thread per image row (row = t * H + y), looping over x, or per
# tile of a row on a GPU (:func:`row_span`)
# ----------------------------------------------------------------------------

@wp.kernel
def median5x5_rows(row_begin: int, tiles: int, src: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, src.shape[2])
    height = src.shape[1]
    width = src.shape[2]
    t = r // height
    y = r - t * height
    y0 = wp.max(y - 2, 0)
    y1 = wp.max(y - 1, 0)
    y3 = wp.min(y + 1, height - 1)
    y4 = wp.min(y + 2, height - 1)
    for x in range(x_begin, x_end):
        x0 = wp.max(x - 2, 0)
        x1 = wp.max(x - 1, 0)
        x3 = wp.min(x + 1, width - 1)
        x4 = wp.min(x + 2, width - 1)
        for c in range(src.shape[3]):
            out[t, y, x, c] = median25(
                src[t, y0, x0, c], src[t, y0, x1, c], src[t, y0, x, c], src[t, y0, x3, c], src[t, y0, x4, c],
                src[t, y1, x0, c], src[t, y1, x1, c], src[t, y1, x, c], src[t, y1, x3, c], src[t, y1, x4, c],
                src[t, y, x0, c], src[t, y, x1, c], src[t, y, x, c], src[t, y, x3, c], src[t, y, x4, c],
                src[t, y3, x0, c], src[t, y3, x1, c], src[t, y3, x, c], src[t, y3, x3, c], src[t, y3, x4, c],
                src[t, y4, x0, c], src[t, y4, x1, c], src[t, y4, x, c], src[t, y4, x3, c], src[t, y4, x4, c])


# The CPU's 5x5 median: one row per kernel thread, written as a native loop over the
# row's pixels that the CPU compiler vectorises (eight medians at a time with AVX2:
# the network's compare-exchanges are a min and a max, branch-free), the same
# network and the same ``wp::min`` / ``wp::max`` as :func:`median25`, so the
# result is bit for bit the same.
_CE = "".join(f"IVK_CE(v{i}, v{j}) " for i, j in median_network(25))

_MEDIAN5X5_ROW = r"""
#if defined(__CUDA_ARCH__)
#define IVK_MEDIAN_SIMD
#else
#define IVK_MEDIAN_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
#define IVK_CE(a, b) { const float lo_ = wp::min(a, b); const float hi_ = wp::max(a, b); a = lo_; b = hi_; }
#define IVK_ROW_LOADS(R, C0, C1, C2, C3, C4, K0, K1, K2, K3, K4) \
    float v##K0 = *(const float*)(R + (C0)); float v##K1 = *(const float*)(R + (C1)); \
    float v##K2 = *(const float*)(R + (C2)); float v##K3 = *(const float*)(R + (C3)); \
    float v##K4 = *(const float*)(R + (C4));
#define IVK_MEDIAN_AT(OUT, C0, C1, C2, C3, C4) { \
    IVK_ROW_LOADS(r0, C0, C1, C2, C3, C4, 0, 1, 2, 3, 4) \
    IVK_ROW_LOADS(r1, C0, C1, C2, C3, C4, 5, 6, 7, 8, 9) \
    IVK_ROW_LOADS(r2, C0, C1, C2, C3, C4, 10, 11, 12, 13, 14) \
    IVK_ROW_LOADS(r3, C0, C1, C2, C3, C4, 15, 16, 17, 18, 19) \
    IVK_ROW_LOADS(r4, C0, C1, C2, C3, C4, 20, 21, 22, 23, 24) \
    """ + _CE + r""" \
    OUT = v12; }
const int height = src.shape[1];
const int width = src.shape[2];
const int channels = src.shape[3];
const size_t sx = src.strides[2];
const size_t ox = out.strides[2];
const int y0 = y - 2 > 0 ? y - 2 : 0;
const int y1 = y - 1 > 0 ? y - 1 : 0;
const int y3 = y + 1 < height - 1 ? y + 1 : height - 1;
const int y4 = y + 2 < height - 1 ? y + 2 : height - 1;
for (int c = 0; c < channels; ++c) {
    const char* base = (const char*)src.data + (size_t)t * src.strides[0] + (size_t)c * src.strides[3];
    const char* r0 = base + (size_t)y0 * src.strides[1];
    const char* r1 = base + (size_t)y1 * src.strides[1];
    const char* r2 = base + (size_t)y * src.strides[1];
    const char* r3 = base + (size_t)y3 * src.strides[1];
    const char* r4 = base + (size_t)y4 * src.strides[1];
    char* o = (char*)out.data + (size_t)t * out.strides[0] + (size_t)y * out.strides[1] + (size_t)c * out.strides[3];
    const int inner_begin = width < 2 ? width : 2;
    const int inner_end = width - 2 > inner_begin ? width - 2 : inner_begin;
    // the border columns, with the indices clamped as the kernel clamps them
    for (int x = 0; x < width; ++x) {
        if (x == inner_begin && inner_end > inner_begin) x = inner_end;
        if (x >= width) break;
        const size_t c0 = (size_t)(x - 2 > 0 ? x - 2 : 0) * sx;
        const size_t c1 = (size_t)(x - 1 > 0 ? x - 1 : 0) * sx;
        const size_t c2 = (size_t)x * sx;
        const size_t c3 = (size_t)(x + 1 < width - 1 ? x + 1 : width - 1) * sx;
        const size_t c4 = (size_t)(x + 2 < width - 1 ? x + 2 : width - 1) * sx;
        IVK_MEDIAN_AT(*(float*)(o + (size_t)x * ox), c0, c1, c2, c3, c4)
    }
    // the inside, where no index needs a clamp: a vectorised loop, with a fixed
    // stride for the contiguous one- and two-channel layouts
    float* of = (float*)o;
    if (sx == sizeof(float) && ox == sizeof(float)) {
        IVK_MEDIAN_SIMD
        for (int x = inner_begin; x < inner_end; ++x)
            IVK_MEDIAN_AT(of[x], 4 * (x - 2), 4 * (x - 1), 4 * x, 4 * (x + 1), 4 * (x + 2))
    } else if (sx == 2 * sizeof(float) && ox == 2 * sizeof(float)) {
        IVK_MEDIAN_SIMD
        for (int x = inner_begin; x < inner_end; ++x)
            IVK_MEDIAN_AT(of[2 * x], 8 * (x - 2), 8 * (x - 1), 8 * x, 8 * (x + 1), 8 * (x + 2))
    } else {
        IVK_MEDIAN_SIMD
        for (int x = inner_begin; x < inner_end; ++x)
            IVK_MEDIAN_AT(*(float*)(o + (size_t)x * ox), (size_t)(x - 2) * sx, (size_t)(x - 1) * sx,
                          (size_t)x * sx, (size_t)(x + 1) * sx, (size_t)(x + 2) * sx)
    }
}
#undef IVK_MEDIAN_AT
#undef IVK_ROW_LOADS
#undef IVK_CE
#undef IVK_MEDIAN_SIMD
"""


@wp.func_native(_MEDIAN5X5_ROW)
def median5x5_row(src: wp.array4d(dtype=float), out: wp.array4d(dtype=float), t: int, y: int):
    """Row ``y`` of frame ``t`` of :func:`median5x5_rows`, every channel (CPU)."""
    ...


@wp.kernel
def median5x5_rows_cpu(row_begin: int, src: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    t, y = frame_row(row_begin + wp.tid(), src.shape[1])
    median5x5_row(src, out, t, y)


@wp.kernel
def surface_centres_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), w_bnd: wp.array3d(dtype=float),
                         centres: wp.array4d(dtype=float), scratch: wp.array2d(dtype=wp.vec2), radius: int,
                         iterations: int, min_separation: float):
    # thread ``slot`` covers one tile of row ``r`` (the whole row on the CPU), with scratch row ``slot``
    slot = row_begin + wp.tid()
    r, x_begin, x_end = row_span(slot, tiles, flow.shape[2])
    height = flow.shape[1]
    width = flow.shape[2]
    t, y = frame_row(r, height)
    for x in range(x_begin, x_end):
        c0 = wp.vec2(0.0, 0.0)
        c1 = c0
        split = False
        if w_bnd[t, y, x] >= 0.5:
            y_lo, y_hi, x_lo, x_hi = window_bounds(y, x, radius, height, width)
            # 2-means of the window's flow vectors, copied (row-major) into
            # scratch[slot, :m]; centre 1 starts at the vector farthest from flow(x)
            c0 = wp.vec2(flow[t, y, x, 0], flow[t, y, x, 1])
            c1 = c0
            far = float(-1.0)
            lo = c0
            hi = c0
            m = int(0)
            for yy in range(y_lo, y_hi):
                for xx in range(x_lo, x_hi):
                    f = wp.vec2(flow[t, yy, xx, 0], flow[t, yy, xx, 1])
                    scratch[slot, m] = f
                    m += 1
                    dx = f[0] - c0[0]
                    dy = f[1] - c0[1]
                    d = dx * dx + dy * dy
                    if d > far:
                        far = d
                        c1 = f
                    lo = wp.min(lo, f)
                    hi = wp.max(hi, f)
            # Both centres are means of window vectors, inside their bounding box,
            # so a box whose diagonal is under sqrt(0.8) min_separation cannot end
            # split (the margin, 0.053 px, is beyond the float32 rounding of the
            # means of flows under 1000 px): the Lloyd passes are skipped.
            box = hi - lo
            if box[0] * box[0] + box[1] * box[1] > 0.8 * min_separation * min_separation:
                for it in range(iterations):
                    s0 = wp.vec2(0.0, 0.0)
                    s1 = wp.vec2(0.0, 0.0)
                    n1 = int(0)
                    for i in range(m):
                        f = scratch[slot, i]
                        near = nearer_second(f[0], f[1], c0[0], c0[1], c1[0], c1[1])
                        s1 += wp.where(near, f, wp.vec2(0.0, 0.0))
                        s0 += wp.where(near, wp.vec2(0.0, 0.0), f)
                        n1 += wp.where(near, 1, 0)
                    n0 = m - n1
                    m0 = c0
                    m1 = c1
                    if n0 > 0:
                        m0 = s0 / float(n0)
                    if n1 > 0:
                        m1 = s1 / float(n1)
                    moved = m0[0] != c0[0] or m0[1] != c0[1] or m1[0] != c1[0] or m1[1] != c1[1]
                    c0 = m0
                    c1 = m1
                    if not moved:
                        break
                split = wp.length_sq(c0 - c1) >= min_separation * min_separation
        if not split:
            # one surface: both centres 0 (a split's centres are at least min_separation apart)
            c0 = wp.vec2(0.0, 0.0)
            c1 = c0
        centres[t, y, x, 0] = c0[0]
        centres[t, y, x, 1] = c0[1]
        centres[t, y, x, 2] = c1[0]
        centres[t, y, x, 3] = c1[1]


@wp.kernel
def weighted_median_shading_rows(row_begin: int, tiles: int, S: wp.array3d(dtype=float),
                                 flow: wp.array4d(dtype=float), w_bnd: wp.array3d(dtype=float),
                                 centres: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                                 scratch: wp.array2d(dtype=wp.vec2), spatial: wp.array(dtype=float), radius: int,
                                 lam: float):
    # thread ``slot`` covers one tile of row ``r`` (the whole row on the CPU), with scratch row ``slot``
    slot = row_begin + wp.tid()
    r, x_begin, x_end = row_span(slot, tiles, S.shape[2])
    height = S.shape[1]
    width = S.shape[2]
    t, y = frame_row(r, height)
    side = 2 * radius + 1
    last = float(0.0)   # the answer at the previous pixel when it had one (has_last = 1):
    has_last = int(0)   # the first pivot tried, as neighbouring windows share most pixels
    for x in range(x_begin, x_end):
        s = S[t, y, x]
        out[t, y, x] = s
        if t >= flow.shape[0]:
            continue
        if w_bnd[t, y, x] < 0.5:
            has_last = 0
            continue
        y_lo, y_hi, x_lo, x_hi = window_bounds(y, x, radius, height, width)
        # surf (Eq. 10): x's cluster of the window's flow vectors (surface_centres_rows)
        c0x = centres[t, y, x, 0]
        c0y = centres[t, y, x, 1]
        c1x = centres[t, y, x, 2]
        c1y = centres[t, y, x, 3]
        split = c0x != c1x or c0y != c1y
        own = nearer_second(flow[t, y, x, 0], flow[t, y, x, 1], c0x, c0y, c1x, c1y)
        # window pairs (value, weight) of x's surface, Eq. 10
        n = int(0)
        for yy in range(y_lo, y_hi):
            k = (yy - y + radius) * side + x_lo - x + radius
            for xx in range(x_lo, x_hi):
                keep = True
                if split:
                    keep = nearer_second(flow[t, yy, xx, 0], flow[t, yy, xx, 1], c0x, c0y, c1x, c1y) == own
                scratch[slot, n] = wp.vec2(S[t, yy, xx], spatial[k])
                n += wp.where(keep, 1, 0)
                k += 1
        last = l1_quadratic_select(scratch, slot, n, 0, 1, 0, s, lam, last, has_last)
        has_last = 1
        out[t, y, x] = last


@wp.kernel
def weighted_median_flow_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                              lab: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                              mask: wp.array3d(dtype=float), out: wp.array4d(dtype=float),
                              scratch: wp.array2d(dtype=wp.vec3), spatial: wp.array(dtype=float), radius: int,
                              sigma_i: float):
    # thread ``slot`` covers one tile of row ``r`` (the whole row on the CPU), with scratch row ``slot``
    slot = row_begin + wp.tid()
    r, x_begin, x_end = row_span(slot, tiles, flow.shape[2])
    height = flow.shape[1]
    width = flow.shape[2]
    t, y = frame_row(r, height)
    side = 2 * radius + 1
    inv_i = 1.0 / (2.0 * sigma_i * sigma_i)
    last_u = float(0.0)   # the answers at the previous pixel when it had them (has_last = 1):
    last_v = float(0.0)   # the first pivots tried, as neighbouring windows share most pixels
    has_last = int(0)
    for x in range(x_begin, x_end):
        u0 = flow[t, y, x, 0]
        v0 = flow[t, y, x, 1]
        out[t, y, x, 0] = u0
        out[t, y, x, 1] = v0
        if mask[t, y, x] < 0.5:
            has_last = 0
            continue
        l0 = lab[t, y, x, 0]
        l1 = lab[t, y, x, 1]
        l2 = lab[t, y, x, 2]
        y_lo, y_hi, x_lo, x_hi = window_bounds(y, x, radius, height, width)
        n = int(0)
        for yy in range(y_lo, y_hi):
            k = (yy - y + radius) * side + x_lo - x + radius
            for xx in range(x_lo, x_hi):
                e0 = lab[t, yy, xx, 0] - l0
                e1 = lab[t, yy, xx, 1] - l1
                e2 = lab[t, yy, xx, 2] - l2
                w = wp.exp(-spatial[k] - (e0 * e0 + e1 * e1 + e2 * e2) * inv_i)
                w = w * occ[t, yy, xx]
                scratch[slot, n] = wp.vec3(flow[t, yy, xx, 0], flow[t, yy, xx, 1], w)
                n += wp.where(w > 0.0, 1, 0)
                k += 1
        # u first, keeping every (u, v, w) triple for v
        last_u = l1_quadratic_select(scratch, slot, n, 0, 2, 1, u0, 0.0, last_u, has_last)
        last_v = l1_quadratic_select(scratch, slot, n, 1, 2, 0, v0, 0.0, last_v, has_last)
        has_last = 1
        out[t, y, x, 0] = last_u
        out[t, y, x, 1] = last_v


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

#: Pixels per thread of the weighted medians on a GPU: each thread keeps its own
#: window of (value, weight) pairs or (u, v, weight) triples, 8 or 12 (2 radius + 1)^2
#: bytes, so one thread per pixel would hold a frame stack's windows at once (6.6 GB
#: for the flow's at 640x480x8; at 16 pixels a thread, 415 MB).
MEDIAN_PIXELS_PER_TILE = 16


def _cached_table(key: tuple, make, dtype, device):
    """A small read-only table (``make()`` as a NumPy array) kept per key and device in the
    bounded table cache (:mod:`ivkernels.kernels.cache`)."""
    return cached((__name__, *key, str(device)), lambda: wp.array(make(), dtype=dtype, device=device))


def spatial_exponent(radius: int, sigma: float) -> np.ndarray:
    """``|d|^2 / (2 sigma^2)`` over the (2r+1)^2 window offsets ``d``, row-major, float32
    ``((2r+1)^2,)``: the spatial part of the flow median's exponent, computed in float32
    in the order a kernel would (``|d|^2`` exactly, times ``1 / (2 sigma sigma)``), so
    the weights come out bit for bit as if it were computed per pixel."""
    d = np.arange(-radius, radius + 1, dtype=np.float32)
    sigma = np.float32(sigma)
    inv = np.float32(1.0) / (np.float32(2.0) * sigma * sigma)
    return ((d[:, None] * d[:, None] + d[None, :] * d[None, :]) * inv).astype(np.float32).ravel()


def _as_vectors(buf, vector):
    """The float32 scratch ``buf`` (rows, k * m) seen as ``(rows, m)`` vectors of length k
    (no copy; ``buf`` must outlive the view)."""
    rows, width = buf.shape
    return wp.array(ptr=buf.ptr, dtype=vector, shape=(rows, width // vector._length_), device=buf.device,
                    capacity=buf.capacity)


def _scratch(workspace, name: str, shape: tuple, device):
    """Float32 scratch ``name`` of ``shape`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, wp.float32,
                          lambda: wp.empty(shape, dtype=wp.float32, device=device), device)


@host("median5x5")
def median5x5(src, out) -> None:
    """5x5 median of every channel, replicate border (Classic+NL's median filter of the flow);
    on a GPU one pixel per thread (row tiles).

    Parameters
    ----------
    src : wp.array float32 (T, H, W, C), any units.
    out : wp.array float32 (T, H, W, C), written.  Must not overlap ``src``.
    """
    t, h, w, c = src.shape
    if native_rows(src.device):
        launch_rows(median5x5_rows_cpu, t * h, [src, out], device=src.device)
        return
    tiles = row_tiles(w, src.device)
    launch_rows(median5x5_rows, t * h * tiles, [tiles, src, out], device=src.device)


def _launch_centres(flow, w_bnd, centres, buf, tiles: int, radius: int) -> None:
    """:func:`surface_centres_rows` over the flow's rows, with the scratch ``buf`` (rows >= T' H tiles)."""
    t, h, w, _ = flow.shape
    launch_rows(surface_centres_rows, t * h * tiles,
                [tiles, flow, w_bnd, centres, _as_vectors(buf, wp.vec2), radius, KMEANS_ITERATIONS, MIN_SEPARATION],
                device=flow.device, balance=True)


@host("surface_centres")
def surface_centres(flow, w_bnd, centres, radius: int = 7, *, workspace=None) -> None:
    """Eq. 10's ``surf``: the two flow centres of each motion-boundary pixel's window.

    For pixels with ``w_bnd >= 0.5`` the window's flow vectors (pixels inside
    the image) are split in two by 2-means, centres started at ``flow(x)``
    and at the window's vector farthest from it, refined by at most
    ``KMEANS_ITERATIONS`` Lloyd iterations.  Where the final centres are at
    least ``MIN_SEPARATION`` (0.5 px) apart, ``centres(x) = (c0x, c0y, c1x,
    c1y)``, ``c0`` being the centre started at ``flow(x)``; elsewhere (one
    surface, or not a boundary pixel) ``centres(x) = 0``.  The clusters depend
    on the flow only, so a solver that runs :func:`weighted_median_shading`
    several times on one flow finds them once and passes them in.

    Parameters
    ----------
    flow : wp.array float32 (T, H, W, 2), forward flow (pixels).
    w_bnd : wp.array float32 (T, H, W), motion-boundary map (0 or 1).
    centres : wp.array float32 (T, H, W, 4), written.
    radius : window half-size (7 gives the paper's 15x15).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the float32 scratch of shape :func:`shading_scratch_shape` (times
        :func:`row_tiles` on a GPU) between calls.
    """
    t, h, w, _ = flow.shape
    tiles = row_tiles(w, flow.device, MEDIAN_PIXELS_PER_TILE)
    rows, width = shading_scratch_shape((t, h, w), radius)
    buf = _scratch(workspace, "centres_window", (rows * tiles, width), flow.device)
    if flow.size:
        _launch_centres(flow, w_bnd, centres, buf, tiles, radius)


@host("weighted_median_shading")
def weighted_median_shading(S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                            lam: float = 0.001, *, centres=None, workspace=None) -> None:
    """Update of the coupling variable S~ (Eq. 13), the non-local term of Eq. 9-10.

    For frames ``t < T'`` and pixels with ``w_bnd >= 0.5`` (the paper's
    ``w_bnd = 1``)::

        out(x) = argmin_u  sum_{y in window} w_nl(x, y) |u - S(y)|  +  lam (u - S(x))^2

    with ``lam = lambda_cpl / lambda_Sm`` (Eq. 13 divided by lambda_Sm), solved
    exactly (Li & Osher's median formula, :func:`l1_quadratic_select`);
    ``lam = 0`` gives the plain (lower) weighted median.  Elsewhere ``out = S``.

    ``w_nl(x, y) = exp(-|x - y|^2 / (2 sigma_s^2)) * surf(x, y)`` (Eq. 10) over
    the ``(2 radius + 1)^2`` window; pixels outside the image are skipped.
    Ties in the window's values and ties in the selection are resolved as in
    :func:`l1_quadratic_select` (the lower weighted median when ``lam = 0``).

    ``surf`` (not specified by the paper): the window's flow vectors are split
    in two by 2-means (:func:`surface_centres`); ``surf = 1`` on the pixels of
    x's cluster (those as near to x's centre as ``flow(x)`` is, strictly
    nearer the other centre or not), 0 on the others; where the window holds
    one surface ``surf = 1`` everywhere.  Clustering flow vectors (rather than
    flood-filling inside the window) also separates regions whose boundary is
    broken or touches the window's border, and costs a few passes over the
    window.

    Parameters
    ----------
    S : wp.array float32 (T, H, W), log shading.
    flow : wp.array float32 (T', H, W, 2), T' <= T, forward flow of frame t (pixels).
    w_bnd : wp.array float32 (T', H, W), motion-boundary map (0 or 1).
    out : wp.array float32 (T, H, W), written (log shading S~).  Must not overlap ``S``.
    radius : window half-size (7 gives the paper's 15x15).
    sigma_s : spatial scale of w_nl in pixels.
    lam : weight of the quadratic pull towards S(x), >= 0.
    centres : optional wp.array float32 (T', H, W, 4), :func:`surface_centres`
        of this ``flow``, ``w_bnd`` and ``radius``; without it they are found
        here (the result is bit for bit the same).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the float32 scratch of shape :func:`shading_scratch_shape` (its
        rows times :func:`row_tiles` on a GPU, one window per thread) and,
        without ``centres``, the centres between calls; without one they are
        allocated for this call.
    """
    t, h, w = S.shape
    tiles = row_tiles(w, S.device, MEDIAN_PIXELS_PER_TILE)
    rows, width = shading_scratch_shape(S.shape, radius)
    buf = _scratch(workspace, "shading_window", (rows * tiles, width), S.device)
    if centres is None:
        centres = scratch_buffer(workspace, f"{__name__}.surface_centres", (*flow.shape[:3], 4), wp.float32,
                                 lambda: wp.empty((*flow.shape[:3], 4), dtype=wp.float32, device=S.device),
                                 S.device)
        if flow.size:
            _launch_centres(flow, w_bnd, centres, buf, tiles, radius)
    spatial = _cached_table(("spatial", radius, sigma_s), lambda: spatial_weights(radius, sigma_s),
                            wp.float32, S.device)
    launch_rows(weighted_median_shading_rows, t * h * tiles,
                [tiles, S, flow, w_bnd, centres, out, _as_vectors(buf, wp.vec2), spatial, radius, lam],
                device=S.device, balance=True)


@host("weighted_median_flow")
def weighted_median_flow(flow, lab, occ, mask, out, radius: int = 7, sigma_x: float = 7.0,
                         sigma_i: float = 7.0, *, workspace=None) -> None:
    """Classic+NL's non-local flow median (each flow component independently).

    Where ``mask >= 0.5``, ``out`` is the (lower) weighted median of the flow
    over the ``(2 radius + 1)^2`` window with weights
    ``exp(-|x - y|^2 / (2 sigma_x^2)) * exp(-|lab(x) - lab(y)|^2 / (2 sigma_i^2)) * occ(y)``
    (pixels outside the image skipped; no positive weight keeps the flow);
    elsewhere ``out = flow``.

    Parameters
    ----------
    flow : wp.array float32 (T, H, W, 2), pixels.
    lab : wp.array float32 (T, H, W, 3), CIE Lab of the first image of each pair.
    occ : wp.array float32 (T, H, W), occlusion weight (1 visible, 0 occluded).
    mask : wp.array float32 (T, H, W), 1 where the median is taken.
    out : wp.array float32 (T, H, W, 2), written.  Must not overlap ``flow``.
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the float32 scratch of shape :func:`flow_scratch_shape` between
        calls (its rows times :func:`row_tiles` on a GPU, one window per
        thread); without one it is allocated for this call.
    """
    t, h, w, _ = flow.shape
    tiles = row_tiles(w, flow.device, MEDIAN_PIXELS_PER_TILE)
    rows, width = flow_scratch_shape(flow.shape, radius)
    buf = _scratch(workspace, "flow_window", (rows * tiles, width), flow.device)
    triples = _as_vectors(buf, wp.vec3)
    spatial = _cached_table(("spatial_exponent", radius, sigma_x), lambda: spatial_exponent(radius, sigma_x),
                            wp.float32, flow.device)
    launch_rows(weighted_median_flow_rows, t * h * tiles,
                [tiles, flow, lab, occ, mask, out, triples, spatial, radius, sigma_i], device=flow.device,
                balance=True)
