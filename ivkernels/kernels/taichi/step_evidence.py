"""Taichi mirror of :mod:`ivkernels.kernels.warp.step_evidence` (the step evidence on Eq. 9's
local term): same host functions and signatures, NumPy arrays passed as ``ti.types.ndarray()``.
The outermost loop runs over rows in parallel.  The arrays live on the host, so the chromatic
share is summed there from the kernel's per-row counts (in int64, exactly), and so is the whole
video's share of :func:`share_weight`, the float64 offset log of :func:`pixel_counts` and the
medians of the noise level function (:func:`level_medians`, from the kernel's histogram).
"""
import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.taichi.maps import log_change_at
from ivkernels.kernels.reference import step_evidence as ref
from ivkernels.kernels.reference.step_evidence import (FAMILY, MAX_STABLE_STEP, least_stable_step, level_axis,
                                                       level_edges, share, step_edges)

host = implements(FAMILY, FRONT)

nd2_i32 = ti.types.ndarray(dtype=ti.i32, ndim=2)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd4_i32 = ti.types.ndarray(dtype=ti.i32, ndim=4)
nd4_f64 = ti.types.ndarray(dtype=ti.f64, ndim=4)
nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd3_i32 = ti.types.ndarray(dtype=ti.i32, ndim=3)

#: Below this argument ``exp(-a)`` and ``1 - exp(-a)`` are read from their series (see the Warp module).
SERIES_BELOW = 1.0e-3


@ti.func
def exp_neg(a):
    """``exp(-a)`` for ``a >= 0``, by its series below ``SERIES_BELOW`` (see the Warp module)."""
    out = 0.0
    if a < SERIES_BELOW:
        out = 1.0 - a * (1.0 - a * (0.5 - a * (1.0 / 6.0)))
    else:
        out = ti.exp(-a)
    return out


@ti.func
def one_minus_exp_neg(a):
    """``1 - exp(-a)`` for ``a >= 0``, by its series below ``SERIES_BELOW`` (see the Warp module)."""
    out = 0.0
    if a < SERIES_BELOW:
        out = a * (1.0 - a * (0.5 - a * (1.0 / 6.0)))
    else:
        out = 1.0 - ti.exp(-a)
    return out


@ti.func
def vec_step(a, b):
    """``(dL, dC)`` of two 3-channel log values (see the Warp module)."""
    d = a - b
    m = (d[0] + d[1] + d[2]) / 3.0
    return ti.abs(m), ti.max(ti.max(ti.abs(d[0] - m), ti.abs(d[1] - m)), ti.abs(d[2] - m))


@ti.func
def pixel(img: ti.template(), t, y, x):
    """The 3 channels of a pixel."""
    return ti.Vector([img[t, y, x, 0], img[t, y, x, 1], img[t, y, x, 2]])


@ti.func
def pair_step(img: ti.template(), t, y, x, yy, xx):
    """:func:`vec_step` of the pixels ``(y, x)`` and ``(yy, xx)`` of frame ``t``."""
    return vec_step(pixel(img, t, y, x), pixel(img, t, yy, xx))


@ti.func
def net_of_floor(d, floor: ti.template(), t, y, x, yy, xx, c, k):
    """``sqrt(max(d^2 - k^2 (f(y, x)^2 + f(yy, xx)^2) / 2, 0))``, ``f = floor[t, ..., c]``; ``d`` for ``k = 0``
    (see the Warp module)."""
    out = d
    if k > 0.0:
        fa = floor[t, y, x, c]
        fb = floor[t, yy, xx, c]
        out = ti.sqrt(ti.max(d * d - k * k * (fa * fa + fb * fb) / 2.0, 0.0))
    return out


@ti.func
def net_step(img: ti.template(), floor: ti.template(), t, y, x, yy, xx, k):
    """:func:`pair_step` net of the noise ``floor`` at ``k``."""
    dl, dc = pair_step(img, t, y, x, yy, xx)
    return net_of_floor(dl, floor, t, y, x, yy, xx, 0, k), net_of_floor(dc, floor, t, y, x, yy, xx, 1, k)


