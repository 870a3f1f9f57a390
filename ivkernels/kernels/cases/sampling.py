"""Cases of :mod:`ivkernels.kernels.warp.sampling` (bilinear / bicubic warp, bilinear splat)."""
from __future__ import annotations

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import flow, log_image, nans, normal
from ivkernels.kernels.reference import sampling as ref


def sampling_flow(rng, T, H, W):
    """Fractional flow (T, H, W, 2), 5% of vectors far outside, the top row sampling above
    the image and the right column beyond the border."""
    f = flow(rng, T, H, W, scale=4.0, far=0.05)
    f[:, :1, :, 1] = -0.5
    f[:, :, -1:, 0] = 0.75
    return f


def _warp(function, channels, tol):
    def make(rng, T, H, W):
        return {"src": log_image(rng, (T, H, W, channels)), "flow": sampling_flow(rng, T, H, W),
                "out": nans((T, H, W, channels)), "inside": nans((T, H, W))}

    def reference(v):
        out, inside = getattr(ref, function)(v["src"], v["flow"])
        return {"out": out, "inside": inside}

    return Case("sampling", function, make, ("src", "flow", "out", "inside"), ("out", "inside"), reference,
                variant=f"C{channels}", tol={"out": tol, "inside": EXACT},
                no_alias=(("src", "out"),))


def _splat(rng, T, H, W):
    return {"values": normal(rng, (T, H, W, 2)), "flow": sampling_flow(rng, T, H, W),
            "out": normal(rng, (T, H, W, 2))}


CASES = (
    _warp("warp_bilinear", 1, Tol(0.0, 2e-5)),
    _warp("warp_bilinear", 3, Tol(0.0, 2e-5)),
    Case("sampling", "splat_bilinear", _splat, ("values", "flow", "out"), ("out",),
         lambda v: {"out": v["out"] + ref.splat_bilinear(v["values"], v["flow"])}, updates=("out",),
         tol=Tol(0.0, 5e-5), no_alias=(("values", "out"),)),
    _warp("warp_bicubic", 1, Tol(0.0, 5e-5)),
    _warp("warp_bicubic", 2, Tol(0.0, 5e-5)),
)
