"""Does re-estimating the flow on the recovered albedo help? (paper Sec. 5.1, 6)

On the synthetic kinds whose illumination changes while things move, compares
decompose() with flow from the input frames against flow_passes=2 (flow re-estimated on the albedo)
(flow re-estimated on the first pass's albedo, then solved again): flow EPE
against ground truth (all pixels, and visible ones) and the LMSE of the
decomposition.  Reports the numbers whichever way they fall.

    python perf/flow_from_albedo.py [--method classic_nl_fast] [--frames 8] [--size 240 320]
"""
from __future__ import annotations

import argparse


import ivkernels as iv
from ivkernels.evaluation import metrics, synthetic

KINDS_WITH_LIGHT_CHANGE = ("free_camera", "rotating_shadows")
SEED = 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--method", default=iv.DEFAULT_FLOW_METHOD)
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    args = parser.parse_args(argv)
    print(f"flow method {args.method}, {args.frames} frames at {args.size[1]}x{args.size[0]}, seed {SEED}")
    print(f"{'kind':<18} {'flow from':<8} {'EPE':>6} {'EPE vis':>8} {'LMSE A':>7} {'LMSE S':>7} {'LMSE':>7}")
    for kind in KINDS_WITH_LIGHT_CHANGE:
        seq = synthetic.render_sequence(kind, n_frames=args.frames, size=tuple(args.size), seed=SEED)
        for label, from_albedo in (("input", False), ("albedo", True)):
            video = iv.decompose(seq.frames, flow=args.method, flow_passes=2 if from_albedo else 1)
            epe = metrics.endpoint_error(video.flow, seq.flow)
            epe_vis = metrics.endpoint_error(video.flow, seq.flow, mask=seq.visibility > 0.5)
            l = metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)
            print(f"{kind:<18} {label:<8} {epe:6.3f} {epe_vis:8.3f} {l['albedo']:7.4f} "
                  f"{l['shading']:7.4f} {l['mean']:7.4f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
