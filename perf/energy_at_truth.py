"""Each term of Eq. 2 at the ground truth beside its value at the solver's answer.

For every training sequence (synthetic seeds other than 0, with their
ground-truth flow, and with ``--mit`` the MIT-Berkeley objects with their
exact zero flow) the script decomposes the video as one window, rebuilds the
finest level's energy with the same motion maps, and evaluates each term at
three points of the data-consistent set ``A = I - S`` (the set the solver
searches, :class:`ivkernels.solver.energy.ConstrainedEnergy`):

- ``solution``: the log shading ``decompose()`` returned;
- ``truth``: the log of the true shading (synthetic: the renderer's; MIT: the
  per-frame shading of :class:`ivkernels.evaluation.datasets.MITObject`);
- ``weiss``: the log shading that Weiss's temporal median implies
  (``I - A_weiss``, grey part), the baseline the MIT objects are scored against.

On the MIT objects the truth exists inside the mask only; outside it (the
black background) the ``truth`` and ``weiss`` points keep the solution's
shading, so their energies differ from the solution's only on the object.

If the truth's energy is above the solution's, the model prefers the wrong
split and weights (not iterations) must change; if it is below, the solver
stops short of a better minimum.  The albedo LMSE of each point is printed
beside its energy.  The coupling variable ``S~`` is set from each point's own
``S`` (Eq. 13's median step) before the terms are evaluated.

    python perf/energy_at_truth.py --seeds 12 --frames 6 --size 120 160
    python perf/energy_at_truth.py --kinds --mit --mit-objects teabag2 squirrel
"""
from __future__ import annotations

import argparse

import numpy as np

import ivkernels as iv
from common import EVAL_SEED, parse_grid
from ivkernels.evaluation import baselines, datasets, metrics, synthetic
from ivkernels.backends.registry import get_backend
from ivkernels.priors import load_albedo_prior
from ivkernels.solver.energy import ConstrainedEnergy, WindowEnergy
from ivkernels.solver.independent_shadings import independent_shadings, window_params
from ivkernels.solver.motion_maps import motion_maps, window_occlusion
from ivkernels.solver.window_solver import log_and_weight

TERMS = ConstrainedEnergy.TERMS


def finest_energy(be, frames, flow, params, prior) -> WindowEnergy:
    """The finest level's :class:`WindowEnergy` of a one-window decomposition,
    with the window's settings as the solve makes them (:func:`window_params`: the albedo
    priors divided by its independent shadings, Weiss's cue only where its light changes, the
    brightness test of :func:`window_occlusion` where it does not)."""
    frames_be = be.asarray(frames)
    flow_be = be.asarray(flow)
    occlusion, boundary = motion_maps(be, frames_be, flow_be, params)
    n = independent_shadings(be, frames_be, flow_be, params.independent_shading_gain, params.log_floor)
    params = window_params(params, n)
    occlusion = window_occlusion(be, frames_be, flow_be, occlusion, params, n)
    log_image, w_lum = log_and_weight(be, frames_be, params)
    return WindowEnergy(be, log_image, w_lum, flow_be, occlusion, boundary, params, prior)


def terms_at(energy: WindowEnergy, log_shading: np.ndarray) -> dict[str, float]:
    """Each term (and ``total``) at ``S = log_shading``, ``A = I - S``, ``S~`` from ``S``."""
    be = energy.be
    be.vecops.copy(be.asarray(np.ascontiguousarray(log_shading, np.float32).reshape(-1)),
                   energy.S.reshape((energy.n,)))
    ConstrainedEnergy(energy).sync_albedo()
    energy.update_coupling()
    terms = {name: value for name, value in energy.term_energies().items() if name in TERMS}
    terms["total"] = sum(terms.values())
    return terms


def grey_log_shading(frames: np.ndarray, albedo: np.ndarray, floor: float) -> np.ndarray:
    """``mean_c (log i - log a)``: the grey log shading a colour albedo implies, (T, H, W)."""
    log_i = np.log(np.maximum(frames, floor))
    log_a = np.log(np.maximum(np.broadcast_to(albedo, frames.shape), floor))
    return (log_i - log_a).mean(axis=3).astype(np.float32)


