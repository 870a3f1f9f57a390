"""Accuracy and speed of the built-in optical flows, measured in one run.

Prints, for every method, the end-point error (EPE, pixels) and average
angular error (AAE, degrees) on each Middlebury training pair with ground
truth (``shared/data/middlebury``), their means, and the seconds per pair
(wall clock, Classic+NL kernels compiled beforehand on a small pair).
``--synthetic`` adds the project's rendered sequences (the flow of each
consecutive pair against the renderer's exact flow).

    python perf/eval_flow.py                                  # all methods, Middlebury
    python perf/eval_flow.py --methods classic_nl_fast dis --sequences RubberWhale Venus
    python perf/eval_flow.py --synthetic --threads 1
    python perf/eval_flow.py --methods classic_nl_fast --set data_term=brightness lam=3
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from common import SEQUENCES, default_data_dir, middlebury_pairs, parse_settings
from ivkernels.flow import FLOW_METHODS, estimate_flow
from ivkernels.kernels.launch import set_threads
from ivkernels.evaluation.metrics import flow_errors

def synthetic_pairs(size, n_frames: int):
    from ivkernels.evaluation.synthetic import KINDS, render_sequence

    for kind in KINDS:
        seq = render_sequence(kind, n_frames=n_frames, size=size, seed=1)
        yield f"syn:{kind}", seq.frames, seq.flow


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--methods", nargs="+", default=list(FLOW_METHODS), choices=FLOW_METHODS)
    ap.add_argument("--sequences", nargs="+", default=list(SEQUENCES))
    ap.add_argument("--data", type=Path, default=None, help="Middlebury folder (default: shared/data/middlebury)")
    ap.add_argument("--synthetic", action="store_true", help="also the rendered synthetic sequences")
    ap.add_argument("--synthetic-size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    ap.add_argument("--backend", default="warp")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--threads", type=int, default=None, help="launch threads (default: all the cores available)")
    ap.add_argument("--set", nargs="+", default=[], metavar="FIELD=VALUE",
                    help="ClassicNLSettings fields for the Classic+NL methods")
    args = ap.parse_args(argv)
    set_threads(args.threads)
    options = parse_settings(args.set)

    def flow_of(frames, m):
        extra = options if m.startswith("classic_nl") else {}
        return estimate_flow(frames, method=m, backend=args.backend, device=args.device, **extra)

    data = list(middlebury_pairs(args.data or default_data_dir(), args.sequences))
    if args.synthetic:
        data += list(synthetic_pairs(tuple(args.synthetic_size), 3))

    # Compile every kernel once so that timings measure the flow, not the JIT.
    warm = data[0][1][:, :48, :64]
    for m in args.methods:
        flow_of(warm, m)

    results = {m: {} for m in args.methods}
    for name, frames, gt in data:
        for m in args.methods:
            t0, c0 = time.perf_counter(), time.process_time()
            flow = flow_of(frames, m)
            pairs = frames.shape[0] - 1
            seconds = (time.perf_counter() - t0) / pairs
            cpu = (time.process_time() - c0) / pairs
            err = flow_errors(flow, gt)
            results[m][name] = (err["epe"], err["aae"], seconds, cpu)
            print(f"  {name:24s} {m:16s} EPE {err['epe']:6.3f}  AAE {err['aae']:6.2f}  {seconds:6.2f} s/pair"
                  f"  ({cpu:.2f} CPU s)", file=sys.stderr, flush=True)

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    if options:
        print(f"Classic+NL settings changed: {options}")
    print(f"backend={args.backend} device={args.device} threads={args.threads or 'all'} "
          f"cores={os.cpu_count()} load average at the end={load:.2f}")
    print("s/pair: wall-clock seconds per frame pair; cpu: CPU seconds of this process per pair")
    header = f"{'sequence':24s}" + "".join(f" | {m:>29s}" for m in args.methods)
    print(header)
    print(f"{'':24s}" + " | {:>6s} {:>6s} {:>7s} {:>6s}".format("EPE", "AAE", "s/pair", "cpu") * len(args.methods))
    print("-" * len(header))
    for name, _, _ in data:
        row = f"{name:24s}"
        for m in args.methods:
            e, a, s, c = results[m][name]
            row += f" | {e:6.3f} {a:6.2f} {s:7.2f} {c:6.2f}"
        print(row)
    print("-" * len(header))
    for label, keep in (("mean (Middlebury)", lambda n: not n.startswith("syn:")),
                        ("mean (synthetic)", lambda n: n.startswith("syn:"))):
        names = [n for n, _, _ in data if keep(n)]
        if not names:
            continue
        row = f"{label:24s}"
        for m in args.methods:
            vals = np.array([results[m][n] for n in names])
            row += (f" | {vals[:, 0].mean():6.3f} {vals[:, 1].mean():6.2f} {vals[:, 2].mean():7.2f}"
                    f" {vals[:, 3].mean():6.2f}")
        print(row)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
