"""Cases of :mod:`ivkernels.kernels.warp.energy_albedo_gsm` (Eq. 11: GSM smoothness of log albedo)."""
from __future__ import annotations

import functools

import numpy as np

from ivkernels.kernels.cases import Case, Gradient, Tol
from ivkernels.kernels.cases.inputs import F32, normal
from ivkernels.kernels.reference import energy_albedo_gsm as ref
from ivkernels.priors import load_albedo_prior, tabulate_gsm

DENSE_TABLE = 2 ** 17      # table points for the gradient check (the shipped table has 8192)


@functools.lru_cache(maxsize=None)
def gsm_tables(n: int | None = None) -> tuple:
    """float32 ``(sigma_inv, table_g, table_dg)`` and ``r2_max`` of the shipped prior;
    ``n`` re-tabulates the mixture on ``n`` points."""
    prior = load_albedo_prior()
    if n is None:
        tg, tdg = prior.table_g, prior.table_dg
    else:
        tg, tdg, _ = tabulate_gsm(prior.alphas, prior.sigmas, prior.r2_max, n)
    return prior.sigma_inv.astype(F32), tg.astype(F32), tdg.astype(F32), float(prior.r2_max)


def patchy_albedo(rng, T, H, W, patch=6, outliers=True):
    """Log albedo (T, H, W, 3): flat patches (large differences at their edges), mild noise, and
    a few outliers whose differences lie beyond the table (r2 > r2_max)."""
    base = rng.normal(-1.0, 0.5, (T, H // patch + 1, W // patch + 1, 3))
    A = np.repeat(np.repeat(base, patch, 1), patch, 2)[:, :H, :W]
    A = A + rng.normal(0.0, 0.02, (T, H, W, 3))
    if outliers and A.size:
        idx = rng.integers(0, T * H * W, max(1, T * H * W // 50))
        A.reshape(-1, 3)[idx] += 4.0
    return A.astype(F32)


def _values(A, rng, tables, radius):
    T, H, W, _ = A.shape
    sigma_inv, tg, tdg, r2_max = tables
    return {"A": A, "sigma_inv": sigma_inv, "table_g": tg, "table_dg": tdg, "r2_max": r2_max,
            "gA": normal(rng, A.shape), "energy_rows": rng.normal(size=T * H), "lam": 0.7, "radius": radius}


def _gsm(radius):
    def make(rng, T, H, W):
        return _values(patchy_albedo(rng, T, H, W), rng, gsm_tables(), radius)

    def make_smooth(rng, T, H, W):
        """Patches of 3 without outliers on the dense table: the energy is smooth where sampled."""
        return _values(patchy_albedo(rng, T, H, W, patch=3, outliers=False), rng, gsm_tables(DENSE_TABLE), radius)

    def reference(v):
        er, gA = ref.gsm_smoothness(v["A"], v["sigma_inv"], v["table_g"], v["table_dg"], v["r2_max"], v["lam"],
                                    radius=v["radius"])
        return {"energy_rows": v["energy_rows"] + er, "gA": v["gA"] + gA}

    return Case("energy_albedo_gsm", "gsm_smoothness", make,
                ("A", "sigma_inv", "table_g", "table_dg", "r2_max", "gA", "energy_rows"), ("gA", "energy_rows"),
                reference, variant=f"radius={radius}", keywords=("lam", "radius"), updates=("gA", "energy_rows"),
                tol={"energy_rows": Tol(2e-5, 1e-6), "gA": Tol(1e-4, 1e-5, 1e-4)}, no_alias=(("A", "gA"),),
                gradients=(Gradient("A", "gA", size=(1, 5, 6), make=make_smooth, rtol=2e-3, atol=0.0,
                                    atol_rel=2e-3),) if radius == 2 else ())


CASES = (_gsm(1), _gsm(2), _gsm(3))
