"""Energy against time: how close the default solver gets to a long reference run.

For each training sequence (synthetic, seeds other than 0), decompose() runs
with the default parameters, then with other L-BFGS budgets
(``Params.lbfgs_iterations``, which also scales the coarse levels' budgets)
and a reference run of ``--reference`` iterations.  The table gives, per
run, the solve time (wall and CPU seconds), the finest level's final energy,
the share of the drop from the default run's finest-level start energy to
the reference energy that it reaches, and the LMSE (to check that lower
energy means lower error).

``--flow truth`` (the default) solves with the ground-truth flow, so every
budget minimises the same energy.  ``--flow estimated`` measures the path
a user gets (``decompose()``'s own flow, its passes and guide solves): each
run estimates its flow again, so its energy differs a little from run to
run, and the LMSE column is the measure that counts.

    python perf/convergence.py --seeds 12 --frames 8 --size 240 320 --budgets 20 80 160 --reference 1000
    python perf/convergence.py --seeds 1 --flow estimated --budgets 80 --reference 300
"""
from __future__ import annotations

import argparse
import time


import ivkernels as iv
from common import parse_grid
from ivkernels.evaluation import metrics, synthetic


def finest_energies(video) -> tuple[float, float]:
    """(first, last) energy recorded at level 0 of the first window."""
    rows = [e for (w, level, outer, k, e) in video.diagnostics["energy"] if w == 0 and level == 0]
    return rows[0], rows[-1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[12])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=list(synthetic.KINDS), choices=list(synthetic.SCENE_KINDS),
                        metavar="KIND", help="names of synthetic.SCENE_KINDS (default: the four classic kinds)")
    parser.add_argument("--budgets", type=int, nargs="*", default=[20, 80, 160])
    parser.add_argument("--reference", type=int, default=1000)
    parser.add_argument("--set", nargs="*", default=[], help="name=value Params fields")
    parser.add_argument("--flow", choices=("truth", "estimated"), default="truth",
                        help="the ground-truth flow (the same energy for every budget) or "
                             "decompose()'s own estimate (the default path)")
    args = parser.parse_args(argv)
    if 0 in args.seeds:
        raise SystemExit("seed 0 is the evaluation seed; measure on other seeds")
    base = iv.Params().replace(**parse_grid(args.set)[0])
    print(f"{'sequence':<28} {'iters':>6} {'solve s':>8} {'CPU s':>8} {'E final':>12} {'drop %':>7} "
          f"{'LMSE':>7}")
    for seed in args.seeds:
        for kind in args.kinds:
            seq = synthetic.render_kind(kind, n_frames=args.frames, size=tuple(args.size), seed=seed)
            flow = seq.flow if args.flow == "truth" else None
            rows = []
            for iters in [base.lbfgs_iterations, *args.budgets, args.reference]:
                params = base.replace(lbfgs_iterations=iters)
                cpu = time.process_time()
                video = iv.decompose(seq.frames, flow=flow, params=params)
                cpu = time.process_time() - cpu
                start, final = finest_energies(video)
                lmse = metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)["mean"]
                rows.append((iters, video.diagnostics["seconds"].get("solve", 0.0), cpu, start, final,
                             lmse))
            e_start, e_ref = rows[0][3], rows[-1][4]
            for i, (iters, seconds, cpu, start, final, lmse) in enumerate(rows):
                drop = 100.0 * (e_start - final) / (e_start - e_ref) if e_start != e_ref else 100.0
                name = f"{kind}/{seed}" + (" (default)" if i == 0 else "")
                print(f"{name:<28} {iters:6d} {seconds:8.1f} {cpu:8.1f} {final:12.6g} {drop:7.2f} "
                      f"{lmse:7.4f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
