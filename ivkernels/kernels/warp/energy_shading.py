"""Shading terms of the intrinsic-video energy, log domain: the local
smoothness of Eq. 9 (with the stable steps' weighted axis pairs added in
the same pass), and the coupling to S~ of Eq. 13.

Energy conventions as in :mod:`ivkernels.kernels`: gradients are *added* into
``gS``, energies *added* per row into ``energy_rows`` (float64, row ``t*H + y``).
The non-local part of Eq. 9 is minimised through S~ by
:func:`ivkernels.kernels.warp.median.weighted_median_shading`.  The local
term's Charbonnier penalty is the data term's (:mod:`ivkernels.kernels.warp.energy_data`).
On the CPU the local term runs as native row loops (:func:`local_row`; 640x480,
8 frames, gated, 2 threads: 16-18 -> 9-10 ms, bit for bit the kernel's).
"""
from __future__ import annotations

import functools

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.energy_shading import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows
from ivkernels.kernels.warp.row_tiles import frame_row, row_span
from ivkernels.kernels.warp.energy_data import charbonnier

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.func
def local_pair(s: float, s_y: float, eps: float, gated: int, gate_x: float, gate_y: float, extra: float):
    """One pair of Eq. 9's local term: ``(energy, d energy / d S(x))`` of
    ``w rho(S(x) - S(y))``, ``w = (gate(x) + gate(y)) / 2 + extra`` when ``gated``, else 1."""
    d = s - s_y
    rho = charbonnier(d, eps)
    if gated != 0:
        wgt = 0.5 * (gate_x + gate_y) + extra      # the pair's weight, symmetric
        return wgt * rho, wgt * d / rho
    return rho, d / rho


@wp.func
def axis_pair_weight(pairs: wp.array3d(dtype=float), y: int, x: int, j: int, i: int):
    """The stable-pair weight of the pair of ``(y, x)`` with its neighbour ``(y + j - 1, x + i - 1)``:
    ``pairs`` holds each pixel's right (k = 0) and lower (k = 1) pair; diagonal pairs get 0."""
    if j == 1 and i == 2:
        return pairs[y, x, 0]
    if j == 1 and i == 0:
        return pairs[y, x - 1, 0]
    if j == 2 and i == 1:
        return pairs[y, x, 1]
    if j == 0 and i == 1:
        return pairs[y - 1, x, 1]
    return 0.0


@functools.lru_cache(maxsize=None)
def _local_kernel_for(gated: bool, paired: bool = False):
    """Eq. 9's local term with ``gated`` (and ``paired``: the stable steps' axis pairs
    added) compiled in (one module each, built on first use): the 3x3 loops are
    unrolled, and pixels whose 8 neighbours all lie in the image skip the bounds
    tests.  The pairs are visited in the same order on both branches, so the sums
    are bitwise those of one general loop (640x480, 8 frames, 2 threads: 39 -> 27 ms
    plain, 49 -> 31-38 ms gated)."""
    G = 1 if gated else 0
    P = 1 if paired else 0

    @wp.kernel(module="unique")
    def shading_smoothness_rows(row_begin: int, tiles: int, S: wp.array3d(dtype=float), gate: wp.array3d(dtype=float),
                                pairs: wp.array3d(dtype=float), gS: wp.array3d(dtype=float),
                                energy_rows: wp.array(dtype=wp.float64), lam: float, half_pair_gain: float,
                                eps: float):
        """Eq. 9's local term; gated: each pair is weighted by the mean of its two
        ``gate`` values (``gate`` is not read otherwise); paired: an axis pair's weight
        also gets ``half_pair_gain`` times its ``pairs`` weight (``pairs`` is not read otherwise)."""
        r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, S.shape[2])
        height = S.shape[1]
        width = S.shape[2]
        t = r // height
        y = r - t * height
        e = wp.float64(0.0)
        inside_rows = y >= 1 and y + 1 < height
        for x in range(x_begin, x_end):
            s = S[t, y, x]
            gx = float(1.0)
            if wp.static(G != 0):
                gx = gate[t, y, x]
            g = float(0.0)
            if inside_rows and x >= 1 and x + 1 < width:
                for j in range(wp.static(3)):
                    for i in range(wp.static(3)):
                        if wp.static(i != 1 or j != 1):
                            gy = float(1.0)
                            if wp.static(G != 0):
                                gy = gate[t, y + j - 1, x + i - 1]
                            extra = float(0.0)
                            if wp.static(P != 0 and (i == 1 or j == 1)):
                                extra = half_pair_gain * axis_pair_weight(pairs, y, x, j, i)
                            pe, pg = local_pair(s, S[t, y + j - 1, x + i - 1], eps, G, gx, gy, extra)
                            e += wp.float64(pe)
                            g += pg
            else:
                for j in range(wp.static(3)):
                    yy = y + j - 1
                    if yy >= 0 and yy < height:
                        for i in range(wp.static(3)):
                            xx = x + i - 1
                            if xx >= 0 and xx < width and (i != 1 or j != 1):
                                gy = float(1.0)
                                if wp.static(G != 0):
                                    gy = gate[t, yy, xx]
                                extra = float(0.0)
                                if wp.static(P != 0):
                                    extra = half_pair_gain * axis_pair_weight(pairs, y, x, j, i)
                                pe, pg = local_pair(s, S[t, yy, xx], eps, G, gx, gy, extra)
                                e += wp.float64(pe)
                                g += pg
            # S(x) appears in the pair (x, y) and in (y, x): twice the derivative
            gS[t, y, x] = gS[t, y, x] + 2.0 * lam * g
        wp.atomic_add(energy_rows, r, wp.float64(lam) * e)

    return shading_smoothness_rows