@ti.func
def pair_counts(img: ti.template(), floor: ti.template(), t, y, x, yy, xx, tau, tau_chroma, k):
    """``(sharp, chromatic)``, each 0 or 1, of one pair of neighbours."""
    dl, dc = net_step(img, floor, t, y, x, yy, xx, k)
    chromatic = 0
    if tau_chroma > 0.0 and dc > tau_chroma:
        chromatic = 1
    sharp = chromatic
    if dl > tau:
        sharp = 1
    return sharp, chromatic


@ti.func
def pair_evidence(img: ti.template(), floor: ti.template(), t, y, x, yy, xx, tau, tau_chroma, k):
    """``(1 - exp(-(dL / tau)^2)) * exp(-(dC / tau_chroma)^2)`` (the second factor 1 for ``tau_chroma = 0``),
    the steps net of the noise ``floor`` at ``k``."""
    dl, dc = net_step(img, floor, t, y, x, yy, xx, k)
    q = dl / tau
    ev = one_minus_exp_neg(q * q)
    if tau_chroma > 0.0:
        qc = dc / tau_chroma
        ev = ev * exp_neg(qc * qc)
    return ev


@ti.func
def rounded_target(position, shift, size):
    """The pixel ``position + shift`` rounds to, clamped to the frame (see the Warp module)."""
    target = ti.floor(ti.cast(position, ti.f32) + shift + 0.5)
    index = 0
    if target > 0.0:
        index = ti.cast(ti.min(target, ti.cast(size - 1, ti.f32)), ti.i32)
    return index


@ti.func
def change_along_flow(img: ti.template(), flow: ti.template(), p, y, x):
    """``img[p + 1, x + round(u(x))] - img[p, x]`` (3 channels), the target clamped to the frame."""
    ty = rounded_target(y, flow[p, y, x, 1], img.shape[1])
    tx = rounded_target(x, flow[p, y, x, 0], img.shape[2])
    return pixel(img, p + 1, ty, tx) - pixel(img, p, y, x)


@ti.kernel
def temporal_steps_rows(img: nd4, flow: nd4, steps: nd4):
    height = img.shape[1]
    width = img.shape[2]
    n_pairs = flow.shape[0]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        p = ti.min(t, n_pairs - 1)
        for x in range(width):
            sl = 0.0
            sc = 0.0
            if n_pairs > 0:
                e = change_along_flow(img, flow, p, y, x)
                if x + 1 < width:
                    dl, dc = vec_step(e, change_along_flow(img, flow, p, y, x + 1))
                    sl = ti.max(sl, dl)
                    sc = ti.max(sc, dc)
                if y + 1 < height:
                    dl, dc = vec_step(e, change_along_flow(img, flow, p, y + 1, x))
                    sl = ti.max(sl, dl)
                    sc = ti.max(sc, dc)
            steps[t, y, x, 0] = sl / ti.sqrt(2.0)
            steps[t, y, x, 1] = sc / ti.sqrt(2.0)


@ti.kernel
def typical_steps_rows(img: nd4, steps: nd4):
    height = img.shape[1]
    width = img.shape[2]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            sl = 0.0
            sc = 0.0
            if x + 1 < width:
                dl, dc = pair_step(img, t, y, x, y, x + 1)
                sl = ti.max(sl, dl)
                sc = ti.max(sc, dc)
            if y + 1 < height:
                dl, dc = pair_step(img, t, y, x, y + 1, x)
                sl = ti.max(sl, dl)
                sc = ti.max(sc, dc)
            steps[t, y, x, 0] = sl
            steps[t, y, x, 1] = sc


