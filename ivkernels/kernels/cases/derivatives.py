"""Cases of :mod:`ivkernels.kernels.warp.derivatives` (image gradient, flow Sobel, divergence)."""
from __future__ import annotations

from ivkernels.kernels.cases import Case, Tol
from ivkernels.kernels.cases.inputs import flow, log_image, nans, pairs
from ivkernels.kernels.reference import derivatives as ref


def _gradient(channels):
    def make(rng, T, H, W):
        shape = (T, H, W, channels)
        return {"src": log_image(rng, shape), "gx": nans(shape), "gy": nans(shape)}

    def reference(v):
        gx, gy = ref.image_gradient(v["src"])
        return {"gx": gx, "gy": gy}

    return Case("derivatives", "image_gradient", make, ("src", "gx", "gy"), ("gx", "gy"), reference,
                variant=f"C{channels}", tol=Tol(0.0, 1e-6), no_alias=(("src", "gx"), ("src", "gy")))


def _flow_map(function, tol):
    def make(rng, T, H, W):
        P = pairs(T)
        return {"flow": flow(rng, P, H, W), "out": nans((P, H, W))}

    return Case("derivatives", function, make, ("flow", "out"), ("out",),
                lambda v: {"out": getattr(ref, function)(v["flow"])}, tol=tol)


CASES = (
    _gradient(1),
    _gradient(3),
    _flow_map("flow_sobel_magnitude", Tol(1e-5, 1e-6)),
    _flow_map("divergence_negative", Tol(0.0, 1e-6)),
)