# The CPU's local term (plain, gated and paired): one row per kernel thread as native
# loops.  The row's inner pixels (all 8 neighbours in the image) run in a loop
# the compiler vectorises, which stores each pair's energy in a short stack
# buffer; a scalar loop then adds them to the row's float64 sum in the order of
# :func:`_local_kernel_for`'s kernel, and the border pixels run that kernel's
# bounds-tested loop.  Every operation is the kernel's, in its order and none
# fused into a multiply-add: bit for bit the same.
_LOCAL_ROW = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
#if defined(__CUDA_ARCH__)
#define IVK_LOCAL_SIMD
#else
#define IVK_LOCAL_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
const int height = S.shape[1];
const int width = S.shape[2];
const size_t srow = S.strides[1];
const char* s_frame = (const char*)S.data + (size_t)t * S.strides[0];
const char* g_frame = (const char*)gate.data + (size_t)t * gate.strides[0];
const size_t grow = gate.strides[1];
float* gs = (float*)((char*)gS.data + (size_t)t * gS.strides[0] + (size_t)y * gS.strides[1]);
const float e2 = eps * eps;
const float* pw = (const float*)pairs.data;
const size_t prow = pairs.strides[0] / 4;
const float scale = 2.0f * lam;
double e = 0.0;
// one pair: its energy PE and its derivative in S(x) added to G
#define IVK_PAIR(SX, SY, GX, GY, EXTRA, PE, G) { \
    const float d = SX - SY; \
    const float dd = d * d; \
    const float r2 = dd + e2; \
    const float rho = sqrtf(r2); \
    if (gated) { \
        const float gsum = GX + GY; \
        const float half = 0.5f * gsum; \
        const float wgt = half + (EXTRA); \
        PE = wgt * rho; \
        const float wd = wgt * d; \
        const float pg = wd / rho; \
        G = G + pg; \
    } else { \
        PE = rho; \
        const float pg = d / rho; \
        G = G + pg; \
    } }
#define IVK_AT(YY, XX) (*(const float*)(s_frame + (size_t)(YY) * srow + (size_t)(XX) * 4))
#define IVK_GATE(YY, XX) (gated ? *(const float*)(g_frame + (size_t)(YY) * grow + (size_t)(XX) * 4) : 1.0f)
// the stable pairs' weight of an axis pair (j, i) of pixel (y, X) (``axis_pair_weight``), 0 for a diagonal one
#define IVK_PAIR_W(X, J, I) (((J) == 1 && (I) == 2) ? pw[(size_t)y * prow + 2 * (X)] : \
                             ((J) == 1 && (I) == 0) ? pw[(size_t)y * prow + 2 * ((X) - 1)] : \
                             ((J) == 2 && (I) == 1) ? pw[(size_t)y * prow + 2 * (X) + 1] : \
                             ((J) == 0 && (I) == 1) ? pw[(size_t)(y - 1) * prow + 2 * (X) + 1] : 0.0f)
