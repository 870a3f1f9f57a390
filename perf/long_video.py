"""A long video streamed through iter_decompose: time per frame and resident memory along the way.

Cost must grow linearly with the frames and memory must stay bounded by the
window.  One run over ``--frames`` frames says both: the video is cut into
equal parts (``--parts``), and for each part the script prints the seconds
per new frame and the largest resident set (VmRSS) seen while solving it.
Linear cost is a flat seconds-per-frame column; bounded memory a flat RSS
column (the input itself is held in memory from the start, as a reader
would hand frames over; it is counted before the first window).

The input is made of synthetic renders of 20 frames each (``objects_camera``,
consecutive seeds starting at 1), so every 20 frames the scene cuts; the
solver sees one long video.  Nothing of the output is kept but a checksum.

    python perf/long_video.py --frames 1000 --size 240 320 --flow dis
    python perf/long_video.py --frames 60 --size 60 80 --parts 3          (a smoke run)
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import ivkernels as iv
from ivkernels.evaluation import synthetic

RENDER_FRAMES = 20


def resident_mib() -> float:
    """The process's resident set now (VmRSS), MiB; NaN where /proc is missing."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def long_input(n_frames: int, size: tuple[int, int]) -> np.ndarray:
    """(n_frames, H, W, 3) float32: renders of RENDER_FRAMES frames, one seed each, back to back."""
    parts = [synthetic.render_sequence("objects_camera", n_frames=RENDER_FRAMES, size=size, seed=1 + k).frames
             for k in range(-(-n_frames // RENDER_FRAMES))]
    return np.concatenate(parts)[:n_frames]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1000)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    parser.add_argument("--flow", default=None, help="flow method (default: decompose()'s own)")
    parser.add_argument("--parts", type=int, default=4, help="parts of the video reported apart")
    args = parser.parse_args(argv)
    if args.frames < 2 or args.parts < 1:
        raise SystemExit("--frames must be >= 2 and --parts >= 1")
    frames = long_input(args.frames, tuple(args.size))
    rss_input = resident_mib()
    kwargs = {} if args.flow is None else {"flow": args.flow}
    print(f"{args.frames} frames at {args.size[1]}x{args.size[0]}, flow {args.flow or 'default'}; "
          f"input {frames.nbytes / 2**20:.0f} MiB, RSS with the input {rss_input:.0f} MiB", flush=True)
    bounds = [round(k * args.frames / args.parts) for k in range(args.parts + 1)]
    seconds = np.zeros(args.parts)
    new_frames = np.zeros(args.parts, int)
    peak = np.zeros(args.parts)
    checksum, windows, reported = 0.0, 0, 0

    def report(k: int) -> None:
        per_frame = seconds[k] / max(new_frames[k], 1)
        print(f"{bounds[k]:5d}-{bounds[k + 1]:<6d} {per_frame:8.3f} "
              f"{per_frame / (seconds[0] / max(new_frames[0], 1)):8.2f} {peak[k]:13.0f}", flush=True)

    print(f"{'frames':>12} {'s/frame':>8} {'vs first':>8} {'peak RSS MiB':>13}", flush=True)
    t0 = time.perf_counter()
    for res in iv.iter_decompose(frames, progress=False, **kwargs):
        now = time.perf_counter()
        part = min(np.searchsorted(bounds, res.start + res.n_carried, side="right") - 1, args.parts - 1)
        while reported < part:                      # the parts before this window's are complete
            report(reported)
            reported += 1
        seconds[part] += now - t0
        new_frames[part] += res.stop - res.start - res.n_carried
        peak[part] = max(peak[part], resident_mib())
        checksum += float(res.albedo[res.n_carried:].sum())
        windows += 1
        t0 = time.perf_counter()
    if not np.isfinite(checksum):
        raise SystemExit("the albedo is not finite")
    while reported < args.parts:
        report(reported)
        reported += 1
    print(f"{windows} windows, {seconds.sum():.1f} s in all, {seconds.sum() / args.frames:.3f} s per frame")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
