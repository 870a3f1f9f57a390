"""Choose the energy's weights on training data: a grid search that prints a table.

Every configuration is a set of :class:`ivkernels.Params` fields; for each it
decomposes the synthetic training sequences (seeds other than 0, which is kept
for reporting) with ground-truth flow and without temporal terms, and prints
the LMSE (Grosse et al., mean of albedo and shading) per kind and the mean.
The kinds are names of ``synthetic.SCENE_KINDS`` (``--kinds``, or a
``--suite`` of them).  With ``--mit`` it also decomposes the MIT-Berkeley
training objects (each a static object under ten lights, so with their exact
zero flow; ``--mit-achromatic`` as greyscale footage) and prints the albedo
LMSE inside the mask per object and its mean, on separate rows.
Choices made with it are recorded in the docstring of :class:`ivkernels.Params`
and in perf/RESULTS.md with the command that produced them.

    python perf/calibrate.py --seeds 12 13 --frames 6 --size 120 160 \\
        --grid lam_shading_local=2,10,30 lam_albedo_smooth=0.1,0.3,1
    python perf/calibrate.py --kinds --mit --grid lam_shading_local=10,30
    python perf/calibrate.py --suite new --seeds 1 --mit --mit-achromatic --grid lam_shading_local=10,30,100
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import ivkernels as iv
from common import EVAL_SEED, parse_grid
from ivkernels.evaluation import datasets, metrics, synthetic


def score(seq, params, temporal: bool) -> float:
    video = iv.decompose(seq.frames, flow=seq.flow if temporal else None, temporal=temporal,
                         params=params)
    return metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)["mean"]


def mit_albedo_lmse(obj, params) -> float:
    """Albedo LMSE in the mask of one MIT object (:class:`ivkernels.evaluation.datasets.MITObject`), zero flow."""
    t, h, w, _ = obj.frames.shape
    video = iv.decompose(obj.frames, flow=np.zeros((t - 1, h, w, 2), np.float32), params=params)
    truth = np.broadcast_to(obj.albedo, obj.frames.shape)
    return metrics.intrinsic_lmse(video.albedo, video.shading, truth, obj.frame_shading, mask=obj.mask)["albedo"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[12])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=None, choices=list(synthetic.SCENE_KINDS), metavar="KIND",
                        help="names of synthetic.SCENE_KINDS (default: the suite's); none for MIT only")
    parser.add_argument("--suite", default="classic",
                        choices=("classic", "new", "all", "static", "achromatic", "hard"),
                        help="the kinds when --kinds is not given (synthetic.scene_kinds; default classic)")
    parser.add_argument("--grid", nargs="*", default=[], help="name=v1,v2 ... (Params fields)")
    parser.add_argument("--base", nargs="*", default=[], help="name=v fields fixed for every row")
    parser.add_argument("--no-ablation", action="store_true", help="skip the temporal=False rows")
    parser.add_argument("--mit", action="store_true", help="also the MIT-Berkeley training objects")
    parser.add_argument("--mit-scale", type=float, default=0.5)
    parser.add_argument("--mit-achromatic", action="store_true",
                        help="the MIT objects as greyscale footage (luminance in, luminance reflectance as truth)")
    parser.add_argument("--mit-objects", nargs="+", default=None, metavar="NAME",
                        help="a subset of the MIT objects (default: every one present)")
    args = parser.parse_args(argv)
    if EVAL_SEED in args.seeds:
        raise SystemExit(f"seed {EVAL_SEED} is the evaluation seed; choose weights on other seeds")
    base = parse_grid(args.base)[0]
    kinds = args.kinds if args.kinds is not None else synthetic.scene_kinds(args.suite)
    seqs = [(kind, seed, synthetic.render_kind(kind, n_frames=args.frames, size=tuple(args.size), seed=seed))
            for seed in args.seeds for kind in kinds]
    objects = []
    if args.mit:
        names = args.mit_objects or datasets.available_mit_objects()
        objects = [datasets.load_mit_object(name, scale=args.mit_scale, achromatic=args.mit_achromatic)
                   for name in names]
        if not objects:
            raise SystemExit("--mit: the MIT-Berkeley objects are not present (ivkernels.evaluation.datasets)")
    header = " ".join(f"{k[:8]}/{s}" for k, s, _ in seqs)
    if seqs:
        print(f"{'config':<60} {'mode':<8} {header}   mean      s")
    if objects:
        print(f"MIT albedo LMSE: {'config':<43} " + " ".join(f"{o.name[:10]:>10}" for o in objects)
              + "     mean      s")
    for cfg in parse_grid(args.grid):
        params = iv.Params().replace(**base, **cfg)
        label = ", ".join(f"{k}={v}" for k, v in cfg.items()) or "defaults"
        if objects:
            t0 = time.perf_counter()
            vals = [mit_albedo_lmse(o, params) for o in objects]
            print(f"MIT albedo LMSE: {label:<43} " + " ".join(f"{v:10.4f}" for v in vals)
                  + f" {np.mean(vals):8.4f} {time.perf_counter() - t0:6.0f}", flush=True)
        if not seqs:
            continue
        for temporal in ([True] if args.no_ablation else [True, False]):
            t0 = time.perf_counter()
            vals = [score(seq, params, temporal) for _, _, seq in seqs]
            print(f"{label:<60} {'IV' if temporal else 'noflow':<8} "
                  + " ".join(f"{v:10.4f}" for v in vals)
                  + f" {np.mean(vals):8.4f} {time.perf_counter() - t0:6.0f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