// a pixel with a neighbour outside the image: the kernel's bounds-tested loop
#define IVK_BORDER(X) { \
    const float sx = IVK_AT(y, X); \
    const float gx = IVK_GATE(y, X); \
    float g = 0.0f; \
    for (int j = 0; j < 3; ++j) { \
        const int yy = y + j - 1; \
        if (yy >= 0 && yy < height) { \
            for (int i = 0; i < 3; ++i) { \
                const int xx = X + i - 1; \
                if (xx >= 0 && xx < width && (i != 1 || j != 1)) { \
                    float pe; \
                    const float extra = paired ? half_pair_gain * IVK_PAIR_W(X, j, i) : 0.0f; \
                    IVK_PAIR(sx, IVK_AT(yy, xx), gx, IVK_GATE(yy, xx), extra, pe, g) \
                    e = e + (double)pe; \
                } \
            } \
        } \
    } \
    const float add = scale * g; \
    gs[X] = gs[X] + add; }
if (y >= 1 && y + 1 < height && width >= 3) {
    IVK_BORDER(0)
    const float* up = (const float*)(s_frame + (size_t)(y - 1) * srow);
    const float* mid = (const float*)(s_frame + (size_t)y * srow);
    const float* down = (const float*)(s_frame + (size_t)(y + 1) * srow);
    const float* gup = (const float*)(g_frame + (size_t)(y - 1) * grow);
    const float* gmid = (const float*)(g_frame + (size_t)y * grow);
    const float* gdown = (const float*)(g_frame + (size_t)(y + 1) * grow);
    const float* p_up = pw + (size_t)(y - 1) * prow;
    const float* p_mid = pw + (size_t)y * prow;
    const int chunk = 256;
    float pes[8 * 256];
    for (int begin = 1; begin < width - 1; begin += chunk) {
        const int end = begin + chunk < width - 1 ? begin + chunk : width - 1;
        IVK_LOCAL_SIMD
        for (int x = begin; x < end; ++x) {
            const float sx = mid[x];
            const float gx = gated ? gmid[x] : 1.0f;
            float* pe = pes + 8 * (x - begin);
            float g = 0.0f;
            const float x_up = paired ? half_pair_gain * p_up[2 * x + 1] : 0.0f;
            const float x_left = paired ? half_pair_gain * p_mid[2 * (x - 1)] : 0.0f;
            const float x_right = paired ? half_pair_gain * p_mid[2 * x] : 0.0f;
            const float x_down = paired ? half_pair_gain * p_mid[2 * x + 1] : 0.0f;
            IVK_PAIR(sx, up[x - 1], gx, (gated ? gup[x - 1] : 1.0f), 0.0f, pe[0], g)
            IVK_PAIR(sx, up[x], gx, (gated ? gup[x] : 1.0f), x_up, pe[1], g)
            IVK_PAIR(sx, up[x + 1], gx, (gated ? gup[x + 1] : 1.0f), 0.0f, pe[2], g)
            IVK_PAIR(sx, mid[x - 1], gx, (gated ? gmid[x - 1] : 1.0f), x_left, pe[3], g)
            IVK_PAIR(sx, mid[x + 1], gx, (gated ? gmid[x + 1] : 1.0f), x_right, pe[4], g)
            IVK_PAIR(sx, down[x - 1], gx, (gated ? gdown[x - 1] : 1.0f), 0.0f, pe[5], g)
            IVK_PAIR(sx, down[x], gx, (gated ? gdown[x] : 1.0f), x_down, pe[6], g)
            IVK_PAIR(sx, down[x + 1], gx, (gated ? gdown[x + 1] : 1.0f), 0.0f, pe[7], g)
            const float add = scale * g;
            gs[x] = gs[x] + add;
        }
        for (int x = begin; x < end; ++x) {
            const float* pe = pes + 8 * (x - begin);
            for (int k = 0; k < 8; ++k)
                e = e + (double)pe[k];
        }
    }
    IVK_BORDER(width - 1)
} else {
    for (int x = 0; x < width; ++x)
        IVK_BORDER(x)
}
double* er = (double*)energy_rows.data + r;
const double le = (double)lam * e;
er[0] = er[0] + le;
#undef IVK_BORDER
#undef IVK_PAIR_W
#undef IVK_GATE
#undef IVK_AT
#undef IVK_PAIR
#undef IVK_LOCAL_SIMD
}
"""


@wp.func_native(_LOCAL_ROW)
def local_row(S: wp.array3d(dtype=float), gate: wp.array3d(dtype=float), pairs: wp.array3d(dtype=float),
              gS: wp.array3d(dtype=float), energy_rows: wp.array(dtype=wp.float64), lam: float, eps: float,
              half_pair_gain: float, gated: int, paired: int, t: int, y: int, r: int):
    """Row ``y`` of frame ``t`` of Eq. 9's local term, plain, gated or paired (CPU, rows contiguous)."""
    ...