def sequences(args):
    """(label, frames, flow, albedo truth, shading truth, mask) per training sequence."""
    for seed in args.seeds:
        if seed == EVAL_SEED:
            raise SystemExit("seed 0 is kept for reporting; measure on training seeds only")
        for kind in args.kinds:
            seq = synthetic.render_kind(kind, n_frames=args.frames, size=tuple(args.size), seed=seed)
            yield f"{kind}/{seed}", seq.frames, seq.flow, seq.albedo, seq.shading, None
    if args.mit:
        for name in args.mit_objects or datasets.available_mit_objects():
            obj = datasets.load_mit_object(name, scale=args.mit_scale, achromatic=args.mit_achromatic)
            t, h, w, _ = obj.frames.shape
            shading = np.where(obj.mask, obj.frame_shading, 1.0).astype(np.float32)
            yield (f"MIT {name}{' (grey)' if args.mit_achromatic else ''}", obj.frames, np.zeros((t - 1, h, w, 2), np.float32),
                   np.broadcast_to(obj.albedo, obj.frames.shape), shading, obj.mask)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="*", default=[12])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=None, choices=list(synthetic.SCENE_KINDS), metavar="KIND",
                        help="names of synthetic.SCENE_KINDS (default: the suite's); none for MIT only")
    parser.add_argument("--suite", default="classic",
                        choices=("classic", "new", "all", "static", "achromatic", "hard"),
                        help="the kinds when --kinds is not given (synthetic.scene_kinds; default classic)")
    parser.add_argument("--mit", action="store_true", help="also the MIT-Berkeley training objects")
    parser.add_argument("--mit-scale", type=float, default=0.5)
    parser.add_argument("--mit-objects", nargs="+", metavar="NAME")
    parser.add_argument("--mit-achromatic", action="store_true",
                        help="the MIT objects as greyscale footage (luminance in, luminance reflectance as truth)")
    parser.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="Params fields")
    parser.add_argument("--backend", default="warp")
    args = parser.parse_args(argv)
    if args.kinds is None:
        args.kinds = synthetic.scene_kinds(args.suite)

    fields = parse_grid(args.set)[0]
    be = get_backend(args.backend)
    prior = load_albedo_prior()
    print(f"terms of Eq. 2 at the finest level (A = I - S); Params changes: {fields or 'none'}")
    print(f"{'sequence':28s} {'point':9s} " + " ".join(f"{n:>16s}" for n in (*TERMS, "total"))
          + f" {'LMSE A':>8s}")
    for label, frames, flow, albedo, shading, mask in sequences(args):
        t = frames.shape[0]
        params = iv.Params(**{"window": max(t, 2), "overlap": 0, **fields})
        video = iv.decompose(frames, flow=flow, params=params, backend=args.backend)
        energy = finest_energy(be, frames, flow, params, prior)
        weiss_albedo, _ = baselines.weiss(frames)
        solution = np.log(np.maximum(video.shading, 1e-12))
        points = {
            "solution": solution,
            "truth": np.log(np.maximum(shading, params.log_floor)),
            "weiss": grey_log_shading(frames, weiss_albedo, params.log_floor),
        }
        if mask is not None:
            # No truth outside the mask (black background): every point keeps the
            # solution's shading there, so the totals differ only where truth exists.
            for name in ("truth", "weiss"):
                points[name] = np.where(mask, points[name], solution).astype(np.float32)
        for point, log_shading in points.items():
            terms = terms_at(energy, log_shading)
            implied = np.exp(np.log(np.maximum(frames, params.log_floor)) - log_shading[..., None])
            lmse = metrics.intrinsic_lmse(implied, np.exp(log_shading), albedo, shading,
                                          mask=mask)["albedo"]
            print(f"{label:28s} {point:9s} " + " ".join(f"{terms[n]:16.6e}" for n in (*TERMS, "total"))
                  + f" {lmse:8.4f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
