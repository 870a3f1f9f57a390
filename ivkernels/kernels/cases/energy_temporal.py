"""Cases of :mod:`ivkernels.kernels.warp.energy_temporal` (Eq. 4, 5, 8: Tukey of warped differences)."""
from __future__ import annotations

from ivkernels.kernels.cases import Case, Gradient, Tol
from ivkernels.kernels.cases.inputs import flow, normal, pairs, soft_mask
from ivkernels.kernels.reference import energy_temporal as ref


def _temporal(channels, variant):
    def make(rng, T, H, W):
        """X of order 1 (log albedo or shading), a flow of a few pixels partly leaving the image,
        w_occ of 0, 1 and 0.5; |differences| on both sides of alpha."""
        shape = (T, H, W) if channels is None else (T, H, W, channels)
        P = pairs(T)
        f = flow(rng, P, H, W, scale=2.0)
        return {"X": normal(rng, shape), "flow": f, "occ": soft_mask(rng, (P, H, W)),
                "gX": normal(rng, shape), "energy_rows": rng.normal(size=T * H), "lam": 10.0, "alpha": 1.5}

    def reference(v):
        er, gX = ref.temporal_term(v["X"], v["flow"], v["occ"], v["lam"], v["alpha"])
        return {"energy_rows": v["energy_rows"] + er, "gX": v["gX"] + gX}

    return Case("energy_temporal", "temporal_term", make, ("X", "flow", "occ", "gX", "energy_rows"),
                ("gX", "energy_rows"), reference, variant=variant, keywords=("lam", "alpha"),
                updates=("gX", "energy_rows"), tol={"energy_rows": Tol(1e-5, 1e-6), "gX": Tol(1e-5, 1e-4)},
                no_alias=(("X", "gX"),), gradients=(Gradient("X", "gX", min_peak=1.0),))


def _both(rng, T, H, W):
    """Log albedo and shading of order 1 under one flow and w_occ, as in :func:`_temporal`."""
    P = pairs(T)
    return {"A": normal(rng, (T, H, W, 3)), "S": normal(rng, (T, H, W)), "flow": flow(rng, P, H, W, scale=2.0),
            "occ": soft_mask(rng, (P, H, W)), "gA": normal(rng, (T, H, W, 3)), "gS": normal(rng, (T, H, W)),
            "energy_rows": rng.normal(size=T * H), "lam_albedo": 10.0, "lam_shading": 3.0, "alpha": 1.5}


def _both_reference(v):
    er, gA, gS = ref.temporal_terms(v["A"], v["S"], v["flow"], v["occ"], v["lam_albedo"], v["lam_shading"],
                                    v["alpha"])
    return {"energy_rows": v["energy_rows"] + er, "gA": v["gA"] + gA, "gS": v["gS"] + gS}


CASES = (
    _temporal(3, "C3"),
    _temporal(1, "C1"),
    _temporal(None, "HW"),
    Case("energy_temporal", "temporal_terms", _both, ("A", "S", "flow", "occ", "gA", "gS", "energy_rows"),
         ("gA", "gS", "energy_rows"), _both_reference, keywords=("lam_albedo", "lam_shading", "alpha"),
         updates=("gA", "gS", "energy_rows"),
         tol={"energy_rows": Tol(1e-5, 1e-6), "gA": Tol(1e-5, 1e-4), "gS": Tol(1e-5, 1e-4)},
         no_alias=(("A", "gA"), ("S", "gS")),
         gradients=(Gradient("A", "gA", min_peak=1.0), Gradient("S", "gS", min_peak=1.0))),
)