@wp.kernel
def local_rows_cpu(row_begin: int, S: wp.array3d(dtype=float), gate: wp.array3d(dtype=float),
                   pairs: wp.array3d(dtype=float), gS: wp.array3d(dtype=float),
                   energy_rows: wp.array(dtype=wp.float64), lam: float, eps: float, half_pair_gain: float,
                   gated: int, paired: int):
    r = row_begin + wp.tid()
    t, y = frame_row(r, S.shape[1])
    local_row(S, gate, pairs, gS, energy_rows, lam, eps, half_pair_gain, gated, paired, t, y, r)


@wp.kernel
def coupling_rows(row_begin: int, tiles: int, S: wp.array3d(dtype=float), S_tilde: wp.array3d(dtype=float),
                  w_bnd: wp.array3d(dtype=float), gS: wp.array3d(dtype=float),
                  energy_rows: wp.array(dtype=wp.float64), lam: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, S.shape[2])
    height = S.shape[1]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(x_begin, x_end):
        w = w_bnd[t, y, x]
        d = S[t, y, x] - S_tilde[t, y, x]
        e += wp.float64(w * d * d)
        gS[t, y, x] = gS[t, y, x] + 2.0 * lam * w * d
    wp.atomic_add(energy_rows, r, wp.float64(lam) * e)


