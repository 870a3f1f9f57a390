"""Median filters: the flow's 5x5 median, the weighted (non-local) medians of
Classic+NL's flow and of the shading coupling variable (Eq. 9, 10, 13).

Weighted medians are computed per pixel inside the kernel: one kernel thread
owns one image row and, for each pixel, copies the window's (value, weight)
pairs into its own slice of a *scratch* buffer (one row of floats per image
row), then selects the minimiser from there in expected linear time
(:func:`l1_quadratic_select`, a weighted quickselect).  The 225 weights of a
15x15 window are never stored per pixel (the spatial factor of the shading
weights is one shared (2r+1)^2 table).  The 5x5 median runs a branch-free
compare-exchange network (:func:`median_network`) written out as straight-line
code on 25 scalars (:func:`median25`).

Scratch convention: the weighted medians take ``workspace=None``, a
:class:`ivkernels.kernels.workspace.Workspace` that keeps their float32
scratch (:func:`shading_scratch_shape`, :func:`flow_scratch_shape`) between
calls; without one the buffer is allocated for the call.  The shading
median's spatial weight table depends on (radius, sigma) only and is shared
through the bounded table cache of :mod:`ivkernels.kernels.cache`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.cache import cached
from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import (KMEANS_ITERATIONS, MIN_SEPARATION, flow_scratch_shape,  # noqa: F401
                                    median_network, shading_scratch_shape, spatial_weights)
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.median import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def move_entry(buf: wp.array2d(dtype=float), row: int, base: int, i: int, j: int, v: float, w: float):
    """Swap the (value, weight) pairs ``i`` and ``j`` of ``buf[row, base:]``, given
    ``(v, w)``, the pair now at ``i``: entry ``j`` moves to ``i`` and ``(v, w)`` to ``j``."""
    buf[row, base + 2 * i] = buf[row, base + 2 * j]
    buf[row, base + 2 * i + 1] = buf[row, base + 2 * j + 1]
    buf[row, base + 2 * j] = v
    buf[row, base + 2 * j + 1] = w


@wp.func
def l1_quadratic_select(buf: wp.array2d(dtype=float), row: int, base: int, n: int, s: float, lam: float):
    """``argmin_u sum_i w_i |u - v_i| + lam (u - s)^2`` over the ``n`` pairs
    ``(v_i, w_i) = buf[row, base + 2i], buf[row, base + 2i + 1]`` (all ``w_i > 0``).

    Weighted quickselect on the subgradient ``g(u) = 2 lam (u - s) + W(< u) - W(> u)``,
    which is non-decreasing in ``u``: three-way partition the active entries
    around a pivot value ``p``; if ``g(p-) < 0 <= g(p+)`` the answer is ``p``,
    else keep the side holding the zero crossing.  When no entry remains the
    minimiser lies strictly between two values, where ``g`` is linear:
    ``u = s + (W_above - W_below) / (2 lam)`` (Li & Osher's median formula
    gives the same point).  ``lam = 0`` returns the lower weighted median
    (smallest ``v`` with ``W(<= v) >= W / 2``); ``n = 0`` returns ``s``.
    The pairs are reordered in place.
    """
    lo = int(0)
    hi = int(n)
    w_below = float(0.0)
    w_above = float(0.0)
    result = float(s)
    found = int(0)
    while lo < hi and found == 0:
        pivot = buf[row, base + 2 * ((lo + hi) // 2)]
        lt = int(lo)
        i = int(lo)
        gt = int(hi)
        w_lt = float(0.0)
        w_eq = float(0.0)
        w_gt = float(0.0)
        while i < gt:
            v = buf[row, base + 2 * i]
            w = buf[row, base + 2 * i + 1]
            if v < pivot:
                if lt != i:                       # an entry equal to the pivot sits at lt
                    move_entry(buf, row, base, i, lt, v, w)
                w_lt += w
                lt += 1
                i += 1
            elif v > pivot:
                gt -= 1
                move_entry(buf, row, base, i, gt, v, w)
                w_gt += w
            else:
                w_eq += w
                i += 1
        below = w_below + w_lt
        above = w_above + w_gt
        g_lo = 2.0 * lam * (pivot - s) + below - above - w_eq
        g_hi = g_lo + 2.0 * w_eq
        if g_lo < 0.0 and g_hi >= 0.0:
            result = pivot
            found = 1
        elif g_hi < 0.0:
            w_below = below + w_eq
            lo = gt
        else:
            w_above = above + w_eq
            hi = lt
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
def nearer_second(fx: float, fy: float, c0x: float, c0y: float, c1x: float, c1y: float):
    """True if ``(fx, fy)`` is strictly nearer to centre 1 than to centre 0."""
    d0 = (fx - c0x) * (fx - c0x) + (fy - c0y) * (fy - c0y)
    d1 = (fx - c1x) * (fx - c1x) + (fy - c1y) * (fy - c1y)
    return d1 < d0


# ----------------------------------------------------------------------------
# Kernels: one thread per image row (row = t * H + y), looping over x
# ----------------------------------------------------------------------------

@wp.kernel
def median5x5_rows(row_begin: int, src: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = src.shape[1]
    width = src.shape[2]
    t = r // height
    y = r - t * height
    y0 = wp.max(y - 2, 0)
    y1 = wp.max(y - 1, 0)
    y3 = wp.min(y + 1, height - 1)
    y4 = wp.min(y + 2, height - 1)
    for x in range(width):
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


@wp.kernel
def weighted_median_shading_rows(row_begin: int, S: wp.array3d(dtype=float), flow: wp.array4d(dtype=float),
                                 w_bnd: wp.array3d(dtype=float), out: wp.array3d(dtype=float),
                                 scratch: wp.array2d(dtype=float), spatial: wp.array(dtype=float), radius: int,
                                 lam: float, iterations: int, min_separation: float):
    r = row_begin + wp.tid()
    height = S.shape[1]
    width = S.shape[2]
    t = r // height
    y = r - t * height
    side = 2 * radius + 1
    for x in range(width):
        s = S[t, y, x]
        out[t, y, x] = s
        if t >= flow.shape[0]:
            continue
        if w_bnd[t, y, x] < 0.5:
            continue
        y_lo = wp.max(y - radius, 0)
        y_hi = wp.min(y + radius + 1, height)
        x_lo = wp.max(x - radius, 0)
        x_hi = wp.min(x + radius + 1, width)
        # surf (Eq. 10): 2-means of the window's flow vectors
        c0x = flow[t, y, x, 0]
        c0y = flow[t, y, x, 1]
        c1x = c0x
        c1y = c0y
        far = float(-1.0)
        for yy in range(y_lo, y_hi):
            for xx in range(x_lo, x_hi):
                dx = flow[t, yy, xx, 0] - c0x
                dy = flow[t, yy, xx, 1] - c0y
                d = dx * dx + dy * dy
                if d > far:
                    far = d
                    c1x = flow[t, yy, xx, 0]
                    c1y = flow[t, yy, xx, 1]
        for it in range(iterations):
            s0x = float(0.0)
            s0y = float(0.0)
            s1x = float(0.0)
            s1y = float(0.0)
            n0 = int(0)
            n1 = int(0)
            for yy in range(y_lo, y_hi):
                for xx in range(x_lo, x_hi):
                    fx = flow[t, yy, xx, 0]
                    fy = flow[t, yy, xx, 1]
                    if nearer_second(fx, fy, c0x, c0y, c1x, c1y):
                        s1x += fx
                        s1y += fy
                        n1 += 1
                    else:
                        s0x += fx
                        s0y += fy
                        n0 += 1
            m0x = c0x
            m0y = c0y
            m1x = c1x
            m1y = c1y
            if n0 > 0:
                m0x = s0x / float(n0)
                m0y = s0y / float(n0)
            if n1 > 0:
                m1x = s1x / float(n1)
                m1y = s1y / float(n1)
            moved = m0x != c0x or m0y != c0y or m1x != c1x or m1y != c1y
            c0x = m0x
            c0y = m0y
            c1x = m1x
            c1y = m1y
            if not moved:
                break
        split = (c0x - c1x) * (c0x - c1x) + (c0y - c1y) * (c0y - c1y) >= min_separation * min_separation
        own = nearer_second(flow[t, y, x, 0], flow[t, y, x, 1], c0x, c0y, c1x, c1y)
        # window pairs (value, weight) of x's surface, Eq. 10
        n = int(0)
        for yy in range(y_lo, y_hi):
            for xx in range(x_lo, x_hi):
                keep = True
                if split:
                    keep = nearer_second(flow[t, yy, xx, 0], flow[t, yy, xx, 1], c0x, c0y, c1x, c1y) == own
                if keep:
                    scratch[r, 2 * n] = S[t, yy, xx]
                    scratch[r, 2 * n + 1] = spatial[(yy - y + radius) * side + xx - x + radius]
                    n += 1
        out[t, y, x] = l1_quadratic_select(scratch, r, 0, n, s, lam)


@wp.kernel
def weighted_median_flow_rows(row_begin: int, flow: wp.array4d(dtype=float), lab: wp.array4d(dtype=float),
                              occ: wp.array3d(dtype=float), mask: wp.array3d(dtype=float),
                              out: wp.array4d(dtype=float), scratch: wp.array2d(dtype=float),
                              radius: int, sigma_x: float, sigma_i: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    width = flow.shape[2]
    t = r // height
    y = r - t * height
    side = 2 * radius + 1
    base = side * side  # scratch[r, :base] holds the window's weights, then the pairs
    inv_x = 1.0 / (2.0 * sigma_x * sigma_x)
    inv_i = 1.0 / (2.0 * sigma_i * sigma_i)
    for x in range(width):
        out[t, y, x, 0] = flow[t, y, x, 0]
        out[t, y, x, 1] = flow[t, y, x, 1]
        if mask[t, y, x] < 0.5:
            continue
        l0 = lab[t, y, x, 0]
        l1 = lab[t, y, x, 1]
        l2 = lab[t, y, x, 2]
        k = int(0)
        for yy in range(y - radius, y + radius + 1):
            for xx in range(x - radius, x + radius + 1):
                w = float(0.0)
                if yy >= 0 and yy < height and xx >= 0 and xx < width:
                    ddx = float(xx - x)
                    ddy = float(yy - y)
                    e0 = lab[t, yy, xx, 0] - l0
                    e1 = lab[t, yy, xx, 1] - l1
                    e2 = lab[t, yy, xx, 2] - l2
                    w = wp.exp(-(ddx * ddx + ddy * ddy) * inv_x - (e0 * e0 + e1 * e1 + e2 * e2) * inv_i)
                    w = w * occ[t, yy, xx]
                scratch[r, k] = w
                k += 1
        for c in range(2):
            n = int(0)
            k = int(0)
            for yy in range(y - radius, y + radius + 1):
                for xx in range(x - radius, x + radius + 1):
                    w = scratch[r, k]
                    if w > 0.0:
                        scratch[r, base + 2 * n] = flow[t, yy, xx, c]
                        scratch[r, base + 2 * n + 1] = w
                        n += 1
                    k += 1
            out[t, y, x, c] = l1_quadratic_select(scratch, r, base, n, flow[t, y, x, c], 0.0)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _cached_table(key: tuple, make, dtype, device):
    """A small read-only table (``make()`` as a NumPy array) kept per key and device in the
    bounded table cache (:mod:`ivkernels.kernels.cache`)."""
    return cached((__name__, *key, str(device)), lambda: wp.array(make(), dtype=dtype, device=device))


def _scratch(workspace, name: str, shape: tuple, device):
    """Float32 scratch ``name`` of ``shape`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, wp.float32,
                          lambda: wp.empty(shape, dtype=wp.float32, device=device), device)


@host("median5x5")
def median5x5(src, out) -> None:
    """5x5 median of every channel, replicate border (Classic+NL's median filter of the flow).

    Parameters
    ----------
    src : wp.array float32 (T, H, W, C), any units.
    out : wp.array float32 (T, H, W, C), written.  Must not overlap ``src``.
    """
    t, h, w, c = src.shape
    launch_rows(median5x5_rows, t * h, [src, out], device=src.device)


@host("weighted_median_shading")
def weighted_median_shading(S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                            lam: float = 0.001, *, workspace=None) -> None:
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
    in two by 2-means, centres started at ``flow(x)`` and at the window's
    vector farthest from it, refined by at most ``KMEANS_ITERATIONS`` Lloyd
    iterations; ``surf = 1`` on the pixels of x's cluster, 0 on the other.  If
    the final centres are closer than ``MIN_SEPARATION`` (0.5 px) the window
    holds no motion boundary and ``surf = 1`` everywhere.  Clustering flow
    vectors (rather than flood-filling inside the window) also separates
    regions whose boundary is broken or touches the window's border, and
    costs a few passes over the window.

    Parameters
    ----------
    S : wp.array float32 (T, H, W), log shading.
    flow : wp.array float32 (T', H, W, 2), T' <= T, forward flow of frame t (pixels).
    w_bnd : wp.array float32 (T', H, W), motion-boundary map (0 or 1).
    out : wp.array float32 (T, H, W), written (log shading S~).  Must not overlap ``S``.
    radius : window half-size (7 gives the paper's 15x15).
    sigma_s : spatial scale of w_nl in pixels.
    lam : weight of the quadratic pull towards S(x), >= 0.
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the float32 scratch of shape :func:`shading_scratch_shape`
        between calls; without one it is allocated for this call.
    """
    t, h, w = S.shape
    buf = _scratch(workspace, "shading_window", shading_scratch_shape(S.shape, radius), S.device)
    spatial = _cached_table(("spatial", radius, sigma_s), lambda: spatial_weights(radius, sigma_s),
                            wp.float32, S.device)
    launch_rows(weighted_median_shading_rows, t * h,
                [S, flow, w_bnd, out, buf, spatial, radius, lam, KMEANS_ITERATIONS, MIN_SEPARATION],
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
        calls; without one it is allocated for this call.
    """
    t, h, w, _ = flow.shape
    buf = _scratch(workspace, "flow_window", flow_scratch_shape(flow.shape, radius), flow.device)
    launch_rows(weighted_median_flow_rows, t * h,
                [flow, lab, occ, mask, out, buf, radius, sigma_x, sigma_i], device=flow.device, balance=True)
