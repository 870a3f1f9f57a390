"""The edge-aware coarse basis of the solver: weights, prolongation and its transpose.

At the finest levels, the slow modes of Eq. 2 on ``A = I - S`` are smooth
changes of the shading that stop at albedo edges: inside a flat albedo
region the albedo GSM (Eq. 11) is stiff, across its edges it is soft, and a
descent method on single pixels moves a whole region only slowly.  The
solver therefore also optimises a coarse field ``z`` on a grid of nodes every
``spacing`` pixels, added to the shading through an interpolation ``P`` whose
weights follow the albedo (Szeliski, "Locally adapted hierarchical basis
preconditioning", SIGGRAPH 2006, builds the same kind of basis from the
system's own weights):

* :func:`coarse_weights`: per pixel, 16 weights over the 4 x 4 nodes around
  it, a tent of half-width two node spacings times
  ``exp(-|A(x) - A(node)|^2 / sigma^2)``, normalised to sum to one;
* :func:`prolong_add`: ``out += P z`` (a gather of 16 nodes per pixel);
* :func:`restrict_add`: ``out += P^T values``, the exact transpose: each
  pixel scatters into its 16 nodes.  Nodes belong to one frame, so the CPU
  launch is split only at frame boundaries and the sums do not depend on
  the thread count.

The pixels of a row between two node columns (a run of ``spacing``
pixels) share their 16 nodes, so both transfers work run by run: the
prolongation reads the run's nodes once, and the restriction sums the
run's contributions to each node locally and adds them to the node once
(at 640x480, 8 frames, spacing 4, 2 threads: 31 -> 20 ms and 40 -> 20 ms
against one node access per pixel and tap; ``perf/RESULTS.md``).  On the CPU
the prolongation runs as a native row loop the compiler vectorises
(:func:`prolong_add_row`; 14-18 -> 12 ms, bit for bit the same), at the
memory's speed as the restriction already is.

Node ``j`` of a frame sits on pixel row ``min(j * spacing, H - 1)``; the grid
has ``(H - 1) // spacing + 2`` rows (:func:`grid_shape`), so every pixel has
nodes on both sides.  Pixel ``y``'s taps are the nodes ``floor(y / spacing)
+ d``, ``d = -1, 0, 1, 2``; a tap off the grid has weight 0.  Tap ``k = 4 *
(dy + 1) + (dx + 1)``.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import MAX_EXPONENT, grid_shape
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.coarse_basis import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows
from ivkernels.kernels.warp.row_tiles import frame_row, row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

@wp.func
def tent(f: float, node: int):
    """Weight along one axis of ``node`` for a pixel at ``f = p / spacing`` nodes: ``max(0, 1 - |f - node| / 2)``."""
    return wp.max(0.0, 1.0 - wp.abs(f - float(node)) * 0.5)


@wp.kernel
def coarse_weights_rows(row_begin: int, tiles: int, A: wp.array4d(dtype=float), weights: wp.array4d(dtype=float),
                        spacing: int, inv_sigma2: float, grid_h: int, grid_w: int):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, A.shape[2])
    height = A.shape[1]
    width = A.shape[2]
    channels = A.shape[3]
    t = r // height
    y = r - t * height
    j0 = y // spacing
    fy = float(y) / float(spacing)
    for x in range(x_begin, x_end):
        i0 = x // spacing
        fx = float(x) / float(spacing)
        total = float(0.0)
        for iy in range(4):
            j = j0 + iy - 1
            by = tent(fy, j)
            py = wp.min(j * spacing, height - 1)
            for ix in range(4):
                i = i0 + ix - 1
                wk = float(0.0)
                if j >= 0 and j < grid_h and i >= 0 and i < grid_w:
                    px = wp.min(i * spacing, width - 1)
                    d2 = float(0.0)
                    for c in range(channels):
                        d = A[t, y, x, c] - A[t, py, px, c]
                        d2 += d * d
                    wk = by * tent(fx, i) * wp.exp(-wp.min(d2 * inv_sigma2, MAX_EXPONENT))
                weights[t, y, x, 4 * iy + ix] = wk
                total += wk
        inv = 1.0 / total
        for k in range(16):
            weights[t, y, x, k] = weights[t, y, x, k] * inv


@wp.kernel
def prolong_add_rows(row_begin: int, tiles: int, z: wp.array3d(dtype=float), weights: wp.array4d(dtype=float),
                     out: wp.array3d(dtype=float), spacing: int):
    # The pixels of a row between two node columns share their 4 x 4 nodes: read them
    # once per run of ``spacing`` pixels (clamped reads; off-grid taps have weight 0).
    # A row's runs are cut into ``tiles`` tiles (one per row on the CPU).
    r, run_begin, run_end = row_span(row_begin + wp.tid(), tiles, (out.shape[2] - 1) // spacing + 1)
    height = out.shape[1]
    width = out.shape[2]
    grid_h = z.shape[1]
    grid_w = z.shape[2]
    t = r // height
    y = r - t * height
    j0 = y // spacing
    for i0 in range(run_begin, run_end):
        nodes = wp.mat44()
        for iy in range(4):
            j = wp.clamp(j0 + iy - 1, 0, grid_h - 1)
            for ix in range(4):
                nodes[iy, ix] = z[t, j, wp.clamp(i0 + ix - 1, 0, grid_w - 1)]
        for x in range(i0 * spacing, wp.min((i0 + 1) * spacing, width)):
            acc = float(0.0)
            for iy in range(4):
                for ix in range(4):
                    acc += weights[t, y, x, 4 * iy + ix] * nodes[iy, ix]
            out[t, y, x] = out[t, y, x] + acc


# The CPU's prolongation: one row per kernel thread as a native loop over the
# row's pixels that the compiler vectorises (the 16 weights and nodes of each
# pixel read with gathers), summing each pixel's 16 products in the order of
# :func:`prolong_add_rows`, one rounding per product and per add: bit for bit
# the same.  ``z``, ``weights`` and ``out`` must be contiguous along their last
# axes (:func:`~ivkernels.kernels.warp._checks.native_rows`), else the kernel above runs.
_PROLONG_ROW = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
#if defined(__CUDA_ARCH__)
#define IVK_PROLONG_SIMD
#else
#define IVK_PROLONG_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
const int width = out.shape[2];
const int grid_h = z.shape[1];
const int grid_w = z.shape[2];
const int j0 = y / spacing;
const float* zr[4];
for (int iy = 0; iy < 4; ++iy) {
    int j = j0 + iy - 1;
    j = j < 0 ? 0 : (j > grid_h - 1 ? grid_h - 1 : j);
    zr[iy] = (const float*)((const char*)z.data + (size_t)t * z.strides[0] + (size_t)j * z.strides[1]);
}
const float* z0 = zr[0];
const float* z1 = zr[1];
const float* z2 = zr[2];
const float* z3 = zr[3];
const float* w = (const float*)((const char*)weights.data + (size_t)t * weights.strides[0] + (size_t)y * weights.strides[1]);
float* o = (float*)((char*)out.data + (size_t)t * out.strides[0] + (size_t)y * out.strides[1]);
const int chunk = 512;
int cols[4 * 512];
int run = 0;
int within = 0;
for (int begin = 0; begin < width; begin += chunk) {
    const int end = begin + chunk < width ? begin + chunk : width;
    // each pixel's four node columns, clamped to the grid
    for (int x = begin; x < end; ++x) {
        for (int ix = 0; ix < 4; ++ix) {
            int i = run + ix - 1;
            cols[4 * (x - begin) + ix] = i < 0 ? 0 : (i > grid_w - 1 ? grid_w - 1 : i);
        }
        if (++within == spacing) {
            within = 0;
            ++run;
        }
    }
    IVK_PROLONG_SIMD
    for (int x = begin; x < end; ++x) {
        const float* wx = w + 16 * (size_t)x;
        const int* c = cols + 4 * (x - begin);
        float acc = 0.0f;
#define IVK_TAP(ZR, K, IX) { const float p = wx[K] * ZR[c[IX]]; acc = acc + p; }
        IVK_TAP(z0, 0, 0) IVK_TAP(z0, 1, 1) IVK_TAP(z0, 2, 2) IVK_TAP(z0, 3, 3)
        IVK_TAP(z1, 4, 0) IVK_TAP(z1, 5, 1) IVK_TAP(z1, 6, 2) IVK_TAP(z1, 7, 3)
        IVK_TAP(z2, 8, 0) IVK_TAP(z2, 9, 1) IVK_TAP(z2, 10, 2) IVK_TAP(z2, 11, 3)
        IVK_TAP(z3, 12, 0) IVK_TAP(z3, 13, 1) IVK_TAP(z3, 14, 2) IVK_TAP(z3, 15, 3)
#undef IVK_TAP
        o[x] = o[x] + acc;
    }
}
#undef IVK_PROLONG_SIMD
}
"""


