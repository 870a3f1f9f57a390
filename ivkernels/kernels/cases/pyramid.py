"""Cases of :mod:`ivkernels.kernels.warp.pyramid` (Gaussian blur, bilinear resize of images and flows)."""
from __future__ import annotations

from ivkernels.kernels.cases import Case, Tol
from ivkernels.kernels.cases.inputs import flow, log_image, nans, pairs
from ivkernels.kernels.reference import pyramid as ref

# Output sizes of the resize cases, from the input (H, W).
SIZES = {
    "half": lambda H, W: ((H + 1) // 2, (W + 1) // 2),
    "double": lambda H, W: (2 * H, 2 * W),
    "same": lambda H, W: (H, W),
    "one": lambda H, W: (1, 1),
    "skew": lambda H, W: ((H + 6) // 7, 2 * W + 3),
}


def _blur(sigma):
    def make(rng, T, H, W):
        src = log_image(rng, (T, H, W, 3))
        return {"src": src, "out": nans(src.shape), "scratch": nans(src.shape), "sigma": sigma}

    return Case("pyramid", "gaussian_blur", make, ("src", "out", "scratch", "sigma"), ("out", "scratch"),
                lambda v: {"out": ref.gaussian_blur(v["src"], v["sigma"])}, variant=f"sigma={sigma:g}",
                scratch=("scratch",), tol=Tol(0.0, 2e-6), in_place=(("src", "out"),), no_alias=(("src", "scratch"),))


def _resize(size):
    def make(rng, T, H, W):
        return {"src": log_image(rng, (T, H, W, 3)), "out": nans((T, *SIZES[size](H, W), 3))}

    return Case("pyramid", "resize_bilinear", make, ("src", "out"), ("out",),
                lambda v: {"out": ref.resize_bilinear(v["src"], v["out"].shape[1:3])}, variant=size,
                tol=Tol(0.0, 1e-5))


def _resize_flow(size):
    def make(rng, T, H, W):
        P = pairs(T)
        return {"src": flow(rng, P, H, W), "out": nans((P, *SIZES[size](H, W), 2))}

    return Case("pyramid", "resize_flow", make, ("src", "out"), ("out",),
                lambda v: {"out": ref.resize_flow(v["src"], v["out"].shape[1:3])}, variant=size,
                tol=Tol(1e-5, 1e-5))


CASES = (
    _blur(0.3), _blur(1.0), _blur(2.3),
    *(_resize(size) for size in SIZES),
    _resize_flow("double"), _resize_flow("half"),
)
