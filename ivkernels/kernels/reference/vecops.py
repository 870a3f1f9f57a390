"""``vecops``: the declared contract of its host functions, and the NumPy references (float64 unless noted)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.checks import check_basis_rows
from ivkernels.kernels.contract import Family, Real, Rule, Vector

FAMILY = Family("vecops", "BLAS-1 on 1-D float32 vectors (n,) and (k, n) bases.")


def _rows(sizes, args):
    rows, coeffs = check_basis_rows(sizes["k"], args["rows"], args.get("coeffs"))
    return {"rows": rows, "coeffs": coeffs} if "coeffs" in args else {"rows": rows}


FAMILY.declare("dot(a, b)", "``sum(a * b)``, accumulated in float64 (returns a float).", a=Vector(), b=Vector())
FAMILY.declare("norm_inf(x)", "``max |x|`` (returns a float).", x=Vector())
FAMILY.declare("axpy(alpha, x, y)", "``y += alpha x``.", alpha=Real, x=Vector(), y=Vector(output=True))
FAMILY.declare("scale(alpha, x)", "``x *= alpha``.", alpha=Real, x=Vector(output=True))
FAMILY.declare("multiply(x, y)", "``x *= y``, element by element; y may be x.", x=Vector(output=True), y=Vector())
FAMILY.declare("lincomb(out, a, x, b, y)", "``out = a x + b y``; out may be x or y.",
               out=Vector(output=True), a=Real, x=Vector(), b=Real, y=Vector())
FAMILY.declare("copy(src, dst)", "``dst[:] = src``.", src=Vector(), dst=Vector(output=True))
FAMILY.declare("fill(x, value)", "``x[:] = value``.", x=Vector(output=True), value=Real)
FAMILY.declare("dots(basis, x, rows=None)", "float64 (len(rows),) dot products of x with rows of basis.",
               order=("x",), x=Vector(), basis="k n", rules=(Rule(_rows),))
FAMILY.declare("combine(out, basis, rows, coeffs)", "``out = sum_r coeffs[r] basis[rows[r]]``.",
               out=Vector(output=True), basis="k n", rules=(Rule(_rows),))


def dot(a, b) -> float:
    return float(np.dot(np.asarray(a, np.float64), np.asarray(b, np.float64)))


def norm_inf(x) -> float:
    return float(np.abs(np.asarray(x, np.float64)).max())


def axpy(alpha: float, x, y) -> np.ndarray:
    """Returns ``y + alpha * x``."""
    return np.asarray(y, np.float64) + alpha * np.asarray(x, np.float64)


def scale(alpha: float, x) -> np.ndarray:
    return alpha * np.asarray(x, np.float64)


def multiply(x, y) -> np.ndarray:
    """Returns ``x * y``."""
    return np.asarray(x, np.float64) * np.asarray(y, np.float64)


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
