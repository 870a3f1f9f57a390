"""Temporal coherence terms of the intrinsic-video energy (Eq. 4, 5, 8), log domain.

``E_T = lam * sum_{t<T-1} sum_{x,c} occ_t(x) rho(X_{t+1}(x + u_t(x), c) - X_t(x, c))``

for the albedo (Eq. 4, ``X = A``, C = 3, lambda_TA = 10) and the shading
(Eq. 8, ``X = S`` as a (T, H, W, 1) view, lambda_TS = 1).  ``X_{t+1}(x + u)`` is
the bilinear sample with corners clamped to the image (the convention of
:mod:`ivkernels.kernels.warp.sampling`, whose ``@wp.func`` helpers are used).

``rho`` is the *continuous* Tukey biweight (Eq. 5 as printed jumps from 1/3 to
1/alpha^2 at |z| = alpha)::

    rho(z)  = z^2/a^2 - z^4/a^4 + z^6/(3 a^6)   for |z| <= a,   1/3 outside
    rho'(z) = (2/a^2) z (1 - z^2/a^2)^2          for |z| <= a,   0 outside

The gradient in ``X_t`` is a gather; the gradient in ``X_{t+1}`` lands on the
four corners of ``x + u`` (a bilinear splat with atomic adds).  They are two
launches: the gather over all rows, which also stores each pixel's
``lam occ rho'(d)`` in a scratch buffer (from the caller's workspace,
:mod:`ivkernels.kernels.workspace`), then the splat of the stored values,
split only at frame boundaries so concurrent CPU launches never write the
same gradient frame.
Energies go to the rows of frame ``t`` (conventions in :mod:`ivkernels.kernels`).

:func:`temporal_terms` adds both terms, the albedo's and the shading's, in
one gather and one splat: they share the flow, the occlusion weights and the
bilinear corners, which each pixel then reads and computes once instead of
twice (640x480, 8 frames, 2 threads: 101 against 130 ms for the two
``temporal_term`` calls, with bitwise the same result).  On the CPU that
gather and splat run as native row loops (:func:`pair_gather_row`, a loop the
compiler vectorises, and :func:`pair_splat_row`): 640x480, 8 frames, a smooth
flow, 2 threads: gather 30 -> 14 ms, splat 28 -> 18 ms, bit for bit the same.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.energy_temporal import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows
from ivkernels.kernels.warp.row_tiles import frame_row, row_span
from ivkernels.kernels.warp.sampling import bilinear_at, clamped_corners
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.func
def tukey(z: float, alpha: float):
    """Continuous Tukey penalty (Eq. 5 made continuous), saturating at 1/3."""
    q = z * z / (alpha * alpha)
    result = 1.0 / 3.0
    if q <= 1.0:
        result = q - q * q + q * q * q / 3.0
    return result


@wp.func
def tukey_derivative(z: float, alpha: float):
    """``(2/a^2) z (1 - z^2/a^2)^2`` inside ``|z| <= a``, else 0."""
    q = z * z / (alpha * alpha)
    result = 0.0
    if q <= 1.0:
        result = 2.0 / (alpha * alpha) * z * (1.0 - q) * (1.0 - q)
    return result


@wp.func
def gather_channel(X: wp.array4d(dtype=float), gX: wp.array4d(dtype=float), weight: wp.array4d(dtype=float),
                   weight_channel: int, t: int, y: int, x: int, c: int, x0: int, x1: int, fx: float,
                   y0: int, y1: int, fy: float, o: float, lam: float, alpha: float):
    """One channel of one pixel of the gather: ``d = X_{t+1}(x + u, c) - X_t(x, c)``;
    stores ``lam o rho'(d)`` in ``weight[..., weight_channel]``, subtracts it from
    ``gX_t``, and returns ``o rho(d)`` (the energy before ``lam``)."""
    d = bilinear_at(X, t + 1, c, x0, x1, fx, y0, y1, fy) - X[t, y, x, c]
    g = lam * o * tukey_derivative(d, alpha)
    weight[t, y, x, weight_channel] = g
    gX[t, y, x, c] = gX[t, y, x, c] - g
    return o * tukey(d, alpha)


@wp.kernel
def temporal_gather_rows(row_begin: int, tiles: int, X: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                         occ: wp.array3d(dtype=float), gX: wp.array4d(dtype=float),
                         weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64),
                         lam: float, alpha: float):
    """Energy of frame ``t`` rows and the gradient in ``X_t`` (rows of frames 0 .. T-2);
    stores ``weight = lam occ rho'(d)`` per pixel and channel for the splat."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, X.shape[2])
    height = X.shape[1]
    width = X.shape[2]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(x_begin, x_end):
        o = occ[t, y, x]
        if o == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(X.shape[3]):
            e += wp.float64(gather_channel(X, gX, weight, c, t, y, x, c, x0, x1, fx, y0, y1, fy, o, lam, alpha))
    wp.atomic_add(energy_rows, r, wp.float64(lam) * e)


