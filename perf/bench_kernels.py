#!/usr/bin/env python
"""Time every kernel host function on Warp, Taichi and the NumPy reference, on 1, 2 and all threads.

The calls are those of the kernel case table (:mod:`ivkernels.kernels.cases`),
the table the tests check every backend against: each case makes the inputs
of a video of ``--frames`` frames of ``--size`` pixels (log images, flows of a
few pixels, masks, in the solver's ranges), and the same inputs are given to
Warp, Taichi and the NumPy reference.  One case per host function is timed
(its first variant; ``--all-variants`` times every one).

Thread counts: 1, 2 and "all" (:func:`ivkernels.kernels.launch.default_threads`:
``IVKERNELS_THREADS`` if set, else the cores this process may use; ``--threads``
overrides it), without repeats (on a 2-core machine "all" is 2).  Warp runs
each launch in up to N row bands on N threads (:mod:`ivkernels.kernels.launch`);
Taichi fixes its thread count when it is initialised, so the run has one
phase per thread count: Taichi is initialised with that count and every case
is timed on Taichi with it, and on Warp with every count, in rotating order
(so a load change on a shared machine hits every configuration alike).
A pure-arithmetic probe at the start and the end measures how much of n
cores the machine actually gave (its n-thread speedup bounds every kernel's).  Each
configuration's median over its rounds is printed, with the ratios between
them, all from this one process.  A configuration stops after 3 rounds once
the case has used ``--case-budget`` seconds in a phase.

The NumPy reference is timed on smaller inputs (2 frames at 1/4, then 1/2
the size, then the full input) for as long as the next size is predicted to
take under ``--ref-budget`` seconds; a time measured on a smaller input is
scaled to the full one by the ratio of pixels and printed with ``~``.

    python perf/bench_kernels.py                          # 640x480, 8 frames, every family
    python perf/bench_kernels.py --only median energy_albedo_gsm --repeat 9
    python perf/bench_kernels.py --size 240 320 --frames 4 --json out.json
    python perf/bench_kernels.py --quick                  # 120x160, 3 frames: smoke run
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import warp as wp

wp.set_module_options({"enable_backward": False})


@wp.kernel
def spin_rows(row_begin: int, out: wp.array(dtype=float), iterations: int):
    r = row_begin + wp.tid()
    a = float(r) * 0.001
    for i in range(iterations):
        a = a * 0.999 + 0.001
    out[r] = a


def thread_capacity(counts: list[int], rounds: int = 5) -> dict:
    """Speedup of n threads over 1 on pure arithmetic, launched in row bands like the kernels.

    Close to n on an idle machine with n free cores, lower when other
    processes hold them: it bounds the speedup any kernel can show in the same run.
    """
    from ivkernels.kernels.launch import launch_rows, threads

    rows = 1 << 20
    out = wp.empty(rows, dtype=wp.float32, device="cpu")
    times = {n: [] for n in counts}
    for n in counts:
        with threads(n):
            launch_rows(spin_rows, rows, [out, 32])
    for r in range(rounds):
        for n in counts[r % len(counts):] + counts[:r % len(counts)]:
            with threads(n):
                t0 = time.perf_counter()
                launch_rows(spin_rows, rows, [out, 32])
                times[n].append(time.perf_counter() - t0)
    return {n: statistics.median(times[1]) / statistics.median(times[n]) for n in counts}


@dataclass
class Timing:
    """Every wall time (seconds) of one case, per configuration, and the reference's."""

    key: str
    seconds: dict = field(default_factory=dict)       # ("warp" | "taichi", threads) -> [s, ...]
    reference: float | None = None
    reference_note: str = ""                           # "" = measured on the full input, else the size used
    error: str = ""

    def median(self, backend: str, n: int) -> float | None:
        values = self.seconds.get((backend, n))
        return statistics.median(values) if values else None


def thread_counts(all_threads: int) -> list[int]:
    """The distinct counts among 1, 2 and ``all_threads``, ascending."""
    return sorted({1, min(2, all_threads), all_threads})


