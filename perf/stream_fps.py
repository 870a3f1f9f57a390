"""Frames per second of the default decomposition on a stream of windows: ``python perf/stream_fps.py --help``.

A video of ``--frames`` frames (renders of the training kind ``objects_camera``,
seeds 1, 2, ... joined end to end) goes through :func:`ivkernels.iter_decompose`
with the default flow and ``Params``, as the command line streams a long clip.
After a warm-up that compiles and loads every kernel module on the device
(``warp.force_load``), it prints the seconds of each window as it arrives, and
the amortised rate: new frames per second over the windows after the first
(the first window also runs the pipeline's one-off steps), and over all of
them.  On a CUDA device it also prints the device memory held by Warp's
allocator at the end.

    python perf/stream_fps.py --device cuda --frames 40 --size 480 640
    python perf/stream_fps.py --frames 12 --size 120 160           # the CPU, 2 threads
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def stream_frames(n_frames: int, size: tuple[int, int]) -> np.ndarray:
    """(n_frames, H, W, 3) float32: ``objects_camera`` renders of seeds 1, 2, ... end to end."""
    from ivkernels.evaluation import synthetic

    part = 20
    parts = [synthetic.render_sequence("objects_camera", n_frames=part, size=size, seed=s).frames
             for s in range(1, 2 + (n_frames - 1) // part)]
    return np.concatenate(parts)[:n_frames]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cpu", help="'cpu' or 'cuda[:N]'")
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    ap.add_argument("--threads", type=int, default=2, help="CPU launch threads")
    ap.add_argument("--flow-passes", type=int, default=None, help="default: decompose()'s")
    ap.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="Params fields")
    args = ap.parse_args(argv)

    import warp as wp

    import ivkernels as iv
    from common import parse_grid
    from ivkernels.decompose import DEFAULT_FLOW_PASSES
    from ivkernels.evaluation import synthetic

    params = iv.Params(**parse_grid(args.set)[0])
    passes = args.flow_passes or DEFAULT_FLOW_PASSES
    H, W = args.size
    print(f"iter_decompose(): {args.frames} frames at {W}x{H} on {args.device}, windows of "
          f"{params.window} (overlap {params.overlap}), flow_passes {passes}")
    tiny = synthetic.render_sequence("objects_camera", n_frames=3, size=(32, 40), seed=1)
    t0 = time.perf_counter()
    iv.decompose(tiny.frames, device=args.device, threads=args.threads)
    wp.force_load(device=args.device)
    print(f"warm-up (compile / load every module) {time.perf_counter() - t0:.1f} s")
    frames = stream_frames(args.frames, (H, W))
    stream = iv.iter_decompose(frames, device=args.device, params=params, threads=args.threads,
                               flow_passes=passes)
    print(f"  {'window':>6} {'frames':>9} {'new':>4} {'s':>8} {'new frames/s':>13}")
    rows = []
    t0 = time.perf_counter()
    last = t0
    for i, res in enumerate(stream):
        now = time.perf_counter()
        new = res.stop - res.start - res.n_carried
        rows.append((now - last, new))
        print(f"  {i:6d} {res.start:4d}-{res.stop - 1:<4d} {new:4d} {now - last:8.2f} {new / (now - last):13.2f}")
        last = now
    total = time.perf_counter() - t0
    later_s = sum(s for s, _ in rows[1:])
    later_n = sum(n for _, n in rows[1:])
    print(f"all windows: {args.frames} frames in {total:.1f} s = {args.frames / total:.2f} frames/s")
    if later_n:
        print(f"after the first window: {later_n} frames in {later_s:.1f} s = {later_n / later_s:.2f} frames/s "
              f"({later_s / later_n:.3f} s per frame)")
    if args.device != "cpu":
        dev = wp.get_device(args.device)
        if dev.is_mempool_enabled:
            print(f"device memory held by Warp's pool at the end: {wp.get_mempool_used_mem_current(dev) / 2**20:.0f} "
                  f"MiB (high water {wp.get_mempool_used_mem_high(dev) / 2**20:.0f} MiB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
