"""How much the light changes between frames: the input to the albedo prior's count.

Prints, per sequence, the change of the log shading between consecutive
frames along the flow (``c_t`` of :mod:`ivkernels.solver.independent_shadings`,
mean and largest over the pairs), the share above the floor ``r`` and the
count ``n`` a window of those frames gets at the default gain.  The floor
``SHADING_CHANGE_FLOOR`` is chosen to lie above every pair of the synthetic
training sequences (one lamp, or a lamp moving slowly) and below the MIT
training objects (ten very different lights); this script shows where the
sequences fall.

    python perf/light_change.py --seeds 12 13 --frames 6 --size 120 160
    python perf/light_change.py --seeds 1 2 --flow estimated
    python perf/light_change.py --kinds --mit
    python perf/light_change.py --kinds objects_camera free_camera --brightness 0.3 --noise 0.01
"""
from __future__ import annotations

import argparse

import numpy as np

import ivkernels as iv
from ivkernels.evaluation import synthetic
from ivkernels.backends import get_backend
from ivkernels.solver.independent_shadings import (SHADING_CHANGE_FLOOR, count_from_ratios,
                                                   ratios_from_changes, shading_changes)


def report(label: str, frames: np.ndarray, flow: np.ndarray, params) -> None:
    be = get_backend("warp")
    changes = shading_changes(be, be.asarray(np.ascontiguousarray(frames, np.float32)),
                              be.asarray(np.ascontiguousarray(flow, np.float32)), params.log_floor)
    ratios = ratios_from_changes(changes)
    r = float(np.nanmean(ratios))
    n = count_from_ratios(ratios, params.independent_shading_gain, len(frames))
    print(f"{label:<42} {np.nanmean(changes):10.4f} {np.nanmax(changes):10.4f} {r:8.3f} {n:7.2f}", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="*", default=[12])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=list(synthetic.KINDS))
    parser.add_argument("--flow", choices=("truth", "estimated"), default="truth",
                        help="the synthetic sequences' flow: ground truth or the default estimator's")
    parser.add_argument("--brightness", type=float, default=1.0,
                        help="scale the synthetic frames by this (a dim scene)")
    parser.add_argument("--noise", type=float, default=0.0,
                        help="add Gaussian pixel noise of this standard deviation (linear, 1 = white)")
    parser.add_argument("--mit", action="store_true", help="also the MIT-Berkeley training objects (zero flow)")
    parser.add_argument("--mit-scale", type=float, default=0.5)
    args = parser.parse_args(argv)
    params = iv.Params()
    rng = np.random.default_rng(0)
    print(f"floor {SHADING_CHANGE_FLOOR}, gain {params.independent_shading_gain}, "
          f"brightness {args.brightness}, noise {args.noise}")
    print(f"{'sequence':<42} {'c_t mean':>10} {'c_t max':>10} {'r':>8} {'n':>7}")
    for seed in args.seeds:
        for kind in args.kinds:
            seq = synthetic.render_sequence(kind, n_frames=args.frames, size=tuple(args.size), seed=seed)
            frames = args.brightness * seq.frames
            if args.noise > 0:
                frames = np.clip(frames + rng.normal(0.0, args.noise, frames.shape), 0.0, 1.0)
            truth = args.flow == "truth"
            flow = seq.flow if truth else iv.estimate_flow(frames)
            report(f"{kind}/{seed} ({'true' if truth else 'estimated'} flow)", frames, flow, params)
    if args.mit:
        from ivkernels.evaluation import datasets

        for name in datasets.available_mit_objects():
            obj = datasets.load_mit_object(name, scale=args.mit_scale)
            frames = obj.frames[:params.window]
            t, h, w, _ = frames.shape
            report(f"MIT {name} ({t} frames)", frames, np.zeros((t - 1, h, w, 2), np.float32), params)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