def select_cases(only: list[str] | None, all_variants: bool) -> list:
    """Cases of the families (or case keys) in ``only``, one per host function unless ``all_variants``."""
    from ivkernels.kernels.cases import all_cases

    chosen, seen = [], set()
    for case in all_cases():
        if only and case.family not in only and case.key not in only \
                and f"{case.family}.{case.function}" not in only:
            continue
        name = (case.family, case.function)
        if not all_variants and name in seen:
            continue
        seen.add(name)
        chosen.append(case)
    return chosen


def case_values(case, size: tuple[int, int, int], seed: int) -> dict:
    """The inputs of ``case`` for a video of ``size = (T, H, W)`` (the same on every call)."""
    return case.make(np.random.default_rng(seed), *size)


def _timed(call, be) -> float:
    t0 = time.perf_counter()
    call()
    be.synchronize()
    return time.perf_counter() - t0


def time_phase(case, values: dict, backends: dict, counts: list[int], taichi_threads: int | None,
               timing: Timing, repeat: int, budget_s: float) -> None:
    """Time ``case`` on Warp at every count and on Taichi at ``taichi_threads`` (None: no Taichi)."""
    from ivkernels.kernels.cases import bind
    from ivkernels.kernels.launch import threads

    configs = [("warp", n) for n in counts]
    if taichi_threads is not None and "taichi" in backends:
        configs.append(("taichi", taichi_threads))
    calls = {}
    for name, n in configs:
        be = backends[name]
        call, _ = bind(case, be, values)
        with threads(n):
            call()                     # first call: compile or load, and touch the buffers
            be.synchronize()
        calls[(name, n)] = (call, be)
    t_start = time.perf_counter()
    for r in range(repeat):
        order = configs[r % len(configs):] + configs[:r % len(configs)]
        for name, n in order:
            call, be = calls[(name, n)]
            with threads(n):
                timing.seconds.setdefault((name, n), []).append(_timed(call, be))
        if r >= 2 and time.perf_counter() - t_start > budget_s:
            break