@host("shading_smoothness")
def shading_smoothness(S, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add the local shading smoothness of Eq. 9 and its gradient.

    ``E = lam * sum_x sum_{y in N3(x)} sqrt((S(x) - S(y))^2 + eps^2)``, N3 the 8
    neighbours inside the image; as in the paper's double sum every unordered
    pair is counted twice, so ``dE/dS(x) = 2 lam sum_y psi(S(x) - S(y))`` with
    ``psi(d) = d / sqrt(d^2 + eps^2)`` (a gather, no atomics).

    Parameters
    ----------
    S : wp.array float32 (T, H, W), log shading.
    gS : wp.array float32 (T, H, W), accumulated.  Must not overlap ``S``.
    energy_rows : wp.array float64 (T*H,), accumulated.
    lam : lambda_Ss.  eps : Charbonnier epsilon.
    """
    _local_term(S, None, gS, energy_rows, lam, eps)


@host("shading_smoothness_gated")
def shading_smoothness_gated(S, gate, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add Eq. 9's local shading smoothness with a per-pixel gate on its pair terms, and its gradient.

    ``E = lam * sum_x sum_{y in N3(x)} w(x, y) sqrt((S(x) - S(y))^2 + eps^2)`` with
    the pair weight ``w(x, y) = (gate(x) + gate(y)) / 2`` (symmetric, so
    ``dE/dS(x) = 2 lam sum_y w(x, y) psi(S(x) - S(y))``).  With ``gate = 1``
    everywhere it is :func:`shading_smoothness`.  The gate comes from the
    input (:func:`ivkernels.kernels.warp.maps.shading_gate`): low
    across a likely shading edge, which the term then lets through.

    Parameters
    ----------
    S : wp.array float32 (T, H, W), log shading.
    gate : wp.array float32 (T, H, W), per-pixel weight, dimensionless, in [0, 1].
    gS : wp.array float32 (T, H, W), accumulated.  Must not overlap ``S`` or ``gate``.
    energy_rows : wp.array float64 (T*H,), accumulated.
    lam : lambda_Ss.  eps : Charbonnier epsilon.
    """
    _local_term(S, gate, gS, energy_rows, lam, eps)


def _local_term(S, gate, gS, energy_rows, lam: float, eps: float, pairs=None, pair_gain: float = 0.0) -> None:
    """Launch of Eq. 9's local term (arguments checked), gated unless ``gate`` is None, with the
    axis pairs' weights when ``pairs`` is given (``S`` stands in for the arrays a variant does
    not read)."""
    t, h, w = S.shape
    if native_rows(S.device, S, gS, S if gate is None else gate) \
            and (pairs is None or (pairs.strides[2] == 4 and pairs.strides[1] == 8)):
        launch_rows(local_rows_cpu, t * h,
                    [S, S if gate is None else gate, S if pairs is None else pairs, gS, energy_rows, float(lam),
                     float(eps), 0.5 * float(pair_gain), 0 if gate is None else 1, 0 if pairs is None else 1],
                    device=S.device)
        return
    tiles = row_tiles(w, S.device)
    launch_rows(_local_kernel_for(gate is not None, pairs is not None), t * h * tiles,
                [tiles, S, S if gate is None else gate, S if pairs is None else pairs, gS, energy_rows,
                 float(lam), 0.5 * float(pair_gain), float(eps)], device=S.device)


@host("shading_smoothness_paired")
def shading_smoothness_paired(S, gate, pairs, gS, energy_rows, lam: float = 2.0, pair_gain: float = 1.0,
                              eps: float = 0.001) -> None:
    """Add Eq. 9's gated local smoothness with weighted axis pairs, and its gradient.

    ``E = gated + lam * pair_gain * sum_t sum_x sum_k pairs[x, k] sqrt((S(t, x + d_k) - S(t, x))^2 + eps^2)``
    with ``gated`` :func:`shading_smoothness_gated`, ``d_0 = (0, 1)``, ``d_1 = (1, 0)``:
    each axis pair once, the same weight in every frame.  The weights are the
    stable-step evidence (:func:`ivkernels.kernels.warp.step_evidence.stable_pairs`):
    a pair across a step that holds its contrast under every light of the
    window, whose shading should not change there.  One pass with the gated
    term: an axis pair's weight becomes ``(gate(x) + gate(y)) / 2 + pair_gain
    pairs / 2`` (the local term counts each pair twice).

    Parameters
    ----------
    S : wp.array float32 (T, H, W), log shading.
    gate : wp.array float32 (T, H, W), per-pixel weight of the local term.
    pairs : wp.array float32 (H, W, 2), weight of the right (0) and lower (1) pair of each pixel.
    gS : wp.array float32 (T, H, W), accumulated.  Must not overlap ``S``, ``gate`` or ``pairs``.
    energy_rows : wp.array float64 (T*H,), accumulated.
    lam : lambda_Ss.  pair_gain : the pairs' weight relative to ``lam``.  eps : Charbonnier epsilon.
    """
    _local_term(S, gate, gS, energy_rows, lam, eps, pairs, pair_gain)


@host("coupling_term")
def coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
    """Add the coupling term of Eq. 13 and its gradient in S.

    ``E = lam * sum_{t < T'} sum_x w_bnd (S - S~)^2``; ``dE/dS = 2 lam w_bnd (S - S~)``.
    Frames ``t >= T'`` (the last frame has no flow) get no term.

    Parameters
    ----------
    S, S_tilde : wp.array float32 (T, H, W), log shading and its coupling variable.
    w_bnd : wp.array float32 (T', H, W), ``T' <= T``, motion-boundary map.
    gS : wp.array float32 (T, H, W), accumulated.
    energy_rows : wp.array float64 (T*H,), accumulated.
    lam : lambda_cpl.
    """
    t, h, w = S.shape
    dev = S.device
    tiles = row_tiles(w, dev)
    launch_rows(coupling_rows, w_bnd.shape[0] * h * tiles, [tiles, S, S_tilde, w_bnd, gS, energy_rows, float(lam)],
                device=dev)
