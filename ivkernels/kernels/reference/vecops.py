"""NumPy reference of :mod:`ivkernels.kernels.warp.vecops` (float64 unless noted)."""
from __future__ import annotations

import numpy as np


def dot(a, b) -> float:
    return float(np.dot(np.asarray(a, np.float64), np.asarray(b, np.float64)))


def norm_inf(x) -> float:
    return float(np.abs(np.asarray(x, np.float64)).max())


def axpy(alpha: float, x, y) -> np.ndarray:
    """Returns ``y + alpha * x``."""
    return np.asarray(y, np.float64) + alpha * np.asarray(x, np.float64)


def scale(alpha: float, x) -> np.ndarray:
    return alpha * np.asarray(x, np.float64)


def lincomb(a: float, x, b: float, y) -> np.ndarray:
    return a * np.asarray(x, np.float64) + b * np.asarray(y, np.float64)


def copy(src) -> np.ndarray:
    return np.array(src, copy=True)


def fill(x, value: float) -> np.ndarray:
    return np.full(np.shape(x), value, dtype=np.asarray(x).dtype)


def dots(basis, x, rows=None) -> np.ndarray:
    """``basis[rows] @ x`` in float64 (all rows by default)."""
    basis = np.asarray(basis, np.float64)
    rows = np.arange(basis.shape[0]) if rows is None else np.asarray(rows)
    return basis[rows] @ np.asarray(x, np.float64)


def combine(basis, rows, coeffs) -> np.ndarray:
    """``sum_r coeffs[r] * basis[rows[r]]`` in float64."""
    return np.asarray(coeffs, np.float64) @ np.asarray(basis, np.float64)[np.asarray(rows)]
