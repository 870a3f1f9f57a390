"""Cases of :mod:`ivkernels.kernels.warp.energy_albedo_entropy` (Eq. 12: global sparsity by histogram).

The histogram cube is the smallest cube on the lattice ``hist_lo + n h`` of the
shipped prior that holds the whitened albedo with 3 bins to spare (any cube
holding the data gives the same energy), so the references stay fast.
"""
from __future__ import annotations

import functools

import numpy as np

from ivkernels.kernels.cases import EXACT, Allocate, Case, Gradient, Tol
from ivkernels.kernels.cases.inputs import F32, nans, normal
from ivkernels.kernels.reference import energy_albedo_entropy as ref
from ivkernels.priors import entropy_blur_weights, load_albedo_prior

BIN_WIDTH = 0.06


@functools.lru_cache(maxsize=None)
def prior():
    return load_albedo_prior()


def clustered_albedo(rng, T, H, W, spread=0.05, n_colours=4):
    """Log albedo of a few materials: per-frame cluster centres plus ``spread``."""
    centres = rng.normal(-1.0, 0.5, (T, n_colours, 3))
    label = rng.integers(0, n_colours, (T, H * W))
    A = np.take_along_axis(centres, label[..., None], axis=1).reshape(T, H, W, 3)
    return (A + rng.normal(0.0, spread, A.shape)).astype(F32)


def tight_cube(A, whiten, h, margin=3):
    """``(lo, bins)``: the smallest cube on the lattice ``hist_lo + n h`` holding ``whiten @ A``
    with ``margin`` bins to spare (a cube of 2 margins for empty ``A``)."""
    base = prior().hist_lo
    u = np.asarray(A, np.float64).reshape(-1, 3) @ np.asarray(whiten, np.float64).T
    u_min, u_max = (u.min(), u.max()) if u.size else (base, base)
    lo = base + np.floor((u_min - base) / h - margin) * h
    return float(lo), int(np.ceil((u_max - lo) / h + margin)) + 1


def _setting(rng, T, H, W, spread=0.05, n_colours=4):
    """Albedo, whitening, cube, blur taps and the reference histogram, blur and dots."""
    p = prior()
    A = clustered_albedo(rng, T, H, W, spread, n_colours)
    whiten = p.whiten.astype(F32)
    lo, bins = tight_cube(A, whiten, BIN_WIDTH)
    taps = entropy_blur_weights(p.sigma_p, BIN_WIDTH).astype(F32)
    return {"A": A, "whiten": whiten, "lo": lo, "h": BIN_WIDTH, "taps": taps, "sigma_p": float(p.sigma_p),
            "bins": bins}


def _with_reference_cube(v):
    """``v`` plus the reference histogram, its row flags, blur and per-frame dots (float32 / float64)."""
    T, B = v["A"].shape[0], v["bins"]
    if v["A"].size:
        hist = ref.entropy_histogram(v["A"], v["whiten"], v["lo"], v["h"], B)
        blurred = ref.entropy_blur(hist.astype(F32), v["taps"])
    else:
        hist = blurred = np.zeros((T, B, B, B))
    flags = np.zeros((2, T, B, B), np.int32)
    flags[0] = hist.sum(axis=3) > 0
    return {**v, "hist": hist.astype(F32), "row_flags": flags, "blurred": blurred.astype(F32),
            "dots": np.einsum("tijk,tijk->t", hist.astype(F32).astype(np.float64), blurred.astype(F32))}


def _histogram(rng, T, H, W):
    v = _setting(rng, T, H, W)
    B = v["bins"]
    return {**v, "hist": nans((T, B, B, B)), "row_flags": np.full((2, T, B, B), -1, np.int32)}


def _histogram_reference(v):
    r = _with_reference_cube(v)
    return {"hist": r["hist"], "row_flags": r["row_flags"]}


def _empty_rows(v):
    """A row that received only zero weights may be flagged either way."""
    hist = ref.entropy_histogram(v["A"], v["whiten"], v["lo"], v["h"], v["bins"])
    empty = np.zeros(v["row_flags"].shape, bool)
    empty[0] = hist.sum(axis=3) == 0
    return {"row_flags": empty}


def _blur(rng, T, H, W):
    v = _with_reference_cube(_setting(rng, T, H, W))
    return {**v, "tmp": nans(v["hist"].shape), "blurred": nans(v["hist"].shape)}


