"""Taichi mirror of :mod:`ivkernels.kernels.warp.median` (5x5 median, weighted
flow median, S~ update of Eq. 13): same host functions and signatures, NumPy
arrays passed as ``ti.types.ndarray()``.

The algorithms are those of the Warp module (see its docstrings): one loop
iteration per image row, the window's entries ((value, weight) pairs of the
shading, (u, v, weight) triples of the flow) written into that row's slice of
a scratch array seen as (rows, slots, entry), then a branch-free weighted
quickselect started at the previous pixel's answer; the shading's 2-means on
a copy of the window's flow vectors, skipped where they cannot split, is a
kernel of its own (``surface_centres``) whose centres the median reads.  The
outermost loop runs over rows in parallel; each row only touches its own
scratch row.
"""
import numpy as np
import taichi as ti

from ivkernels.kernels.cache import cached
from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import (KMEANS_ITERATIONS, MIN_SEPARATION, flow_scratch_shape,  # noqa: F401
                                    median_network, shading_scratch_shape, spatial_weights)
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.median import FAMILY
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)

#: The 5x5 median's compare-exchange pairs (:func:`median_network`).
_PAIRS25 = tuple(median_network(25))


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@ti.func
def keep_side(buf: ti.template(), row, n, vc: ti.template(), width: ti.template(), pivot, above,
              whole: ti.template()):
    """Move the entries ``buf[row, i, :]``, ``i < n``, whose component ``vc`` lies above
    ``pivot`` (``above = 1``) or below it (``above = 0``) to the front and return how
    many there are; branch-free (:func:`ivkernels.kernels.warp.median.keep_side`).
    ``whole = 0`` overwrites the others, ``whole = 1`` swaps (all ``n`` remain)."""
    kept = 0
    for i in range(n):
        v = buf[row, i, vc]
        keep = ti.select(v > pivot, 1, 0)
        if above == 0:
            keep = ti.select(v < pivot, 1, 0)
        for c in ti.static(range(width)):
            e = buf[row, i, c]
            if ti.static(whole == 1):
                buf[row, i, c] = buf[row, kept, c]
            buf[row, kept, c] = e
        kept += keep
    return kept


