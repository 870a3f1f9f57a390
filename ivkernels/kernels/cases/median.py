"""Cases of :mod:`ivkernels.kernels.warp.median` (5x5 median, weighted medians of S~ and of the flow)."""
from __future__ import annotations

import dataclasses

import numpy as np

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import F32, mask, nans, normal, pairs, uniform
from ivkernels.kernels.reference import median as ref


def two_region_flow(rng, P, H, W, noise=0.05, radius=None):
    """Flow (P, H, W, 2): a static background and a disc moving by (3, 1), plus noise; and the disc."""
    yy, xx = np.mgrid[0:H, 0:W]
    radius = min(H, W) / 3 if radius is None else radius
    disc = (yy - H / 2) ** 2 + (xx - W / 3) ** 2 < radius ** 2
    f = np.zeros((P, H, W, 2), F32)
    f[:, disc] = (3.0, 1.0)
    f += rng.normal(0.0, noise, f.shape).astype(F32)
    return f, disc


def _median5x5(rng, T, H, W):
    src = normal(rng, (T, H, W, 2))
    src[1:] = np.round(src[1:])                      # many ties
    return {"src": src, "out": nans(src.shape)}


def _shading(radius, lam):
    def make(rng, T, H, W):
        P = pairs(T)
        S = (rng.integers(0, 6, (T, H, W)) / 5.0).astype(F32)           # ties
        S += normal(rng, S.shape, 0.0, 0.02) * (rng.random(S.shape) < 0.5)
        return {"S": S, "flow": two_region_flow(rng, P, H, W)[0], "w_bnd": mask(rng, (P, H, W), 0.4),
                "out": nans((T, H, W)), "radius": radius, "sigma_s": 7.0, "lam": lam}

    return Case("median", "weighted_median_shading", make, ("S", "flow", "w_bnd", "out"), ("out",),
                lambda v: {"out": ref.weighted_median_shading(v["S"], v["flow"], v["w_bnd"], radius=v["radius"],
                                                              sigma_s=v["sigma_s"], lam=v["lam"],
                                                              centres=v.get("centres"))},
                variant=f"radius={radius},lam={lam:g}", keywords=("radius", "sigma_s", "lam"), tol=Tol(0.0, 1e-5),
                no_alias=(("S", "out"),))


def _centres(radius):
    def make(rng, T, H, W):
        P = pairs(T)
        return {"flow": two_region_flow(rng, P, H, W)[0], "w_bnd": mask(rng, (P, H, W), 0.4),
                "centres": nans((P, H, W, 4)), "radius": radius}

    return Case("median", "surface_centres", make, ("flow", "w_bnd", "centres"), ("centres",),
                lambda v: {"centres": ref.surface_centres(v["flow"], v["w_bnd"], radius=v["radius"])},
                variant=f"radius={radius}", keywords=("radius",), tol=Tol(0.0, 1e-5))


def _shading_given_centres(radius, lam):
    """The S~ update given the centres (as the solver passes them): the flow of
    :func:`two_region_flow` and its centres by the reference."""
    plain = _shading(radius, lam)

    def make(rng, T, H, W):
        v = plain.make(rng, T, H, W)
        v["centres"] = ref.surface_centres(v["flow"], v["w_bnd"], radius=radius).astype(F32)
        return v

    return dataclasses.replace(plain, make=make, variant=f"{plain.variant},centres",
                               keywords=(*plain.keywords, "centres"))


def _flow(radius):
    def make(rng, T, H, W):
        P = pairs(T)
        occ = np.where(rng.random((P, H, W)) < 0.8, 1.0, rng.random((P, H, W))).astype(F32)
        return {"flow": (rng.integers(-4, 5, (P, H, W, 2)) / 2.0).astype(F32),      # ties
                "lab": uniform(rng, (P, H, W, 3), 0.0, 30.0), "occ": occ, "mask": mask(rng, (P, H, W), 0.5),
                "out": nans((P, H, W, 2)), "radius": radius, "sigma_x": 7.0, "sigma_i": 10.0}

    return Case("median", "weighted_median_flow", make, ("flow", "lab", "occ", "mask", "out"), ("out",),
                lambda v: {"out": ref.weighted_median_flow(v["flow"], v["lab"], v["occ"], v["mask"],
                                                           radius=v["radius"], sigma_x=v["sigma_x"],
                                                           sigma_i=v["sigma_i"])},
                variant=f"radius={radius}", keywords=("radius", "sigma_x", "sigma_i"), tol=EXACT,
                no_alias=(("flow", "out"),))


CASES = (
    Case("median", "median5x5", _median5x5, ("src", "out"), ("out",), lambda v: {"out": ref.median5x5(v["src"])},
         tol=EXACT, no_alias=(("src", "out"),)),
    _shading(3, 0.0), _shading(3, 0.001), _shading(7, 0.001), _shading(7, 2.0),
    _shading_given_centres(3, 0.001), _centres(2), _centres(7),
    _flow(2), _flow(7),
)
