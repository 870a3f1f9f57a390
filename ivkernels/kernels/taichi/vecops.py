"""Taichi mirror of :mod:`ivkernels.kernels.warp.vecops`: BLAS-1 operations on
flat float32 vectors for the optimiser, same host functions and signatures,
NumPy arrays passed as ``ti.types.ndarray()``.

As in the Warp module the vector is cut into chunks of :data:`CHUNK` elements
(parallel over chunks), and the reductions write one partial per chunk that
the host finishes, so both backends reduce in the same order.
"""
import numpy as np
import taichi as ti

from ivkernels.kernels.checks import check_basis_rows
from ivkernels.kernels.taichi._checks import check_array, check_vector

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


def dot(a, b) -> float:
    """``sum(a * b)`` as a Python float (float64 per chunk, summed on the host); see
    :func:`ivkernels.kernels.warp.vecops.dot` (NumPy arrays here)."""
    a = check_vector("a", a)
    b = check_vector("b", b, a.shape[0])
    partial = np.empty(_chunks(a.shape[0]), np.float64)
    dot_chunks(a, b, partial, CHUNK)
    return float(partial.sum())


def norm_inf(x) -> float:
    """``max |x|`` as a Python float."""
    x = check_vector("x", x)
    partial = np.empty(_chunks(x.shape[0]), np.float32)
    max_abs_chunks(x, partial, CHUNK)
    return float(partial.max())


def axpy(alpha: float, x, y) -> None:
    """``y += alpha * x`` (float32)."""
    x = check_vector("x", x)
    check_vector("y", y, x.shape[0], output=True)
    axpy_flat(float(alpha), x, y)


def scale(alpha: float, x) -> None:
    """``x *= alpha`` (float32)."""
    check_vector("x", x, output=True)
    scale_flat(float(alpha), x)


def lincomb(out, a: float, x, b: float, y) -> None:
    """``out = a * x + b * y`` (float32); ``out`` may be ``x`` or ``y``."""
    check_vector("out", out, output=True)
    x = check_vector("x", x, out.shape[0])
    y = check_vector("y", y, out.shape[0])
    lincomb_flat(out, float(a), x, float(b), y)


def copy(src, dst) -> None:
    """``dst[:] = src``."""
    src = check_vector("src", src)
    check_vector("dst", dst, src.shape[0], output=True)
    copy_flat(src, dst)


def fill(x, value: float) -> None:
    """``x[:] = value``."""
    check_vector("x", x, output=True)
    fill_flat(x, float(value))


def dots(basis, x, rows=None) -> np.ndarray:
    """``basis[rows] @ x`` as float64 in one pass; see :func:`ivkernels.kernels.warp.vecops.dots`."""
    x = check_vector("x", x)
    basis = check_array("basis", basis, (None, x.shape[0]), "(k, n)")
    rows, _ = check_basis_rows(basis.shape[0], rows)
    partial = np.empty((len(rows), _chunks(x.shape[0])), np.float64)
    basis_dots_chunks(basis, x, rows, partial, CHUNK)
    return partial.sum(axis=1)


def combine(out, basis, rows, coeffs) -> None:
    """``out = sum_r coeffs[r] * basis[rows[r]]``; see :func:`ivkernels.kernels.warp.vecops.combine`."""
    check_vector("out", out, output=True)
    basis = check_array("basis", basis, (None, out.shape[0]), "(k, n)")
    rows, coeffs = check_basis_rows(basis.shape[0], rows, coeffs)
    basis_combine_chunks(out, basis, rows, coeffs, CHUNK)