@wp.func_native(_PROLONG_ROW)
def prolong_add_row(z: wp.array3d(dtype=float), weights: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                    spacing: int, t: int, y: int):
    """Row ``y`` of frame ``t`` of :func:`prolong_add_rows` (CPU, contiguous rows)."""
    ...


@wp.kernel
def prolong_add_rows_cpu(row_begin: int, z: wp.array3d(dtype=float), weights: wp.array4d(dtype=float),
                         out: wp.array3d(dtype=float), spacing: int):
    t, y = frame_row(row_begin + wp.tid(), out.shape[1])
    prolong_add_row(z, weights, out, spacing, t, y)


@wp.kernel
def restrict_add_rows(row_begin: int, tiles: int, values: wp.array3d(dtype=float),
                      weights: wp.array4d(dtype=float), out: wp.array3d(dtype=float), spacing: int):
    # Each run of ``spacing`` pixels between two node columns sums its 16 node
    # contributions locally and adds them to the nodes once (runs cut into tiles as above).
    r, run_begin, run_end = row_span(row_begin + wp.tid(), tiles, (values.shape[2] - 1) // spacing + 1)
    height = values.shape[1]
    width = values.shape[2]
    grid_h = out.shape[1]
    grid_w = out.shape[2]
    t = r // height
    y = r - t * height
    j0 = y // spacing
    for i0 in range(run_begin, run_end):
        sums = wp.mat44()
        for x in range(i0 * spacing, wp.min((i0 + 1) * spacing, width)):
            v = values[t, y, x]
            for iy in range(4):
                for ix in range(4):
                    sums[iy, ix] = sums[iy, ix] + weights[t, y, x, 4 * iy + ix] * v
        for iy in range(4):
            j = j0 + iy - 1
            if j >= 0 and j < grid_h:
                for ix in range(4):
                    i = i0 + ix - 1
                    if i >= 0 and i < grid_w:
                        wp.atomic_add(out, t, j, i, sums[iy, ix])


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@wp.kernel
def node_samples_kernel(src: wp.array4d(dtype=float), out: wp.array4d(dtype=float), spacing: int):
    """``out[t, j, i] = src[t, min(j spacing, H - 1), min(i spacing, W - 1)]``, every channel."""
    t, j, i = wp.tid()
    y = wp.min(j * spacing, src.shape[1] - 1)
    x = wp.min(i * spacing, src.shape[2] - 1)
    for c in range(src.shape[3]):
        out[t, j, i, c] = src[t, y, x, c]


@host("node_samples")
def node_samples(src, out, spacing: int) -> None:
    """The guide at the nodes: what :func:`coarse_weights` of the next coarser level reads
    (the solver's nested levels, :class:`ivkernels.solver.coarse_basis.CoarseBasisProblem`),
    gathered on the device.

    Parameters
    ----------
    src : wp.array float32 (T, H, W, C).
    out : wp.array float32 (T, Hc, Wc, C), ``(Hc, Wc) = grid_shape(H, W, spacing)``, written:
        node ``(j, i)`` gets the pixel ``(min(j spacing, H - 1), min(i spacing, W - 1))``.
    spacing : pixels between nodes, >= 1.
    """
    if out.size:
        wp.launch(node_samples_kernel, dim=out.shape[:3], inputs=[src, out, spacing], device=src.device)


@host("coarse_weights")
def coarse_weights(A, weights, spacing: int, sigma: float) -> None:
    """Interpolation weights of the edge-aware coarse basis (on a GPU one pixel per
    thread: row tiles).

    Parameters
    ----------
    A : wp.array float32 (T, H, W, C), the guide (the log albedo), C >= 1.
    weights : wp.array float32 (T, H, W, 16), written: tap ``k = 4 iy + ix``
        is node ``(floor(y / spacing) + iy - 1, floor(x / spacing) + ix - 1)``;
        ``b_k exp(-min(|A(y, x) - A(node)|^2 / sigma^2, 30))`` normalised over
        the 16 taps, ``b_k`` the tents of both axes (0 off the grid).
    spacing : pixels between nodes, >= 1.
    sigma : albedo distance (in the units of ``A``) at which the affinity
        falls to ``1/e``; > 0.
    """
    t, h, w, _ = A.shape
    grid_h, grid_w = grid_shape(h, w, spacing)
    tiles = row_tiles(w, A.device)
    launch_rows(coarse_weights_rows, t * h * tiles,
                [tiles, A, weights, spacing, 1.0 / (sigma * sigma), grid_h, grid_w], device=A.device)


@host("prolong_add")
def prolong_add(z, weights, out, spacing: int) -> None:
    """``out += P z``: each pixel adds its 16 nodes' ``z``, weighted by ``weights``.

    Parameters
    ----------
    z : wp.array float32 (T, Hc, Wc), the coarse field (:func:`grid_shape`).
    weights : wp.array float32 (T, H, W, 16), from :func:`coarse_weights` (same ``spacing``).
    out : wp.array float32 (T, H, W), added into.  Must not overlap ``z``.
    spacing : pixels between nodes, as for the weights.
    """
    t, h, w, _ = weights.shape
    if native_rows(weights.device, z, weights, out):
        launch_rows(prolong_add_rows_cpu, t * h, [z, weights, out, spacing], device=weights.device)
        return
    tiles = row_tiles((w - 1) // spacing + 1, weights.device)
    launch_rows(prolong_add_rows, t * h * tiles, [tiles, z, weights, out, spacing], device=weights.device)


@host("restrict_add")
def restrict_add(values, weights, out, spacing: int) -> None:
    """``out += P^T values``, the transpose of :func:`prolong_add`.

    Parameters
    ----------
    values : wp.array float32 (T, H, W), a per-pixel field (the gradient in ``S``).
    weights : wp.array float32 (T, H, W, 16), from :func:`coarse_weights`.
    out : wp.array float32 (T, Hc, Wc), added into: each node gets ``weights *
        values`` of every pixel whose taps reach it.  Must not overlap ``values``.
    spacing : pixels between nodes, as for the weights.
    """
    t, h, w, _ = weights.shape
    tiles = row_tiles((w - 1) // spacing + 1, weights.device)
    launch_rows(restrict_add_rows, t * h * tiles, [tiles, values, weights, out, spacing], device=weights.device,
                align=h * tiles)
