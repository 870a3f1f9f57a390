"""BLAS-1 operations on flat float32 vectors, for the optimiser (L-BFGS, CG).

The solver stacks its unknowns (albedo and shading of every frame) into one
flat float32 vector of length ``n``; these functions are the vector algebra of
the optimiser on it.  The vector is cut into chunks of :data:`CHUNK` elements,
one kernel thread per chunk, launched through :func:`launch_rows` so two CPU
threads share the work.

Reductions (:func:`dot`, :func:`norm_inf`) write one partial result per chunk
and finish on the host: the result depends on the chunking only, never on the
number of threads.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.warp._checks import check_vector

wp.set_module_options({"enable_backward": False})

#: Elements per kernel thread.
CHUNK = 4096


# ----------------------------------------------------------------------------
# Kernels (one thread per chunk of CHUNK elements)
# ----------------------------------------------------------------------------

@wp.kernel
def dot_chunks(row_begin: int, a: wp.array(dtype=float), b: wp.array(dtype=float),
               partial: wp.array(dtype=wp.float64), chunk: int):
    k = row_begin + wp.tid()
    begin = k * chunk
    end = wp.min(begin + chunk, a.shape[0])
    acc = wp.float64(0.0)
    for i in range(begin, end):
        acc += wp.float64(a[i]) * wp.float64(b[i])
    partial[k] = acc


@wp.kernel
def max_abs_chunks(row_begin: int, x: wp.array(dtype=float), partial: wp.array(dtype=float), chunk: int):
    k = row_begin + wp.tid()
    begin = k * chunk
    end = wp.min(begin + chunk, x.shape[0])
    m = float(0.0)
    for i in range(begin, end):
        m = wp.max(m, wp.abs(x[i]))
    partial[k] = m


@wp.kernel
def axpy_chunks(row_begin: int, alpha: float, x: wp.array(dtype=float), y: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, x.shape[0])
    for i in range(begin, end):
        y[i] = y[i] + alpha * x[i]


@wp.kernel
def scale_chunks(row_begin: int, alpha: float, x: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, x.shape[0])
    for i in range(begin, end):
        x[i] = alpha * x[i]


@wp.kernel
def lincomb_chunks(row_begin: int, out: wp.array(dtype=float), a: float, x: wp.array(dtype=float),
                   b: float, y: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, x.shape[0])
    for i in range(begin, end):
        out[i] = a * x[i] + b * y[i]


@wp.kernel
def copy_chunks(row_begin: int, src: wp.array(dtype=float), dst: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        dst[i] = src[i]


@wp.kernel
def fill_chunks(row_begin: int, x: wp.array(dtype=float), value: float, chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, x.shape[0])
    for i in range(begin, end):
        x[i] = value


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _chunks(n: int) -> int:
    return (n + CHUNK - 1) // CHUNK


def dot(a, b) -> float:
    """``sum(a * b)`` as a Python float: float64 products and sums per chunk, chunks summed on the host.

    ``a``, ``b``: 1-D float32 wp.arrays of equal length n >= 1.
    """
    n = check_vector("a", a)
    check_vector("b", b, n, a.device)
    partial = wp.empty(_chunks(n), dtype=wp.float64, device=a.device)
    launch_rows(dot_chunks, _chunks(n), [a, b, partial, CHUNK], device=a.device)
    return float(partial.numpy().sum())


def norm_inf(x) -> float:
    """``max |x|`` as a Python float.  ``x``: 1-D float32 wp.array, n >= 1."""
    n = check_vector("x", x)
    partial = wp.empty(_chunks(n), dtype=wp.float32, device=x.device)
    launch_rows(max_abs_chunks, _chunks(n), [x, partial, CHUNK], device=x.device)
    return float(partial.numpy().max())


def axpy(alpha: float, x, y) -> None:
    """``y += alpha * x`` (float32).  ``x``, ``y``: 1-D float32 wp.arrays of equal length."""
    n = check_vector("x", x)
    check_vector("y", y, n, x.device)
    launch_rows(axpy_chunks, _chunks(n), [float(alpha), x, y, CHUNK], device=x.device)


def scale(alpha: float, x) -> None:
    """``x *= alpha`` (float32).  ``x``: 1-D float32 wp.array."""
    n = check_vector("x", x)
    launch_rows(scale_chunks, _chunks(n), [float(alpha), x, CHUNK], device=x.device)


def lincomb(out, a: float, x, b: float, y) -> None:
    """``out = a * x + b * y`` (float32); ``out`` may be ``x`` or ``y``.

    ``out``, ``x``, ``y``: 1-D float32 wp.arrays of equal length.
    """
    n = check_vector("out", out)
    check_vector("x", x, n, out.device)
    check_vector("y", y, n, out.device)
    launch_rows(lincomb_chunks, _chunks(n), [out, float(a), x, float(b), y, CHUNK], device=out.device)


def copy(src, dst) -> None:
    """``dst[:] = src``.  1-D float32 wp.arrays of equal length."""
    n = check_vector("src", src)
    check_vector("dst", dst, n, src.device)
    launch_rows(copy_chunks, _chunks(n), [src, dst, CHUNK], device=src.device)


def fill(x, value: float) -> None:
    """``x[:] = value``.  ``x``: 1-D float32 wp.array."""
    n = check_vector("x", x)
    launch_rows(fill_chunks, _chunks(n), [x, float(value), CHUNK], device=x.device)