def time_reference(case, size: tuple[int, int, int], seed: int, budget_s: float) -> tuple[float | None, str]:
    """Seconds of the NumPy reference on ``size``, measured there or scaled from a smaller input."""
    T, H, W = size
    ladder = [(min(T, 2), max(H // 4, 8), max(W // 4, 8)), (min(T, 2), max(H // 2, 8), max(W // 2, 8)),
              (T, H, W)]
    ladder = [s for i, s in enumerate(ladder) if s not in ladder[:i]]
    best = None
    for s in ladder:
        pixels = s[0] * s[1] * s[2]
        if best is not None and best[0] * pixels / best[1] > budget_s:
            break
        values = case_values(case, s, seed)
        t0 = time.perf_counter()
        case.reference(values)
        best = (time.perf_counter() - t0, pixels, s)
    if best is None:
        return None, ""
    seconds, pixels, s = best
    scaled = seconds * (T * H * W) / pixels
    return scaled, "" if s == (T, H, W) else f"{s[0]}x{s[1]}x{s[2]}"


# ----------------------------------------------------------------------------
# Report
# ----------------------------------------------------------------------------

def ms(t: float | None, approx: bool = False) -> str:
    if t is None:
        return "-"
    text = f"{t * 1e3:.3f}" if t < 0.01 else f"{t * 1e3:.2f}" if t < 1 else f"{t * 1e3:.0f}"
    return ("~" if approx else "") + text


def ratio(a: float | None, b: float | None) -> str:
    return "-" if a is None or b is None or b <= 0 else f"{a / b:.2f}"


def table(headers: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(headers)]

    def line(cells):
        return "| " + " | ".join(c.ljust(w) if i == 0 else c.rjust(w)
                                 for i, (c, w) in enumerate(zip(cells, widths))) + " |"
    sep = "|" + "|".join("-" * (w + 1) + (":" if i else "-") for i, w in enumerate(widths)) + "|"
    return "\n".join([line(headers), sep, *(line(r) for r in rows)])


def report(timings: list[Timing], counts: list[int], all_threads: int, with_taichi: bool) -> str:
    """The table of medians (ms) and ratios, one row per case."""
    def label(n):
        return f"{n}=all" if n == all_threads else str(n)

    headers = ["kernel"] + [f"W{label(n)} ms" for n in counts]
    if with_taichi:
        headers += [f"T{label(n)} ms" for n in counts]
    headers += ["NumPy ms"] + [f"W1/W{n}" for n in counts if n > 1]
    if with_taichi:
        headers += [f"T1/T{n}" for n in counts if n > 1] + [f"T{n}/W{n}" for n in counts]
    headers += [f"NumPy/W{all_threads}"]
    rows = []
    for t in timings:
        if t.error:
            rows.append([t.key] + ["-"] * (len(headers) - 2) + [f"error: {t.error}"])
            continue
        w = {n: t.median("warp", n) for n in counts}
        ti = {n: t.median("taichi", n) for n in counts}
        row = [t.key] + [ms(w[n]) for n in counts]
        if with_taichi:
            row += [ms(ti[n]) for n in counts]
        row += [ms(t.reference, bool(t.reference_note))] + [ratio(w[1], w[n]) for n in counts if n > 1]
        if with_taichi:
            row += [ratio(ti[1], ti[n]) for n in counts if n > 1] + [ratio(ti[n], w[n]) for n in counts]
        row += [ratio(t.reference, w[all_threads])]
        rows.append(row)
    return table(headers, rows)


def geometric_means(timings: list[Timing], counts: list[int]) -> str:
    """One line: the geometric mean over cases of each thread-count speedup."""
    parts = []
    for backend, letter in (("warp", "W"), ("taichi", "T")):
        for n in counts:
            if n == 1:
                continue
            r = [t.median(backend, 1) / t.median(backend, n) for t in timings
                 if t.median(backend, 1) and t.median(backend, n)]
            if r:
                parts.append(f"{letter}1/{letter}{n} {np.exp(np.mean(np.log(r))):.2f}")
    return "geometric mean over kernels: " + ", ".join(parts) if parts else ""


# ----------------------------------------------------------------------------
# Main
# ----------------------------------------------------------------------------

def parse_args(argv=None):
    from ivkernels.kernels.cases import FAMILIES

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--size", nargs=2, type=int, metavar=("H", "W"), default=None,
                   help="image size (default 480 640; 120 160 with --quick)")
    p.add_argument("--frames", type=int, default=None, help="frames T (default 8; 3 with --quick)")
    p.add_argument("--repeat", type=int, default=None, help="timed rounds per kernel (default 5; 2 with --quick)")
    p.add_argument("--only", nargs="+", metavar="NAME", default=None,
                   help=f"families among {FAMILIES}, or case keys (family.function)")
    p.add_argument("--all-variants", action="store_true", help="time every case, not one per host function")
    p.add_argument("--threads", type=int, default=None,
                   help="the 'all' thread count (default: IVKERNELS_THREADS, else the cores available)")
    p.add_argument("--quick", action="store_true", help="small input, few repeats: a smoke run")
    p.add_argument("--no-taichi", action="store_true", help="skip Taichi")
    p.add_argument("--no-reference", action="store_true", help="skip the NumPy reference")
    p.add_argument("--ref-budget", type=float, default=None,
                   help="seconds the reference may take on one input (default 2; 0.2 with --quick)")
    p.add_argument("--case-budget", type=float, default=4.0,
                   help="stop repeating a case after this many seconds per phase (at least 3 rounds)")
    p.add_argument("--seed", type=int, default=0, help="seed of the generated inputs")
    p.add_argument("--json", metavar="PATH", default=None, help="also write every measurement as JSON")
    args = p.parse_args(argv)
    if args.only:
        from ivkernels.kernels.cases import all_cases

        names = set(FAMILIES) | {c.key for c in all_cases()} | {f"{c.family}.{c.function}" for c in all_cases()}
        unknown = sorted(set(args.only) - names)
        if unknown:
            p.error(f"unknown families or cases {unknown}; families are {', '.join(FAMILIES)}")
    H, W = args.size if args.size else ((120, 160) if args.quick else (480, 640))
    if H < 16 or W < 16:
        p.error(f"--size must be at least 16 x 16, got {H} x {W}")
    args.size = (H, W)
    args.frames = args.frames if args.frames is not None else (3 if args.quick else 8)
    if args.frames < 2:
        p.error(f"--frames must be >= 2 (the temporal kernels need a pair), got {args.frames}")
    args.repeat = args.repeat if args.repeat is not None else (2 if args.quick else 5)
    if args.repeat < 1:
        p.error(f"--repeat must be >= 1, got {args.repeat}")
    if args.threads is not None and args.threads < 1:
        p.error(f"--threads must be an integer >= 1, got {args.threads}")
    args.ref_budget = args.ref_budget if args.ref_budget is not None else (0.2 if args.quick else 2.0)
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    wp.config.quiet = True
    wp.config.log_level = wp.LOG_WARNING
    from ivkernels.backends import get_backend
    from ivkernels.kernels.launch import available_cores, default_threads

    all_threads = args.threads or default_threads()
    counts = thread_counts(all_threads)
    H, W = args.size
    T = args.frames
    size = (T, H, W)
    cases = select_cases(args.only, args.all_variants)
    print(f"# ivkernels kernel benchmark: {H}x{W}, {T} frames, {args.repeat} rounds, {len(cases)} cases",
          flush=True)
    print(f"machine: {available_cores()} cores available to this process ({os.cpu_count()} CPUs), load "
          f"average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; python {platform.python_version()}, "
          f"numpy {np.__version__}, warp {wp.config.version}", flush=True)
    print(f"threads: {', '.join(map(str, counts))} (all = {all_threads})", flush=True)

    backends = {"warp": get_backend("warp")}
    if not args.no_taichi:
        from ivkernels.kernels.taichi import init as taichi_init

        backends["taichi"] = get_backend("taichi")
        import taichi as ti
    capacity = thread_capacity(counts)
    print("thread capacity at the start (pure arithmetic, 1 thread / n threads): "
          + ", ".join(f"{n}: {capacity[n]:.2f}x" for n in counts if n > 1), flush=True)
    timings = {case.key: Timing(case.key) for case in cases}
    t_total = time.perf_counter()
    for phase, n in enumerate(counts):
        taichi_n = None
        if "taichi" in backends:
            t0 = time.perf_counter()
            taichi_init(n)
            ti.set_logging_level(ti.ERROR)   # compile warnings would interleave with the table
            taichi_n = n
            print(f"phase {phase + 1}/{len(counts)}: Taichi initialised on {n} thread(s) in "
                  f"{time.perf_counter() - t0:.2f} s", flush=True)
        for case in cases:
            timing = timings[case.key]
            if timing.error:
                continue
            values = None
            try:
                values = case_values(case, size, args.seed)
                time_phase(case, values, backends, counts, taichi_n, timing, args.repeat, args.case_budget)
                if phase == 0 and not args.no_reference:
                    timing.reference, timing.reference_note = time_reference(case, size, args.seed,
                                                                             args.ref_budget)
            except Exception as err:           # one failing case must not hide the others' timings
                timing.error = f"{type(err).__name__}: {' '.join(str(err).split())[:120]}"
            del values
    ordered = [timings[c.key] for c in cases]
    print()
    print(report(ordered, counts, all_threads, "taichi" in backends))
    print()
    print("W<n> / T<n>: Warp / Taichi on n threads (median ms); NumPy: the reference (~ scaled from a "
          "smaller input); ratios > 1 mean the second is faster.")
    print(geometric_means(ordered, counts))
    capacity = thread_capacity(counts)
    print("thread capacity at the end: " + ", ".join(f"{n}: {capacity[n]:.2f}x" for n in counts if n > 1))
    print(f"total {time.perf_counter() - t_total:.0f} s; load average at the end "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"size": size, "threads": counts, "all": all_threads,
                       "cases": [{"key": t.key, "error": t.error, "reference_s": t.reference,
                                  "reference_on": t.reference_note,
                                  "seconds": {f"{b}{n}": v for (b, n), v in t.seconds.items()}}
                                 for t in ordered]}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
