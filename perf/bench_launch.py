#!/usr/bin/env python
"""Where splitting a Warp launch into row bands stops paying: 1 thread against N bands, by size.

For a few kernels of the case table (:mod:`ivkernels.kernels.cases`), from
the lightest per element to the heaviest, and a ladder of image sizes (2
frames each), this times in one process, in rotating order:

* ``W1``: Warp on 1 thread;
* ``WN``: Warp on N threads with the minimum band size of
  :data:`ivkernels.kernels.launch.MIN_BAND_ELEMENTS` (what the library does);
* ``WN split``: Warp on N threads with every launch split into N bands
  whatever its size (the minimum set to 1 element);

and prints the medians, ``W1/WN`` and ``W1/WN split``, and the elements of
the largest array per band of the split launch.  Where ``W1/WN split`` is
below 1 the hand-off to other threads costs more than it saves, and the
minimum should keep that size on one thread.  N defaults to the resolved
thread count (``IVKERNELS_THREADS`` or the cores available).

    python perf/bench_launch.py
    python perf/bench_launch.py --threads 4 --repeat 30
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from common import largest_input_elements, time_configs

KERNELS = ("vecops.axpy", "colour.luminance", "energy_shading.shading_smoothness", "median.median5x5")
SIZES = ((15, 20), (30, 40), (60, 80), (120, 160), (240, 320), (480, 640))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--threads", type=int, default=None, help="N (default: the resolved thread count)")
    p.add_argument("--repeat", type=int, default=20, help="timed rounds per size (default 20)")
    p.add_argument("--budget", type=float, default=3.0, help="seconds per kernel and size (at least 5 rounds)")
    p.add_argument("--only", nargs="+", default=None, choices=KERNELS, help="kernels to time")
    args = p.parse_args(argv)
    import warp as wp

    wp.config.quiet = True
    from ivkernels.backends import get_backend
    from ivkernels.kernels import launch
    from ivkernels.kernels.cases import all_cases, bind
    from ivkernels.kernels.thread_count import check_threads

    n = launch.default_threads() if args.threads is None else check_threads(args.threads, "--threads")
    if n < 2:
        p.error("needs at least 2 threads (--threads or IVKERNELS_THREADS)")
    be = get_backend("warp")
    cases = {c.key: c for c in all_cases()}
    configs = {"W1": (1, launch.MIN_BAND_ELEMENTS), f"W{n}": (n, launch.MIN_BAND_ELEMENTS),
               f"W{n} split": (n, 1)}
    print(f"# row bands: 1 thread against {n}; MIN_BAND_ELEMENTS = {launch.MIN_BAND_ELEMENTS}; "
          f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}", flush=True)
    print(f"| kernel | T x H x W | elements per band | W1 ms | W{n} ms | W{n} split ms | "
          f"W1/W{n} | W1/W{n} split |")
    print("|---|---|--:|--:|--:|--:|--:|--:|")
    for key in args.only or KERNELS:
        case = cases[key]
        for H, W in SIZES:
            values = case.make(np.random.default_rng(0), 2, H, W)
            call, _ = bind(case, be, values)
            med = time_configs(call, be, configs, args.repeat, args.budget)
            w1, wn, ws = med["W1"], med[f"W{n}"], med[f"W{n} split"]
            print(f"| {key} | 2x{H}x{W} | {largest_input_elements(values) // n} | {w1 * 1e3:.3f} | "
                  f"{wn * 1e3:.3f} | {ws * 1e3:.3f} | {w1 / wn:.2f} | {w1 / ws:.2f} |", flush=True)
    print(f"load average at the end {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
