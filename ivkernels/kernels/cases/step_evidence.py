"""Cases of :mod:`ivkernels.kernels.warp.step_evidence` (the offset log, the step counts of the
chromatic share per row and per pixel, the share read around each pixel, the step gate of Eq. 9's
local term, Weiss's stability cue where the scene holds still, and the stable pairs)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import F32, nans, normal, pairs, uniform
from ivkernels.kernels.reference import step_evidence as ref

#: Width of the band around a threshold (log units, pixels) where float32 and float64 may
#: decide a comparison differently: pairs there are not compared.
TIE = 1e-5

#: The same band where both sides compute in float64.
FLOAT64_TIE = 1e-12


def steps_image(rng, T: int, H: int, W: int) -> np.ndarray:
    """An offset log image (T, H, W, 3) with every kind of step: grey blocks (sharp grey steps),
    a coloured band (chromatic steps), a ramp (soft steps), sensor noise, and dark pixels."""
    yy, xx = np.mgrid[0:H, 0:W]
    grey = np.where(((yy // 3) + (xx // 4)) % 2 == 0, -0.4, -1.2)
    ramp = -0.02 * xx
    img = np.repeat((grey + ramp)[None, :, :, None], 3, axis=-1).repeat(T, axis=0)
    img[:, H // 3: 2 * H // 3 + 1] += np.log(np.array([1.0, 0.6, 0.8]))       # a coloured band
    img = img + normal(rng, (T, H, W, 3), 0.0, 0.03) + normal(rng, (T, 1, 1, 1), 0.0, 0.1)
    img[:, ::5, ::3] = np.log(ref.DARK_OFFSET)                                   # the darkest pixels
    return img.astype(F32)


def _pair_ties(log_image, tau, tau_chroma, floor=None, k=0.0, band=TIE):
    """Per pixel (T, H, W): whether one of its horizontal or vertical pairs, its steps net of
    the noise ``floor`` at ``k``, lies within ``band`` of ``tau`` or ``tau_chroma``."""
    L, C = ref.luminance_chroma(log_image)
    near = np.zeros(L.shape, bool)
    for dy, dx in ref.AXIS_NEIGHBOURS:
        a, b = ref.pair_slices(L.shape, dy, dx)
        dL, dC = ref.net_steps(np.abs(L[a] - L[b]), np.abs(C[a] - C[b]).max(axis=-1), floor, k, a, b)
        close = np.abs(dL - tau) < band
        if tau_chroma > 0:
            close |= np.abs(dC - tau_chroma) < band
        near[a] |= close
    return near


def noise_floor(rng, T: int, H: int, W: int) -> np.ndarray:
    """A noise floor (T, H, W, 2) as ``median5x5(typical_steps)`` gives: 0 over most of the frame,
    up to the size of :func:`steps_image`'s noise steps elsewhere."""
    f = uniform(rng, (T, H, W, 2), 0.0, 0.06)
    f[:, : H // 2] = 0.0
    return f.astype(F32)


def _typical_steps():
    def make(rng, T, H, W):
        return {"log_image": steps_image(rng, T, H, W), "steps": nans((T, H, W, 2))}

    return Case("step_evidence", "typical_steps", make, ("log_image", "steps"), ("steps",),
                lambda v: {"steps": ref.typical_steps(v["log_image"])}, tol=Tol(1e-5, 1e-6))


def _temporal_steps():
    def make(rng, T, H, W):
        # whole-pixel shifts with a fractional part away from the rounding tie (float32 and
        # float64 round alike), some carrying samples out of the frame
        f = rng.integers(-3, 4, (pairs(T), H, W, 2)) + uniform(rng, (pairs(T), H, W, 2), -0.4, 0.4)
        f[:, :, :2, 0] -= W + 2.0
        return {"log_image": steps_image(rng, T, H, W), "flow": f.astype(F32), "steps": nans((T, H, W, 2))}

    return Case("step_evidence", "temporal_steps", make, ("log_image", "flow", "steps"), ("steps",),
                lambda v: {"steps": ref.temporal_steps(v["log_image"], v["flow"])}, tol=Tol(1e-5, 1e-6))


def _noise_image(rng, T, H, W):
    """An offset log image over the whole brightness range (some pixels beyond it), and steps
    over the whole range of the step bins and beyond, zeros included.  Every side compares the
    same float32 values with the same float32 edges, so the bins agree exactly."""
    img = uniform(rng, (T, H, W, 3), np.log(ref.DARK_OFFSET) - 0.3, 0.3)
    steps = np.exp(uniform(rng, (T, H, W, 2), np.log(1e-5), np.log(3.0))).astype(F32)
    steps[:, ::4, ::3] = 0.0
    return img, steps


def _step_histogram():
    def make(rng, T, H, W):
        img, steps = _noise_image(rng, T, H, W)
        shape = (2, ref.NOISE_LEVEL_BINS, ref.NOISE_STEP_BINS)
        return {"log_image": img, "steps": steps, "counts": np.full(shape, -1, np.int32)}

    return Case("step_evidence", "step_histogram", make, ("log_image", "steps", "counts"), ("counts",),
                lambda v: {"counts": ref.step_histogram(v["log_image"], v["steps"])}, tol=EXACT)


def _level_medians():
    def make(rng, T, H, W):
        # per bin a few hundred pixels or fewer than NOISE_LEVEL_MIN_COUNT (the first and last
        # bins of channel 0, inner runs of both), or none at all; channel 1 has one counted bin
        counts = rng.integers(0, 6, (2, ref.NOISE_LEVEL_BINS, ref.NOISE_STEP_BINS)).astype(np.int32)
        counts[:, :, : rng.integers(0, 60)] = 0
        for b in (0, 5, 6, ref.NOISE_LEVEL_BINS - 1):
            counts[0, b] = 0
            counts[0, b, rng.integers(0, ref.NOISE_STEP_BINS)] = ref.NOISE_LEVEL_MIN_COUNT - 1
        counts[1, :] = 0
        counts[1, 9, 40] = ref.NOISE_LEVEL_MIN_COUNT
        return {"counts": counts, "table": nans((2, ref.NOISE_LEVEL_BINS))}

    return Case("step_evidence", "level_medians", make, ("counts", "table"), ("table",),
                lambda v: {"table": ref.level_medians(v["counts"])}, tol=Tol(1e-5, 1e-7))


def _cap_at_level(scale):
    def make(rng, T, H, W):
        img, steps = _noise_image(rng, T, H, W)
        return {"log_image": img, "table": uniform(rng, (2, ref.NOISE_LEVEL_BINS), 0.0, 0.2), "scale": scale,
                "floor": (steps * 0.1).astype(F32)}

    return Case("step_evidence", "cap_at_level", make, ("log_image", "table", "scale", "floor"), ("floor",),
                lambda v: {"floor": ref.cap_at_level(v["log_image"], v["table"], v["scale"], v["floor"])},
                variant=f"scale={scale:g}", tol=Tol(1e-5, 1e-7))


def _offset_log(offset):
    def make(rng, T, H, W):
        img = np.log(uniform(rng, (T, H, W, 3), 1e-6, 1.0)).astype(F32)      # down to the darkest pixels
        return {"log_image": img, "out": nans((T, H, W, 3)), "offset": offset}

    return Case("step_evidence", "offset_log", make, ("log_image", "out", "offset"), ("out",),
                lambda v: {"out": ref.offset_log(v["log_image"], v["offset"])}, variant=f"offset={offset:g}",
                tol=Tol(1e-6, 1e-6), in_place=(("log_image", "out"),))


def _floor_args(rng, T, H, W, k):
    """The ``floor`` and ``k`` arguments of a case: none at ``k = 0``."""
    return {"floor": noise_floor(rng, T, H, W), "k": k} if k > 0 else {}


def _counts(tau, tau_chroma, k=0.0):
    def make(rng, T, H, W):
        return {"log_image": steps_image(rng, T, H, W), "counts": np.full((T * H, 2), -1, np.int32),
                "tau": tau, "tau_chroma": tau_chroma, **_floor_args(rng, T, H, W, k)}

    def tied(v):
        near = _pair_ties(v["log_image"], v["tau"], v["tau_chroma"], v.get("floor"), v.get("k", 0.0)).any(axis=2)
        return {"counts": np.repeat(near.reshape(-1)[:, None], 2, axis=1)}

    args = ("log_image", "counts", "tau", "tau_chroma") + (("floor", "k") if k > 0 else ())
    return Case("step_evidence", "step_counts", make, args, ("counts",),
                lambda v: {"counts": ref.step_counts(v["log_image"], v["tau"], v["tau_chroma"], v.get("floor"),
                                                     v.get("k", 0.0))},
                variant=f"tau={tau:g},tau_chroma={tau_chroma:g}" + (f",k={k:g}" if k > 0 else ""), tol=EXACT,
                ignore=tied)


def _pixel_counts(tau, tau_chroma, k=0.0):
    def make(rng, T, H, W):
        return {"log_image": steps_image(rng, T, H, W), "counts": np.full((T, H, W, 2), -1, np.int32),
                "offset": ref.DARK_OFFSET, "tau": tau, "tau_chroma": tau_chroma, **_floor_args(rng, T, H, W, k)}

    def tied(v):
        """Pixels with a pair within :data:`FLOAT64_TIE` of a threshold: a last-place difference of
        ``exp`` or ``log`` between libraries could decide them differently."""
        near = _pair_ties(ref.offset_log(v["log_image"], v["offset"]), v["tau"], v["tau_chroma"], v.get("floor"),
                          v.get("k", 0.0), FLOAT64_TIE)
        return {"counts": np.repeat(near[..., None], 2, axis=-1)}

    args = ("log_image", "counts", "offset", "tau", "tau_chroma") + (("floor", "k") if k > 0 else ())
    return Case("step_evidence", "pixel_counts", make, args,
                ("counts",), lambda v: {"counts": ref.pixel_counts(v["log_image"], v["offset"], v["tau"],
                                                                   v["tau_chroma"], v.get("floor"),
                                                                   v.get("k", 0.0))},
                variant=f"tau={tau:g},tau_chroma={tau_chroma:g}" + (f",k={k:g}" if k > 0 else ""), tol=EXACT,
                ignore=tied)


def _share_weight(radius, counts):
    """``counts``: "random" (0 to 2 sharp steps per pixel, some chromatic, empty patches),
    or "none" (no sharp step anywhere: the share is the prior's, 0)."""
    def make(rng, T, H, W):
        if counts == "random":
            sharp = rng.integers(0, 3, (T, H, W))
            sharp[:, : H // 2, : W // 2] = 0                                  # a patch without steps
            c = np.stack([sharp, rng.integers(0, sharp + 1)], axis=-1).astype(np.int32)
        else:
            c = np.zeros((T, H, W, 2), np.int32)
        return {"counts": c, "weight": uniform(rng, (T, H, W), 0.0, 1.0), "radius": radius,
                "prior_steps": 4.0}

    # integer window sums, one float64 division rounded to float32, then float32 products: bit for bit
    return Case("step_evidence", "share_weight", make, ("counts", "weight", "radius", "prior_steps"), ("weight",),
                lambda v: {"weight": ref.share_weight(v["counts"], v["weight"], v["radius"], v["prior_steps"])},
                variant=f"radius={radius},{counts}", updates=("weight",), tol=EXACT)


def _gate(tau, tau_chroma, counts, k=0.0):
    """``counts``: "image" (those of the image, as the solver passes them), "random", or "none"
    (no sharp step: the gain is not scaled); ``k > 0``: the steps net of a noise floor."""
    def make(rng, T, H, W):
        img = steps_image(rng, T, H, W)
        extra = _floor_args(rng, T, H, W, k)
        if counts == "image":
            c = ref.step_counts(img, tau, tau_chroma, extra.get("floor"), k)
        elif counts == "random":
            sharp = rng.integers(0, 2 * W + 1, (T * H, 1))
            c = np.concatenate([sharp, rng.integers(0, sharp + 1)], axis=1).astype(np.int32)
        else:
            c = np.zeros((T * H, 2), np.int32)
        return {"log_image": img, "counts": c, "weight": uniform(rng, (T, H, W), 0.0, 1.0),
                "gate": uniform(rng, (T, H, W), 0.0, 1.0), "gain": 8.0, "tau": tau, "tau_chroma": tau_chroma,
                **extra}

    def reference(v):
        return {"gate": ref.step_gate(v["log_image"], v["counts"], v["weight"], v["gate"], v["gain"], v["tau"],
                                      v["tau_chroma"], v.get("floor"), v.get("k", 0.0))}

    # float32 steps of log values up to 5 in size: the evidence to about 4e-6, the gate to 8 times that
    args = ("log_image", "counts", "weight", "gate", "gain", "tau", "tau_chroma") + (("floor", "k") if k > 0 else ())
    return Case("step_evidence", "step_gate", make, args, ("gate",), reference,
                variant=f"tau={tau:g},tau_chroma={tau_chroma:g},{counts}" + (f",k={k:g}" if k > 0 else ""),
                updates=("gate",),
                tol=Tol(1e-5, 4e-5), in_place=(("weight", "gate"),))


def _still(tau, static_flow):
    def make(rng, T, H, W):
        img = normal(rng, (T, H, W, 3), -1.0, 0.5)
        img[:, H // 4: H // 2 + 1, W // 4: W // 2 + 1] = -1.0          # a flat patch
        f = normal(rng, (pairs(T), H, W, 2), 0.0, 0.3)                  # around the threshold
        f[:, : H // 2] *= 10.0                                            # and a moving half
        f[:, :, :3, 0] -= 4.0 * static_flow                               # samples leaving the image
        return {"log_image": img, "flow": f, "weight": nans((T, H, W)), "tau": tau, "static_flow": static_flow}

    def tied(v):
        speed = np.sqrt((np.asarray(v["flow"], np.float64) ** 2).sum(axis=-1))
        near = np.abs(speed - v["static_flow"]) < TIE
        out = np.zeros(np.shape(v["weight"]), bool)
        out[:-1] |= near
        out[1:] |= near
        return {"weight": out}

    return Case("step_evidence", "still_stability", make, ("log_image", "flow", "weight", "tau", "static_flow"),
                ("weight",), lambda v: {"weight": ref.still_stability(v["log_image"], v["flow"], v["tau"],
                                                                      v["static_flow"])},
                variant=f"tau={tau:g},static_flow={static_flow:g}", tol=Tol(1e-4, 1e-5), ignore=tied)


def _stable(T_steps, floor):
    """Pairs of every kind over the frames: stable grey steps, steps whose contrast changes with the
    light, a silhouette over ``MAX_STABLE_STEP``, flat pairs, and a moving patch."""
    def make(rng, T, H, W):
        yy, xx = np.mgrid[0:H, 0:W]
        base = np.where(((yy // 3) + (xx // 4)) % 2 == 0, -0.4, -0.75)           # stable steps of 0.35
        img = np.repeat(base[None, :, :, None], 3, axis=-1).repeat(T, axis=0)
        light = normal(rng, (T, 1, W, 1), 0.0, 0.25)                             # contrast changing per column
        img[:, H // 2:] += np.cumsum(light, axis=2)[:, :, : W] * (yy[None, H // 2:, :, None] % 2)
        img[:, :, W - 2:] -= 3.0                                                  # a dark border: big steps
        img = img + normal(rng, (T, H, W, 3), 0.0, T_steps) + normal(rng, (T, 1, 1, 1), 0.0, 0.1)
        f = normal(rng, (pairs(T), H, W, 2), 0.0, 0.2)
        f[:, : H // 3, : W // 3] += 3.0                                            # a moving patch
        return {"log_image": img.astype(F32), "flow": f, "pairs": nans((H, W, 2)), "tau": 0.1,
                "stability": 0.1, "floor": floor, "static_flow": 1.0}

    def tied(v):
        """Pairs whose evidence, median step or speed lies within a band of a threshold: float32 and
        float64 may decide them differently."""
        speed = np.sqrt((np.asarray(v["flow"], np.float64) ** 2).sum(axis=-1))
        near_speed = (np.abs(speed - v["static_flow"]) < TIE).any(axis=0)
        out = np.zeros((*near_speed.shape, 2), bool)
        for k, (a, b), m, ev in ref.stable_step_parts(v["log_image"], v["tau"], v["stability"]):
            out[a[1], a[2], k] = ((np.abs(np.abs(m) - ref.MAX_STABLE_STEP) < 1e-4)
                                  | (np.abs(ev - v["floor"]) < 1e-4) | near_speed[a[1:]] | near_speed[b[1:]])
        return {"pairs": out}

    return Case("step_evidence", "stable_pairs", make,
                ("log_image", "flow", "pairs", "tau", "stability", "floor", "static_flow"), ("pairs",),
                lambda v: {"pairs": ref.stable_pairs(v["log_image"], v["flow"], v["tau"], v["stability"],
                                                     v["floor"], v["static_flow"])},
                variant=f"noise={T_steps:g},floor={floor:g}", tol=Tol(1e-4, 1e-4), ignore=tied)


def _moving(tau, spread):
    """Still pairs with a steady step, pairs an edge of the light crosses in some frames, flat
    pairs, a relief whose steps change in every frame (the right third), a moving patch and
    speeds around the threshold."""
    def make(rng, T, H, W):
        yy, xx = np.mgrid[0:H, 0:W]
        base = np.where(((yy // 3) + (xx // 4)) % 2 == 0, -0.4, -0.75)           # steady steps of 0.35
        img = np.repeat(base[None, :, :, None], 3, axis=-1).repeat(T, axis=0)
        for t in range(T):                                                        # a shadow's edge moving right
            img[t, :, : (t * W) // max(T, 1)] -= 1.2
        img[:, :, 2 * W // 3:] += normal(rng, (T, H, W - 2 * W // 3, 1), 0.0, 0.3)  # a relief under moving light
        img = img + normal(rng, (T, H, W, 3), 0.0, 0.02)
        f = normal(rng, (pairs(T), H, W, 2), 0.0, 0.3)
        f[:, : H // 3, : W // 3] += 3.0                                            # a moving patch
        return {"log_image": img.astype(F32), "flow": f, "factor": nans((T, H, W)), "tau": tau,
                "spread": spread, "static_flow": 1.0}

    def tied(v):
        speed = np.sqrt((np.asarray(v["flow"], np.float64) ** 2).sum(axis=-1))
        near = (np.abs(speed - v["static_flow"]) < TIE).any(axis=0)             # (H, W)
        grown = near.copy()                                                      # and its axis neighbours
        grown[1:] |= near[:-1]
        grown[:-1] |= near[1:]
        grown[:, 1:] |= near[:, :-1]
        grown[:, :-1] |= near[:, 1:]
        return {"factor": np.broadcast_to(grown, np.shape(v["factor"]))}

    return Case("step_evidence", "moving_steps", make,
                ("log_image", "flow", "factor", "tau", "spread", "static_flow"), ("factor",),
                lambda v: {"factor": ref.moving_steps(v["log_image"], v["flow"], v["tau"], v["spread"],
                                                      v["static_flow"])},
                variant=f"tau={tau:g},spread={spread:g}", tol=Tol(1e-4, 1e-4), ignore=tied)


CASES = (
    _offset_log(ref.DARK_OFFSET),
    _offset_log(0.5),
    _typical_steps(),
    _temporal_steps(),
    _step_histogram(),
    _level_medians(),
    _cap_at_level(3.0),
    _cap_at_level(0.5),
    _counts(0.1, 0.05),
    _counts(0.3, 0.0),
    _counts(0.1, 0.05, k=3.5),
    _pixel_counts(0.1, 0.05),
    _pixel_counts(0.3, 0.0),
    _pixel_counts(0.1, 0.05, k=3.5),
    _share_weight(2, "random"),
    _share_weight(0, "random"),
    _share_weight(1000, "random"),
    _share_weight(3, "none"),
    _gate(0.1, 0.05, "image"),
    _gate(0.1, 0.05, "random"),
    _gate(0.25, 0.0, "none"),
    _gate(0.1, 0.05, "image", k=3.5),
    _still(0.3, 0.25),
    _still(0.1, 1.0),
    _stable(0.01, 0.3),
    _stable(0.03, 0.0),
    _moving(0.25, 0.0),
    _moving(1.0, 0.0),
    _moving(0.25, 2.0),
    _moving(0.5, 4.0),
)
