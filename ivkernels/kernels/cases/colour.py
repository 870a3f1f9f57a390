"""Cases of :mod:`ivkernels.kernels.warp.colour` (sRGB transfer curves, Lab, luminance, log)."""
from __future__ import annotations

from ivkernels.kernels.cases import Case, Tol
from ivkernels.kernels.cases.inputs import nans, normal, uniform
from ivkernels.kernels.reference import colour as ref


def _rgb(rng, T, H, W):
    """Colours in [0, 1] with the curves' thresholds and the ends at the first pixels."""
    rgb = uniform(rng, (T, H, W, 3))
    flat = rgb.reshape(-1)
    n = min(flat.size, 4)
    flat[:n] = [0.0, 0.04045, 0.0031308, 1.0][:n]
    return rgb


def _elementwise(function, tol, extra=None, src=_rgb):
    extra = extra or {}

    def make(rng, T, H, W):
        s = src(rng, T, H, W)
        return {"src": s, "out": nans(s.shape), **extra}

    def reference(v):
        return {"out": getattr(ref, function)(v["src"], *(v[k] for k in extra))}

    return Case("colour", function, make, ("src", "out", *extra), ("out",), reference, tol=tol,
                in_place=(("src", "out"),))


def _lab(rng, T, H, W):
    return {"rgb": _rgb(rng, T, H, W), "out": nans((T, H, W, 3))}


def _luminance(rng, T, H, W):
    return {"rgb": _rgb(rng, T, H, W), "out": nans((T, H, W))}


CASES = (
    _elementwise("srgb_to_linear", Tol(1e-5, 1e-7)),
    _elementwise("linear_to_srgb", Tol(1e-5, 1e-7)),
    _elementwise("log_floor", Tol(1e-6, 1e-7), {"floor": 1e-4}, src=lambda rng, T, H, W: normal(rng, (T, H, W, 3))),
    Case("colour", "linear_rgb_to_lab", _lab, ("rgb", "out"), ("out",),
         lambda v: {"out": ref.linear_rgb_to_lab(v["rgb"])}, tol=Tol(0.0, 2e-4), in_place=(("rgb", "out"),)),
    Case("colour", "luminance", _luminance, ("rgb", "out"), ("out",),
         lambda v: {"out": ref.luminance(v["rgb"])}, tol=Tol(1e-6, 1e-7)),
)
