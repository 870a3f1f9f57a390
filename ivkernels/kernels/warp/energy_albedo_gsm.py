"""Albedo smoothness of Eq. 11: a Gaussian scale mixture on 5x5 log-RGB differences.

``E = lam * sum_x sum_{y in N(x)} g(r2)``,  ``r2 = d^T Sigma^-1 d``,
``d = A(x) - A(y)``, where ``N(x)`` holds the other pixels of the
``(2 radius + 1)^2`` window around ``x`` inside the image (24 for the paper's
5x5) and ``g(r2) = -log sum_m alpha_m N(d; 0, sigma_m Sigma)`` (minus its
value at 0).  All 40 components share ``Sigma``, so ``g`` depends on ``r2``
only and is read from a 1-D table (:mod:`ivkernels.priors`): the grid is
uniform in ``sqrt(r2)``, ``r2_i = (i sqrt(r2_max) / (n-1))^2``, so the cell is
found in O(1) and ``g``, ``g'`` are interpolated linearly in ``r2`` inside it;
beyond ``r2_max`` ``g`` continues linearly with the last slope.  Each call
first turns the table into per-cell coefficients, ``g = a + b r2`` and
``g' = c + d r2`` (four planes of ``n`` floats, the extrapolation as the last
cell), so a look-up is a square root, four reads and two multiply-adds.

Gradient.  The double sum visits every unordered pair ``{x, y}`` twice
(``y in N(x)`` and ``x in N(y)``), and ``d/dA(x) g(r2) = 2 g'(r2) Sigma^-1 d``
for ``d = A(x) - A(y)`` (the other ordering has ``-d`` and the same ``r2``), so

    dE/dA(x) = 4 lam sum_{y in N(x)} g'(r2(x, y)) Sigma^-1 (A(x) - A(y)),

and each unordered pair is looked up once (12 look-ups per pixel instead of
24): from its first pixel in scan order (the forward half of the window,
``dy > 0``, or ``dy = 0`` and ``dx > 0``), adding ``g' d`` to its first pixel,
``-g' d`` to its second, and ``g`` to the energy of both.

Whitening.  With ``L`` upper triangular, ``L^T L = Sigma^-1`` (Cholesky),
``B(x) = L A(x)`` gives ``r2 = |B(x) - B(y)|^2`` and

    dE/dA(x) = 4 lam L^T sum_{y in N(x)} g'(r2) (B(x) - B(y)),

so a pair costs a 3-vector difference, a dot product, a square root and one
cell's coefficients, and the 3x3 products are once per pixel.

One pass, in row bands.  One thread per band of rows (about sixteen bands per
launch thread on the CPU, :func:`band_rows_for`) walks its rows in order,
with a ring of ``radius + 1`` row slots: the whitened rows ``r .. r + radius``
(each row whitened once, as it enters) and each pixel's running sums
``(sum g' (B(x) - B(y)), sum g)`` (four planes).  Row ``r``'s pairs all lie
in rows ``r .. r + radius``, so once row ``r`` is done its sums are complete:
its gradient ``4 lam L^T sum`` and energy are written and its slot is cleared
for row ``r + radius + 1``.  A band also walks the ``radius`` rows above it
(in its frame), for the pairs that reach into its first rows, keeping only
their halves in the band: every pair is added exactly once to each of its
pixels, with no atomics and no scratch the size of the image (the buffers are
``(radius + 1) * 7 + 4`` floats per band and column).

The row loops are native snippets (``wp.func_native``: :func:`pair_row`,
:func:`whiten_row`, :func:`finish_row`).  Written as plain C++ loops over
contiguous planes, marked free of overlaps between lanes, the CPU compiler
vectorises them (square roots and coefficient reads eight at a time, with
gathers, on an AVX2 machine), and no index pays the negative-index wrap and
stride arithmetic of a Warp array access: a loop over one offset's pairs
along a row ran 2.8x faster as a snippet even unvectorised.  Where the two
pixels of the offset lie in different row slots (``dy > 0``) one loop adds
both halves; within a row (``dy = 0``) the other halves land on other lanes'
pixels, so they go through a scratch row and a second loop.

On a GPU a band per thread leaves all but a few hundred of the device's
threads idle, so there the term runs one thread per pixel
(:func:`gsm_pixels`): each pixel visits its whole window (24 look-ups instead
of 12, no atomics), adds its gradient, writes its energy, and a second kernel
sums each row's energies (:func:`energy_row_sums`).
Measurements (640x480, 8 frames, radius 2): ``perf/RESULTS.md``.
"""
from __future__ import annotations

