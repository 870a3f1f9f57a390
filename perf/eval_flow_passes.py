"""decompose() with 1, 2, ... passes of flow and intrinsic video together: flow, maps and LMSE.

For every synthetic kind, ``decompose(frames, flow_passes=N)`` with the
estimated flow (the default method), against the renderer's ground truth:
flow end-point error (all pixels, and pixels visible in the next frame),
occlusion IoU against the visibility (:func:`ivkernels.evaluation.joint.occlusion_iou`),
LMSE of albedo / shading / mean, and the seconds of the flow, the guide
solves ("-" where none ran) and the final solve, with the process's CPU seconds.  Choose on
training seeds (not 0); report on seed 0.

    python perf/eval_flow_passes.py --seed 1 --passes 1 2
    python perf/eval_flow_passes.py --seed 0 --passes 1 2
    python perf/eval_flow_passes.py --seed 1 --passes 2 --set start_from_guide=false
    python perf/eval_flow_passes.py --seed 1 --passes 2 --refine max_levels=3 sor_sweeps=30

``--refine FIELD=VALUE ...`` sets fields of
:class:`ivkernels.flow.ClassicNLSettings` in the Classic+NL runs that start
from a previous flow (the passes after the first), to measure cheaper
settings of the warm-started flow.
"""
from __future__ import annotations

import argparse
import functools
import sys
import time

import ivkernels as iv
from common import parse_grid, parse_settings
from ivkernels.evaluation import metrics, synthetic
from ivkernels.evaluation.joint import occlusion_iou


def _with_refine(estimate_flow, refine: dict):
    """``estimate_flow`` with ``refine`` added to the options of calls given an initial flow."""
    @functools.wraps(estimate_flow)
    def wrapped(frames, *args, **options):
        if options.get("init") is not None:
            options = {**options, **refine}
        return estimate_flow(frames, *args, **options)
    return wrapped


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kinds", nargs="+", default=list(synthetic.KINDS), choices=list(synthetic.SCENE_KINDS),
                    metavar="KIND", help="names of synthetic.SCENE_KINDS (default: the four classic kinds)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    ap.add_argument("--passes", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--guide-scale", type=float, default=None, help="Params.flow_guide_scale")
    ap.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="other Params fields")
    ap.add_argument("--refine", nargs="*", default=[], metavar="FIELD=VALUE",
                    help="ClassicNLSettings fields of the warm-started passes")
    args = ap.parse_args(argv)
    refine = parse_settings(args.refine)
    if refine:
        # wherever the package holds estimate_flow (decompose imports it at its top)
        original = iv.estimate_flow
        for module in [m for name, m in sys.modules.items() if name.startswith("ivkernels")]:
            if getattr(module, "estimate_flow", None) is original:
                module.estimate_flow = _with_refine(original, refine)
    fields = parse_grid(args.set)[0]
    if args.guide_scale is not None:
        fields["flow_guide_scale"] = args.guide_scale
    params = iv.Params(**fields)
    print(f"{args.frames} frames at {args.size[1]}x{args.size[0]}, seed {args.seed}, "
          f"guide scale {params.flow_guide_scale}, Params changes: {fields or 'none'}, "
          f"warm-started flow changes: {refine or 'none'}")
    print(f"{'kind':28s} {'passes':>6s} {'EPE':>6s} {'EPE vis':>7s} {'occ IoU':>7s} {'LMSE A':>7s} "
          f"{'LMSE S':>7s} {'LMSE':>7s} {'flow s':>6s} {'guide s':>7s} {'solve s':>7s} {'CPU s':>6s}")
    for kind in args.kinds:
        seq = synthetic.render_kind(kind, n_frames=args.frames, size=tuple(args.size), seed=args.seed)
        for passes in args.passes:
            cpu = time.process_time()
            video = iv.decompose(seq.frames, params=params, flow_passes=passes)
            cpu = time.process_time() - cpu
            s = video.diagnostics["seconds"]
            lmse = metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)
            guide = f"{s['guide']:7.1f}" if "guide" in s else f"{'-':>7s}"      # "-": no guide solve ran
            print(f"{kind:28s} {passes:6d} {metrics.endpoint_error(video.flow, seq.flow):6.3f} "
                  f"{metrics.endpoint_error(video.flow, seq.flow, mask=seq.visibility > 0.5):7.3f} "
                  f"{occlusion_iou(video.occlusion, seq.visibility):7.3f} {lmse['albedo']:7.4f} "
                  f"{lmse['shading']:7.4f} {lmse['mean']:7.4f} {s.get('flow', 0.0):6.1f} "
                  f"{guide} {s.get('solve', 0.0):7.1f} {cpu:6.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