@ti.func
def bin_of(value, edges: ti.template()):
    """How many inner edges ``edges[1:-1]`` are ``<= value`` (see the Warp module)."""
    lo = 0
    hi = edges.shape[0] - 2
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if edges[mid] <= value:
            lo = mid
        else:
            hi = mid - 1
    return lo


@ti.func
def mean_channel(img: ti.template(), t, y, x):
    """The mean over the 3 channels of pixel ``(t, y, x)``: the log luminance ``L``."""
    return (img[t, y, x, 0] + img[t, y, x, 1] + img[t, y, x, 2]) / 3.0


@ti.kernel
def step_histogram_rows(img: nd4, steps: nd4, levels: nd1, bins: nd1, counts: nd3_i32):
    height = img.shape[1]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(img.shape[2]):
            b = bin_of(mean_channel(img, t, y, x), levels)
            for c in ti.static(range(2)):
                ti.atomic_add(counts[c, b, bin_of(steps[t, y, x, c], bins)], 1)


@ti.kernel
def cap_at_level_rows(img: nd4, table: nd2, lo: ti.f32, width: ti.f32, scale: ti.f32, floor: nd4):
    height = img.shape[1]
    last = table.shape[1] - 1
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(img.shape[2]):
            u = (mean_channel(img, t, y, x) - lo) / width - 0.5
            if not (u > 0.0):
                u = 0.0
            u = ti.min(u, ti.cast(last, ti.f32))
            i0 = ti.min(ti.cast(ti.floor(u), ti.i32), last)
            i1 = ti.min(i0 + 1, last)
            f = u - ti.cast(i0, ti.f32)
            for c in ti.static(range(2)):
                level = table[c, i0] * (1.0 - f) + table[c, i1] * f
                floor[t, y, x, c] = ti.min(floor[t, y, x, c], scale * level)


@ti.kernel
def offset_log_rows(img: nd4, out: nd4, offset: ti.f32):
    height = img.shape[1]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(img.shape[2]):
            for c in ti.static(range(3)):
                out[t, y, x, c] = ti.log(ti.exp(img[t, y, x, c]) + offset)