import math

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import get_threads, gpu_layout, launch_rows
from ivkernels.kernels.reference.energy_albedo_gsm import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.kernel
def cell_coefficients(table_g: wp.array(dtype=float), table_dg: wp.array(dtype=float), r2_max: float,
                      cells_per_root: float, coef: wp.array(dtype=float)):
    """Per table cell ``i``, ``(a, b, c, d)`` at ``coef[i], coef[n + i], coef[2n + i],
    coef[3n + i]`` with ``g = a + b r2`` and ``g' = c + d r2`` inside it (the
    linear-in-r2 interpolation of the table); the last cell holds the linear
    extrapolation beyond ``r2_max``.  Float64 arithmetic."""
    i = wp.tid()
    n = table_g.shape[0]
    if i < n - 1:
        root_lo = wp.float64(i) / wp.float64(cells_per_root)
        root_hi = wp.float64(i + 1) / wp.float64(cells_per_root)
        r2_lo = root_lo * root_lo
        inv_width = wp.float64(1.0) / (root_hi * root_hi - r2_lo)
        slope_g = (wp.float64(table_g[i + 1]) - wp.float64(table_g[i])) * inv_width
        slope_dg = (wp.float64(table_dg[i + 1]) - wp.float64(table_dg[i])) * inv_width
        coef[i] = float(wp.float64(table_g[i]) - slope_g * r2_lo)
        coef[n + i] = float(slope_g)
        coef[2 * n + i] = float(wp.float64(table_dg[i]) - slope_dg * r2_lo)
        coef[3 * n + i] = float(slope_dg)
    else:
        last_dg = wp.float64(table_dg[n - 1])
        coef[i] = float(wp.float64(table_g[n - 1]) - last_dg * wp.float64(r2_max))
        coef[n + i] = float(last_dg)
        coef[2 * n + i] = float(last_dg)
        coef[3 * n + i] = 0.0


@wp.func
def precision_factor(sigma_inv: wp.array2d(dtype=float)):
    """Upper-triangular ``L`` with ``L^T L = Sigma^-1`` (Cholesky of the symmetric
    part of ``sigma_inv``, which must be positive definite)."""
    p01 = 0.5 * (sigma_inv[0, 1] + sigma_inv[1, 0])
    p02 = 0.5 * (sigma_inv[0, 2] + sigma_inv[2, 0])
    p12 = 0.5 * (sigma_inv[1, 2] + sigma_inv[2, 1])
    l00 = wp.sqrt(sigma_inv[0, 0])
    l01 = p01 / l00
    l02 = p02 / l00
    l11 = wp.sqrt(sigma_inv[1, 1] - l01 * l01)
    l12 = (p12 - l01 * l02) / l11
    l22 = wp.sqrt(sigma_inv[2, 2] - l02 * l02 - l12 * l12)
    return wp.mat33(l00, l01, l02,
                    0.0, l11, l12,
                    0.0, 0.0, l22)


# The snippets' loops are marked for the CPU compiler: vectorise, the planes they
# read and write do not overlap within a loop (a GPU build ignores the mark).
_SIMD = r"""
#if defined(__CUDA_ARCH__)
#define IVK_GSM_SIMD
#else
#define IVK_GSM_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
"""

