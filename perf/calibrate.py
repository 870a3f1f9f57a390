"""Choose the energy's weights on training data: a grid search that prints a table.

Every configuration is a set of :class:`ivkernels.Params` fields; for each it
decomposes the synthetic training sequences (seeds other than 0, which is kept
for reporting) with ground-truth flow and without temporal terms, and prints
the LMSE (Grosse et al., mean of albedo and shading) per kind and the mean.
Choices made with it are recorded in the docstring of :class:`ivkernels.Params`
and in perf/RESULTS.md with the command that produced them.

    python perf/calibrate.py --seeds 12 13 --frames 6 --size 120 160 \\
        --grid lam_shading_local=2,10,30 lam_albedo_smooth=0.1,0.3,1
"""
from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

import ivkernels as iv
from ivkernels import metrics, synthetic

EVAL_SEED = 0


def parse_grid(items: list[str]) -> list[dict]:
    """``["a=1,2", "b=3"]`` -> every combination as a dict of floats (ints kept int)."""
    axes = []
    for item in items:
        name, _, values = item.partition("=")
        if not values:
            raise SystemExit(f"--grid entries look like name=v1,v2; got {item!r}")
        axes.append([(name, int(v) if v.lstrip("-").isdigit() else float(v)) for v in values.split(",")])
    return [dict(combo) for combo in itertools.product(*axes)] if axes else [{}]


def score(seq, params, temporal: bool) -> float:
    video = iv.decompose(seq.frames, flow=seq.flow if temporal else None, temporal=temporal,
                         params=params)
    return metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)["mean"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[12])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=list(synthetic.KINDS))
    parser.add_argument("--grid", nargs="*", default=[], help="name=v1,v2 ... (Params fields)")
    parser.add_argument("--base", nargs="*", default=[], help="name=v fields fixed for every row")
    parser.add_argument("--no-ablation", action="store_true", help="skip the temporal=False rows")
    args = parser.parse_args(argv)
    if EVAL_SEED in args.seeds:
        raise SystemExit(f"seed {EVAL_SEED} is the evaluation seed; choose weights on other seeds")
    base = parse_grid(args.base)[0]
    seqs = [(kind, seed, synthetic.render_sequence(kind, n_frames=args.frames, size=tuple(args.size),
                                                   seed=seed))
            for seed in args.seeds for kind in args.kinds]
    header = " ".join(f"{k[:8]}/{s}" for k, s, _ in seqs)
    print(f"{'config':<60} {'mode':<8} {header}   mean      s")
    for cfg in parse_grid(args.grid):
        params = iv.Params().replace(**base, **cfg)
        for temporal in ([True] if args.no_ablation else [True, False]):
            t0 = time.perf_counter()
            vals = [score(seq, params, temporal) for _, _, seq in seqs]
            label = ", ".join(f"{k}={v}" for k, v in cfg.items()) or "defaults"
            print(f"{label:<60} {'IV' if temporal else 'noflow':<8} "
                  + " ".join(f"{v:10.4f}" for v in vals)
                  + f" {np.mean(vals):8.4f} {time.perf_counter() - t0:6.0f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
