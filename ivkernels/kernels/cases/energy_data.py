"""Cases of :mod:`ivkernels.kernels.warp.energy_data` (Eq. 3 data term; the constraint A = I - S)."""
from __future__ import annotations



from ivkernels.kernels.cases import Case, Gradient, Tol
from ivkernels.kernels.cases.inputs import log_image, nans, normal, uniform
from ivkernels.kernels.reference import energy_data as ref


def _data_term(rng, T, H, W):
    """Log input, albedo and shading with residuals of order 1, luminance weights, random
    accumulator contents."""
    return {"I": log_image(rng, (T, H, W, 3)), "A": log_image(rng, (T, H, W, 3)),
            "S": normal(rng, (T, H, W), -0.5, 0.5), "w_lum": uniform(rng, (T, H, W), 0.001, 1.0),
            "gA": normal(rng, (T, H, W, 3)), "gS": normal(rng, (T, H, W)),
            "energy_rows": rng.normal(size=T * H), "lam": 7.0, "eps": 0.01}


def _data_reference(v):
    er, gA, gS = ref.data_term(v["I"], v["A"], v["S"], v["w_lum"], v["lam"], v["eps"])
    return {"energy_rows": v["energy_rows"] + er, "gA": v["gA"] + gA, "gS": v["gS"] + gS}


def _constrained_albedo(rng, T, H, W):
    return {"I": log_image(rng, (T, H, W, 3)), "S": normal(rng, (T, H, W), -0.5, 0.5), "A": nans((T, H, W, 3))}


def _constrained_gradient(rng, T, H, W):
    return {"gA": normal(rng, (T, H, W, 3)), "gS": normal(rng, (T, H, W)), "out": nans((T, H, W))}


# d/dz of z / sqrt(z^2 + eps^2) is up to 1/eps: float32 rounding of z shows up scaled by lam / eps
_GRAD_TOL = Tol(1e-5, 1e-3)

CASES = (
    Case("energy_data", "data_term", _data_term, ("I", "A", "S", "w_lum", "gA", "gS", "energy_rows"),
         ("gA", "gS", "energy_rows"), _data_reference, keywords=("lam", "eps"),
         updates=("gA", "gS", "energy_rows"),
         tol={"energy_rows": Tol(1e-5, 1e-6), "gA": _GRAD_TOL, "gS": _GRAD_TOL},
         gradients=(Gradient("A", "gA", overrides={"lam": 10.0, "eps": 0.05}),
                    Gradient("S", "gS", overrides={"lam": 10.0, "eps": 0.05}))),
    Case("energy_data", "constrained_albedo", _constrained_albedo, ("I", "S", "A"), ("A",),
         lambda v: {"A": ref.constrained_albedo(v["I"], v["S"])}, tol=Tol(0.0, 1e-6), no_alias=(("I", "A"),)),
    Case("energy_data", "constrained_gradient", _constrained_gradient, ("gA", "gS", "out"), ("out",),
         lambda v: {"out": ref.constrained_gradient(v["gA"], v["gS"])}, tol=Tol(1e-6, 1e-6),
         in_place=(("gS", "out"),)),
)