_PAIR_ROW = _SIMD + r"""
const int n_cells = coef.shape[0] / 4;
const float last = (float)(n_cells - 1);
const float* ca = (const float*)coef.data;
const float* cb = ca + n_cells;
const float* cc = cb + n_cells;
const float* cd = cc + n_cells;
const float* b0 = (const float*)whitened.data + (size_t)own * 3 * width;
const float* b1 = b0 + width;
const float* b2 = b1 + width;
const float* q0 = (const float*)whitened.data + (size_t)other * 3 * width;
const float* q1 = q0 + width;
const float* q2 = q1 + width;
float* s_own = (float*)sums.data + (size_t)own * 4 * width;
float* s_other = (float*)sums.data + (size_t)other * 4 * width + dx;
float* t_g = (float*)scratch.data + (size_t)band * 4 * width;
float* t0 = t_g + width;
float* t1 = t0 + width;
float* t2 = t1 + width;
const int x0 = dx < 0 ? -dx : 0;
const int x1 = dx > 0 ? width - dx : width;
#define IVK_GSM_PAIR                                             \
    const float d0 = b0[x] - q0[x + dx];                         \
    const float d1 = b1[x] - q1[x + dx];                         \
    const float d2 = b2[x] - q2[x + dx];                         \
    const float r2 = d0 * d0 + d1 * d1 + d2 * d2;                \
    float u = sqrtf(r2) * cells_per_root;                        \
    u = u < last ? u : last;                                     \
    const int i = (int)u;                                        \
    const float g = ca[i] + cb[i] * r2;                          \
    const float dg = cc[i] + cd[i] * r2;                         \
    const float v0 = dg * d0, v1 = dg * d1, v2 = dg * d2;        \
    s_own[x] += v0;                                              \
    s_own[x + width] += v1;                                      \
    s_own[x + 2 * width] += v2;                                  \
    s_own[x + 3 * width] += g;
if (other != own) {
    // the other pixel lies in another row slot: one loop
    IVK_GSM_SIMD
    for (int x = x0; x < x1; ++x) {
        IVK_GSM_PAIR
        s_other[x] -= v0;
        s_other[x + width] -= v1;
        s_other[x + 2 * width] -= v2;
        s_other[x + 3 * width] += g;
    }
} else {
    // the same row: x + dx is another lane's x, so the other halves go through scratch
    IVK_GSM_SIMD
    for (int x = x0; x < x1; ++x) {
        IVK_GSM_PAIR
        t_g[x] = g;
        t0[x] = v0;
        t1[x] = v1;
        t2[x] = v2;
    }
    IVK_GSM_SIMD
    for (int x = x0; x < x1; ++x) {
        s_other[x] -= t0[x];
        s_other[x + width] -= t1[x];
        s_other[x + 2 * width] -= t2[x];
        s_other[x + 3 * width] += t_g[x];
    }
}
#undef IVK_GSM_PAIR
#undef IVK_GSM_SIMD
"""


@wp.func_native(_PAIR_ROW)
def pair_row(whitened: wp.array(dtype=float), sums: wp.array(dtype=float), scratch: wp.array(dtype=float),
             coef: wp.array(dtype=float), cells_per_root: float, own: int, other: int, dx: int, band: int,
             width: int):
    """The pairs of one row with offset ``(dy, dx)``: for every ``x`` with
    ``0 <= x + dx < width``, ``d = B_own(x) - B_other(x + dx)``, ``r2 = |d|^2``,
    ``(g, g')`` from the cell coefficients; adds ``(g' d, g)`` to the sums of
    ``x`` in slot ``own`` and ``(-g' d, g)`` to those of ``x + dx`` in slot
    ``other`` (``other`` is the slot of row ``r + dy``).  Slot ``k`` of
    ``whitened`` holds three planes of ``width`` floats at ``3 k width``, of
    ``sums`` four at ``4 k width`` (gradient x, y, z, energy); ``scratch``
    holds four planes per band; ``coef`` the four coefficient planes."""
    ...


_WHITEN_ROW = _SIMD + r"""
const char* row = (const char*)A.data + (size_t)t * A.strides[0] + (size_t)y * A.strides[1];
const size_t sx = A.strides[2];
const size_t sc = A.strides[3];
float* w0 = (float*)whitened.data + (size_t)slot * 3 * width;
float* w1 = w0 + width;
float* w2 = w1 + width;
const float l00 = L.data[0][0], l01 = L.data[0][1], l02 = L.data[0][2];
const float l11 = L.data[1][1], l12 = L.data[1][2], l22 = L.data[2][2];
if (sx == 3 * sizeof(float) && sc == sizeof(float)) {
    const float* a = (const float*)row;
    IVK_GSM_SIMD
    for (int x = 0; x < width; ++x) {
        const float a0 = a[3 * x], a1 = a[3 * x + 1], a2 = a[3 * x + 2];
        w0[x] = l00 * a0 + l01 * a1 + l02 * a2;
        w1[x] = l11 * a1 + l12 * a2;
        w2[x] = l22 * a2;
    }
} else {
    for (int x = 0; x < width; ++x) {
        const char* p = row + (size_t)x * sx;
        const float a0 = *(const float*)p;
        const float a1 = *(const float*)(p + sc);
        const float a2 = *(const float*)(p + 2 * sc);
        w0[x] = l00 * a0 + l01 * a1 + l02 * a2;
        w1[x] = l11 * a1 + l12 * a2;
        w2[x] = l22 * a2;
    }
}
#undef IVK_GSM_SIMD
"""


