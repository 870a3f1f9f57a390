"""The ROF structure-texture decomposition the flow is computed on (Chambolle's dual projection).

:func:`rof_dual_step` iterates the dual ``p`` of
``min_S |grad S|_TV + |S - img|^2 / (2 theta)``; :func:`rof_texture` keeps the
texture ``img - alpha (img + theta div p)``.  Part of
:mod:`ivkernels.kernels.warp.flow_classic`.  On the CPU the dual step runs as
native row loops (:func:`dual_step_row`; 640x480, 8 frames, 2 threads:
12.7 -> 2.6 ms, bit for bit the kernel's).
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows
from ivkernels.kernels.warp.row_tiles import frame_row, row_span

host = implements(FAMILY, FRONT)

__all__ = ["rof_dual_step", "rof_texture"]

wp.set_module_options({"enable_backward": False})


@wp.func
def rof_divergence(p: wp.array4d(dtype=float), t: int, y: int, x: int):
    """Backward-difference divergence of the dual field ``p`` at ``(y, x)``;
    ``p`` is taken as zero outside the image (Chambolle 2004, Eq. 8)."""
    d = p[t, y, x, 0] + p[t, y, x, 1]
    if x > 0:
        d -= p[t, y, x - 1, 0]
    if y > 0:
        d -= p[t, y - 1, x, 1]
    return d


# The CPU's dual step: one row per kernel thread as native loops the compiler
# vectorises: ``v`` of rows y and y + 1 into short stack buffers, then the update;
# the kernel's operations in its order, none fused: bit for bit the same.
_DUAL_STEP_ROW = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
#if defined(__CUDA_ARCH__)
#define IVK_ROF_SIMD
#else
#define IVK_ROF_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
const int height = img.shape[1];
const int width = img.shape[2];
const char* im = (const char*)img.data + (size_t)t * img.strides[0];
const char* pin = (const char*)p_in.data + (size_t)t * p_in.strides[0];
float* pout = (float*)((char*)p_out.data + (size_t)t * p_out.strides[0] + (size_t)y * p_out.strides[1]);
const size_t irow = img.strides[1];
const size_t prow = p_in.strides[1];
const int below = y < height - 1;
const int chunk = 512;
float v0[513];
float v1[513];
// v = img + theta div(p) of row YY over [B, E) into BUF
#define IVK_V(BUF, YY, B, E) { \
    const float* ir = (const float*)(im + (size_t)(YY) * irow); \
    const float* pr = (const float*)(pin + (size_t)(YY) * prow); \
    const float* pu = (const float*)(pin + (size_t)((YY) > 0 ? (YY) - 1 : 0) * prow); \
    IVK_ROF_SIMD \
    for (int x = B; x < E; ++x) { \
        float d = pr[2 * x] + pr[2 * x + 1]; \
        if (x > 0) d = d - pr[2 * x - 2]; \
        if ((YY) > 0) d = d - pu[2 * x + 1]; \
        const float td = theta * d; \
        BUF[x - (B)] = ir[x] + td; \
    } }
const float* pr = (const float*)(pin + (size_t)y * prow);
for (int begin = 0; begin < width; begin += chunk) {
    const int end = begin + chunk < width ? begin + chunk : width;
    const int end1 = end < width ? end + 1 : end;
    IVK_V(v0, y, begin, end1)
    if (below)
        IVK_V(v1, y + 1, begin, end)
    IVK_ROF_SIMD
    for (int x = begin; x < end; ++x) {
        const float v = v0[x - begin];
        const float gx = x < width - 1 ? v0[x + 1 - begin] - v : 0.0f;
        const float gy = below ? v1[x - begin] - v : 0.0f;
        const float dx = delta * gx;
        const float dy = delta * gy;
        const float px = pr[2 * x] + dx;
        const float py = pr[2 * x + 1] + dy;
        const float xx = px * px;
        const float yy = py * py;
        const float n2 = xx + yy;
        const float norm = wp::max(1.0f, sqrtf(n2));
        pout[2 * x] = px / norm;
        pout[2 * x + 1] = py / norm;
    }
}
#undef IVK_V
#undef IVK_ROF_SIMD
}
"""


