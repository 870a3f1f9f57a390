"""BLAS-1 operations on flat float32 vectors, for the optimiser (L-BFGS, CG).

The solver stacks its unknowns (albedo and shading of every frame) into one
flat float32 vector of length ``n``; these functions are the vector algebra of
the optimiser on it.  The vector is cut into chunks of :data:`CHUNK` elements
on the CPU, one kernel thread per chunk, launched through :func:`launch_rows`
so two CPU threads share the work; on a GPU the chunks are
:data:`CUDA_CHUNK` elements (:data:`CUDA_REDUCTION_CHUNK` for reductions).

:func:`dots` and :func:`combine` work on a basis of vectors stored as the
rows of one (k, n) array: all dot products of a vector with chosen rows, and
a linear combination of chosen rows, each in one pass over memory (the
optimiser's L-BFGS direction is such a combination).

Reductions (:func:`dot`, :func:`dots`, :func:`norm_inf`) write one partial result per chunk
and finish on the host: the result depends on the chunking only, never on the
number of threads.

Contiguous vectors are read and written as ``wp.vec4`` (one address
computation per four elements), with the last ``n % 4`` elements as scalars;
the reductions keep four independent accumulators (float64 for :func:`dot`).
On the CPU, :func:`dots` and :func:`combine` run as native loops with the same
accumulators and order (:func:`basis_dots_chunk`, :func:`basis_combine_chunk`:
9 rows of 640x480x8, 2 threads: 13 -> 5 ms and 8 -> 2 ms, bit for bit the same).
"""
from __future__ import annotations

import threading

import numpy as np

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import gpu_layout, launch_rows
from ivkernels.kernels.reference.vecops import FAMILY
from ivkernels.kernels.warp._checks import FRONT, native_rows

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

#: Elements per kernel thread on the CPU.
CHUNK = 4096

#: Elements per kernel thread on a GPU: one ``vec4`` for the element-wise
#: operations (a warp's loads are then contiguous), more for the reductions so
#: their partial results stay few (the CPU's 4096 leave a 640x480x8 vector to
#: a few hundred threads: 0.1 % of an H200, perf/RESULTS.md).
CUDA_CHUNK = 4
CUDA_REDUCTION_CHUNK = 256


# ----------------------------------------------------------------------------
# Kernels (one thread per chunk of CHUNK elements)
#
# Each kernel takes the vector both as float32 (``a``) and, where it is
# contiguous, as a ``wp.vec4`` view of its first ``4 * (n // 4)`` elements
# (``a4``; empty otherwise).  A chunk runs over its part of the view, then
# over its elements at or beyond ``4 * a4.shape[0]`` as scalars.
# ----------------------------------------------------------------------------

@wp.func
def chunk_begin(k: int, chunk: int):
    return k * chunk


@wp.func
def chunk_end(k: int, chunk: int, n: int):
    return wp.min(k * chunk + chunk, n)


@wp.func
def vec_range_end(k: int, chunk: int, n4: int):
    """End (exclusive, in vec4 units) of chunk ``k``'s part of a view of ``n4`` vec4."""
    return wp.min((k * chunk + chunk) // 4, n4)


@wp.func
def tail_begin(k: int, chunk: int, n4: int):
    """First element of chunk ``k`` not covered by the vec4 view."""
    return wp.max(k * chunk, 4 * n4)


@wp.kernel
def dot_chunks(row_begin: int, a: wp.array(dtype=float), b: wp.array(dtype=float),
               a4: wp.array(dtype=wp.vec4), b4: wp.array(dtype=wp.vec4),
               partial: wp.array(dtype=wp.float64), chunk: int):
    k = row_begin + wp.tid()
    n4 = a4.shape[0]
    acc0 = wp.float64(0.0)
    acc1 = wp.float64(0.0)
    acc2 = wp.float64(0.0)
    acc3 = wp.float64(0.0)
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        u = a4[i]
        v = b4[i]
        acc0 += wp.float64(u[0]) * wp.float64(v[0])
        acc1 += wp.float64(u[1]) * wp.float64(v[1])
        acc2 += wp.float64(u[2]) * wp.float64(v[2])
        acc3 += wp.float64(u[3]) * wp.float64(v[3])
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, a.shape[0])):
        acc0 += wp.float64(a[i]) * wp.float64(b[i])
    partial[k] = (acc0 + acc1) + (acc2 + acc3)