@ti.kernel
def step_counts_rows(img: nd4, counts: nd2_i32, tau: ti.f32, tau_chroma: ti.f32, floor: nd4, k: ti.f32):
    height = img.shape[1]
    width = img.shape[2]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        sharp = 0
        chromatic = 0
        for x in range(width):
            if x + 1 < width:
                s, c = pair_counts(img, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
                sharp += s
                chromatic += c
            if y + 1 < height:
                s, c = pair_counts(img, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
                sharp += s
                chromatic += c
        counts[r, 0] = sharp
        counts[r, 1] = chromatic


@ti.func
def net_of_floor64(d, floor: ti.template(), t, y, x, yy, xx, c, k):
    """:func:`net_of_floor` in float64 (the floor read as float64)."""
    out = d
    if k > 0.0:
        fa = ti.cast(floor[t, y, x, c], ti.f64)
        fb = ti.cast(floor[t, yy, xx, c], ti.f64)
        out = ti.sqrt(ti.max(d * d - k * k * (fa * fa + fb * fb) / 2.0, 0.0))
    return out


@ti.func
def pair_counts64(lc: ti.template(), floor: ti.template(), t, y, x, yy, xx, tau, tau_chroma, k):
    """``(sharp, chromatic)`` of one pair from the float64 ``(L, C_0, C_1, C_2)`` of ``lc`` (see the Warp module),
    the steps net of the noise ``floor`` at ``k``."""
    dc = ti.max(ti.max(ti.abs(lc[t, y, x, 1] - lc[t, yy, xx, 1]), ti.abs(lc[t, y, x, 2] - lc[t, yy, xx, 2])),
                ti.abs(lc[t, y, x, 3] - lc[t, yy, xx, 3]))
    dc = net_of_floor64(dc, floor, t, y, x, yy, xx, 1, k)
    dl = net_of_floor64(ti.abs(lc[t, y, x, 0] - lc[t, yy, xx, 0]), floor, t, y, x, yy, xx, 0, k)
    chromatic = 0
    if tau_chroma > 0.0 and dc > tau_chroma:
        chromatic = 1
    sharp = chromatic
    if dl > tau:
        sharp = 1
    return sharp, chromatic


@ti.kernel
def pixel_counts_rows(lc: nd4_f64, counts: nd4_i32, tau: ti.f64, tau_chroma: ti.f64, floor: nd4, k: ti.f64):
    height = lc.shape[1]
    width = lc.shape[2]
    for r in range(lc.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            sharp = 0
            chromatic = 0
            if x + 1 < width:
                s, c = pair_counts64(lc, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
                sharp += s
                chromatic += c
            if y + 1 < height:
                s, c = pair_counts64(lc, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
                sharp += s
                chromatic += c
            counts[t, y, x, 0] = sharp
            counts[t, y, x, 1] = chromatic


@ti.kernel
def row_window_rows(counts: nd4_i32, sums: nd4_i32, totals: nd2_i32, radius: ti.i32):
    """Running window sums along each row and the row's totals (see the Warp module)."""
    height = counts.shape[1]
    width = counts.shape[2]
    for r in range(counts.shape[0] * height):
        t = r // height
        y = r - t * height
        for k in ti.static(range(2)):
            run = 0
            for x in range(ti.min(radius, width - 1) + 1):
                run += counts[t, y, x, k]
            total = 0
            for x in range(width):
                sums[t, y, x, k] = run
                total += counts[t, y, x, k]
                if x + radius + 1 < width:
                    run += counts[t, y, x + radius + 1, k]
                if x - radius >= 0:
                    run -= counts[t, y, x - radius, k]
            totals[r, k] = total


@ti.kernel
def share_weight_columns(sums: nd4_i32, weight: nd3, radius: ti.i32, prior_whole: ti.f64, prior_steps: ti.f64):
    """Running window sums down each column, the share in float64 rounded to float32, and
    ``weight *= (1 - s)^2`` in float32 (see the Warp module)."""
    height = sums.shape[1]
    width = sums.shape[2]
    for c in range(sums.shape[0] * width):
        t = c // width
        x = c - t * width
        sharp = 0
        chromatic = 0
        for y in range(ti.min(radius, height - 1) + 1):
            sharp += sums[t, y, x, 0]
            chromatic += sums[t, y, x, 1]
        for y in range(height):
            s = ti.cast((ti.cast(chromatic, ti.f64) + prior_whole) / (ti.cast(sharp, ti.f64) + prior_steps), ti.f32)
            keep = ti.f32(1.0) - s
            weight[t, y, x] = weight[t, y, x] * (keep * keep)
            if y + radius + 1 < height:
                sharp += sums[t, y + radius + 1, x, 0]
                chromatic += sums[t, y + radius + 1, x, 1]
            if y - radius >= 0:
                sharp -= sums[t, y - radius, x, 0]
                chromatic -= sums[t, y - radius, x, 1]


@ti.kernel
def half_pair_evidence_rows(img: nd4, pairs: nd4, tau: ti.f32, tau_chroma: ti.f32, floor: nd4, k: ti.f32):
    """``pairs[t, y, x, k]``: the evidence of the pair of ``(y, x)`` with ``(y, x) + HALF_NEIGHBOURS[k]``."""
    height = img.shape[1]
    width = img.shape[2]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            e0 = 0.0
            e1 = 0.0
            e2 = 0.0
            e3 = 0.0
            if x + 1 < width:
                e0 = pair_evidence(img, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
            if y + 1 < height:
                e1 = pair_evidence(img, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
                if x + 1 < width:
                    e2 = pair_evidence(img, floor, t, y, x, y + 1, x + 1, tau, tau_chroma, k)
                if x >= 1:
                    e3 = pair_evidence(img, floor, t, y, x, y + 1, x - 1, tau, tau_chroma, k)
            pairs[t, y, x, 0] = e0
            pairs[t, y, x, 1] = e1
            pairs[t, y, x, 2] = e2
            pairs[t, y, x, 3] = e3


@ti.kernel
def step_gate_rows(pairs: nd4, weight: nd3, gate: nd3, gain: ti.f32):
    """``gate *= 1 + gain weight ev``, ``ev`` the largest of the pixel's 8 pairs (see the Warp module)."""
    height = pairs.shape[1]
    width = pairs.shape[2]
    for r in range(pairs.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            ev = ti.max(ti.max(pairs[t, y, x, 0], pairs[t, y, x, 1]), ti.max(pairs[t, y, x, 2], pairs[t, y, x, 3]))
            if x >= 1:
                ev = ti.max(ev, pairs[t, y, x - 1, 0])
            if y >= 1:
                ev = ti.max(ev, pairs[t, y - 1, x, 1])
                if x >= 1:
                    ev = ti.max(ev, pairs[t, y - 1, x - 1, 2])
                if x + 1 < width:
                    ev = ti.max(ev, pairs[t, y - 1, x + 1, 3])
            gate[t, y, x] = gate[t, y, x] * (1.0 + gain * weight[t, y, x] * ev)


@ti.kernel
def log_change_rows(img: nd4, flow: nd4, change: nd4):
    """``change[p, y, x] = (D, valid)`` of ``maps.log_change_at`` (see the Warp module)."""
    height = img.shape[1]
    for r in range(flow.shape[0] * height):
        p = r // height
        y = r - p * height
        for x in range(img.shape[2]):
            d, valid = log_change_at(img, flow, p, y, x)
            change[p, y, x, 0] = d
            change[p, y, x, 1] = valid


@ti.kernel
def still_stability_rows(flow: nd4, change: nd4, weight: nd3, tau: ti.f32, static_flow: ti.f32):
    """1 where the scene moves, else ``maps.shading_gate``'s ``exp(-(e / tau)^2)`` (see the Warp module)."""
    height = weight.shape[1]
    width = weight.shape[2]
    n_pairs = flow.shape[0]
    for r in range(weight.shape[0] * height):
        t = r // height
        y = r - t * height
        p = ti.min(t, n_pairs - 1)      # the frame's pair with the next frame; the last uses the one before
        for x in range(width):
            moving = 0
            for k in ti.static(range(2)):
                pk = t - k              # the pair the frame starts (k = 0) and the one ending on it
                if 0 <= pk < n_pairs:
                    fx = flow[pk, y, x, 0]
                    fy = flow[pk, y, x, 1]
                    if ti.sqrt(fx * fx + fy * fy) >= static_flow:
                        moving = 1
            if moving != 0:
                weight[t, y, x] = 1.0
            else:
                d = change[p, y, x, 0]
                e = 0.0
                if change[p, y, x, 1] > 0.0:
                    for j in ti.static(range(3)):
                        yy = y + j - 1
                        if 0 <= yy < height:
                            for i in ti.static(range(3)):
                                xx = x + i - 1
                                if ti.static(i != 1 or j != 1):
                                    if 0 <= xx < width:
                                        if change[p, yy, xx, 1] > 0.0:
                                            e = ti.max(e, ti.abs(d - change[p, yy, xx, 0]))
                q = e / tau
                weight[t, y, x] = ti.exp(-q * q)


@ti.kernel
def luminance_steps_rows(img: nd4, steps: nd4):
    """``steps[t, y, x, k] = L(t, x + d_k) - L(t, x)`` (right, lower), 0 outside (see the Warp module)."""
    height = img.shape[1]
    width = img.shape[2]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            here = mean_channel(img, t, y, x)
            right = 0.0
            below = 0.0
            if x + 1 < width:
                right = mean_channel(img, t, y, x + 1) - here
            if y + 1 < height:
                below = mean_channel(img, t, y + 1, x) - here
            steps[t, y, x, 0] = right
            steps[t, y, x, 1] = below


@ti.func
def moves(flow: nd4, y, x, static_flow):
    """1 when the flow of ``(y, x)`` in any frame pair is ``static_flow`` px or longer, else 0."""
    out = 0
    for p in range(flow.shape[0]):
        fx = flow[p, y, x, 0]
        fy = flow[p, y, x, 1]
        if ti.sqrt(fx * fx + fy * fy) >= static_flow:
            out = 1
    return out


@ti.func
def still_pair(flow: nd4, here, y, x, k, height, width, static_flow):
    """1 when the pair of ``(y, x)`` and its right (k = 0) or lower (k = 1) neighbour lies in the
    image and holds still (see the Warp module)."""
    yy = y + k
    xx = x + 1 - k
    out = 0
    if here == 0 and yy < height and xx < width:
        if moves(flow, yy, xx, static_flow) == 0:
            out = 1
    return out


@ti.func
def median_of(values: nd4, y, x, k, centre, absolute):
    """The median over ``t`` of ``values[t, y, x, k] - centre`` (of its magnitude where
    ``absolute`` is 1), by ranks (see the Warp module)."""
    n = values.shape[0]
    lo = 0.0
    hi = 0.0
    for i in range(n):
        v = values[i, y, x, k] - centre
        if absolute == 1:
            v = ti.abs(v)
        rank = 0
        for j in range(n):
            u = values[j, y, x, k] - centre
            if absolute == 1:
                u = ti.abs(u)
            if u < v or (u == v and j < i):
                rank += 1
        if rank == (n - 1) // 2:
            lo = v
        if rank == n // 2:
            hi = v
    return 0.5 * (lo + hi)


@ti.func
def largest_step(values: nd4, y, x, k, centre):
    """``max_t |values[t, y, x, k] - centre|``."""
    out = 0.0
    for i in range(values.shape[0]):
        out = ti.max(out, ti.abs(values[i, y, x, k] - centre))
    return out


@ti.kernel
def stable_pairs_rows(steps: nd4, flow: nd4, pairs: nd3, tau: ti.f32, stability: ti.f32, floor: ti.f32,
                      static_flow: ti.f32, least_step: ti.f32):
    """The stable-step evidence of each pixel's right and lower pair, skipping the medians of
    pairs none of whose steps reaches ``least_step`` (see the Warp module)."""
    height = pairs.shape[0]
    width = pairs.shape[1]
    for y in range(height):
        for x in range(width):
            here = moves(flow, y, x, static_flow)
            for k in ti.static(range(2)):
                ev = 0.0
                if still_pair(flow, here, y, x, k, height, width, static_flow) == 1:
                    if largest_step(steps, y, x, k, 0.0) >= least_step:
                        m = median_of(steps, y, x, k, 0.0, 0)
                        if ti.abs(m) < MAX_STABLE_STEP:
                            q = m / tau
                            qs = largest_step(steps, y, x, k, m) / stability
                            ev = (1.0 - ti.exp(-q * q)) * ti.exp(-qs * qs)
                            if ev < floor:
                                ev = 0.0
                pairs[y, x, k] = ev


@ti.kernel
def light_edge_pairs(steps: nd4, flow: nd4, tau: ti.f32, spread: ti.f32, static_flow: ti.f32):
    """Pass 1, each pair once: its steps replaced in place by its light-edge factor, 1 where the
    pair leaves the image or a pixel moves (see the Warp module)."""
    height = steps.shape[1]
    width = steps.shape[2]
    for y in range(height):
        for x in range(width):
            here = moves(flow, y, x, static_flow)
            for k in ti.static(range(2)):
                if still_pair(flow, here, y, x, k, height, width, static_flow) == 1:
                    m = median_of(steps, y, x, k, 0.0, 0)
                    w = tau
                    if spread > 0.0:
                        widen = spread * median_of(steps, y, x, k, m, 1)
                        w = ti.sqrt(tau * tau + widen * widen)
                    for t in range(steps.shape[0]):
                        q = (steps[t, y, x, k] - m) / w
                        steps[t, y, x, k] = ti.exp(-q * q)
                else:
                    for t in range(steps.shape[0]):
                        steps[t, y, x, k] = 1.0


@ti.kernel
def light_edge_pixels(pairs: nd4, factor: nd3):
    """Pass 2, each pixel: the smallest of 1 and its four pairs' factors (see the Warp module)."""
    for t, y, x in factor:
        f = ti.min(1.0, ti.min(pairs[t, y, x, 0], pairs[t, y, x, 1]))
        if x >= 1:
            f = ti.min(f, pairs[t, y, x - 1, 0])
        if y >= 1:
            f = ti.min(f, pairs[t, y - 1, x, 1])
        factor[t, y, x] = f


@host("offset_log")
def offset_log(log_image, out, offset: float) -> None:
    """``out = log(exp(log_image) + offset)``; see :func:`ivkernels.kernels.warp.step_evidence.offset_log`."""
    if out.size:
        offset_log_rows(log_image, out, offset)


#: The kernels' placeholder ``floor`` when there is none (never read: ``k`` is then 0).
_NO_FLOOR = np.zeros((1, 1, 1, 2), np.float32)


def _floor_args(floor, k: float) -> tuple:
    """The kernels' ``floor, k``: without a floor, ``k = 0`` (the steps as read, as the reference does)."""
    return (floor, k) if floor is not None else (_NO_FLOOR, 0.0)


@host("typical_steps")
def typical_steps(log_image, steps) -> None:
    """Per pixel, the larger step of its right and lower pairs; see
    :func:`ivkernels.kernels.warp.step_evidence.typical_steps`."""
    if steps.size:
        typical_steps_rows(log_image, steps)


@host("temporal_steps")
def temporal_steps(log_image, flow, steps) -> None:
    """The steps of what changes between frames along the flow; see
    :func:`ivkernels.kernels.warp.step_evidence.temporal_steps`."""
    if steps.size:
        temporal_steps_rows(log_image, flow, steps)


_LEVEL_EDGES = level_edges()
_STEP_EDGES = step_edges()


@host("step_histogram")
def step_histogram(log_image, steps, counts) -> None:
    """The histogram of the steps per brightness bin; see
    :func:`ivkernels.kernels.warp.step_evidence.step_histogram`."""
    counts[...] = 0
    if log_image.size:
        step_histogram_rows(log_image, steps, _LEVEL_EDGES, _STEP_EDGES, counts)


@host("level_medians")
def level_medians(counts, table) -> None:
    """The noise level function from the histogram, on the host (the reference's float64 medians);
    see :func:`ivkernels.kernels.warp.step_evidence.level_medians`."""
    table[...] = ref.level_medians(counts).astype(np.float32)


@host("cap_at_level")
def cap_at_level(log_image, table, scale: float, floor) -> None:
    """The floor capped at ``scale`` times the noise level function; see
    :func:`ivkernels.kernels.warp.step_evidence.cap_at_level`."""
    lo, width = level_axis()
    if floor.size:
        cap_at_level_rows(log_image, table, lo, width, float(scale), floor)


@host("step_counts")
def step_counts(log_image, counts, tau: float, tau_chroma: float = 0.0, floor=None, k: float = 0.0) -> None:
    """Per row, the sharp and the chromatic steps; see :func:`ivkernels.kernels.warp.step_evidence.step_counts`."""
    if counts.size:
        step_counts_rows(log_image, counts, tau, tau_chroma, *_floor_args(floor, k))


@host("pixel_counts")
def pixel_counts(log_image, counts, offset: float, tau: float, tau_chroma: float = 0.0, floor=None,
                 k: float = 0.0) -> None:
    """Per pixel, the sharp and the chromatic steps in float64; see
    :func:`ivkernels.kernels.warp.step_evidence.pixel_counts`."""
    if counts.size:
        # the float64 offset log by NumPy on the (host) arrays: Taichi's float64 exp and log call the C
        # library, measured 35 times slower once another kernel of this family has run; the counting is the kernel's
        L, C = ref.luminance_chroma(ref.offset_log(log_image, offset))
        lc = np.empty((*counts.shape[:3], 4), np.float64)
        lc[..., 0] = L
        lc[..., 1:] = C
        pixel_counts_rows(lc, counts, tau, tau_chroma, *_floor_args(floor, k))


@host("share_weight")
def share_weight(counts, weight, radius: int, prior_steps: float) -> None:
    """``weight *= (1 - s)^2``, ``s`` the share read around each pixel; see
    :func:`ivkernels.kernels.warp.step_evidence.share_weight`."""
    t, h, w, _ = counts.shape
    if weight.size:
        radius = min(radius, max(h, w))
        sums = np.empty(counts.shape, np.int32)
        totals = np.empty((t * h, 2), np.int32)
        row_window_rows(counts, sums, totals, radius)
        share_weight_columns(sums, weight, radius, prior_steps * share(totals), prior_steps)


@host("step_gate")
def step_gate(log_image, counts, weight, gate, gain: float, tau: float, tau_chroma: float = 0.0, floor=None,
              k: float = 0.0) -> None:
    """``gate *= 1 + gain (1 - s)^2 weight evidence``; see :func:`ivkernels.kernels.warp.step_evidence.step_gate`."""
    if gate.size:
        pairs = np.empty((*gate.shape, 4), np.float32)         # each pair once, then each pixel's largest
        half_pair_evidence_rows(log_image, pairs, tau, tau_chroma, *_floor_args(floor, k))
        step_gate_rows(pairs, weight, gate, gain * (1.0 - share(counts)) ** 2)


@host("still_stability")
def still_stability(log_image, flow, weight, tau: float, static_flow: float) -> None:
    """Weiss's cue where the scene holds still, 1 where it moves; see
    :func:`ivkernels.kernels.warp.step_evidence.still_stability`."""
    t, h, w, _ = log_image.shape
    if t == 1:
        weight[...] = 1.0
    elif weight.size:
        change = np.empty((t - 1, h, w, 2), np.float32)
        log_change_rows(log_image, flow, change)
        still_stability_rows(flow, change, weight, tau, static_flow)


def _luminance_steps(log_image) -> np.ndarray:
    """The (T, H, W, 2) float32 steps of the log luminance to the right and lower neighbour."""
    t, h, w, _ = log_image.shape
    steps = np.empty((t, h, w, 2), np.float32)
    luminance_steps_rows(log_image, steps)
    return steps


@host("stable_pairs")
def stable_pairs(log_image, flow, pairs, tau: float, stability: float, floor: float, static_flow: float) -> None:
    """Weiss's stable-step evidence of each pixel's right and lower pair; see
    :func:`ivkernels.kernels.warp.step_evidence.stable_pairs`."""
    if pairs.size == 0:
        return
    steps = _luminance_steps(log_image)
    stable_pairs_rows(steps, flow, pairs, tau, stability, floor, static_flow, least_stable_step(tau, floor))


@host("moving_steps")
def moving_steps(log_image, flow, factor, tau: float, spread: float, static_flow: float) -> None:
    """Weiss's cue for the light's own edges; see
    :func:`ivkernels.kernels.warp.step_evidence.moving_steps`."""
    if factor.size == 0:
        return
    pairs = _luminance_steps(log_image)                 # each pair once, then each pixel's smallest
    light_edge_pairs(pairs, flow, tau, spread, static_flow)
    light_edge_pixels(pairs, factor)