def _dot(rng, T, H, W):
    v = _with_reference_cube(_setting(rng, T, H, W))
    return {**v, "dots": np.full(T, np.nan)}


def _slice_gradient(rng, T, H, W):
    v = _with_reference_cube(_setting(rng, T, H, W))
    return {**v, "gA": normal(rng, v["A"].shape), "lam": 0.7}


def _energy(rng, T, H, W):
    v = _with_reference_cube(_setting(rng, T, H, W))
    return {**v, "n_pixels": H * W, "energy_rows": rng.normal(size=T * H), "lam": 0.7}


def _term_values(v, rng):
    T, H = v["A"].shape[:2]
    bins = v["bins"]
    scratch = Allocate(lambda be, _: be.energy_albedo_entropy.allocate_entropy_scratch(T, bins, device=be.device))
    return {**v, "scratch": scratch, "gA": normal(rng, v["A"].shape), "energy_rows": rng.normal(size=T * H),
            "lam": 0.7}


def _term(rng, T, H, W):
    return _term_values(_setting(rng, T, H, W), rng)


def _term_smooth(rng, T, H, W):
    """Two loose clusters: every pixel's gradient is well away from zero."""
    return _term_values(_setting(rng, T, H, W, spread=0.1, n_colours=2), rng)


def _reference_term(v):
    return ref.entropy_term(v["A"], v["whiten"], v["lo"], v["h"], v["taps"], v["sigma_p"], v["lam"], v["bins"])


_PEAK_TOL = Tol(1e-5, 1e-4)

CASES = (
    Case("energy_albedo_entropy", "entropy_histogram", _histogram, ("A", "whiten", "lo", "h", "hist", "row_flags"),
         ("hist", "row_flags"), _histogram_reference, tol={"hist": _PEAK_TOL, "row_flags": EXACT},
         ignore=_empty_rows),
    Case("energy_albedo_entropy", "entropy_blur", _blur, ("hist", "taps", "row_flags", "tmp", "blurred"),
         ("row_flags", "tmp", "blurred"), lambda v: {"blurred": ref.entropy_blur(v["hist"], v["taps"])},
         updates=("row_flags",), scratch=("row_flags", "tmp"), tol={"blurred": Tol(0.0, 0.0, 1e-5)},
         no_alias=(("hist", "blurred"), ("hist", "tmp"))),
    Case("energy_albedo_entropy", "entropy_dot", _dot, ("hist", "blurred", "dots"), ("dots",),
         lambda v: {"dots": np.einsum("tijk,tijk->t", v["hist"].astype(np.float64), v["blurred"])},
         tol={"dots": Tol(1e-6, 0.0)}),
    Case("energy_albedo_entropy", "entropy_slice_gradient", _slice_gradient,
         ("A", "whiten", "lo", "h", "blurred", "dots", "gA", "lam"), ("gA",),
         lambda v: {"gA": v["gA"] + _reference_term(v)[1]}, updates=("gA",), tol={"gA": Tol(1e-3, 0.0, 1e-4)},
         no_alias=(("A", "gA"),)),
    Case("energy_albedo_entropy", "entropy_energy", _energy, ("dots", "sigma_p", "n_pixels", "energy_rows", "lam"),
         ("energy_rows",), lambda v: {"energy_rows": v["energy_rows"] + _reference_term(v)[0]},
         updates=("energy_rows",), tol={"energy_rows": Tol(1e-6, 1e-6)}),
    Case("energy_albedo_entropy", "entropy_term", _term, ("A", "whiten", "lo", "h", "taps", "sigma_p", "scratch",
                                                          "gA", "energy_rows"),
         ("gA", "energy_rows"), lambda v: dict(zip(("energy_rows", "gA"), (
             v[k] + r for k, r in zip(("energy_rows", "gA"), _reference_term(v))))),
         keywords=("lam",), updates=("gA", "energy_rows"),
         tol={"energy_rows": Tol(1e-6, 1e-6), "gA": Tol(1e-3, 0.0, 1e-4)}, no_alias=(("A", "gA"),),
         gradients=(Gradient("A", "gA", size=(2, 3, 4), make=_term_smooth, rtol=1e-3, atol=0.0, atol_rel=1e-3),)),
)
