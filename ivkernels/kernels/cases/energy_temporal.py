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


CASES = (
    _temporal(3, "C3"),
    _temporal(1, "C1"),
    _temporal(None, "HW"),
)