@wp.kernel
def max_abs_chunks(row_begin: int, x: wp.array(dtype=float), x4: wp.array(dtype=wp.vec4),
                   partial: wp.array(dtype=float), chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    m0 = float(0.0)
    m1 = float(0.0)
    m2 = float(0.0)
    m3 = float(0.0)
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        v = x4[i]
        m0 = wp.max(m0, wp.abs(v[0]))
        m1 = wp.max(m1, wp.abs(v[1]))
        m2 = wp.max(m2, wp.abs(v[2]))
        m3 = wp.max(m3, wp.abs(v[3]))
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        m0 = wp.max(m0, wp.abs(x[i]))
    partial[k] = wp.max(wp.max(m0, m1), wp.max(m2, m3))


@wp.kernel
def axpy_chunks(row_begin: int, alpha: float, x: wp.array(dtype=float), y: wp.array(dtype=float),
                x4: wp.array(dtype=wp.vec4), y4: wp.array(dtype=wp.vec4), chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        y4[i] = y4[i] + alpha * x4[i]
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        y[i] = y[i] + alpha * x[i]


@wp.kernel
def scale_chunks(row_begin: int, alpha: float, x: wp.array(dtype=float), x4: wp.array(dtype=wp.vec4), chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        x4[i] = alpha * x4[i]
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        x[i] = alpha * x[i]


@wp.kernel
def multiply_chunks(row_begin: int, x: wp.array(dtype=float), y: wp.array(dtype=float),
                    x4: wp.array(dtype=wp.vec4), y4: wp.array(dtype=wp.vec4), chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        x4[i] = wp.cw_mul(x4[i], y4[i])
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        x[i] = x[i] * y[i]


@wp.kernel
def lincomb_chunks(row_begin: int, out: wp.array(dtype=float), a: float, x: wp.array(dtype=float),
                   b: float, y: wp.array(dtype=float), out4: wp.array(dtype=wp.vec4),
                   x4: wp.array(dtype=wp.vec4), y4: wp.array(dtype=wp.vec4), chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        out4[i] = a * x4[i] + b * y4[i]
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        out[i] = a * x[i] + b * y[i]


@wp.kernel
def copy_chunks(row_begin: int, src: wp.array(dtype=float), dst: wp.array(dtype=float),
                src4: wp.array(dtype=wp.vec4), dst4: wp.array(dtype=wp.vec4), chunk: int):
    k = row_begin + wp.tid()
    n4 = src4.shape[0]
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        dst4[i] = src4[i]
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, src.shape[0])):
        dst[i] = src[i]


@wp.kernel
def fill_chunks(row_begin: int, x: wp.array(dtype=float), x4: wp.array(dtype=wp.vec4), value: float, chunk: int):
    k = row_begin + wp.tid()
    n4 = x4.shape[0]
    v = wp.vec4(value, value, value, value)
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        x4[i] = v
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        x[i] = value


@wp.func
def basis_chunk_dot(basis: wp.array2d(dtype=float), x: wp.array(dtype=float),
                    basis4: wp.array2d(dtype=wp.vec4), x4: wp.array(dtype=wp.vec4), j: int, k: int, chunk: int):
    """Sum over chunk ``k`` of ``basis[j] * x``: float64 products, four accumulators.

    The loop of :func:`dot_chunks` on a row.  It is written out in both on purpose: a
    shared ``wp.func`` taking 1-D arrays (``basis[j]`` a row view) gives the same bits but
    made ``vecops.dot`` 15-20% slower on the CPU (``perf/bench_kernels.py --only
    vecops.dot``, 12.8-13.1 against 15.0-15.2 ms on one thread)."""
    n4 = x4.shape[0]
    acc0 = wp.float64(0.0)
    acc1 = wp.float64(0.0)
    acc2 = wp.float64(0.0)
    acc3 = wp.float64(0.0)
    for i in range(chunk_begin(k, chunk) // 4, vec_range_end(k, chunk, n4)):
        u = basis4[j, i]
        v = x4[i]
        acc0 += wp.float64(u[0]) * wp.float64(v[0])
        acc1 += wp.float64(u[1]) * wp.float64(v[1])
        acc2 += wp.float64(u[2]) * wp.float64(v[2])
        acc3 += wp.float64(u[3]) * wp.float64(v[3])
    for i in range(tail_begin(k, chunk, n4), chunk_end(k, chunk, x.shape[0])):
        acc0 += wp.float64(basis[j, i]) * wp.float64(x[i])
    return (acc0 + acc1) + (acc2 + acc3)


@wp.kernel
def basis_dots_chunks(row_begin: int, basis: wp.array2d(dtype=float), x: wp.array(dtype=float),
                      basis4: wp.array2d(dtype=wp.vec4), x4: wp.array(dtype=wp.vec4),
                      rows: wp.array(dtype=int), partial: wp.array2d(dtype=wp.float64), chunk: int):
    """``partial[r, k] = sum over chunk k of basis[rows[r]] * x`` (the CPU's layout: one
    thread per chunk, so the chunk of ``x`` stays in cache while the rows stream past it)."""
    k = row_begin + wp.tid()
    for r in range(rows.shape[0]):
        partial[r, k] = basis_chunk_dot(basis, x, basis4, x4, rows[r], k, chunk)


@wp.kernel
def basis_dots_cells(row_begin: int, basis: wp.array2d(dtype=float), x: wp.array(dtype=float),
                     basis4: wp.array2d(dtype=wp.vec4), x4: wp.array(dtype=wp.vec4),
                     rows: wp.array(dtype=int), partial: wp.array2d(dtype=wp.float64), chunk: int):
    """The same partial sums in a GPU's layout: one thread per (row, chunk) cell."""
    cell = row_begin + wp.tid()
    r = cell // partial.shape[1]
    k = cell - r * partial.shape[1]
    partial[r, k] = basis_chunk_dot(basis, x, basis4, x4, rows[r], k, chunk)


@wp.kernel
def basis_combine_chunks(row_begin: int, out: wp.array(dtype=float), basis: wp.array2d(dtype=float),
                         out4: wp.array(dtype=wp.vec4), basis4: wp.array2d(dtype=wp.vec4),
                         rows: wp.array(dtype=int), coeffs: wp.array(dtype=float), chunk: int):
    """``out = sum_r coeffs[r] * basis[rows[r]]`` over chunk k (the chunk of
    ``out`` stays in cache while the rows stream past it)."""
    k = row_begin + wp.tid()
    n4 = out4.shape[0]
    i_begin = chunk_begin(k, chunk) // 4
    i_end = vec_range_end(k, chunk, n4)
    t_begin = tail_begin(k, chunk, n4)
    t_end = chunk_end(k, chunk, out.shape[0])
    zero = wp.vec4(0.0, 0.0, 0.0, 0.0)
    for i in range(i_begin, i_end):
        out4[i] = zero
    for i in range(t_begin, t_end):
        out[i] = 0.0
    for r in range(rows.shape[0]):
        j = rows[r]
        c = coeffs[r]
        if c != 0.0:
            for i in range(i_begin, i_end):
                out4[i] = out4[i] + c * basis4[j, i]
            for i in range(t_begin, t_end):
                out[i] = out[i] + c * basis[j, i]


# The CPU's basis dots and combination: one chunk per kernel thread as native
# loops.  The dots keep the kernels' four float64 accumulators (element ``i``
# into accumulator ``i mod 4``, the tail into the first) and their final sum;
# the combination adds the rows in the kernels' order; no product is fused
# into an add.  Bit for bit :func:`basis_dots_chunks` and
# :func:`basis_combine_chunks`, for contiguous vectors.
_BASIS_DOTS_CHUNK = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
const int n = x.shape[0];
const int n4 = n / 4;       // the elements the kernels' vec4 view covers, over 4 (x is contiguous)
const float* xv = (const float*)x.data;
const float* bv = (const float*)basis.data;
const int begin = k * chunk;
int vend = (k * chunk + chunk) / 4;
vend = 4 * (vend < n4 ? vend : n4);
int tail = 4 * n4 > begin ? 4 * n4 : begin;
const int end = begin + chunk < n ? begin + chunk : n;
for (int r = 0; r < rows.shape[0]; ++r) {
    const float* b = bv + (size_t)((const int*)rows.data)[r] * (size_t)n;
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
    for (int i = begin; i < vend; i += 4) {
        const double p0 = (double)b[i] * (double)xv[i];
        const double p1 = (double)b[i + 1] * (double)xv[i + 1];
        const double p2 = (double)b[i + 2] * (double)xv[i + 2];
        const double p3 = (double)b[i + 3] * (double)xv[i + 3];
        a0 = a0 + p0;
        a1 = a1 + p1;
        a2 = a2 + p2;
        a3 = a3 + p3;
    }
    for (int i = tail; i < end; ++i) {
        const double p = (double)b[i] * (double)xv[i];
        a0 = a0 + p;
    }
    const double s01 = a0 + a1;
    const double s23 = a2 + a3;
    *(double*)((char*)partial.data + (size_t)r * partial.strides[0] + (size_t)k * partial.strides[1]) = s01 + s23;
}
}
"""

_BASIS_COMBINE_CHUNK = r"""
{
#if !defined(__CUDA_ARCH__)
#pragma clang fp contract(off)
#endif
#if defined(__CUDA_ARCH__)
#define IVK_VEC_SIMD
#else
#define IVK_VEC_SIMD _Pragma("clang loop vectorize(assume_safety)")
#endif
const int n = out.shape[0];
float* o = (float*)out.data;
const float* bv = (const float*)basis.data;
const int begin = k * chunk;
const int end = begin + chunk < n ? begin + chunk : n;
IVK_VEC_SIMD
for (int i = begin; i < end; ++i)
    o[i] = 0.0f;
for (int r = 0; r < rows.shape[0]; ++r) {
    const float c = ((const float*)coeffs.data)[r];
    if (c != 0.0f) {
        const float* b = bv + (size_t)((const int*)rows.data)[r] * (size_t)n;
        IVK_VEC_SIMD
        for (int i = begin; i < end; ++i) {
            const float p = c * b[i];
            o[i] = o[i] + p;
        }
    }
}
#undef IVK_VEC_SIMD
}
"""


@wp.func_native(_BASIS_DOTS_CHUNK)
def basis_dots_chunk(basis: wp.array2d(dtype=float), x: wp.array(dtype=float), rows: wp.array(dtype=int),
                     partial: wp.array2d(dtype=wp.float64), k: int, chunk: int):
    """Chunk ``k`` of :func:`basis_dots_chunks` (CPU, contiguous)."""
    ...


@wp.func_native(_BASIS_COMBINE_CHUNK)
def basis_combine_chunk(out: wp.array(dtype=float), basis: wp.array2d(dtype=float), rows: wp.array(dtype=int),
                        coeffs: wp.array(dtype=float), k: int, chunk: int):
    """Chunk ``k`` of :func:`basis_combine_chunks` (CPU, contiguous)."""
    ...


@wp.kernel
def basis_dots_chunks_cpu(row_begin: int, basis: wp.array2d(dtype=float), x: wp.array(dtype=float),
                          rows: wp.array(dtype=int), partial: wp.array2d(dtype=wp.float64), chunk: int):
    basis_dots_chunk(basis, x, rows, partial, row_begin + wp.tid(), chunk)


@wp.kernel
def basis_combine_chunks_cpu(row_begin: int, out: wp.array(dtype=float), basis: wp.array2d(dtype=float),
                             rows: wp.array(dtype=int), coeffs: wp.array(dtype=float), chunk: int):
    basis_combine_chunk(out, basis, rows, coeffs, row_begin + wp.tid(), chunk)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _chunk(device, reduction: bool = False) -> int:
    """Elements per thread on ``device`` (a multiple of 4): :data:`CHUNK` on the CPU,
    :data:`CUDA_CHUNK` or, for a reduction, :data:`CUDA_REDUCTION_CHUNK` on a GPU."""
    if not gpu_layout(device):
        return CHUNK
    return CUDA_REDUCTION_CHUNK if reduction else CUDA_CHUNK


def _chunks(n: int, chunk: int) -> int:
    return (n + chunk - 1) // chunk


_VIEW_CACHE_SIZE = 64
_view_cache: dict = {}
_view_lock = threading.Lock()


def _vec4(*arrays):
    """``wp.vec4`` views of the first ``4 * (n // 4)`` elements of each array, or
    empty vec4 arrays (everything then runs as scalars) unless all are contiguous.

    A view is a pure function of (device, address, length), so views are cached
    by that key: building one costs more than a small vector's whole operation.
    """
    n4 = arrays[0].shape[0] // 4
    if n4 == 0 or not all(a.is_contiguous for a in arrays):
        n4 = 0
    if n4 == 0:
        return [_cached_view((str(a.device), 0, 0), lambda a=a: wp.empty(0, dtype=wp.vec4, device=a.device))
                for a in arrays]
    return [_cached_view((str(a.device), a.ptr, n4),
                         lambda a=a: wp.array(ptr=a.ptr, dtype=wp.vec4, shape=(n4,), device=a.device))
            for a in arrays]


def _cached_view(key: tuple, make):
    """A view (a pure function of ``key``: device, address, shape) from a small bounded cache."""
    view = _view_cache.get(key)
    if view is None:
        view = make()
        with _view_lock:
            if len(_view_cache) >= _VIEW_CACHE_SIZE:
                _view_cache.clear()
            _view_cache[key] = view
    return view


@host("dot")
def dot(a, b) -> float:
    """``sum(a * b)`` as a Python float: float64 products and sums per chunk, chunks summed on the host.

    ``a``, ``b``: 1-D float32 wp.arrays of equal length n >= 1.
    """
    n, chunk = a.shape[0], _chunk(a.device, reduction=True)
    partial = wp.empty(_chunks(n, chunk), dtype=wp.float64, device=a.device)
    launch_rows(dot_chunks, _chunks(n, chunk), [a, b, *_vec4(a, b), partial, chunk], device=a.device)
    return float(partial.numpy().sum())


@host("norm_inf")
def norm_inf(x) -> float:
    """``max |x|`` as a Python float.  ``x``: 1-D float32 wp.array, n >= 1."""
    n, chunk = x.shape[0], _chunk(x.device, reduction=True)
    partial = wp.empty(_chunks(n, chunk), dtype=wp.float32, device=x.device)
    launch_rows(max_abs_chunks, _chunks(n, chunk), [x, *_vec4(x), partial, chunk], device=x.device)
    return float(partial.numpy().max())


@host("axpy")
def axpy(alpha: float, x, y) -> None:
    """``y += alpha * x`` (float32).  ``x``, ``y``: 1-D float32 wp.arrays of equal length."""
    n, chunk = x.shape[0], _chunk(x.device)
    launch_rows(axpy_chunks, _chunks(n, chunk), [float(alpha), x, y, *_vec4(x, y), chunk], device=x.device)


@host("scale")
def scale(alpha: float, x) -> None:
    """``x *= alpha`` (float32).  ``x``: 1-D float32 wp.array."""
    n, chunk = x.shape[0], _chunk(x.device)
    launch_rows(scale_chunks, _chunks(n, chunk), [float(alpha), x, *_vec4(x), chunk], device=x.device)


@host("multiply")
def multiply(x, y) -> None:
    """``x *= y``, element by element (float32); ``y`` may be ``x``.

    ``x``, ``y``: 1-D float32 wp.arrays of equal length.
    """
    n, chunk = x.shape[0], _chunk(x.device)
    launch_rows(multiply_chunks, _chunks(n, chunk), [x, y, *_vec4(x, y), chunk], device=x.device)


@host("lincomb")
def lincomb(out, a: float, x, b: float, y) -> None:
    """``out = a * x + b * y`` (float32); ``out`` may be ``x`` or ``y``.

    ``out``, ``x``, ``y``: 1-D float32 wp.arrays of equal length.
    """
    n, chunk = out.shape[0], _chunk(out.device)
    launch_rows(lincomb_chunks, _chunks(n, chunk), [out, float(a), x, float(b), y, *_vec4(out, x, y), chunk],
                device=out.device)


@host("copy")
def copy(src, dst) -> None:
    """``dst[:] = src``.  1-D float32 wp.arrays of equal length."""
    n, chunk = src.shape[0], _chunk(src.device)
    launch_rows(copy_chunks, _chunks(n, chunk), [src, dst, *_vec4(src, dst), chunk], device=src.device)


@host("fill")
def fill(x, value: float) -> None:
    """``x[:] = value``.  ``x``: 1-D float32 wp.array."""
    n, chunk = x.shape[0], _chunk(x.device)
    launch_rows(fill_chunks, _chunks(n, chunk), [x, *_vec4(x), float(value), chunk], device=x.device)


def _basis_vec4(basis, n4: int):
    """A (k, n4) ``wp.vec4`` view of the first ``4 * n4`` columns of a contiguous (k, n) basis."""
    k, n = basis.shape
    if n4 == 0:
        return wp.empty((0, 0), dtype=wp.vec4, device=basis.device)
    return _cached_view((str(basis.device), basis.ptr, k, n, n4),
                        lambda: wp.array(ptr=basis.ptr, dtype=wp.vec4, shape=(k, n4), strides=(4 * n, 16),
                                         device=basis.device))


def _basis_rows(basis, rows, coeffs=None):
    """A checked (k, n) float32 basis, its row indices (int32) and coefficients (float32, or ``None``)
    as the kernels take them: the basis (a contiguous copy if it is not contiguous: the kernels
    read its rows as ``wp.vec4``), the rows as an int32 wp.array and, when given, the
    coefficients as a float32 wp.array.
    """
    out = [basis.contiguous(), wp.array(rows, dtype=wp.int32, device=basis.device)]
    if coeffs is not None:
        out.append(wp.array(coeffs, dtype=wp.float32, device=basis.device))
    return out


@host("dots")
def dots(basis, x, rows=None) -> np.ndarray:
    """Dot products of ``x`` with rows of ``basis`` in one pass over memory.

    basis : (k, n) float32 wp.array, the vectors as rows (copied first if not contiguous).
    x : 1-D float32 wp.array of length n (may be a row of ``basis``).
    rows : row indices to use (default all k).
    Returns (len(rows),) float64 NumPy array, ``basis[rows] @ x``, each with
    float64 products and sums per chunk (as :func:`dot`).  On a GPU one thread
    per (row, chunk), on the CPU one per chunk over all rows: the same sums.
    """
    n, chunk = x.shape[0], _chunk(x.device, reduction=True)
    basis, rows_wp = _basis_rows(basis, rows)
    n_rows, n_chunks = rows_wp.shape[0], _chunks(n, chunk)
    partial = wp.empty((n_rows, n_chunks), dtype=wp.float64, device=x.device)
    if native_rows(x.device, x):
        launch_rows(basis_dots_chunks_cpu, n_chunks, [basis, x, rows_wp, partial, chunk], device=x.device)
        return partial.numpy().sum(axis=1)
    x4, = _vec4(x)
    args = [basis, x, _basis_vec4(basis, x4.shape[0]), x4, rows_wp, partial, chunk]
    if gpu_layout(x.device):
        launch_rows(basis_dots_cells, n_rows * n_chunks, args, device=x.device)
    else:
        launch_rows(basis_dots_chunks, n_chunks, args, device=x.device)
    return partial.numpy().sum(axis=1)


@host("combine")
def combine(out, basis, rows, coeffs) -> None:
    """``out = sum_r coeffs[r] * basis[rows[r]]`` (float32) in one pass over memory.

    out : 1-D float32 wp.array of length n, not a row of ``basis``.
    basis : (k, n) float32 wp.array (copied first if not contiguous).
    rows, coeffs : row indices and their (finite) coefficients, equal lengths.
    """
    n, chunk = out.shape[0], _chunk(out.device)
    basis, rows_wp, coeffs_wp = _basis_rows(basis, rows, coeffs)
    if native_rows(out.device, out):
        launch_rows(basis_combine_chunks_cpu, _chunks(n, chunk), [out, basis, rows_wp, coeffs_wp, chunk],
                    device=out.device)
        return
    out4, = _vec4(out)
    launch_rows(basis_combine_chunks, _chunks(n, chunk), [out, basis, out4, _basis_vec4(basis, out4.shape[0]),
                                                          rows_wp, coeffs_wp, chunk], device=out.device)