@wp.func
def splat_corners(gX: wp.array4d(dtype=float), t: int, c: int, x0: int, x1: int, fx: float,
                  y0: int, y1: int, fy: float, g: float):
    """Add ``g`` to the four corners of a bilinear sample of frame ``t``, channel ``c``."""
    wp.atomic_add(gX, t, y0, x0, c, (1.0 - fx) * (1.0 - fy) * g)
    wp.atomic_add(gX, t, y0, x1, c, fx * (1.0 - fy) * g)
    wp.atomic_add(gX, t, y1, x0, c, (1.0 - fx) * fy * g)
    wp.atomic_add(gX, t, y1, x1, c, fx * fy * g)


@wp.kernel
def temporal_splat_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                        weight: wp.array4d(dtype=float), gX: wp.array4d(dtype=float)):
    """Gradient in ``X_{t+1}``: splat the stored ``lam occ rho'(d)`` onto the
    corners of ``x + u_t(x)``."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gX.shape[2])
    height = gX.shape[1]
    width = gX.shape[2]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if occ[t, y, x] == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(gX.shape[3]):
            g = weight[t, y, x, c]
            if g != 0.0:
                splat_corners(gX, t + 1, c, x0, x1, fx, y0, y1, fy, g)


@wp.kernel
def temporal_pair_gather_rows(row_begin: int, tiles: int, A: wp.array4d(dtype=float), S: wp.array4d(dtype=float),
                              flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                              gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float),
                              weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64),
                              lam_albedo: float, lam_shading: float, alpha: float):
    """:func:`temporal_gather_rows` for the albedo (3 channels) and the shading
    (1) at once; ``weight`` holds 4 channels, the albedo's then the shading's."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, A.shape[2])
    height = A.shape[1]
    width = A.shape[2]
    t = r // height
    y = r - t * height
    e_albedo = wp.float64(0.0)
    e_shading = wp.float64(0.0)
    for x in range(x_begin, x_end):
        o = occ[t, y, x]
        if o == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(3):
            e_albedo += wp.float64(gather_channel(A, gA, weight, c, t, y, x, c, x0, x1, fx, y0, y1, fy, o,
                                                  lam_albedo, alpha))
        e_shading += wp.float64(gather_channel(S, gS, weight, 3, t, y, x, 0, x0, x1, fx, y0, y1, fy, o,
                                               lam_shading, alpha))
    # two adds, in the order of the one-thread-per-row sum ``(rows + albedo) + shading``
    wp.atomic_add(energy_rows, r, wp.float64(lam_albedo) * e_albedo)
    wp.atomic_add(energy_rows, r, wp.float64(lam_shading) * e_shading)


