"""Taichi mirror of :mod:`ivkernels.kernels.warp.vecops`: BLAS-1 operations on
flat float32 vectors for the optimiser, same host functions and signatures,
NumPy arrays passed as ``ti.types.ndarray()``.

As in the Warp module the vector is cut into chunks of :data:`CHUNK` elements
(parallel over chunks), and the reductions write one partial per chunk that
the host finishes, so both backends reduce in the same order.
"""
import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.vecops import FAMILY

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd1_i32 = ti.types.ndarray(dtype=ti.i32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd2_f64 = ti.types.ndarray(dtype=ti.f64, ndim=2)

#: Elements per parallel iteration (the same as the Warp module's).
CHUNK = 4096


@ti.kernel
def dot_chunks(a: nd1, b: nd1, partial: nd1_f64, chunk: ti.i32):
    for k in range(partial.shape[0]):
        begin = k * chunk
        end = ti.min(begin + chunk, a.shape[0])
        acc = ti.f64(0.0)
        for i in range(begin, end):
            acc += ti.cast(a[i], ti.f64) * ti.cast(b[i], ti.f64)
        partial[k] = acc


@ti.kernel
def max_abs_chunks(x: nd1, partial: nd1, chunk: ti.i32):
    for k in range(partial.shape[0]):
        begin = k * chunk
        end = ti.min(begin + chunk, x.shape[0])
        m = 0.0
        for i in range(begin, end):
            m = ti.max(m, ti.abs(x[i]))
        partial[k] = m


@ti.kernel
def axpy_flat(alpha: ti.f32, x: nd1, y: nd1):
    for i in range(x.shape[0]):
        y[i] = y[i] + alpha * x[i]


@ti.kernel
def scale_flat(alpha: ti.f32, x: nd1):
    for i in range(x.shape[0]):
        x[i] = alpha * x[i]


@ti.kernel
def multiply_flat(x: nd1, y: nd1):
    for i in range(x.shape[0]):
        x[i] = x[i] * y[i]


@ti.kernel
def lincomb_flat(out: nd1, a: ti.f32, x: nd1, b: ti.f32, y: nd1):
    for i in range(x.shape[0]):
        out[i] = a * x[i] + b * y[i]


@ti.kernel
def copy_flat(src: nd1, dst: nd1):
    for i in range(src.shape[0]):
        dst[i] = src[i]


@ti.kernel
def fill_flat(x: nd1, value: ti.f32):
    for i in range(x.shape[0]):
        x[i] = value


@ti.kernel
def basis_dots_chunks(basis: nd2, x: nd1, rows: nd1_i32, partial: nd2_f64, chunk: ti.i32):
    for k in range(partial.shape[1]):
        begin = k * chunk
        end = ti.min(begin + chunk, x.shape[0])
        for r in range(rows.shape[0]):
            j = rows[r]
            acc = ti.f64(0.0)
            for i in range(begin, end):
                acc += ti.cast(basis[j, i], ti.f64) * ti.cast(x[i], ti.f64)
            partial[r, k] = acc


@ti.kernel
def basis_combine_chunks(out: nd1, basis: nd2, rows: nd1_i32, coeffs: nd1, chunk: ti.i32):
    for k in range((out.shape[0] + chunk - 1) // chunk):
        begin = k * chunk
        end = ti.min(begin + chunk, out.shape[0])
        for i in range(begin, end):
            out[i] = 0.0
        for r in range(rows.shape[0]):
            j = rows[r]
            c = coeffs[r]
            if c != 0.0:
                for i in range(begin, end):
                    out[i] = out[i] + c * basis[j, i]


def _chunks(n: int) -> int:
    return (n + CHUNK - 1) // CHUNK


@host("dot")
def dot(a, b) -> float:
    """``sum(a * b)`` as a Python float (float64 per chunk, summed on the host); see
    :func:`ivkernels.kernels.warp.vecops.dot` (NumPy arrays here)."""
    partial = np.empty(_chunks(a.shape[0]), np.float64)
    dot_chunks(a, b, partial, CHUNK)
    return float(partial.sum())


@host("norm_inf")
def norm_inf(x) -> float:
    """``max |x|`` as a Python float."""
    partial = np.empty(_chunks(x.shape[0]), np.float32)
    max_abs_chunks(x, partial, CHUNK)
    return float(partial.max())


@host("axpy")
def axpy(alpha: float, x, y) -> None:
    """``y += alpha * x`` (float32)."""
    axpy_flat(float(alpha), x, y)


@host("scale")
def scale(alpha: float, x) -> None:
    """``x *= alpha`` (float32)."""
    scale_flat(float(alpha), x)


@host("multiply")
def multiply(x, y) -> None:
    """``x *= y``, element by element (float32); ``y`` may be ``x``."""
    multiply_flat(x, y)


@host("lincomb")
def lincomb(out, a: float, x, b: float, y) -> None:
    """``out = a * x + b * y`` (float32); ``out`` may be ``x`` or ``y``."""
    lincomb_flat(out, float(a), x, float(b), y)


@host("copy")
def copy(src, dst) -> None:
    """``dst[:] = src``."""
    copy_flat(src, dst)


@host("fill")
def fill(x, value: float) -> None:
    """``x[:] = value``."""
    fill_flat(x, float(value))


@host("dots")
def dots(basis, x, rows=None) -> np.ndarray:
    """``basis[rows] @ x`` as float64 in one pass; see :func:`ivkernels.kernels.warp.vecops.dots`."""
    partial = np.empty((len(rows), _chunks(x.shape[0])), np.float64)
    basis_dots_chunks(basis, x, rows, partial, CHUNK)
    return partial.sum(axis=1)


@host("combine")
def combine(out, basis, rows, coeffs) -> None:
    """``out = sum_r coeffs[r] * basis[rows[r]]``; see :func:`ivkernels.kernels.warp.vecops.combine`."""
    basis_combine_chunks(out, basis, rows, coeffs, CHUNK)
