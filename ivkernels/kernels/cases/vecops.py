"""Cases of :mod:`ivkernels.kernels.warp.vecops` (flat-vector algebra of the optimiser).

Vectors have ``4 T H W - 1`` elements (:func:`~ivkernels.kernels.cases.inputs.vector_length`):
an odd length, so the vectorised bodies and their scalar tails both run.
"""
from __future__ import annotations

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import nans, normal, vector_length
from ivkernels.kernels.reference import vecops as ref

ROWS = [4, 0, 2]            # basis rows picked by dots / combine (out of order)
COEFFS = [0.5, -2.0, 0.0]


def _vectors(*names, alpha=None):
    def make(rng, T, H, W):
        n = vector_length(T, H, W)
        v = {name: normal(rng, n) for name in names}
        return v if alpha is None else {"alpha": alpha, **v}
    return make


def _peaked(rng, T, H, W):
    """A vector whose largest magnitude is one negative entry (norm_inf must take |.|)."""
    x = normal(rng, vector_length(T, H, W))
    if x.size:
        x[x.size // 2] = -50.0
    return {"x": x}


def _lincomb(rng, T, H, W):
    n = vector_length(T, H, W)
    return {"out": nans(n), "a": 0.5, "x": normal(rng, n), "b": -1.5, "y": normal(rng, n)}


def _copy(rng, T, H, W):
    n = vector_length(T, H, W)
    return {"src": normal(rng, n), "dst": nans(n)}


def _fill(rng, T, H, W):
    return {"x": nans(vector_length(T, H, W)), "value": 7.25}


def _basis(rows):
    def make(rng, T, H, W):
        n = vector_length(T, H, W)
        return {"basis": normal(rng, (5, n)), "x": normal(rng, n), "rows": rows}
    return make


def _combine(rng, T, H, W):
    n = vector_length(T, H, W)
    return {"out": nans(n), "basis": normal(rng, (5, n)), "rows": ROWS, "coeffs": COEFFS}


CASES = (
    Case("vecops", "dot", _vectors("a", "b"), ("a", "b"), (), lambda v: {"return": ref.dot(v["a"], v["b"])},
         returns=True, tol=Tol(1e-12, 1e-9)),
    Case("vecops", "norm_inf", _peaked, ("x",), (), lambda v: {"return": ref.norm_inf(v["x"])},
         returns=True, tol=EXACT),
    Case("vecops", "axpy", _vectors("x", "y", alpha=0.3), ("alpha", "x", "y"), ("y",),
         lambda v: {"y": ref.axpy(v["alpha"], v["x"], v["y"])}, updates=("y",), tol=Tol(1e-6, 1e-7),
         in_place=(("x", "y"),)),
    Case("vecops", "scale", _vectors("x", alpha=-2.5), ("alpha", "x"), ("x",),
         lambda v: {"x": ref.scale(v["alpha"], v["x"])}, updates=("x",), tol=Tol(1e-6, 0.0)),
    Case("vecops", "multiply", _vectors("x", "y"), ("x", "y"), ("x",),
         lambda v: {"x": ref.multiply(v["x"], v["y"])}, updates=("x",), tol=Tol(1e-6, 0.0),
         in_place=(("y", "x"),)),
    Case("vecops", "lincomb", _lincomb, ("out", "a", "x", "b", "y"), ("out",),
         lambda v: {"out": ref.lincomb(v["a"], v["x"], v["b"], v["y"])}, tol=Tol(1e-6, 1e-7),
         in_place=(("x", "out"), ("y", "out"))),
    Case("vecops", "copy", _copy, ("src", "dst"), ("dst",), lambda v: {"dst": ref.copy(v["src"])}, tol=EXACT,
         in_place=(("src", "dst"),)),
    Case("vecops", "fill", _fill, ("x", "value"), ("x",), lambda v: {"x": ref.fill(v["x"], v["value"])},
         tol=EXACT),
    Case("vecops", "dots", _basis(ROWS), ("basis", "x", "rows"), (),
         lambda v: {"return": ref.dots(v["basis"], v["x"], v["rows"])}, variant="rows", returns=True,
         tol=Tol(1e-12, 1e-9)),
    Case("vecops", "dots", _basis(None), ("basis", "x"), (),
         lambda v: {"return": ref.dots(v["basis"], v["x"])}, variant="all", returns=True, tol=Tol(1e-12, 1e-9)),
    Case("vecops", "combine", _combine, ("out", "basis", "rows", "coeffs"), ("out",),
         lambda v: {"out": ref.combine(v["basis"], v["rows"], v["coeffs"])}, tol=Tol(1e-5, 1e-5)),
)