@wp.kernel
def temporal_pair_splat_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                             weight: wp.array4d(dtype=float), gA: wp.array4d(dtype=float),
                             gS: wp.array4d(dtype=float)):
    """:func:`temporal_splat_rows` for the albedo and the shading at once."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gA.shape[2])
    height = gA.shape[1]
    width = gA.shape[2]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if occ[t, y, x] == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(3):
            g = weight[t, y, x, c]
            if g != 0.0:
                splat_corners(gA, t + 1, c, x0, x1, fx, y0, y1, fy, g)
        g = weight[t, y, x, 3]
        if g != 0.0:
            splat_corners(gS, t + 1, 0, x0, x1, fx, y0, y1, fy, g)


# The CPU's pair gather and splat: one row per kernel thread as native loops.
# The gather's loop over the row is vectorised (the bilinear corners read with
# gathers); the per-pixel energies go through a short stack buffer and are then
# added to the row's float64 sums in the kernels' order, pixel by pixel, so the
# energies and every gradient are bit for bit those of the kernels above (the
# same operations in the same order, none fused into a multiply-add).  The
# splat stays a scalar loop (neighbouring pixels add into the same corners), with
# its addresses computed once per pixel.  Arrays must be contiguous along
# (x, channel) (:func:`~ivkernels.kernels.warp._checks.native_rows`), else the
# kernels above run.
_PAIR_ROW_COMMON = r"""
#if defined(__CUDA_ARCH__)
#define IVK_TEMPORAL_SIMD
#else
#define IVK_TEMPORAL_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
const int height = A.shape[1];
const int width = A.shape[2];
const float* fl = (const float*)((const char*)flow.data + (size_t)t * flow.strides[0] + (size_t)y * flow.strides[1]);
const float* oc = (const float*)((const char*)occ.data + (size_t)t * occ.strides[0] + (size_t)y * occ.strides[1]);
float* wt = (float*)((char*)weight.data + (size_t)t * weight.strides[0] + (size_t)y * weight.strides[1]);
const float x_hi = (float)width + 1.0f;
const float y_hi = (float)height + 1.0f;
"""

# clamped_corners() of :mod:`ivkernels.kernels.warp.sampling`, for pixel x of the row.
_CORNERS = r"""
        const float qx = wp::clamp((float)x + fl[2 * x], -2.0f, x_hi);
        const float qy = wp::clamp((float)y + fl[2 * x + 1], -2.0f, y_hi);
        const float flx = wp::floor(qx);
        const float fly = wp::floor(qy);
        const int ix = (int)flx;
        const int iy = (int)fly;
        const int x0 = wp::clamp(ix, 0, width - 1);
        const int x1 = wp::clamp(ix + 1, 0, width - 1);
        const int y0 = wp::clamp(iy, 0, height - 1);
        const int y1 = wp::clamp(iy + 1, 0, height - 1);
        const float fx = qx - flx;
        const float fy = qy - fly;
