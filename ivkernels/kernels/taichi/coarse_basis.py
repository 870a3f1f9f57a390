"""Taichi mirror of :mod:`ivkernels.kernels.warp.coarse_basis`: the edge-aware
coarse basis of the solver (per-pixel weights over 4 x 4 nodes, the
prolongation ``P z`` and its transpose), same host functions and signatures,
NumPy arrays passed as ``ti.types.ndarray()``.

Node ``j`` sits on pixel row ``min(j * spacing, H - 1)``; pixel ``y``'s taps
are the nodes ``floor(y / spacing) + iy - 1``, ``iy = 0..3``, tap ``k = 4 iy +
ix``, a tap off the grid has weight 0 (:func:`grid_shape`).  The weights and
the prolongation run in parallel over the ``T * H`` pixel rows; the
restriction gathers per node, in parallel over the ``T * Hc`` node rows, so
no two iterations write the same memory and no atomics are needed.
"""
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import MAX_EXPONENT, grid_shape
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.coarse_basis import FAMILY

host = implements(FAMILY, FRONT)

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)

@ti.func
def tent(f, node):
    """Weight along one axis of ``node`` for a pixel at ``f = p / spacing`` nodes: ``max(0, 1 - |f - node| / 2)``."""
    return ti.max(0.0, 1.0 - ti.abs(f - ti.cast(node, ti.f32)) * 0.5)


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@ti.kernel
def coarse_weights_rows(A: nd4, weights: nd4, spacing: ti.i32, inv_sigma2: ti.f32, grid_h: ti.i32,
                        grid_w: ti.i32):
    height = A.shape[1]
    width = A.shape[2]
    channels = A.shape[3]
    for r in range(A.shape[0] * height):
        t = r // height
        y = r - t * height
        j0 = y // spacing
        fy = ti.cast(y, ti.f32) / ti.cast(spacing, ti.f32)
        for x in range(width):
            i0 = x // spacing
            fx = ti.cast(x, ti.f32) / ti.cast(spacing, ti.f32)
            total = 0.0
            for iy in ti.static(range(4)):
                j = j0 + iy - 1
                for ix in ti.static(range(4)):
                    i = i0 + ix - 1
                    wk = 0.0
                    if j >= 0 and j < grid_h and i >= 0 and i < grid_w:
                        py = ti.min(j * spacing, height - 1)
                        px = ti.min(i * spacing, width - 1)
                        d2 = 0.0
                        for c in range(channels):
                            d = A[t, y, x, c] - A[t, py, px, c]
                            d2 += d * d
                        wk = tent(fy, j) * tent(fx, i) * ti.exp(
                            -ti.min(d2 * inv_sigma2, MAX_EXPONENT))
                    weights[t, y, x, 4 * iy + ix] = wk
                    total += wk
            inv = 1.0 / total
            for k in range(16):
                weights[t, y, x, k] = weights[t, y, x, k] * inv


@ti.kernel
def prolong_add_rows(z: nd3, weights: nd4, out: nd3, spacing: ti.i32):
    height = out.shape[1]
    width = out.shape[2]
    grid_h = z.shape[1]
    grid_w = z.shape[2]
    for r in range(out.shape[0] * height):
        t = r // height
        y = r - t * height
        j0 = y // spacing
        for x in range(width):
            i0 = x // spacing
            acc = 0.0
            for iy in ti.static(range(4)):
                j = ti.math.clamp(j0 + iy - 1, 0, grid_h - 1)
                for ix in ti.static(range(4)):
                    i = ti.math.clamp(i0 + ix - 1, 0, grid_w - 1)
                    acc += weights[t, y, x, 4 * iy + ix] * z[t, j, i]
            out[t, y, x] = out[t, y, x] + acc


