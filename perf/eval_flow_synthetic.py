"""Flow accuracy on the rendered synthetic sequences, per kind, under changing light.

Prints the mean end-point error (EPE, pixels, over all pixels of all frame
pairs) of each flow on each kind of :mod:`ivkernels.evaluation.synthetic` (and the extra
kinds with ``--extra``), for the evaluation seed 0 and the training seeds,
plus the mean seconds per frame pair.  Rows: ``zero`` (no motion), the
OpenCV and Classic+NL methods of :func:`ivkernels.flow.estimate_flow`, and
Classic+NL candidates given as ``NAME=METHOD[:field=value,...]`` with fields
of :class:`ivkernels.flow.ClassicNLSettings`.  Settings are chosen on the
training seeds; seed 0 is for reporting.

    python perf/eval_flow_synthetic.py
    python perf/eval_flow_synthetic.py --seeds 1 --candidate grad=classic_nl_fast:data_term=gradient
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time

import numpy as np

from ivkernels.evaluation import synthetic
from ivkernels.flow import estimate_flow
from ivkernels.kernels.launch import set_threads
from ivkernels.evaluation.metrics import flow_errors

BASELINES = ("zero", "dis", "classic_nl_fast")


def parse_candidate(text: str):
    """``NAME=METHOD[:k=v,...]`` -> (name, method, options)."""
    name, _, rest = text.partition("=")
    method, _, opts = rest.partition(":")
    from ivkernels.flow import ClassicNLSettings

    fields = {f.name: f.type for f in dataclasses.fields(ClassicNLSettings)}
    options = {}
    for item in filter(None, opts.split(",")):
        k, _, v = item.partition("=")
        typ = fields.get(k, "str")
        if typ == "int":
            options[k] = int(v)
        elif typ == "float":
            options[k] = float(v)
        elif typ == "bool":
            options[k] = v.lower() in ("1", "true", "yes")
        else:
            options[k] = v
    return name, method or "classic_nl_fast", options


def load(kind: str, seed: int, n_frames: int, size, cache: str | None):
    """Render a sequence, or read it from ``cache`` (an .npz per sequence)."""
    path = None
    if cache:
        os.makedirs(cache, exist_ok=True)
        path = os.path.join(cache, f"{kind}_s{seed}_{n_frames}_{size[0]}x{size[1]}.npz")
        if os.path.exists(path):
            with np.load(path) as z:
                return synthetic.SyntheticSequence(**{f.name: (z[f.name].item() if z[f.name].ndim == 0 else z[f.name])
                                                      for f in dataclasses.fields(synthetic.SyntheticSequence)})
    seq = synthetic.render_sequence(kind, n_frames=n_frames, size=tuple(size), seed=seed)
    if path:
        np.savez(path, **{f.name: getattr(seq, f.name) for f in dataclasses.fields(seq)})
    return seq


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    ap.add_argument("--kinds", nargs="+", default=None)
    ap.add_argument("--extra", action="store_true", help="also the kinds of synthetic.EXTRA_KINDS")
    ap.add_argument("--baselines", nargs="*", default=list(BASELINES))
    ap.add_argument("--candidate", action="append", default=[], help="NAME=METHOD[:field=value,...]")
    ap.add_argument("--cache", default=os.environ.get("IVK_SYNTHETIC_CACHE", "/tmp/ivk_syn"))
    ap.add_argument("--threads", type=int, default=2, choices=(1, 2))
    args = ap.parse_args(argv)
    set_threads(args.threads)

    kinds = list(args.kinds or synthetic.KINDS)
    if args.extra:
        kinds += [k for k in getattr(synthetic, "EXTRA_KINDS", ()) if k not in kinds]
    rows = [(b, b, {}) for b in args.baselines] + [parse_candidate(c) for c in args.candidate]
    warm = np.random.default_rng(0).uniform(0, 1, (2, 48, 64, 3)).astype(np.float32)
    for _, method, options in rows:
        if method != "zero":
            estimate_flow(warm, method=method, **options)

    table = {}
    for seed in args.seeds:
        for kind in kinds:
            seq = load(kind, seed, args.frames, args.size, args.cache)
            motion = float(np.sqrt((seq.flow ** 2).sum(-1)).mean())
            for name, method, options in rows:
                t0 = time.perf_counter()
                if method == "zero":
                    flow = np.zeros_like(seq.flow)
                else:
                    flow = estimate_flow(seq.frames, method=method, **options)
                sec = (time.perf_counter() - t0) / (seq.frames.shape[0] - 1)
                epe = flow_errors(flow, seq.flow)["epe"]
                table[name, seed, kind] = (epe, sec)
                print(f"  seed {seed} {kind:20s} {name:18s} EPE {epe:7.3f}  {sec:6.2f} s/pair"
                      f"  (true mean motion {motion:.2f} px)", file=sys.stderr, flush=True)

    print(f"{args.frames} frames at {args.size[1]}x{args.size[0]}, threads={args.threads}; "
          "mean EPE (px) per kind; s/pair = mean wall seconds per frame pair")
    for seed in args.seeds:
        print(f"\nseed {seed}")
        head = f"{'flow':18s}" + "".join(f" | {k[:19]:>19s}" for k in kinds) + " |    mean | s/pair"
        print(head)
        print("-" * len(head))
        for name, _, _ in rows:
            vals = [table[name, seed, k] for k in kinds]
            print(f"{name:18s}" + "".join(f" | {e:19.3f}" for e, _ in vals)
                  + f" | {np.mean([e for e, _ in vals]):7.3f} | {np.mean([s for _, s in vals]):6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