"""

_PAIR_GATHER_ROW = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
""" + _PAIR_ROW_COMMON + r"""
const char* a_next = (const char*)A.data + (size_t)(t + 1) * A.strides[0];
const char* s_next = (const char*)S.data + (size_t)(t + 1) * S.strides[0];
const size_t a_row = A.strides[1];
const size_t s_row = S.strides[1];
const float* a_own = (const float*)((const char*)A.data + (size_t)t * A.strides[0] + (size_t)y * a_row);
const float* s_own = (const float*)((const char*)S.data + (size_t)t * S.strides[0] + (size_t)y * s_row);
float* ga = (float*)((char*)gA.data + (size_t)t * gA.strides[0] + (size_t)y * gA.strides[1]);
float* gs = (float*)((char*)gS.data + (size_t)t * gS.strides[0] + (size_t)y * gS.strides[1]);
const float a2 = alpha * alpha;
const float two_over_a2 = 2.0f / a2;
const float third = 1.0f / 3.0f;
double e_albedo = 0.0;
double e_shading = 0.0;
// one channel of a pixel: the bilinear sample of the next frame, d, Tukey's rho and rho'
#define IVK_CHANNEL(BASE, R0, R1, PX, CH, OWN, GRAD, LAM, K) { \
    const float v00 = *((const float*)(BASE + R0) + PX * x0 + CH); \
    const float v01 = *((const float*)(BASE + R0) + PX * x1 + CH); \
    const float v10 = *((const float*)(BASE + R1) + PX * x0 + CH); \
    const float v11 = *((const float*)(BASE + R1) + PX * x1 + CH); \
    const float m00 = gx * v00; \
    const float m01 = fx * v01; \
    const float top = m00 + m01; \
    const float m10 = gx * v10; \
    const float m11 = fx * v11; \
    const float bottom = m10 + m11; \
    const float mt = gy * top; \
    const float mb = fy * bottom; \
    const float sample = mt + mb; \
    const float d = sample - OWN; \
    const float dd = d * d; \
    const float q = dd / a2; \
    const float one_q = 1.0f - q; \
    const float k1 = two_over_a2 * d; \
    const float k2 = k1 * one_q; \
    const float k3 = k2 * one_q; \
    const float rho_d = q <= 1.0f ? k3 : 0.0f; \
    const float qq = q * q; \
    const float qqq = qq * q; \
    const float cubic = qqq / 3.0f; \
    const float lin = q - qq; \
    const float poly = lin + cubic; \
    const float rho = q <= 1.0f ? poly : third; \
    const float lo = LAM * o; \
    const float g = lo * rho_d; \
    wt[4 * x + K] = g; \
    GRAD = GRAD - g; \
    e[K] = o * rho; }
const int chunk = 256;
float energies[4 * 256];
for (int begin = 0; begin < width; begin += chunk) {
    const int end = begin + chunk < width ? begin + chunk : width;
    IVK_TEMPORAL_SIMD
    for (int x = begin; x < end; ++x) {
        const float o = oc[x];
        float* e = energies + 4 * (x - begin);
        if (o == 0.0f) {
            e[0] = 0.0f; e[1] = 0.0f; e[2] = 0.0f; e[3] = 0.0f;
        } else {
""" + _CORNERS + r"""
        const float gx = 1.0f - fx;
        const float gy = 1.0f - fy;
        const size_t ar0 = (size_t)y0 * a_row;
        const size_t ar1 = (size_t)y1 * a_row;
        const size_t sr0 = (size_t)y0 * s_row;
        const size_t sr1 = (size_t)y1 * s_row;
        IVK_CHANNEL(a_next, ar0, ar1, 3, 0, a_own[3 * x], ga[3 * x], lam_albedo, 0)
        IVK_CHANNEL(a_next, ar0, ar1, 3, 1, a_own[3 * x + 1], ga[3 * x + 1], lam_albedo, 1)
        IVK_CHANNEL(a_next, ar0, ar1, 3, 2, a_own[3 * x + 2], ga[3 * x + 2], lam_albedo, 2)
        IVK_CHANNEL(s_next, sr0, sr1, 1, 0, s_own[x], gs[x], lam_shading, 3)
        }
    }
    for (int x = begin; x < end; ++x) {
        if (oc[x] == 0.0f)
            continue;
        const float* e = energies + 4 * (x - begin);
        e_albedo = e_albedo + (double)e[0];
        e_albedo = e_albedo + (double)e[1];
        e_albedo = e_albedo + (double)e[2];
        e_shading = e_shading + (double)e[3];
    }
}
double* er = (double*)energy_rows.data + r;
const double ea = (double)lam_albedo * e_albedo;
er[0] = er[0] + ea;
const double es = (double)lam_shading * e_shading;
er[0] = er[0] + es;
}
#undef IVK_CHANNEL
#undef IVK_TEMPORAL_SIMD
"""