@wp.func_native(_DUAL_STEP_ROW)
def dual_step_row(img: wp.array3d(dtype=float), p_in: wp.array4d(dtype=float), p_out: wp.array4d(dtype=float),
                  theta: float, delta: float, t: int, y: int):
    """Row ``y`` of frame ``t`` of :func:`rof_dual_step_rows` (CPU, rows contiguous)."""
    ...


@wp.kernel
def rof_dual_step_rows_cpu(row_begin: int, img: wp.array3d(dtype=float), p_in: wp.array4d(dtype=float),
                           p_out: wp.array4d(dtype=float), theta: float, delta: float):
    t, y = frame_row(row_begin + wp.tid(), img.shape[1])
    dual_step_row(img, p_in, p_out, theta, delta, t, y)


@wp.kernel
def rof_dual_step_rows(row_begin: int, tiles: int, img: wp.array3d(dtype=float), p_in: wp.array4d(dtype=float),
                       p_out: wp.array4d(dtype=float), theta: float, delta: float):
    width = img.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    height = img.shape[1]
    t = r // height
    y = r - t * height
    # v = img + theta div(p) at (y, x); its value at x + 1 is carried to the next x.  Only a
    # cache of the same expression, so a tile starts it afresh at its first column: the
    # pixels stay independent and every tiling gives the same bits.
    v = float(0.0)
    if x_begin < x_end:
        v = img[t, y, x_begin] + theta * rof_divergence(p_in, t, y, x_begin)
    for x in range(x_begin, x_end):
        gx = 0.0
        gy = 0.0
        v_right = float(0.0)
        if x < width - 1:
            v_right = img[t, y, x + 1] + theta * rof_divergence(p_in, t, y, x + 1)
            gx = v_right - v
        if y < height - 1:
            gy = img[t, y + 1, x] + theta * rof_divergence(p_in, t, y + 1, x) - v
        px = p_in[t, y, x, 0] + delta * gx
        py = p_in[t, y, x, 1] + delta * gy
        norm = wp.max(1.0, wp.sqrt(px * px + py * py))
        p_out[t, y, x, 0] = px / norm
        p_out[t, y, x, 1] = py / norm
        v = v_right


@wp.kernel
def rof_texture_rows(row_begin: int, tiles: int, img: wp.array3d(dtype=float), p: wp.array4d(dtype=float),
                     out: wp.array3d(dtype=float), theta: float, alpha: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, img.shape[2])
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        structure = img[t, y, x] + theta * rof_divergence(p, t, y, x)
        out[t, y, x] = img[t, y, x] - alpha * structure


@host("rof_dual_step")
def rof_dual_step(img, p_in, p_out, theta: float, delta: float) -> None:
    """One step of Chambolle's projection for the ROF structure image.

    With ``v = img + theta * div(p_in)`` (forward-difference gradient,
    replicate border; backward-difference divergence, zero outside):
    ``p_out = (p_in + delta * grad v) / max(1, |p_in + delta * grad v|)``.
    Iterating from ``p = 0`` converges to the dual of
    ``min_S |grad S|_TV + |S - img|^2 / (2 theta)`` for ``delta <= 1 / (4 theta)``.

    img : (T, H, W) float32 (the public code scales it to [-1, 1]).
    p_in, p_out : (T, H, W, 2) float32 dual field; must be different arrays.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = img.shape
    if native_rows(img.device, img, p_in, p_out):
        launch_rows(rof_dual_step_rows_cpu, t * h, [img, p_in, p_out, float(theta), float(delta)], img.device)
        return
    tiles = row_tiles(w, img.device)
    launch_rows(rof_dual_step_rows, t * h * tiles, [tiles, img, p_in, p_out, float(theta), float(delta)],
                img.device)


@host("rof_texture")
def rof_texture(img, p, out, theta: float, alpha: float) -> None:
    """Texture part of the ROF decomposition: ``out = img - alpha * (img + theta * div p)``.

    ``img + theta * div p`` is the structure image; ``alpha = 0.95`` keeps
    5 % of it (Classic+NL's texture weight).

    img : (T, H, W) float32; p : (T, H, W, 2) float32 from :func:`rof_dual_step`;
    out : (T, H, W) float32 (may be ``img``).

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = img.shape
    tiles = row_tiles(w, img.device)
    launch_rows(rof_texture_rows, t * h * tiles, [tiles, img, p, out, float(theta), float(alpha)], img.device)
