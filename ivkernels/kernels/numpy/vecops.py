"""``vecops`` on the NumPy backend: :mod:`ivkernels.kernels.reference.vecops` on 1-D float32 vectors."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.checks import check_basis_rows
from ivkernels.kernels.ndarray_checks import check_array, check_vector
from ivkernels.kernels.numpy._adapt import write
from ivkernels.kernels.reference import vecops as ref


def _pair(a, b) -> None:
    check_vector("b", b, check_vector("a", a).shape[0])


def dot(a, b) -> float:
    """``sum(a * b)`` of two (n,) vectors, in float64."""
    _pair(a, b)
    return ref.dot(a, b)


def norm_inf(x) -> float:
    """``max |x|`` of an (n,) vector."""
    check_vector("x", x)
    return ref.norm_inf(x)


def axpy(alpha: float, x, y) -> None:
    """``y += alpha * x``."""
    _pair(x, y)
    write("y", y, ref.axpy(float(alpha), x, y))


def scale(alpha: float, x) -> None:
    """``x *= alpha``."""
    check_vector("x", x)
    write("x", x, ref.scale(float(alpha), x))


def lincomb(out, a: float, x, b: float, y) -> None:
    """``out = a x + b y``; ``out`` may be ``x`` or ``y``."""
    _pair(x, y)
    check_vector("out", out, x.shape[0])
    write("out", out, ref.lincomb(float(a), x, float(b), y))


def copy(src, dst) -> None:
    """``dst[:] = src``."""
    _pair(src, dst)
    write("dst", dst, ref.copy(src))


def fill(x, value: float) -> None:
    """``x[:] = value``."""
    check_vector("x", x)
    write("x", x, ref.fill(x, float(value)))


def _basis(basis, x):
    check_array("basis", basis, (None, None), "(k, n)")
    check_vector("x", x, basis.shape[1])


def dots(basis, x, rows=None) -> np.ndarray:
    """float64 dot products of ``x`` (n,) with the ``rows`` of ``basis`` (k, n) (all rows by default)."""
    _basis(basis, x)
    rows, _ = check_basis_rows(basis.shape[0], rows)
    return ref.dots(basis, x, rows)


def combine(out, basis, rows, coeffs) -> None:
    """``out = sum_r coeffs[r] basis[rows[r]]``."""
    _basis(basis, out)
    rows, coeffs = check_basis_rows(basis.shape[0], rows, coeffs)
    write("out", out, ref.combine(basis, rows, coeffs))
