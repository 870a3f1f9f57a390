#!/usr/bin/env python
"""Time a kernel host function against its module at another git revision, alternated in one process.

    python perf/kernel_versions.py energy_albedo_gsm.gsm_smoothness --variant radius=2 --rev main
    python perf/kernel_versions.py energy_albedo_gsm.gsm_smoothness --variant radius=2 --backend taichi --threads 2

The old module is ``git show REV:ivkernels/kernels/<backend>/<family>.py``
loaded beside the current one under another name (its imports resolve to the
current package, so a revision whose module needs helpers that have changed
since cannot be loaded).  Both are called on the inputs of the function's
first case in the kernel case table (:mod:`ivkernels.kernels.cases`) for a
video of ``--frames`` frames of ``--size`` pixels, each with a workspace of
its own when the function takes one (as the solver calls them), after one
call each to compile and load.  Each round calls both, in alternating order,
so a load change on a shared machine hits both alike; prints the medians (ms)
per thread count and their ratio, old / new, each with the CPU time of the
process during the call (every thread; on a loaded machine the CPU time is
the steadier figure, and CPU / wall shows how many cores the call got).  The outputs are accumulated
over the rounds, so nothing is compared here: the kernel tests do that.
"""
from __future__ import annotations

import argparse
import inspect
import pathlib
import resource
import statistics
import tempfile
import time

import numpy as np

from common import load_revision


def cpu_seconds() -> float:
    """CPU seconds of this process so far, every thread (Warp's launch threads, Taichi's pool)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("function", help="family.function, e.g. energy_albedo_gsm.gsm_smoothness")
    ap.add_argument("--variant", default=None, help="the case variant, e.g. radius=2 (default: the first)")
    ap.add_argument("--rev", default="main", help="git revision of the old module (default: main)")
    ap.add_argument("--backend", choices=("warp", "taichi"), default="warp")
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2],
                    help="thread counts (Taichi: one, fixed at initialisation)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.backend == "taichi" and len(args.threads) != 1:
        ap.error("Taichi fixes its thread count when initialised: pass one --threads value")

    from ivkernels.backends import get_backend
    from ivkernels.kernels.cases import all_cases, bind
    from ivkernels.kernels.launch import threads
    from ivkernels.kernels.workspace import Workspace

    family, function = args.function.split(".")
    case = next((c for c in all_cases() if c.family == family and c.function == function
                 and args.variant in (None, c.variant)), None)
    if case is None:
        ap.error(f"no case for {args.function}" + (f" [{args.variant}]" if args.variant else ""))
    if args.backend == "taichi":
        from ivkernels.kernels.taichi import init as taichi_init
        taichi_init(args.threads[0])
    be = get_backend(args.backend)
    values = case.make(np.random.default_rng(args.seed), args.frames, *args.size)
    with tempfile.TemporaryDirectory() as tmp:
        old = getattr(load_revision(args.backend, family, args.rev, pathlib.Path(tmp)), function)
        new = case.host_function(be)
        calls = {}
        for label, fn in ((args.rev, old), ("new", new)):
            _, passed = bind(case, be, values)
            call_args = [passed[n] for n in case.call]
            kwargs = {n: passed[n] for n in case.keywords}
            if "workspace" in inspect.signature(fn).parameters:
                kwargs["workspace"] = Workspace()
            calls[label] = lambda fn=fn, a=call_args, k=kwargs: fn(*a, **k)
        T, (H, W) = args.frames, args.size
        for n in args.threads:
            with threads(n):
                for call in calls.values():
                    call()
                be.synchronize()
                seconds = {label: [] for label in calls}
                cpu = {label: [] for label in calls}
                for r in range(args.rounds):
                    for label, call in list(calls.items())[::1 if r % 2 else -1]:
                        c0, t0 = cpu_seconds(), time.perf_counter()
                        call()
                        be.synchronize()
                        seconds[label].append(time.perf_counter() - t0)
                        cpu[label].append(cpu_seconds() - c0)
            med = {label: statistics.median(s) * 1e3 for label, s in seconds.items()}
            med_cpu = {label: statistics.median(s) * 1e3 for label, s in cpu.items()}
            print(f"{args.function}[{case.variant}] {args.backend} {T}x{H}x{W} threads={n}: "
                  + "  ".join(f"{label} {med[label]:.1f} ms (CPU {med_cpu[label]:.0f} ms)" for label in calls)
                  + f"  {args.rev}/new {med[args.rev] / med['new']:.2f}x"
                  + f" (CPU {med_cpu[args.rev] / med_cpu['new']:.2f}x)", flush=True)


if __name__ == "__main__":
    main()
