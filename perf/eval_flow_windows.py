"""The flow across windows: one timed decompose() of a multi-window video, with or without the next
window's first-pass flow estimated on a second thread (``ivkernels.decompose.FLOW_AHEAD``).

Prints one line: wall and CPU seconds, ``diagnostics["seconds"]`` per stage
(``flow ahead``: the overlapped first-pass flow) and the returned flow's EPE
against the renderer's.  Run it with ``PYTHONPATH`` on another commit's
worktree to compare codes side by side (``--mode base`` only labels the line).

    python perf/eval_flow_windows.py --mode head --frames 20 --size 120 160
    python perf/eval_flow_windows.py --mode noahead --frames 20 --size 120 160
"""
from __future__ import annotations

import argparse
import importlib
import time

import ivkernels as iv
from ivkernels import metrics, synthetic          # as attributes: also on commits before ivkernels.evaluation


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mode", default="head", choices=("head", "noahead", "base"),
                    help="noahead: FLOW_AHEAD = False; head, base: as the code stands")
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    if args.mode == "noahead":
        importlib.import_module("ivkernels.decompose").FLOW_AHEAD = False
    tiny = synthetic.render_sequence("objects_camera", n_frames=3, size=(32, 40), seed=1)
    iv.decompose(tiny.frames, threads=args.threads)                # compile and load the kernels
    seq = synthetic.render_sequence("objects_camera", n_frames=args.frames, size=tuple(args.size), seed=1)
    t0, c0 = time.perf_counter(), time.process_time()
    video = iv.decompose(seq.frames, threads=args.threads)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    stages = " ".join(f"{k}={x:.1f}" for k, x in video.diagnostics["seconds"].items())
    print(f"{args.mode:8s} {args.frames}x{args.size[1]}x{args.size[0]} windows {len(video.diagnostics['windows'])} "
          f"wall {wall:7.1f} s cpu {cpu:7.1f} s  {stages}  flow EPE "
          f"{metrics.endpoint_error(video.flow, seq.flow):.4f}", flush=True)


if __name__ == "__main__":
    main()
