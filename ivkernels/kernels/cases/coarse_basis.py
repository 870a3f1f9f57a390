"""Cases of :mod:`ivkernels.kernels.warp.coarse_basis` (weights, prolongation, restriction).

Each function's input and output differ in shape, so the generic aliasing check
(one array passed as both) does not apply; ``tests/test_kernels_coarse_basis.py``
passes overlapping views instead."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.cases import Case, Tol
from ivkernels.kernels.cases.inputs import log_image, nans, normal
from ivkernels.kernels.reference import coarse_basis as ref


def _weights(rng, T, H, W, spacing):
    """Normalised weights (T, H, W, 16) as the solver makes them, from a random log albedo."""
    return ref.coarse_weights(log_image(rng, (T, H, W, 3)), spacing, 0.5).astype(np.float32)


def _make_weights(spacing, sigma, channels):
    def make(rng, T, H, W):
        return {"A": log_image(rng, (T, H, W, channels)), "weights": nans((T, H, W, 16)),
                "spacing": spacing, "sigma": sigma}
    return make


def _make_transfer(spacing, prolong: bool):
    """Inputs of ``prolong_add`` (z on the grid, out per pixel) or ``restrict_add`` (the reverse)."""
    def make(rng, T, H, W):
        grid, pixels = (T, *ref.grid_shape(H, W, spacing)), (T, H, W)
        source, out = (grid, pixels) if prolong else (pixels, grid)
        return {"z" if prolong else "values": normal(rng, source), "weights": _weights(rng, T, H, W, spacing),
                "out": normal(rng, out), "spacing": spacing}
    return make


def _weights_case(spacing, sigma, channels):
    return Case("coarse_basis", "coarse_weights", _make_weights(spacing, sigma, channels),
                ("A", "weights", "spacing", "sigma"), ("weights",),
                lambda v: {"weights": ref.coarse_weights(v["A"], v["spacing"], v["sigma"])},
                variant=f"s{spacing}-sigma{sigma}-C{channels}", tol=Tol(1e-4, 1e-6))


def _prolong_case(spacing):
    return Case("coarse_basis", "prolong_add", _make_transfer(spacing, True), ("z", "weights", "out", "spacing"),
                ("out",), lambda v: {"out": v["out"] + ref.prolong(v["z"], v["weights"], v["spacing"])},
                variant=f"s{spacing}", updates=("out",), tol=Tol(1e-5, 1e-5))


def _restrict_case(spacing):
    return Case("coarse_basis", "restrict_add", _make_transfer(spacing, False),
                ("values", "weights", "out", "spacing"), ("out",),
                lambda v: {"out": v["out"] + ref.restrict(v["values"], v["weights"], v["spacing"])},
                variant=f"s{spacing}", updates=("out",), tol=Tol(1e-5, 2e-5))


def _nodes_case(spacing, channels):
    def make(rng, T, H, W):
        hc, wc = ref.grid_shape(H, W, spacing)
        return {"src": log_image(rng, (T, H, W, channels)), "out": nans((T, hc, wc, channels)), "spacing": spacing}
    return Case("coarse_basis", "node_samples", make, ("src", "out", "spacing"), ("out",),
                lambda v: {"out": ref.node_samples(v["src"], v["spacing"])}, variant=f"s{spacing}-C{channels}",
                tol=Tol(0.0, 0.0))


CASES = (
    _weights_case(4, 0.5, 3),
    _weights_case(3, 0.05, 1),
    _weights_case(1, 1.0, 3),
    _prolong_case(4),
    _prolong_case(3),
    _prolong_case(1),
    _restrict_case(4),
    _restrict_case(3),
    _restrict_case(1),
    _nodes_case(4, 3),
    _nodes_case(3, 3),
    _nodes_case(1, 1),
)
