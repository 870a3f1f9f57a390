"""Taichi mirror of :mod:`ivkernels.kernels.warp.median` (5x5 median, weighted
flow median, S~ update of Eq. 13): same host functions and signatures, NumPy
arrays passed as ``ti.types.ndarray()``.

The algorithms are those of the Warp module (see its docstrings): one loop
iteration per image row, the window's (value, weight) pairs copied into that
row's slice of a scratch array, then a weighted quickselect.  The outermost
loop runs over rows in parallel; each row only touches its own scratch row.
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
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)

#: The 5x5 median's compare-exchange pairs (:func:`median_network`).
_PAIRS25 = tuple(median_network(25))


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@ti.func
def swap_entries(buf: ti.template(), row, base, i, j):
    """Swap the (value, weight) pairs ``i`` and ``j`` of ``buf[row, base:]``."""
    v = buf[row, base + 2 * i]
    w = buf[row, base + 2 * i + 1]
    buf[row, base + 2 * i] = buf[row, base + 2 * j]
    buf[row, base + 2 * i + 1] = buf[row, base + 2 * j + 1]
    buf[row, base + 2 * j] = v
    buf[row, base + 2 * j + 1] = w


@ti.func
def l1_quadratic_select(buf: ti.template(), row, base, n, s, lam):
    """``argmin_u sum_i w_i |u - v_i| + lam (u - s)^2`` over the ``n`` pairs of
    ``buf[row, base:]``; the weighted quickselect of
    :func:`ivkernels.kernels.warp.median.l1_quadratic_select`."""
    lo = 0
    hi = n
    w_below = 0.0
    w_above = 0.0
    result = s
    found = 0
    while lo < hi and found == 0:
        pivot = buf[row, base + 2 * ((lo + hi) // 2)]
        lt = lo
        i = lo
        gt = hi
        w_lt = 0.0
        w_eq = 0.0
        w_gt = 0.0
        while i < gt:
            v = buf[row, base + 2 * i]
            w = buf[row, base + 2 * i + 1]
            if v < pivot:
                swap_entries(buf, row, base, lt, i)
                w_lt += w
                lt += 1
                i += 1
            elif v > pivot:
                gt -= 1
                swap_entries(buf, row, base, i, gt)
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
def weighted_median_shading_rows(S: nd3, flow: nd4, w_bnd: nd3, out: nd3, scratch: nd2, spatial: nd1,
                                 radius: ti.i32, lam: ti.f32, iterations: ti.i32, min_separation: ti.f32):
    height = S.shape[1]
    width = S.shape[2]
    side = 2 * radius + 1
    for r in range(S.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            s = S[t, y, x]
            out[t, y, x] = s
            if t < flow.shape[0] and w_bnd[t, y, x] >= 0.5:
                y_lo = ti.max(y - radius, 0)
                y_hi = ti.min(y + radius + 1, height)
                x_lo = ti.max(x - radius, 0)
                x_hi = ti.min(x + radius + 1, width)
                # surf (Eq. 10): 2-means of the window's flow vectors
                c0x = flow[t, y, x, 0]
                c0y = flow[t, y, x, 1]
                c1x = c0x
                c1y = c0y
                far = -1.0
                for yy in range(y_lo, y_hi):
                    for xx in range(x_lo, x_hi):
                        dx = flow[t, yy, xx, 0] - c0x
                        dy = flow[t, yy, xx, 1] - c0y
                        d = dx * dx + dy * dy
                        if d > far:
                            far = d
                            c1x = flow[t, yy, xx, 0]
                            c1y = flow[t, yy, xx, 1]
                it = 0
                moved = 1
                while it < iterations and moved == 1:
                    s0x = 0.0
                    s0y = 0.0
                    s1x = 0.0
                    s1y = 0.0
                    n0 = 0
                    n1 = 0
                    for yy in range(y_lo, y_hi):
                        for xx in range(x_lo, x_hi):
                            fx = flow[t, yy, xx, 0]
                            fy = flow[t, yy, xx, 1]
                            if nearer_second(fx, fy, c0x, c0y, c1x, c1y) == 1:
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
                split = 0
                if (c0x - c1x) * (c0x - c1x) + (c0y - c1y) * (c0y - c1y) >= min_separation * min_separation:
                    split = 1
                own = nearer_second(flow[t, y, x, 0], flow[t, y, x, 1], c0x, c0y, c1x, c1y)
                # window pairs (value, weight) of x's surface, Eq. 10
                n = 0
                for yy in range(y_lo, y_hi):
                    for xx in range(x_lo, x_hi):
                        keep = 1
                        if split == 1:
                            keep = ti.select(
                                nearer_second(flow[t, yy, xx, 0], flow[t, yy, xx, 1], c0x, c0y, c1x, c1y) == own, 1, 0)
                        if keep == 1:
                            scratch[r, 2 * n] = S[t, yy, xx]
                            scratch[r, 2 * n + 1] = spatial[(yy - y + radius) * side + xx - x + radius]
                            n += 1
                out[t, y, x] = l1_quadratic_select(scratch, r, 0, n, s, lam)


@ti.kernel
def weighted_median_flow_rows(flow: nd4, lab: nd4, occ: nd3, mask: nd3, out: nd4, scratch: nd2,
                              radius: ti.i32, sigma_x: ti.f32, sigma_i: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    side = 2 * radius + 1
    base = side * side  # scratch[r, :base] holds the window's weights, then the pairs
    inv_x = 1.0 / (2.0 * sigma_x * sigma_x)
    inv_i = 1.0 / (2.0 * sigma_i * sigma_i)
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            out[t, y, x, 0] = flow[t, y, x, 0]
            out[t, y, x, 1] = flow[t, y, x, 1]
            if mask[t, y, x] >= 0.5:
                l0 = lab[t, y, x, 0]
                l1 = lab[t, y, x, 1]
                l2 = lab[t, y, x, 2]
                k = 0
                for yy in range(y - radius, y + radius + 1):
                    for xx in range(x - radius, x + radius + 1):
                        w = 0.0
                        if 0 <= yy < height and 0 <= xx < width:
                            ddx = ti.cast(xx - x, ti.f32)
                            ddy = ti.cast(yy - y, ti.f32)
                            e0 = lab[t, yy, xx, 0] - l0
                            e1 = lab[t, yy, xx, 1] - l1
                            e2 = lab[t, yy, xx, 2] - l2
                            w = ti.exp(-(ddx * ddx + ddy * ddy) * inv_x - (e0 * e0 + e1 * e1 + e2 * e2) * inv_i)
                            w = w * occ[t, yy, xx]
                        scratch[r, k] = w
                        k += 1
                for c in ti.static(range(2)):
                    n = 0
                    kk = 0
                    for yy in range(y - radius, y + radius + 1):
                        for xx in range(x - radius, x + radius + 1):
                            w = scratch[r, kk]
                            if w > 0.0:
                                scratch[r, base + 2 * n] = flow[t, yy, xx, c]
                                scratch[r, base + 2 * n + 1] = w
                                n += 1
                            kk += 1
                    out[t, y, x, c] = l1_quadratic_select(scratch, r, base, n, flow[t, y, x, c], 0.0)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _spatial_table(radius: int, sigma: float) -> np.ndarray:
    """:func:`ivkernels.kernels.host.spatial_weights`, built once per (radius, sigma) and kept (read-only)."""
    return cached((__name__, "spatial", radius, sigma), lambda: spatial_weights(radius, sigma))


def _scratch(workspace, name: str, shape: tuple) -> np.ndarray:
    """Float32 scratch ``name`` of ``shape`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, np.float32,
                          lambda: np.empty(shape, np.float32))


@host("median5x5")
def median5x5(src, out) -> None:
    """5x5 median of every channel, replicate border; see
    :func:`ivkernels.kernels.warp.median.median5x5` (NumPy arrays here)."""
    if src.size:
        median5x5_rows(src, out)


@host("weighted_median_shading")
def weighted_median_shading(S, flow, w_bnd, out, radius: int = 7, sigma_s: float = 7.0,
                            lam: float = 0.001, *, workspace=None) -> None:
    """S~ update of Eq. 13 (weighted median with surf of Eq. 10 and Li & Osher's
    quadratic pull); see :func:`ivkernels.kernels.warp.median.weighted_median_shading`."""
    buf = _scratch(workspace, "shading_window", shading_scratch_shape(S.shape, radius))
    if S.size:
        weighted_median_shading_rows(S, flow, w_bnd, out, buf, _spatial_table(radius, sigma_s), radius, lam,
                                     KMEANS_ITERATIONS, MIN_SEPARATION)


@host("weighted_median_flow")
def weighted_median_flow(flow, lab, occ, mask, out, radius: int = 7, sigma_x: float = 7.0,
                         sigma_i: float = 7.0, *, workspace=None) -> None:
    """Classic+NL's non-local flow median; see
    :func:`ivkernels.kernels.warp.median.weighted_median_flow` (NumPy arrays here)."""
    buf = _scratch(workspace, "flow_window", flow_scratch_shape(flow.shape, radius))
    if flow.size:
        weighted_median_flow_rows(flow, lab, occ, mask, out, buf, radius, sigma_x, sigma_i)
