"""Flow and intrinsic video estimated together: what each outer pass buys.

For each synthetic kind, runs :func:`ivkernels.evaluation.joint.joint_decompose`
for ``--passes`` passes and prints, per pass, the flow's mean change from
the previous pass, flow EPE (all pixels and visible ones), occlusion IoU
against the renderer's visibility (with the fractions of pixels marked
occluded by the estimate and by the truth), LMSE (albedo, shading, mean) and the
seconds spent in flow and decomposition.  Pass 1 is today's
``decompose(frames)`` (flow on the input).

    python perf/eval_joint.py                                    # 160x120, seed 1
    python perf/eval_joint.py --size 240 320 --seed 0 --passes 3 --source relit
"""
from __future__ import annotations

import argparse
import sys

from ivkernels.evaluation import synthetic
from ivkernels.evaluation.joint import FLOW_SOURCES, joint_decompose
from ivkernels.kernels.launch import set_threads


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kinds", nargs="+", default=list(synthetic.KINDS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--method", default="classic_nl_fast")
    ap.add_argument("--source", default="albedo", choices=FLOW_SOURCES)
    ap.add_argument("--cold", action="store_true", help="do not warm-start each pass's flow")
    ap.add_argument("--threads", type=int, default=None, help="launch threads (default: all the cores available)")
    args = ap.parse_args(argv)
    set_threads(args.threads)

    print(f"{args.frames} frames at {args.size[1]}x{args.size[0]}, seed {args.seed}, flow {args.method}, "
          f"passes 2.. on the {args.source}{' (cold start)' if args.cold else ''}")
    print(f"{'kind':20s} {'pass':>4s} {'change':>7s} {'EPE':>6s} {'EPE vis':>7s} {'occ IoU':>7s} "
          f"{'occ':>5s} {'occ gt':>6s} "
          f"{'LMSE A':>7s} {'LMSE S':>7s} {'LMSE':>7s} {'flow s':>7s} {'dec s':>6s}")
    for kind in args.kinds:
        seq = synthetic.render_sequence(kind, n_frames=args.frames, size=tuple(args.size), seed=args.seed)
        result = joint_decompose(seq.frames, passes=args.passes, method=args.method, source=args.source,
                                 warm_start=not args.cold, truth=seq)
        for p in result.history:
            print(f"{kind:20s} {p.index:4d} {p.flow_change:7.3f} {p.epe:6.3f} {p.epe_visible:7.3f} "
                  f"{p.occlusion_iou:7.3f} {p.occluded:5.3f} {p.occluded_true:6.3f} "
                  f"{p.lmse['albedo']:7.4f} {p.lmse['shading']:7.4f} "
                  f"{p.lmse['mean']:7.4f} {p.flow_seconds:7.1f} {p.decompose_seconds:6.1f}", flush=True)
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