@wp.func_native(_WHITEN_ROW)
def whiten_row(A: wp.array4d(dtype=float), t: int, y: int, L: wp.mat33, whitened: wp.array(dtype=float), slot: int,
               width: int):
    """Ring slot ``slot`` of ``whitened`` (three planes of ``width``) gets
    ``B = L A(t, y, x)`` for every ``x`` (``L`` upper triangular)."""
    ...


_FINISH_ROW = _SIMD + r"""
float* s0 = (float*)sums.data + (size_t)slot * 4 * width;
float* s1 = s0 + width;
float* s2 = s1 + width;
float* s3 = s2 + width;
double e = 0.0;
if (write) {
    char* row = (char*)gA.data + (size_t)t * gA.strides[0] + (size_t)y * gA.strides[1];
    const size_t sx = gA.strides[2];
    const size_t sc = gA.strides[3];
    const float l00 = L.data[0][0], l01 = L.data[0][1], l02 = L.data[0][2];
    const float l11 = L.data[1][1], l12 = L.data[1][2], l22 = L.data[2][2];
    if (sx == 3 * sizeof(float) && sc == sizeof(float)) {
        float* a = (float*)row;
        IVK_GSM_SIMD
        for (int x = 0; x < width; ++x) {
            const float g0 = s0[x], g1 = s1[x], g2 = s2[x];
            a[3 * x] += scale * (l00 * g0);
            a[3 * x + 1] += scale * (l01 * g0 + l11 * g1);
            a[3 * x + 2] += scale * (l02 * g0 + l12 * g1 + l22 * g2);
        }
    } else {
        for (int x = 0; x < width; ++x) {
            char* p = row + (size_t)x * sx;
            const float g0 = s0[x], g1 = s1[x], g2 = s2[x];
            *(float*)p += scale * (l00 * g0);
            *(float*)(p + sc) += scale * (l01 * g0 + l11 * g1);
            *(float*)(p + 2 * sc) += scale * (l02 * g0 + l12 * g1 + l22 * g2);
        }
    }
    for (int x = 0; x < width; ++x)
        e += (double)s3[x];
}
IVK_GSM_SIMD
for (int x = 0; x < 4 * width; ++x)
    s0[x] = 0.0f;
return e;
#undef IVK_GSM_SIMD
"""


@wp.func_native(_FINISH_ROW)
def finish_row(sums: wp.array(dtype=float), slot: int, width: int, write: int, L: wp.mat33, scale: float,
               gA: wp.array4d(dtype=float), t: int, y: int) -> wp.float64:
    """With ``write``, adds ``scale L^T s`` to ``gA(t, y, x)`` for the
    gradient sums ``s`` of slot ``slot`` and returns the sum of its energy
    plane (float64); then clears the slot (returns 0 without ``write``)."""
    ...


