#!/usr/bin/env python
"""Balanced launches: the weighted flow median on real flow edges, by chunks per thread.

The weighted median of Classic+NL works only where the flow has edges, and
on real images those crowd one part of the rows: split into one band per
thread, one thread does most of the work while the others wait.  With
``launch_rows(..., balance=True)`` the rows are cut into
:data:`ivkernels.kernels.launch.BALANCE_CHUNKS_PER_THREAD` chunks per thread,
taken in turn by whichever thread is free.

This records every ``weighted_median_flow`` call that Classic+NL-fast makes
on each Middlebury pair, then replays them all, in rotating order:

* ``1 thread``;
* ``N bands``: N threads, one band each (``BALANCE_CHUNKS_PER_THREAD = 1``);
* ``N x k``: N threads, k chunks per thread, for each k of ``--chunks``;

and prints, per pair, the share of masked pixels in the first half of the
rows, the median seconds of all of the pair's calls per configuration, and
``1 thread / configuration``.

    python perf/bench_balance.py
    python perf/bench_balance.py --sequences Urban2 RubberWhale --chunks 2 8 32 --repeat 7
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from common import SEQUENCES, default_data_dir, middlebury_pairs, time_configs


def record_median_calls(be, frames) -> list:
    """Host copies of the inputs of every ``weighted_median_flow`` call of Classic+NL-fast on ``frames``."""
    from ivkernels.flow.classic_nl import PRESETS, ClassicNL

    calls, original = [], be.median.weighted_median_flow

    def spy(flow, lab, occ, mask, out, *args, **kwargs):
        calls.append(([be.numpy(a).copy() for a in (flow, lab, occ, mask)], args, kwargs))
        return original(flow, lab, occ, mask, out, *args, **kwargs)

    be.median.weighted_median_flow = spy
    try:
        ClassicNL(be, PRESETS["classic_nl_fast"])(frames)
    finally:
        be.median.weighted_median_flow = original
    return calls


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sequences", nargs="+", default=list(SEQUENCES), choices=SEQUENCES)
    p.add_argument("--data", type=Path, default=None, help="Middlebury folder (default: shared/data/middlebury)")
    p.add_argument("--threads", type=int, default=None, help="N (default: the resolved thread count)")
    p.add_argument("--chunks", type=int, nargs="+", default=[2, 4, 8, 16], help="chunks per thread to time")
    p.add_argument("--repeat", type=int, default=5, help="timed rounds (default 5)")
    args = p.parse_args(argv)

    from ivkernels.backends import get_backend
    from ivkernels.kernels import launch

    be = get_backend("warp")
    n = args.threads or launch.get_threads()
    configs = {"1 thread": (1, 1), f"{n} bands": (n, 1)}
    configs.update({f"{n} x {k}": (n, k) for k in args.chunks})
    data = args.data or default_data_dir()
    print(f"weighted_median_flow of Classic+NL-fast, Middlebury, Warp; seconds per pair (median of "
          f"{args.repeat}); ratio = 1 thread / configuration")
    header = f"{'sequence':13s} {'1st half':>8s} " + " ".join(f"{name:>10s} {'ratio':>5s}" for name in configs)
    print(header)
    print("-" * len(header))
    ratios = {name: [] for name in configs}
    for name, frames, _ in middlebury_pairs(data, args.sequences):
        calls = record_median_calls(be, frames)
        arrays = [([be.asarray(a) for a in inputs], a, k) for inputs, a, k in calls]
        outs = [be.empty(inputs[0].shape) for inputs, _, _ in arrays]
        masks = [inputs[3] for inputs, _, _ in calls]
        first_half = sum(m.reshape(-1, m.shape[-1])[: m.shape[0] * m.shape[1] // 2].sum() for m in masks) \
            / max(1.0, sum(m.sum() for m in masks))

        def replay():
            for (inputs, a, k), out in zip(arrays, outs):
                be.median.weighted_median_flow(*inputs, out, *a, **k)

        med = time_configs(replay, be, configs, args.repeat, float("inf"), setting="BALANCE_CHUNKS_PER_THREAD")
        row = f"{name:13s} {first_half:8.2f} "
        for c in configs:
            ratios[c].append(med["1 thread"] / med[c])
            row += f" {med[c]:10.3f} {ratios[c][-1]:5.2f}"
        print(row)
    print("-" * len(header))
    gm = {c: float(np.exp(np.mean(np.log(v)))) for c, v in ratios.items()}
    print(f"{'geomean':13s} {'':8s} " + " ".join(f"{'':>10s} {gm[c]:5.2f}" for c in configs))
    print(f"library default: {launch.BALANCE_CHUNKS_PER_THREAD} chunks per thread")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
