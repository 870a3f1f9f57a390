#!/usr/bin/env python
"""The weighted medians of this checkout beside those of another revision, timed in one run.

The Warp and Taichi modules ``kernels/{warp,taichi}/median.py`` of revision
``--rev`` (default ``main``) are read with ``git show`` into a temporary
folder and imported there, so both versions run in the same process on the
same inputs, alternated round by round (a load change on a shared machine
hits both alike).  For each function and backend it prints the median
milliseconds per call of the old and the new kernel, in CPU time of the
process (what a shared machine's load changes least; on 1 thread the kernel's
own cost) and in wall time, their ratios, and how many output values differ
between the two (0: bitwise the same).

Inputs:

* ``case``: the kernel case table's inputs (:mod:`ivkernels.kernels.cases.median`,
  those ``perf/bench_kernels.py`` times): ``--frames`` frames of ``--size``,
  radius 7, masks of 50 % (flow) and 40 % (shading) of the pixels, values
  quantised with many ties;
* ``smooth``: the same with continuous values (flow and shading plus
  Gaussian noise, no ties), the harder case for a selection;
* ``middlebury``: every ``weighted_median_flow`` call Classic+NL-fast makes
  on the ``--sequences`` pairs (inputs recorded once, then replayed).

    python perf/bench_median.py                                  # 8x480x640, 1 thread, warp and taichi
    python perf/bench_median.py --size 240 320 --inputs smooth --backends warp
    python perf/bench_median.py --inputs middlebury --sequences RubberWhale Urban2
    python perf/bench_median.py --rev 2bef556 --threads 2 --repeat 7
"""
from __future__ import annotations

import argparse
import importlib
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from common import default_data_dir, load_revision, middlebury_pairs
from ivkernels.backends import get_backend
from ivkernels.kernels import launch
from ivkernels.kernels.cases import median as median_cases

FUNCTIONS = ("weighted_median_flow", "weighted_median_shading")


def case_inputs(function: str, frames: int, size: tuple, smooth: bool, seed: int = 0) -> list:
    """``[(arrays, keywords)]``: one call of ``function`` on the case table's inputs (radius 7)."""
    variant = {"weighted_median_flow": "radius=7", "weighted_median_shading": "radius=7,lam=0.001"}[function]
    case = next(c for c in median_cases.CASES if c.function == function and c.variant == variant)
    rng = np.random.default_rng(seed)
    v = case.make(rng, frames, *size)
    if smooth:
        if function == "weighted_median_flow":
            v["flow"] = median_cases.two_region_flow(rng, v["flow"].shape[0], *size, noise=0.3)[0]
        else:
            v["S"] = (v["S"] + rng.normal(0.0, 0.05, v["S"].shape)).astype(np.float32)
    arrays = [v[name] for name in case.call if name != "out"]
    return [(arrays, {k: v[k] for k in case.keywords})]


def middlebury_inputs(sequences: list) -> list:
    """``[(arrays, keywords)]``: every ``weighted_median_flow`` call of Classic+NL-fast on the pairs."""
    from ivkernels.flow.classic_nl import PRESETS, ClassicNL

    be = get_backend("warp")
    calls, original = [], be.median.weighted_median_flow

    def spy(flow, lab, occ, mask, out, *args, workspace=None, **kwargs):
        names = ("radius", "sigma_x", "sigma_i")
        calls.append(([be.numpy(a).copy() for a in (flow, lab, occ, mask)], {**dict(zip(names, args)), **kwargs}))
        return original(flow, lab, occ, mask, out, *args, workspace=workspace, **kwargs)

    be.median.weighted_median_flow = spy
    try:
        for _, frames, _ in middlebury_pairs(default_data_dir(), sequences):
            ClassicNL(be, PRESETS["classic_nl_fast"])(frames)
    finally:
        be.median.weighted_median_flow = original
    return calls


def run(module, function: str, be, calls: list, outs: list) -> None:
    fn = getattr(module, function)
    for (arrays, keywords), out in zip(calls, outs):
        fn(*arrays, out, **keywords)
    be.synchronize()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rev", default="main", help="the revision to compare with (default main)")
    p.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    p.add_argument("--frames", type=int, default=8)
    p.add_argument("--inputs", choices=("case", "smooth", "middlebury"), default="case")
    p.add_argument("--sequences", nargs="+", default=["RubberWhale", "Urban2"])
    p.add_argument("--functions", nargs="+", choices=FUNCTIONS, default=list(FUNCTIONS))
    p.add_argument("--backends", nargs="+", choices=("warp", "taichi"), default=["warp", "taichi"])
    p.add_argument("--threads", type=int, default=1, help="launch threads (default 1)")
    p.add_argument("--repeat", type=int, default=5, help="timed rounds (default 5)")
    args = p.parse_args(argv)
    launch.set_threads(args.threads)
    functions = ["weighted_median_flow"] if args.inputs == "middlebury" else args.functions
    where = (f"Middlebury {' '.join(args.sequences)}, Classic+NL-fast's calls" if args.inputs == "middlebury"
             else f"{args.frames}x{args.size[0]}x{args.size[1]}, {args.inputs} inputs")
    print(f"weighted medians, {where}, {args.threads} thread(s): ms per call (median of {args.repeat}), "
          f"old = {args.rev}, new = this checkout; load average {os.getloadavg()[0]:.1f}")
    print(f"{'function':24s} {'backend':7s} {'calls':>5s} {'old cpu':>9s} {'new cpu':>9s} {'old/new':>7s} "
          f"{'old wall':>9s} {'new wall':>9s} {'old/new':>7s} {'differ':>9s} {'of':>9s}")
    with tempfile.TemporaryDirectory() as tmp:
        for backend in args.backends:
            be = get_backend(backend)
            if backend == "taichi":
                from ivkernels.kernels.taichi import init
                init(args.threads)
            new = importlib.import_module(f"ivkernels.kernels.{backend}.median")
            old = load_revision(backend, "median", args.rev, Path(tmp))
            for function in functions:
                raw = (middlebury_inputs(args.sequences) if args.inputs == "middlebury"
                       else case_inputs(function, args.frames, tuple(args.size), args.inputs == "smooth"))
                calls = [([be.asarray(a) for a in arrays], kw) for arrays, kw in raw]
                outs = {name: [be.empty(arrays[0].shape) for arrays, _ in calls] for name in ("old", "new")}
                cpu = {"old": [], "new": []}
                wall = {"old": [], "new": []}
                for r in range(-1, args.repeat):                 # round -1 compiles and warms both
                    for name in (("old", "new") if r % 2 else ("new", "old")):
                        c0, t0 = time.process_time(), time.perf_counter()
                        run(old if name == "old" else new, function, be, calls, outs[name])
                        if r >= 0:
                            cpu[name].append(time.process_time() - c0)
                            wall[name].append(time.perf_counter() - t0)
                ms = {k: 1e3 * statistics.median(v) / len(calls) for k, v in cpu.items()}
                ws = {k: 1e3 * statistics.median(v) / len(calls) for k, v in wall.items()}
                a = np.concatenate([be.numpy(o).ravel() for o in outs["old"]])
                b = np.concatenate([be.numpy(o).ravel() for o in outs["new"]])
                differ = int((a.view(np.uint32) != b.view(np.uint32)).sum())
                print(f"{function:24s} {backend:7s} {len(calls):5d} {ms['old']:9.1f} {ms['new']:9.1f} "
                      f"{ms['old'] / ms['new']:7.2f} {ws['old']:9.1f} {ws['new']:9.1f} {ws['old'] / ws['new']:7.2f} "
                      f"{differ:9d} {a.size:9d}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