@ti.kernel
def restrict_add_rows(values: nd3, weights: nd4, out: nd3, spacing: ti.i32):
    height = values.shape[1]
    width = values.shape[2]
    grid_h = out.shape[1]
    grid_w = out.shape[2]
    for r in range(out.shape[0] * grid_h):
        t = r // grid_h
        j = r - t * grid_h
        for i in range(grid_w):
            acc = 0.0
            # tap (iy, ix) of node (j, i) is read by the pixels of the block whose
            # floor(y / spacing) = j - iy + 1 and floor(x / spacing) = i - ix + 1
            for iy in ti.static(range(4)):
                y_block = (j - iy + 1) * spacing
                for y in range(ti.max(y_block, 0), ti.min(y_block + spacing, height)):
                    for ix in ti.static(range(4)):
                        x_block = (i - ix + 1) * spacing
                        for x in range(ti.max(x_block, 0), ti.min(x_block + spacing, width)):
                            acc += weights[t, y, x, 4 * iy + ix] * values[t, y, x]
            out[t, j, i] = out[t, j, i] + acc


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@ti.kernel
def node_samples_kernel(src: nd4, out: nd4, spacing: ti.i32):
    for t, j, i in ti.ndrange(out.shape[0], out.shape[1], out.shape[2]):
        y = ti.min(j * spacing, src.shape[1] - 1)
        x = ti.min(i * spacing, src.shape[2] - 1)
        for c in range(src.shape[3]):
            out[t, j, i, c] = src[t, y, x, c]


@host("node_samples")
def node_samples(src, out, spacing: int) -> None:
    """The guide at the nodes; see :func:`ivkernels.kernels.warp.coarse_basis.node_samples`."""
    if out.size:
        node_samples_kernel(src, out, spacing)


@host("coarse_weights")
def coarse_weights(A, weights, spacing: int, sigma: float) -> None:
    """Interpolation weights of the edge-aware coarse basis; see
    :func:`ivkernels.kernels.warp.coarse_basis.coarse_weights` (NumPy arrays here).

    ``A`` float32 (T, H, W, C), the guide (the log albedo); ``weights`` float32
    (T, H, W, 16), written: tap ``k = 4 iy + ix`` is node ``(floor(y / spacing)
    + iy - 1, floor(x / spacing) + ix - 1)``, ``b_k exp(-min(|A(y, x) -
    A(node)|^2 / sigma^2, 30))`` normalised over the 16 taps, ``b_k`` the tents
    of both axes (0 off the grid); ``spacing`` pixels between nodes, >= 1;
    ``sigma`` the albedo distance (in the units of ``A``) at which the affinity
    falls to ``1/e``, > 0.
    """
    t, h, w, _ = A.shape
    if weights.size:
        grid_h, grid_w = grid_shape(h, w, spacing)
        coarse_weights_rows(A, weights, spacing, 1.0 / (sigma * sigma), grid_h, grid_w)


@host("prolong_add")
def prolong_add(z, weights, out, spacing: int) -> None:
    """``out += P z``: each pixel adds its 16 nodes' ``z``, weighted by ``weights``; see
    :func:`ivkernels.kernels.warp.coarse_basis.prolong_add` (NumPy arrays here).

    ``z`` float32 (T, Hc, Wc), the coarse field (:func:`grid_shape`);
    ``weights`` float32 (T, H, W, 16) from :func:`coarse_weights` (same
    ``spacing``); ``out`` float32 (T, H, W), added into, must not overlap ``z``.
    """
    if out.size:
        prolong_add_rows(z, weights, out, spacing)


@host("restrict_add")
def restrict_add(values, weights, out, spacing: int) -> None:
    """``out += P^T values``, the transpose of :func:`prolong_add`, gathered per node; see
    :func:`ivkernels.kernels.warp.coarse_basis.restrict_add` (NumPy arrays here).

    ``values`` float32 (T, H, W), a per-pixel field (the gradient in ``S``);
    ``weights`` float32 (T, H, W, 16) from :func:`coarse_weights`; ``out``
    float32 (T, Hc, Wc), added into: each node sums ``weights * values`` over
    the pixels whose taps reach it, must not overlap ``values``.
    """
    if out.size and values.size:
        restrict_add_rows(values, weights, out, spacing)
