"""Cases of :mod:`ivkernels.kernels.warp.maps` (occlusion, warp reliability, chromaticity
consistency, motion boundaries, shading gate, still surface)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import F32, flow, lab_frames, mask, nans, normal, pairs, uniform
from ivkernels.kernels.reference import derivatives as ref_derivatives
from ivkernels.kernels.reference import maps as ref


def _occlusion_inputs(rng, T, H, W):
    """Lab frames (T), a flow partly leaving the image (T-1) and its one-sided divergence."""
    f = flow(rng, pairs(T), H, W)
    return {"lab": lab_frames(rng, T, H, W), "flow": f,
            "div_neg": ref_derivatives.divergence_negative(f).astype(F32) if f.size else f[..., 0].copy(), "out": nans((pairs(T), H, W))}


def _occlusion_soft(sigma_e, sigma_d):
    def make(rng, T, H, W):
        return {**_occlusion_inputs(rng, T, H, W), "sigma_e": sigma_e, "sigma_d": sigma_d}

    return Case("maps", "occlusion_soft", make, ("lab", "flow", "div_neg", "out", "sigma_e", "sigma_d"), ("out",),
                lambda v: {"out": ref.occlusion_soft(v["lab"], v["flow"], v["div_neg"], v["sigma_e"], v["sigma_d"])},
                variant=f"sigma_e={sigma_e:g},sigma_d={sigma_d:g}", tol=Tol(0.0, 2e-5), min_frames=2)


def _occlusion_binary(sigma_e, sigma_d):
    def make(rng, T, H, W):
        return {**_occlusion_inputs(rng, T, H, W), "sigma_e": sigma_e, "sigma_d": sigma_d, "threshold": 0.5}

    def reference(v):
        return {"out": ref.occlusion_binary(v["lab"], v["flow"], v["div_neg"], v["sigma_e"], v["sigma_d"],
                                            v["threshold"])}

    def undecided(v):
        """float32 rounding of ``o`` may fall either side of the threshold."""
        o = ref.occlusion_soft(v["lab"], v["flow"], v["div_neg"], v["sigma_e"], v["sigma_d"])
        return {"out": np.abs(o - v["threshold"]) < 1e-4}

    return Case("maps", "occlusion_binary", make,
                ("lab", "flow", "div_neg", "out", "sigma_e", "sigma_d", "threshold"), ("out",), reference,
                variant=f"sigma_e={sigma_e:g},sigma_d={sigma_d:g}", tol=EXACT, ignore=undecided, min_frames=2)


def _reliability(max_spread):
    def make(rng, T, H, W):
        img = normal(rng, (T, H, W, 3), 0.0, 0.5)
        img[:, H // 4: H // 2 + 1, W // 4: W // 2 + 1] = -1.0          # a flat patch
        return {"log_image": img, "flow": flow(rng, pairs(T), H, W),
                "occ": mask(rng, (pairs(T), H, W), 0.8), "max_spread": max_spread}

    def reference(v):
        return {"occ": ref.warp_reliability(v["log_image"], v["flow"], v["occ"], v["max_spread"])}

    def tied(v):
        """Spreads within float32 rounding of ``max_spread``."""
        return {"occ": np.abs(ref.corner_spread(v["log_image"], v["flow"]) - v["max_spread"]) <= 1e-4}

    return Case("maps", "warp_reliability", make, ("log_image", "flow", "occ", "max_spread"), ("occ",), reference,
                variant=f"max_spread={max_spread:g}", updates=("occ",), tol=EXACT, ignore=tied)


def _chroma(max_change, static):
    def make(rng, T, H, W):
        img = normal(rng, (1, H, W, 3), -1.0, 0.3) + normal(rng, (T, H, W, 1), 0.0, 0.3)  # a grey light change
        img[1:, H // 3: H // 2 + 1, W // 3:] += normal(rng, (pairs(T), H // 2 + 1 - H // 3, W - W // 3, 3), 0.0, 0.3)
        f = np.zeros((pairs(T), H, W, 2), F32) if static else flow(rng, pairs(T), H, W)
        return {"log_image": img.astype(F32), "flow": f, "occ": mask(rng, (pairs(T), H, W), 0.8),
                "max_change": max_change}

    def reference(v):
        return {"occ": ref.chroma_consistency(v["log_image"], v["flow"], v["occ"], v["max_change"])}

    def tied(v):
        """Changes within float32 rounding of ``max_change``."""
        return {"occ": np.abs(ref.chroma_change(v["log_image"], v["flow"]) - v["max_change"]) <= 1e-4}

    return Case("maps", "chroma_consistency", make, ("log_image", "flow", "occ", "max_change"), ("occ",),
                reference, variant=f"max_change={max_change:g},{'static' if static else 'moving'}",
                updates=("occ",), tol=EXACT, ignore=tied)


def _luminance(max_change, static):
    def make(rng, T, H, W):
        img = normal(rng, (1, H, W, 1), -1.0, 0.3) + normal(rng, (T, 1, 1, 1), 0.0, 0.2)  # still, exposure changes
        img = np.repeat(img, 3, axis=3)
        img[1:, H // 3: H // 2 + 1, W // 3:] += normal(rng, (pairs(T), H // 2 + 1 - H // 3, W - W // 3, 1), 0.0, 0.5)
        f = np.zeros((pairs(T), H, W, 2), F32) if static else flow(rng, pairs(T), H, W)
        return {"log_image": img.astype(F32), "flow": f, "near": mask(rng, (pairs(T), H, W), 0.7),
                "offsets": normal(rng, (pairs(T),), 0.0, 0.2), "occ": mask(rng, (pairs(T), H, W), 0.8),
                "max_change": max_change}

    def reference(v):
        return {"occ": ref.luminance_consistency(v["log_image"], v["flow"], v["near"], v["offsets"], v["occ"],
                                                 v["max_change"])}

    def tied(v):
        """Changes within float32 rounding of ``max_change``."""
        D, _ = ref.log_change(v["log_image"], v["flow"])
        return {"occ": np.abs(np.abs(D - np.asarray(v["offsets"], np.float64)[:, None, None])
                              - v["max_change"]) <= 1e-4}

    return Case("maps", "luminance_consistency", make,
                ("log_image", "flow", "near", "offsets", "occ", "max_change"), ("occ",), reference,
                variant=f"max_change={max_change:g},{'static' if static else 'moving'}",
                updates=("occ",), tol=EXACT, ignore=tied)


def _round_trip(max_distance, consistent):
    def make(rng, T, H, W):
        P = pairs(T)
        if consistent:      # a translation per pair and its inverse, both with noise about max_distance
            shift = normal(rng, (P, 1, 1, 2), 0.0, 3.0)
            f = shift + normal(rng, (P, H, W, 2), 0.0, 0.5 * max_distance)
            back = -shift + normal(rng, (P, H, W, 2), 0.0, 0.5 * max_distance)
        else:               # unrelated flows, some vectors far outside the image (clamped samples)
            f, back = flow(rng, P, H, W, far=0.1), flow(rng, P, H, W)
        return {"flow": f, "back_flow": back.astype(F32), "occ": mask(rng, (pairs(T), H, W), 0.8),
                "max_distance": max_distance}

    def reference(v):
        return {"occ": ref.round_trip_consistency(v["flow"], v["back_flow"], v["occ"], v["max_distance"])}

    def tied(v):
        """Distances within float32 rounding of ``max_distance``."""
        return {"occ": np.abs(ref.round_trip_distance(v["flow"], v["back_flow"]) - v["max_distance"]) <= 1e-4}

    return Case("maps", "round_trip_consistency", make, ("flow", "back_flow", "occ", "max_distance"), ("occ",),
                reference, variant=f"max_distance={max_distance:g},{'consistent' if consistent else 'random'}",
                updates=("occ",), tol=EXACT, ignore=tied)


def _boundary(radius):
    def make(rng, T, H, W):
        P = pairs(T)
        return {"sobel_mag": uniform(rng, (P, H, W)) ** 8, "out": nans((P, H, W)), "threshold": 0.8,
                "radius": radius}

    return Case("maps", "motion_boundary", make, ("sobel_mag", "out", "threshold", "radius"), ("out",),
                lambda v: {"out": ref.motion_boundary(v["sobel_mag"], v["threshold"], v["radius"])},
                variant=f"radius={radius}", tol=EXACT, no_alias=(("sobel_mag", "out"),) if radius else ())


def _gate(tau, static, tau_chroma=0.0):
    def make(rng, T, H, W):
        img = normal(rng, (T, H, W, 3), -1.0, 0.5)
        img[:, H // 4: H // 2 + 1, W // 4: W // 2 + 1] = -1.0          # a flat patch
        f = np.zeros((pairs(T), H, W, 2), F32) if static else flow(rng, pairs(T), H, W)
        return {"log_image": img, "flow": f, "gate": nans((T, H, W)), "tau": tau, "tau_chroma": tau_chroma}

    return Case("maps", "shading_gate", make, ("log_image", "flow", "gate", "tau"), ("gate",),
                lambda v: {"gate": ref.shading_gate(v["log_image"], v["flow"], v["tau"], v["tau_chroma"])},
                variant=f"tau={tau:g},tau_chroma={tau_chroma:g},{'static' if static else 'moving'}",
                keywords=("tau_chroma",), tol=Tol(1e-4, 1e-5))


def _still(tau, radius, share):
    def make(rng, T, H, W):
        img = normal(rng, (T, H, W, 3), -1.0, 0.3)
        img[:, :, : W // 2] = img[:1, :, : W // 2]                       # a still half ...
        img[:, :, : W // 2] += normal(rng, (T, 1, 1, 1), 0.0, 0.5)        # ... under a changing light
        return {"log_image": img, "out": nans((H, W)), "tau": tau, "radius": radius, "share": share}

    def tied(v):
        """Window means within float32 rounding of ``tau``."""
        means = ref.still_window_means(v["log_image"], v["radius"])
        return {"out": (np.abs(means - v["tau"]) <= 1e-4).any(0)}

    return Case("maps", "still_surface", make, ("log_image", "out", "tau", "radius", "share"), ("out",),
                lambda v: {"out": ref.still_surface(v["log_image"], v["tau"], v["radius"], v["share"])},
                variant=f"tau={tau:g},radius={radius},share={share:g}", tol=EXACT, ignore=tied)


CASES = (
    _occlusion_soft(20.0, 0.3),
    _occlusion_soft(40.0, 1.0),
    _occlusion_binary(20.0, 0.3),
    _occlusion_binary(40.0, 1.0),
    _reliability(0.05),
    _reliability(0.3),
    _chroma(0.3, False),
    _chroma(0.05, True),
    _luminance(0.2, False),
    _luminance(0.05, True),
    _round_trip(1.0, True),
    _round_trip(4.0, False),
    _boundary(0),
    _boundary(1),
    _boundary(3),
    _gate(0.1, True),
    _gate(0.5, False),
    _gate(0.5, False, 0.3),
    _still(0.3, 1, 0.5),
    _still(0.05, 2, 0.5),
    _still(1.0, 0, 0.75),
)
