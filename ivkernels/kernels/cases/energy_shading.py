"""Cases of :mod:`ivkernels.kernels.warp.energy_shading` (Eq. 9 local smoothness, ungated and gated,
plus the weighted axis pairs of the stable steps, Eq. 13 coupling)."""
from __future__ import annotations

from ivkernels.kernels.cases import Case, Gradient, Tol
from ivkernels.kernels.cases.inputs import mask, normal, pairs, uniform
from ivkernels.kernels.reference import energy_shading as ref


def _smoothness(rng, T, H, W):
    return {"S": normal(rng, (T, H, W), -0.5, 0.5), "gS": normal(rng, (T, H, W)),
            "energy_rows": rng.normal(size=T * H), "lam": 2.0, "eps": 0.01}


def _smoothness_reference(v):
    er, gS = ref.shading_smoothness(v["S"], v["lam"], v["eps"])
    return {"energy_rows": v["energy_rows"] + er, "gS": v["gS"] + gS}


def _smoothness_gated(rng, T, H, W):
    return {**_smoothness(rng, T, H, W), "gate": uniform(rng, (T, H, W))}


def _smoothness_gated_reference(v):
    er, gS = ref.shading_smoothness_gated(v["S"], v["gate"], v["lam"], v["eps"])
    return {"energy_rows": v["energy_rows"] + er, "gS": v["gS"] + gS}


def _smoothness_paired(rng, T, H, W):
    weights = uniform(rng, (H, W, 2))
    weights[rng.uniform(size=(H, W, 2)) < 0.4] = 0.0            # many pairs carry no weight
    return {**_smoothness_gated(rng, T, H, W), "pairs": weights, "pair_gain": 4.0}


def _smoothness_paired_reference(v):
    er, gS = ref.shading_smoothness_paired(v["S"], v["gate"], v["pairs"], v["lam"], v["pair_gain"], v["eps"])
    return {"energy_rows": v["energy_rows"] + er, "gS": v["gS"] + gS}


def _coupling(frames_with_flow):
    def make(rng, T, H, W):
        t_flow = frames_with_flow(T)
        return {"S": normal(rng, (T, H, W), -0.5, 0.5), "S_tilde": normal(rng, (T, H, W), -0.5, 0.5),
                "w_bnd": mask(rng, (t_flow, H, W), 0.3), "gS": normal(rng, (T, H, W)),
                "energy_rows": rng.normal(size=T * H), "lam": 10.0}
    return make


def _coupling_reference(v):
    er, gS = ref.coupling_term(v["S"], v["S_tilde"], v["w_bnd"], v["lam"])
    return {"energy_rows": v["energy_rows"] + er, "gS": v["gS"] + gS}


_TOL = {"energy_rows": Tol(1e-5, 1e-6), "gS": Tol(1e-5, 1e-4)}

CASES = (
    Case("energy_shading", "shading_smoothness", _smoothness, ("S", "gS", "energy_rows"), ("gS", "energy_rows"),
         _smoothness_reference, keywords=("lam", "eps"), updates=("gS", "energy_rows"), tol=_TOL,
         no_alias=(("S", "gS"),), gradients=(Gradient("S", "gS", overrides={"eps": 0.05}),)),
    Case("energy_shading", "shading_smoothness_gated", _smoothness_gated, ("S", "gate", "gS", "energy_rows"),
         ("gS", "energy_rows"), _smoothness_gated_reference, keywords=("lam", "eps"), updates=("gS", "energy_rows"),
         tol=_TOL, no_alias=(("S", "gS"), ("gate", "gS")), gradients=(Gradient("S", "gS", overrides={"eps": 0.05}),)),
    Case("energy_shading", "shading_smoothness_paired", _smoothness_paired,
         ("S", "gate", "pairs", "gS", "energy_rows"), ("gS", "energy_rows"), _smoothness_paired_reference,
         keywords=("lam", "pair_gain", "eps"), updates=("gS", "energy_rows"), tol=_TOL,
         no_alias=(("S", "gS"), ("gate", "gS")), gradients=(Gradient("S", "gS", overrides={"eps": 0.05}),)),
    *(Case("energy_shading", "coupling_term", _coupling(t_flow), ("S", "S_tilde", "w_bnd", "gS", "energy_rows"),
           ("gS", "energy_rows"), _coupling_reference, variant=variant, keywords=("lam",),
           updates=("gS", "energy_rows"), tol=_TOL, gradients=(Gradient("S", "gS"),))
      for variant, t_flow in (("pairs", pairs), ("frames", lambda T: T))),
)