_PAIR_SPLAT_ROW = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
""" + _PAIR_ROW_COMMON + r"""
char* ga_next = (char*)gA.data + (size_t)(t + 1) * gA.strides[0];
char* gs_next = (char*)gS.data + (size_t)(t + 1) * gS.strides[0];
const size_t a_row = gA.strides[1];
const size_t s_row = gS.strides[1];
for (int x = 0; x < width; ++x) {
    if (oc[x] == 0.0f)
        continue;
""" + _CORNERS + r"""
    const float gx = 1.0f - fx;
    const float gy = 1.0f - fy;
    const float w00 = gx * gy;
    const float w01 = fx * gy;
    const float w10 = gx * fy;
    const float w11 = fx * fy;
    float* a00 = (float*)(ga_next + (size_t)y0 * a_row) + 3 * x0;
    float* a01 = (float*)(ga_next + (size_t)y0 * a_row) + 3 * x1;
    float* a10 = (float*)(ga_next + (size_t)y1 * a_row) + 3 * x0;
    float* a11 = (float*)(ga_next + (size_t)y1 * a_row) + 3 * x1;
    for (int c = 0; c < 3; ++c) {
        const float g = wt[4 * x + c];
        if (g != 0.0f) {
            const float v00 = w00 * g; a00[c] = a00[c] + v00;
            const float v01 = w01 * g; a01[c] = a01[c] + v01;
            const float v10 = w10 * g; a10[c] = a10[c] + v10;
            const float v11 = w11 * g; a11[c] = a11[c] + v11;
        }
    }
    const float g = wt[4 * x + 3];
    if (g != 0.0f) {
        float* s00 = (float*)(gs_next + (size_t)y0 * s_row) + x0;
        float* s01 = (float*)(gs_next + (size_t)y0 * s_row) + x1;
        float* s10 = (float*)(gs_next + (size_t)y1 * s_row) + x0;
        float* s11 = (float*)(gs_next + (size_t)y1 * s_row) + x1;
        const float v00 = w00 * g; s00[0] = s00[0] + v00;
        const float v01 = w01 * g; s01[0] = s01[0] + v01;
        const float v10 = w10 * g; s10[0] = s10[0] + v10;
        const float v11 = w11 * g; s11[0] = s11[0] + v11;
    }
}
}
#undef IVK_TEMPORAL_SIMD
"""


@wp.func_native(_PAIR_GATHER_ROW)
def pair_gather_row(A: wp.array4d(dtype=float), S: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                    occ: wp.array3d(dtype=float), gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float),
                    weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64), t: int, y: int,
                    r: int, lam_albedo: float, lam_shading: float, alpha: float):
    """Row ``y`` of pair ``t`` of :func:`temporal_pair_gather_rows` (CPU, contiguous layouts)."""
    ...


@wp.func_native(_PAIR_SPLAT_ROW)
def pair_splat_row(A: wp.array4d(dtype=float), flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                   weight: wp.array4d(dtype=float), gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float),
                   t: int, y: int):
    """Row ``y`` of pair ``t`` of :func:`temporal_pair_splat_rows` (CPU, contiguous layouts)."""
    ...


@wp.kernel
def temporal_pair_gather_rows_cpu(row_begin: int, A: wp.array4d(dtype=float), S: wp.array4d(dtype=float),
                                  flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                                  gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float),
                                  weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64),
                                  lam_albedo: float, lam_shading: float, alpha: float):
    r = row_begin + wp.tid()
    t, y = frame_row(r, A.shape[1])
    pair_gather_row(A, S, flow, occ, gA, gS, weight, energy_rows, t, y, r, lam_albedo, lam_shading, alpha)


@wp.kernel
def temporal_pair_splat_rows_cpu(row_begin: int, A: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                                 occ: wp.array3d(dtype=float), weight: wp.array4d(dtype=float),
                                 gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float)):
    t, y = frame_row(row_begin + wp.tid(), A.shape[1])
    pair_splat_row(A, flow, occ, weight, gA, gS, t, y)


def with_channel_axis(a):
    """A (T, H, W, 1) view of a (T, H, W) ``wp.array``, sharing its memory and strides.

    Unlike ``reshape`` it takes strided arrays too; an empty ``a`` gives a new empty array.
    """
    shape = (*a.shape, 1)
    if a.size == 0:
        return wp.empty(shape, dtype=a.dtype, device=a.device)
    view = wp.array(ptr=a.ptr, dtype=a.dtype, shape=shape, strides=(*a.strides, a.strides[-1]),
                    device=a.device, copy=False)
    view._ref = a               # keep the memory alive as long as the view
    return view


@host("temporal_term")
def temporal_term(X, flow, occ, gX, energy_rows, lam: float, alpha: float = 5.0, *,
                  workspace=None) -> None:
    """Add the temporal term of Eq. 4 (albedo) or Eq. 8 (shading) and its gradient.

    ``E = lam * sum_{t<T-1} sum_{x,c} occ_t(x) rho(X_{t+1}(x + u_t(x), c) - X_t(x, c))``,
    ``rho`` the continuous Tukey with scale ``alpha`` (module docstring).

    Parameters
    ----------
    X : wp.array float32 (T, H, W, C) log albedo (C = 3) or log shading
        (C = 1, a ``reshape((T, H, W, 1))`` view); a (T, H, W) array is
        accepted too and viewed that way.  Any strides.
    flow : wp.array float32 (T-1, H, W, 2), forward flow u_t (pixels).
    occ : wp.array float32 (T-1, H, W), w_occ (1 visible in t+1, 0 occluded).
    gX : wp.array float32, same shape as ``X``, accumulated: ``gX += dE/dX``.
        Must not overlap ``X`` (ValueError).
    energy_rows : wp.array float64 (T*H,), accumulated; the pair (t, t+1)
        adds to the rows of frame t, the last frame's rows get nothing.
    lam : lambda_TA (10) or lambda_TS (1).  alpha : Tukey scale (log units).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the (T-1, H, W, C) float32 splat weights between calls; without
        one they are allocated for this call.

    With T = 1, or no pixels, there is nothing to add.
    """
    if len(X.shape) == 3:
        X = with_channel_axis(X)
        gX = with_channel_axis(gX)
    t, h, w, c = X.shape
    dev = X.device
    if t < 2 or h * w * c == 0:
        return
    shape = (t - 1, h, w, c)
    weight = scratch_buffer(workspace, f"{__name__}.splat_weight", shape, float,
                            lambda: wp.empty(shape, dtype=float, device=dev), dev)
    tiles = row_tiles(w, dev)
    launch_rows(temporal_gather_rows, (t - 1) * h * tiles,
                [tiles, X, flow, occ, gX, weight, energy_rows, float(lam), float(alpha)], device=dev)
    launch_rows(temporal_splat_rows, (t - 1) * h * tiles, [tiles, flow, occ, weight, gX], device=dev,
                align=h * tiles)


@host("temporal_terms")
def temporal_terms(A, S, flow, occ, gA, gS, energy_rows, lam_albedo: float, lam_shading: float,
                   alpha: float = 5.0, *, workspace=None) -> None:
    """Add both temporal terms, Eq. 4 on the albedo and Eq. 8 on the shading, and their gradients.

    The same as ``temporal_term(A, flow, occ, gA, energy_rows, lam_albedo,
    alpha)`` followed by ``temporal_term(S, flow, occ, gS, energy_rows,
    lam_shading, alpha)``, bitwise, in one gather and one splat (module
    docstring).

    Parameters
    ----------
    A, gA : wp.array float32 (T, H, W, 3): log albedo, and its accumulated gradient.
    S, gS : wp.array float32 (T, H, W): log shading, and its accumulated gradient.
    flow : wp.array float32 (T-1, H, W, 2), forward flow u_t (pixels).
    occ : wp.array float32 (T-1, H, W), w_occ.
    energy_rows : wp.array float64 (T*H,), accumulated (pair (t, t+1) on frame t's rows).
    lam_albedo, lam_shading : lambda_TA and lambda_TS.  alpha : Tukey scale, shared.
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the (T-1, H, W, 4) float32 splat weights between calls.
    Neither gradient may overlap ``A`` or ``S`` (ValueError).
    """
    t, h, w, _ = A.shape
    dev = A.device
    if t < 2 or h * w == 0:
        return
    shape = (t - 1, h, w, 4)
    weight = scratch_buffer(workspace, f"{__name__}.pair_splat_weight", shape, float,
                            lambda: wp.empty(shape, dtype=float, device=dev), dev)
    S4, gS4 = with_channel_axis(S), with_channel_axis(gS)
    if native_rows(dev, A, S4, flow, occ, gA, gS4, weight):
        launch_rows(temporal_pair_gather_rows_cpu, (t - 1) * h,
                    [A, S4, flow, occ, gA, gS4, weight, energy_rows, float(lam_albedo), float(lam_shading),
                     float(alpha)], device=dev)
        launch_rows(temporal_pair_splat_rows_cpu, (t - 1) * h, [A, flow, occ, weight, gA, gS4], device=dev,
                    align=h)
        return
    tiles = row_tiles(w, dev)
    launch_rows(temporal_pair_gather_rows, (t - 1) * h * tiles,
                [tiles, A, S4, flow, occ, gA, gS4, weight, energy_rows, float(lam_albedo), float(lam_shading),
                 float(alpha)], device=dev)
    launch_rows(temporal_pair_splat_rows, (t - 1) * h * tiles, [tiles, flow, occ, weight, gA, gS4], device=dev,
                align=h * tiles)