@ti.func
def l1_quadratic_select(buf: ti.template(), row, n, vc: ti.template(), wc: ti.template(), width: ti.template(),
                        whole: ti.template(), s, lam, guess, use_guess):
    """``argmin_u sum_i w_i |u - v_i| + lam (u - s)^2`` over the ``n`` entries of
    ``buf[row]`` (value ``buf[row, i, vc]``, weight ``buf[row, i, wc] > 0``); the
    weighted quickselect of :func:`ivkernels.kernels.warp.median.l1_quadratic_select`
    (first pivot ``guess`` if ``use_guess = 1``)."""
    hi = n
    w_below = 0.0
    w_above = 0.0
    result = s
    found = 0
    first = use_guess
    while hi > 0 and found == 0:
        a = buf[row, 0, vc]
        b = buf[row, hi // 2, vc]
        c = buf[row, hi - 1, vc]
        pivot = ti.max(ti.min(a, b), ti.min(ti.max(a, b), c))
        if first == 1:
            pivot = guess
            first = 0
        w_lt = 0.0
        w_eq = 0.0
        w_gt = 0.0
        w_lt2 = 0.0
        w_eq2 = 0.0
        w_gt2 = 0.0
        i = 0
        while i + 1 < hi:
            v = buf[row, i, vc]
            w = buf[row, i, wc]
            w_lt += ti.select(v < pivot, w, 0.0)
            w_eq += ti.select(v == pivot, w, 0.0)
            w_gt += ti.select(v > pivot, w, 0.0)
            v2 = buf[row, i + 1, vc]
            w2 = buf[row, i + 1, wc]
            w_lt2 += ti.select(v2 < pivot, w2, 0.0)
            w_eq2 += ti.select(v2 == pivot, w2, 0.0)
            w_gt2 += ti.select(v2 > pivot, w2, 0.0)
            i += 2
        if i < hi:
            v = buf[row, i, vc]
            w = buf[row, i, wc]
            w_lt += ti.select(v < pivot, w, 0.0)
            w_eq += ti.select(v == pivot, w, 0.0)
            w_gt += ti.select(v > pivot, w, 0.0)
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
            hi = keep_side(buf, row, hi, vc, width, pivot, 1, whole)
        else:
            w_above = above + w_eq
            hi = keep_side(buf, row, hi, vc, width, pivot, 0, whole)
    if found == 0 and lam > 0.0 and n > 0:
        result = s + (w_above - w_below) / (2.0 * lam)
    return result


@ti.func
def window_bounds(y, x, radius, height, width):
    """Rows ``[y_lo, y_hi)`` and columns ``[x_lo, x_hi)`` of the ``(2 radius + 1)^2`` window
    around ``(y, x)`` that lie inside a ``height x width`` frame."""
    return ti.max(y - radius, 0), ti.min(y + radius + 1, height), ti.max(x - radius, 0), ti.min(x + radius + 1, width)


@ti.func
def nearer_second(fx, fy, c0x, c0y, c1x, c1y):
    """1 if ``(fx, fy)`` is strictly nearer to centre 1 than to centre 0, else 0."""
    d0 = (fx - c0x) * (fx - c0x) + (fy - c0y) * (fy - c0y)
    d1 = (fx - c1x) * (fx - c1x) + (fy - c1y) * (fy - c1y)
    return ti.select(d1 < d0, 1, 0)


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@ti.kernel
def median5x5_rows(src: nd4, out: nd4):
    height = src.shape[1]
    width = src.shape[2]
    for r in range(src.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            for c in range(src.shape[3]):
                v = ti.Vector.zero(ti.f32, 25)
                for j in ti.static(range(5)):
                    yy = ti.min(ti.max(y + j - 2, 0), height - 1)
                    for i in ti.static(range(5)):
                        v[5 * j + i] = src[t, yy, ti.min(ti.max(x + i - 2, 0), width - 1), c]
                # the pruned median network of ivkernels.kernels.host.median_network,
                # unrolled at compile time (static wire indices keep v in registers), in
                # blocks of 16 pairs (Taichi warns on static loops over 32 iterations)
                for q0 in ti.static(range(0, len(_PAIRS25), 16)):
                    for q in ti.static(range(q0, min(q0 + 16, len(_PAIRS25)))):
                        a, b = ti.static(_PAIRS25[q])
                        lo = ti.min(v[a], v[b])
                        hi = ti.max(v[a], v[b])
                        v[a] = lo
                        v[b] = hi
                out[t, y, x, c] = v[12]


@ti.kernel
def surface_centres_rows(flow: nd4, w_bnd: nd3, centres: nd4, scratch: nd3, radius: ti.i32, iterations: ti.i32,
                         min_separation: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            c0x = 0.0
            c0y = 0.0
            c1x = 0.0
            c1y = 0.0
            split = 0
            if w_bnd[t, y, x] >= 0.5:
                y_lo, y_hi, x_lo, x_hi = window_bounds(y, x, radius, height, width)
                # 2-means of the window's flow vectors, copied (row-major) into
                # scratch[r, :m]; centre 1 starts at the vector farthest from flow(x)
                c0x = flow[t, y, x, 0]
                c0y = flow[t, y, x, 1]
                c1x = c0x
                c1y = c0y
                far = -1.0
                lo_x = c0x
                lo_y = c0y
                hi_x = c0x
                hi_y = c0y
                m = 0
                for yy in range(y_lo, y_hi):
                    for xx in range(x_lo, x_hi):
                        fx = flow[t, yy, xx, 0]
                        fy = flow[t, yy, xx, 1]
                        scratch[r, m, 0] = fx
                        scratch[r, m, 1] = fy
                        m += 1
                        dx = fx - c0x
                        dy = fy - c0y
                        d = dx * dx + dy * dy
                        if d > far:
                            far = d
                            c1x = fx
                            c1y = fy
                        lo_x = ti.min(lo_x, fx)
                        lo_y = ti.min(lo_y, fy)
                        hi_x = ti.max(hi_x, fx)
                        hi_y = ti.max(hi_y, fy)
                # both centres are means of window vectors, inside their bounding box:
                # a box whose diagonal is under sqrt(0.8) min_separation cannot end
                # split and skips the Lloyd passes (see the Warp kernel)
                box2 = (hi_x - lo_x) * (hi_x - lo_x) + (hi_y - lo_y) * (hi_y - lo_y)
                if box2 > 0.8 * min_separation * min_separation:
                    it = 0
                    moved = 1
                    while it < iterations and moved == 1:
                        s0x = 0.0
                        s0y = 0.0
                        s1x = 0.0
                        s1y = 0.0
                        n1 = 0
                        for i in range(m):
                            fx = scratch[r, i, 0]
                            fy = scratch[r, i, 1]
                            near = nearer_second(fx, fy, c0x, c0y, c1x, c1y)
                            s1x += ti.select(near == 1, fx, 0.0)
                            s1y += ti.select(near == 1, fy, 0.0)
                            s0x += ti.select(near == 1, 0.0, fx)
                            s0y += ti.select(near == 1, 0.0, fy)
                            n1 += near
                        n0 = m - n1
                        m0x = c0x
                        m0y = c0y
                        m1x = c1x
                        m1y = c1y
                        if n0 > 0:
                            m0x = s0x / n0
                            m0y = s0y / n0
                        if n1 > 0:
                            m1x = s1x / n1
                            m1y = s1y / n1
                        moved = 0
                        if m0x != c0x or m0y != c0y or m1x != c1x or m1y != c1y:
                            moved = 1
                        c0x = m0x
                        c0y = m0y
                        c1x = m1x
                        c1y = m1y
                        it += 1
                    if (c0x - c1x) * (c0x - c1x) + (c0y - c1y) * (c0y - c1y) >= min_separation * min_separation:
                        split = 1
            if split == 0:
                # one surface: both centres 0 (a split's centres are at least min_separation apart)
                c0x = 0.0
                c0y = 0.0
                c1x = 0.0
                c1y = 0.0
            centres[t, y, x, 0] = c0x
            centres[t, y, x, 1] = c0y
            centres[t, y, x, 2] = c1x
            centres[t, y, x, 3] = c1y


@ti.kernel
def weighted_median_shading_rows(S: nd3, flow: nd4, w_bnd: nd3, centres: nd4, out: nd3, scratch: nd3,
                                 spatial: nd1, radius: ti.i32, lam: ti.f32):
    height = S.shape[1]
    width = S.shape[2]
    side = 2 * radius + 1
    for r in range(S.shape[0] * height):
        t = r // height
        y = r - t * height
        last = 0.0        # the answer at the previous pixel when it had one (has_last = 1):
        has_last = 0      # the first pivot tried, as neighbouring windows share most pixels
        for x in range(width):
            s = S[t, y, x]
            out[t, y, x] = s
            if t < flow.shape[0] and w_bnd[t, y, x] >= 0.5:
                y_lo, y_hi, x_lo, x_hi = window_bounds(y, x, radius, height, width)
                # surf (Eq. 10): x's cluster of the window's flow vectors (surface_centres_rows)
                c0x = centres[t, y, x, 0]
                c0y = centres[t, y, x, 1]
                c1x = centres[t, y, x, 2]
                c1y = centres[t, y, x, 3]
                split = 0
                if c0x != c1x or c0y != c1y:
                    split = 1
                own = nearer_second(flow[t, y, x, 0], flow[t, y, x, 1], c0x, c0y, c1x, c1y)
                # window pairs (value, weight) of x's surface, Eq. 10
                n = 0
                for yy in range(y_lo, y_hi):
                    k = (yy - y + radius) * side + x_lo - x + radius
                    for xx in range(x_lo, x_hi):
                        keep = 1
                        if split == 1:
                            keep = ti.select(
                                nearer_second(flow[t, yy, xx, 0], flow[t, yy, xx, 1], c0x, c0y, c1x, c1y) == own, 1, 0)
                        scratch[r, n, 0] = S[t, yy, xx]
                        scratch[r, n, 1] = spatial[k]
                        n += keep
                        k += 1
                last = l1_quadratic_select(scratch, r, n, 0, 1, 2, 0, s, lam, last, has_last)
                has_last = 1
                out[t, y, x] = last
            else:
                has_last = 0


@ti.kernel
def weighted_median_flow_rows(flow: nd4, lab: nd4, occ: nd3, mask: nd3, out: nd4, scratch: nd3,
                              radius: ti.i32, sigma_x: ti.f32, sigma_i: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    inv_x = 1.0 / (2.0 * sigma_x * sigma_x)
    inv_i = 1.0 / (2.0 * sigma_i * sigma_i)
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        last_u = 0.0      # the answers at the previous pixel when it had them (has_last = 1):
        last_v = 0.0      # the first pivots tried, as neighbouring windows share most pixels
        has_last = 0
        for x in range(width):
            u0 = flow[t, y, x, 0]
            v0 = flow[t, y, x, 1]
            out[t, y, x, 0] = u0
            out[t, y, x, 1] = v0
            if mask[t, y, x] >= 0.5:
                l0 = lab[t, y, x, 0]
                l1 = lab[t, y, x, 1]
                l2 = lab[t, y, x, 2]
                # (u, v, weight) of every window pixel with a positive weight: scratch[r, :n]
                n = 0
                for yy in range(ti.max(y - radius, 0), ti.min(y + radius + 1, height)):
                    for xx in range(ti.max(x - radius, 0), ti.min(x + radius + 1, width)):
                        ddx = ti.cast(xx - x, ti.f32)
                        ddy = ti.cast(yy - y, ti.f32)
                        e0 = lab[t, yy, xx, 0] - l0
                        e1 = lab[t, yy, xx, 1] - l1
                        e2 = lab[t, yy, xx, 2] - l2
                        w = ti.exp(-(ddx * ddx + ddy * ddy) * inv_x - (e0 * e0 + e1 * e1 + e2 * e2) * inv_i)
                        w = w * occ[t, yy, xx]
                        scratch[r, n, 0] = flow[t, yy, xx, 0]
                        scratch[r, n, 1] = flow[t, yy, xx, 1]
                        scratch[r, n, 2] = w
                        n += ti.select(w > 0.0, 1, 0)
                # u first, keeping every (u, v, w) triple for v
                last_u = l1_quadratic_select(scratch, r, n, 0, 2, 3, 1, u0, 0.0, last_u, has_last)
                last_v = l1_quadratic_select(scratch, r, n, 1, 2, 3, 0, v0, 0.0, last_v, has_last)
                has_last = 1
                out[t, y, x, 0] = last_u
                out[t, y, x, 1] = last_v
            else:
                has_last = 0


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _spatial_table(radius: int, sigma: float) -> np.ndarray:
    """:func:`ivkernels.kernels.host.spatial_weights`, built once per (radius, sigma) and kept (read-only)."""
    return cached((__name__, "spatial", radius, sigma), lambda: spatial_weights(radius, sigma))


def _scratch(workspace, name: str, shape: tuple, entry: int) -> np.ndarray:
    """Float32 scratch ``name`` of ``shape`` (rows, entry * m) from ``workspace`` (or allocated
    for this call), seen as (rows, m, entry): one window entry of ``entry`` floats per slot."""
    buf = scratch_buffer(workspace, f"{__name__}.{name}", shape, np.float32, lambda: np.empty(shape, np.float32))
    return buf.reshape(shape[0], shape[1] // entry, entry)


@host("median5x5")
def median5x5(src, out) -> None:
    """5x5 median of every channel, replicate border; see
    :func:`ivkernels.kernels.warp.median.median5x5` (NumPy arrays here)."""
    if src.size:
        median5x5_rows(src, out)


@host("surface_centres")
def surface_centres(flow, w_bnd, centres, radius: int = 7, *, workspace=None) -> None:
    """Eq. 10's ``surf``: the two flow centres of each motion-boundary pixel's window; see
    :func:`ivkernels.kernels.warp.median.surface_centres` (NumPy arrays here)."""
    buf = _scratch(workspace, "centres_window", shading_scratch_shape(flow.shape[:3], radius), 2)
    if flow.size:
        surface_centres_rows(flow, w_bnd, centres, buf, radius, KMEANS_ITERATIONS, MIN_SEPARATION)


@host("weighted_median_shading")
def weighted_median_shading(S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                            lam: float = 0.001, *, centres=None, workspace=None) -> None:
    """S~ update of Eq. 13 (weighted median with surf of Eq. 10 and Li & Osher's
    quadratic pull); see :func:`ivkernels.kernels.warp.median.weighted_median_shading`."""
    buf = _scratch(workspace, "shading_window", shading_scratch_shape(S.shape, radius), 2)
    if centres is None:
        shape = (*flow.shape[:3], 4)
        centres = scratch_buffer(workspace, f"{__name__}.surface_centres", shape, np.float32,
                                 lambda: np.empty(shape, np.float32))
        if flow.size:
            surface_centres_rows(flow, w_bnd, centres, buf, radius, KMEANS_ITERATIONS, MIN_SEPARATION)
    if S.size:
        weighted_median_shading_rows(S, flow, w_bnd, centres, out, buf, _spatial_table(radius, sigma_s), radius,
                                     lam)


@host("weighted_median_flow")
def weighted_median_flow(flow, lab, occ, mask, out, radius: int = 7, sigma_x: float = 7.0,
                         sigma_i: float = 7.0, *, workspace=None) -> None:
    """Classic+NL's non-local flow median; see
    :func:`ivkernels.kernels.warp.median.weighted_median_flow` (NumPy arrays here)."""
    buf = _scratch(workspace, "flow_window", flow_scratch_shape(flow.shape, radius), 3)
    if flow.size:
        weighted_median_flow_rows(flow, lab, occ, mask, out, buf, radius, sigma_x, sigma_i)
