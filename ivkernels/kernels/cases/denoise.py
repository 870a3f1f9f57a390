"""Cases of :mod:`ivkernels.kernels.warp.denoise` (the noise's step in ``log i``, the bilateral filter)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.cases import Case, Tol
from ivkernels.kernels.cases.inputs import log_image, nans, uniform
from ivkernels.kernels.reference import denoise as ref

OFFSET = 0.02


def _range_sigma(rng, T, H, W):
    offset_image = np.log(np.exp(log_image(rng, (T, H, W, 3))) + OFFSET).astype(np.float32)
    # a few pixels darker than the offset allows, where the factor is held at 11
    offset_image[:, ::5, ::3] = np.float32(np.log(OFFSET * 1.01))
    return {"offset_image": offset_image, "level": uniform(rng, (T, H, W, 2), 0.0, 0.2),
            "out": nans((T, H, W)), "scale": 2.0, "offset": OFFSET}


def _bilateral(channels: int, radius: int, sigma_space: float):
    def make(rng, T, H, W):
        src = log_image(rng, (T, H, W, channels))
        # a range of 0 at some pixels (kept as they are), small and large ranges elsewhere
        rs = uniform(rng, (T, H, W), -0.05, 1.5)
        rs[rs < 0.0] = 0.0
        return {"src": src, "range_sigma": rs, "out": nans((T, H, W, channels)),
                "radius": radius, "sigma_space": sigma_space}

    return Case("denoise", "bilateral", make, ("src", "range_sigma", "out", "radius", "sigma_space"), ("out",),
                lambda v: {"out": ref.bilateral(v["src"], v["range_sigma"], v["radius"], v["sigma_space"])},
                variant=f"C={channels},r={radius}", tol=Tol(1e-5, 2e-6),
                no_alias=(("src", "out"),))


CASES = (
    Case("denoise", "range_sigma", _range_sigma, ("offset_image", "level", "out", "scale", "offset"), ("out",),
         lambda v: {"out": ref.range_sigma(v["offset_image"], v["level"], v["scale"], v["offset"])},
         tol=Tol(1e-5, 1e-6)),
    _bilateral(1, 3, 2.0), _bilateral(3, 2, 1.0), _bilateral(1, 0, 1.0), _bilateral(2, 1, 1.5),
)