@wp.kernel
def gsm_bands(band_begin: int, band_rows: int, radius: int, A: wp.array4d(dtype=float),
              sigma_inv: wp.array2d(dtype=float), coef: wp.array(dtype=float), cells_per_root: float, lam: float,
              whitened: wp.array(dtype=float), sums: wp.array(dtype=float), scratch: wp.array(dtype=float),
              gA: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64)):
    """One band of rows ``[r0, r1)`` (``r0 = band * band_rows``) with its ring of
    ``radius + 1`` slots (slot ``band (radius + 1) + r mod (radius + 1)``): the
    rows ``max(r0 - radius, frame start) .. r1 - 1`` are walked in order, each
    one's forward pairs added to both pixels (:func:`pair_row`); rows from
    ``r0`` on then get their gradient and energy."""
    band = band_begin + wp.tid()
    height = A.shape[1]
    width = A.shape[2]
    n_rows = A.shape[0] * height
    r0 = band * band_rows
    if r0 >= n_rows:
        return
    r1 = wp.min(r0 + band_rows, n_rows)
    start = wp.max(r0 - radius, (r0 // height) * height)
    S = radius + 1
    base = band * S
    L = precision_factor(sigma_inv)
    scale = 4.0 * lam
    for s in range(S):
        finish_row(sums, base + s, width, 0, L, scale, gA, 0, 0)
    for r in range(start, wp.min(start + radius, n_rows)):
        # the first rows enter the ring (later ones as the row radius above them is walked)
        t = r // height
        whiten_row(A, t, r - t * height, L, whitened, base + r % S, width)
    for r in range(start, r1):
        t = r // height
        y = r - t * height
        ahead = r + radius
        if ahead < n_rows:
            ta = ahead // height
            whiten_row(A, ta, ahead - ta * height, L, whitened, base + ahead % S, width)
        own = base + r % S
        for dy in range(S):
            # a row above the band only serves the pairs that reach into it
            if y + dy < height and r + dy >= r0:
                other = base + (r + dy) % S
                dx0 = -radius
                if dy == 0:
                    dx0 = 1
                for dx in range(dx0, radius + 1):
                    pair_row(whitened, sums, scratch, coef, cells_per_root, own, other, dx, band, width)
        # row r has all its pairs (rows above the band only served the band's first rows)
        e = finish_row(sums, own, width, int(r >= r0), L, scale, gA, t, y)
        if r >= r0:
            energy_rows[r] = energy_rows[r] + wp.float64(lam) * e


@wp.func
def cell_lookup(coef: wp.array(dtype=float), cells_per_root: float, r2: float):
    """``(g, g')`` at ``r2`` from the cell coefficients (as :func:`pair_row` reads them)."""
    n_cells = coef.shape[0] // 4
    u = wp.min(wp.sqrt(r2) * cells_per_root, float(n_cells - 1))
    i = int(u)
    g = coef[i] + coef[n_cells + i] * r2
    dg = coef[2 * n_cells + i] + coef[3 * n_cells + i] * r2
    return g, dg


@wp.kernel
def gsm_pixels(radius: int, A: wp.array4d(dtype=float), sigma_inv: wp.array2d(dtype=float),
               coef: wp.array(dtype=float), cells_per_root: float, lam: float,
               gA: wp.array4d(dtype=float), pixel_energy: wp.array3d(dtype=float)):
    """The GPU form of the term: one thread per pixel ``x`` visits all its
    neighbours ``y`` (each unordered pair is looked up from both of its pixels,
    24 look-ups per pixel instead of 12, with no atomics), adds
    ``4 lam L^T sum_y g'(r2) (B(x) - B(y))`` to ``gA(x)`` and writes
    ``sum_y g(r2)`` to ``pixel_energy(t*H + y, x)`` (row sums: :func:`energy_row_sums`)."""
    t, y, x = wp.tid()
    height = A.shape[1]
    width = A.shape[2]
    L = precision_factor(sigma_inv)
    b = L * wp.vec3(A[t, y, x, 0], A[t, y, x, 1], A[t, y, x, 2])
    acc = wp.vec3(0.0, 0.0, 0.0)
    e = float(0.0)
    for yy in range(wp.max(y - radius, 0), wp.min(y + radius + 1, height)):
        for xx in range(wp.max(x - radius, 0), wp.min(x + radius + 1, width)):
            if yy != y or xx != x:
                d = b - L * wp.vec3(A[t, yy, xx, 0], A[t, yy, xx, 1], A[t, yy, xx, 2])
                g, dg = cell_lookup(coef, cells_per_root, wp.dot(d, d))
                e += g
                acc += dg * d
    v = (4.0 * lam) * (wp.transpose(L) * acc)
    gA[t, y, x, 0] = gA[t, y, x, 0] + v[0]
    gA[t, y, x, 1] = gA[t, y, x, 1] + v[1]
    gA[t, y, x, 2] = gA[t, y, x, 2] + v[2]
    pixel_energy[t, y, x] = e


@wp.kernel
def energy_row_sums(pixel_energy: wp.array3d(dtype=float), lam: float, energy_rows: wp.array(dtype=wp.float64)):
    """``energy_rows[t*H + y] += lam * sum_x pixel_energy(t, y, x)`` (float64), one thread per row."""
    r = wp.tid()
    height = pixel_energy.shape[1]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(pixel_energy.shape[2]):
        e += wp.float64(pixel_energy[t, y, x])
    energy_rows[r] = energy_rows[r] + wp.float64(lam) * e

#: Bands per launch thread on the CPU: enough that a thread held up by
#: another process leaves its share to the others.
BANDS_PER_THREAD = 16

#: Fewest rows of a band on the CPU.
MIN_BAND_ROWS = 32


def band_rows_for(n_rows: int) -> int:
    """Rows per band of the CPU's band kernel: about :data:`BANDS_PER_THREAD` bands
    per launch thread (handed out in turn, :func:`launch_rows` ``balance=True``),
    at least :data:`MIN_BAND_ROWS` rows each, so the ``radius`` rows each band
    walks above itself (1.25 rows' pairs for the 5x5 window) cost a few
    percent at most (a GPU runs :func:`gsm_pixels` instead)."""
    return max(MIN_BAND_ROWS, -(-n_rows // (BANDS_PER_THREAD * get_threads())))


def _scratch(workspace, name: str, shape: tuple, dtype, device):
    """Scratch buffer ``name`` from ``workspace`` (or allocated for this call)."""
    return scratch_buffer(workspace, f"{__name__}.{name}", shape, dtype,
                          lambda: wp.empty(shape, dtype=dtype, device=device), device)


@host("gsm_smoothness")
def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, gA, energy_rows,
                   lam: float, radius: int = 2, *, workspace=None) -> None:
    """Add Eq. 11's GSM smoothness energy and gradient.

    Parameters
    ----------
    A : wp.array float32 (T, H, W, 3), log albedo (natural log, linear RGB).
    sigma_inv : wp.array float32 (3, 3), ``Sigma^-1`` (``AlbedoPrior.sigma_inv``),
        symmetric positive definite.
    table_g, table_dg : wp.array float32 (n,), n >= 2: ``g`` and ``g' = dg/dr2``
        on the grid ``r2_i = (i sqrt(r2_max) / (n-1))^2`` (``AlbedoPrior.table_g``,
        ``.table_dg``).
    r2_max : float > 0, the last grid point.
    gA : wp.array float32 (T, H, W, 3), accumulated: ``gA += dE/dA``
        ``= 4 lam sum_y g'(r2) Sigma^-1 (A(x) - A(y))``.  Must not overlap ``A``.
    energy_rows : wp.array float64 (T*H,), accumulated: row ``t*H + y`` gets
        ``lam * sum_{x in row} sum_{y in N(x)} g(r2)``.
    lam : Eq. 11's ``lambda_As``.
    radius : window radius (2: the paper's 5x5 window, 24 neighbours).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the scratch buffers (per band of rows, ``radius + 1`` row slots
        of the whitened rows and of the pixel sums, 12 and 16 bytes per
        column each, and one row of pair values, 16 bytes per column; the
        cell coefficients, 16 bytes per table entry) between calls; without
        one they are allocated for this call.
    """
    T, H, W, _ = A.shape
    dev = A.device
    n = table_g.shape[0]
    cells_per_root = (n - 1) / math.sqrt(r2_max)
    if T * H == 0 or W == 0:
        return
    coef = _scratch(workspace, "cell_coefficients", (4 * n,), float, dev)
    wp.launch(cell_coefficients, dim=n, inputs=[table_g, table_dg, float(r2_max), float(cells_per_root), coef],
              device=dev)
    if gpu_layout(dev):
        # a GPU: one thread per pixel (a band per thread leaves all but a few hundred of its
        # threads idle: 103 ms a call at 640x480x8 on an H200, perf/RESULTS.md)
        energy = _scratch(workspace, "pixel_energy", (T, H, W), float, dev)
        wp.launch(gsm_pixels, dim=(T, H, W),
                  inputs=[int(radius), A, sigma_inv, coef, float(cells_per_root), float(lam), gA, energy],
                  device=dev)
        wp.launch(energy_row_sums, dim=T * H, inputs=[energy, float(lam), energy_rows], device=dev)
        return
    band_rows = band_rows_for(T * H)
    n_bands = -(-T * H // band_rows)
    slots = n_bands * (radius + 1)
    whitened = _scratch(workspace, "whitened_rows", (slots * 3 * W,), float, dev)
    sums = _scratch(workspace, "pixel_sums", (slots * 4 * W,), float, dev)
    scratch = _scratch(workspace, "pair_values", (n_bands * 4 * W,), float, dev)
    launch_rows(gsm_bands, n_bands,
                [band_rows, int(radius), A, sigma_inv, coef, float(cells_per_root), float(lam), whitened, sums,
                 scratch, gA, energy_rows], device=dev, balance=True)
