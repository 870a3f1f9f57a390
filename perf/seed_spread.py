"""Spread over seeds: the ratio of two methods' LMSE on many synthetic seeds.

A comparison read at one seed can be a draw of the renderer: which shapes,
textures and motions the sequence happened to get.  For every seed this
script runs the evaluation of ``accuracy.py`` (``common.evaluate_kind``, 8 frames at
320x240 by default) for two methods and prints each method's LMSE mean (the
mean of albedo and shading LMSE) over the kinds, the ratio NUM / DEN over the
kinds and per kind, and then, over the training seeds, the ratio's mean,
standard deviation, median and range and on how many seeds it is at most 1.

The training seeds 1-13 are the default.  Seed 0, the evaluation seed, runs
only when ``--seeds`` names it; it is then printed apart and left out of the
summary, with its place among the training seeds, so that nothing is chosen
on it.

    python perf/seed_spread.py                                  # IV-gtflow / IV, seeds 1-13
    python perf/seed_spread.py --seeds 0 1 2 3 --ratio IV IV-noflow --kinds rotating_shadows
    python perf/seed_spread.py --seeds 1 2 3 --ratio IV LRET --suite new
"""
from __future__ import annotations

import argparse
import statistics

from common import EVAL_SEED, IV_METHODS, METHODS, evaluate_kind, iv_params_from, mean_rows

from ivkernels.evaluation import synthetic

TRAINING_SEEDS = tuple(range(1, 14))
SUITES = ("classic", "new", "all", "static", "achromatic", "hard")


def short_label(kind: str) -> str:
    """A column label of at most 8 characters: the first word of a classic kind,
    the first three letters of each word of the others."""
    if kind in synthetic.KINDS:
        return kind.split("_")[0][:8]
    return "".join(w[:3] for w in kind.split("_"))[:8]


def seed_row(seed: int, kinds, methods, args) -> dict:
    """``{kind: {method: row}}`` of one seed, rows as ``common.measure`` returns them."""
    return {kind: evaluate_kind(kind, args.frames, args.size, seed, methods, args) for kind in kinds}


def ratios(per_kind: dict, num: str, den: str) -> tuple[float, float, float, dict]:
    """(NUM mean, DEN mean, their ratio, per kind ratio) of LMSE mean."""
    mean = mean_rows(per_kind)
    per = {kind: rows[num]["mean"] / rows[den]["mean"] for kind, rows in per_kind.items()}
    return mean[num]["mean"], mean[den]["mean"], mean[num]["mean"] / mean[den]["mean"], per


def summary(values: list[float]) -> str:
    """Mean, standard deviation, median, range and count at most 1 of the ratios."""
    n = len(values)
    sd = statistics.stdev(values) if n > 1 else float("nan")
    wins = sum(v <= 1.0 for v in values)
    return (f"mean {statistics.fmean(values):.3f}, sd {sd:.3f}, median {statistics.median(values):.3f}, "
            f"range {min(values):.3f}-{max(values):.3f}, <= 1 on {wins} of {n} seeds")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(TRAINING_SEEDS))
    parser.add_argument("--ratio", nargs=2, default=("IV-gtflow", "IV"), metavar=("NUM", "DEN"),
                        help="the two methods compared, NUM / DEN (names as in accuracy.py)")
    parser.add_argument("--kinds", nargs="+", default=None, choices=list(synthetic.SCENE_KINDS), metavar="KIND",
                        help="names of synthetic.SCENE_KINDS (default: the suite's)")
    parser.add_argument("--suite", default="classic", choices=SUITES,
                        help="the kinds when --kinds is not given (synthetic.scene_kinds; default classic)")
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    parser.add_argument("--backend", default="warp", choices=["warp", "taichi"])
    parser.add_argument("--iv-param", action="append", metavar="NAME=VALUE",
                        help="a field of ivkernels.Params for every IV method (repeatable)")
    args = parser.parse_args(argv)
    num, den = args.ratio
    for name in (num, den):
        if name not in METHODS or name in ("input", "GT"):
            parser.error(f"--ratio: {name!r} is not a method to compare; expected two of "
                         f"{', '.join(m for m in METHODS if m not in ('input', 'GT'))}")
    if num == den:
        parser.error("--ratio: NUM and DEN must differ")
    if len(set(args.seeds)) != len(args.seeds) or min(args.seeds) < 0:
        parser.error("--seeds: give distinct seeds >= 0")
    args.iv_params = iv_params_from(parser, args.iv_param)
    if args.iv_params is not None and not ({num, den} & set(IV_METHODS)):
        parser.error("--iv-param applies to IV methods only, and neither method is one")
    args.iv_options = {}

    kinds = list(args.kinds) if args.kinds is not None else list(synthetic.scene_kinds(args.suite))
    short = {kind: short_label(kind) for kind in kinds}
    print(f"{num} / {den}, LMSE mean, {args.frames} frames at {args.size[1]}x{args.size[0]}"
          + (f", Params changes {' '.join(args.iv_param)}" if args.iv_param else ""))
    print(f"{'seed':>6} {num:>10} {den:>10} {'ratio':>7}  " + " ".join(f"{short[k]:>8}" for k in kinds))
    training, evaluation = [], None
    for seed in args.seeds:
        num_mean, den_mean, ratio, per = ratios(seed_row(seed, kinds, [den, num], args), num, den)
        label = f"{seed}*" if seed == EVAL_SEED else str(seed)
        print(f"{label:>6} {num_mean:10.4f} {den_mean:10.4f} {ratio:7.3f}  "
              + " ".join(f"{per[k]:8.3f}" for k in kinds), flush=True)
        if seed == EVAL_SEED:
            evaluation = ratio
        else:
            training.append(ratio)
    print("(ratio per kind: NUM / DEN on that kind alone)")
    if training:
        print(f"\ntraining seeds, ratio over the kinds: {summary(training)}")
    if evaluation is not None:
        above = sum(r < evaluation for r in training)
        print(f"seed {EVAL_SEED}* (evaluation seed, not in the summary): ratio {evaluation:.3f}, "
              f"above {above} of the {len(training)} training seeds' ratios")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
