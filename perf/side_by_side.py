"""Time one default decompose() by stage, for side-by-side runs of two versions of the code.

Run it once per version, one after the other on an otherwise idle machine,
with the other version on ``PYTHONPATH``::

    PYTHONPATH=<worktree of the old commit> python perf/side_by_side.py old
    python perf/side_by_side.py new

Prints the label, the seconds of the call and its ``diagnostics["seconds"]``
by stage.  8 frames of objects_camera (training seed 1) at 640x480 by
default (fixed lamps: its windows count one shading); ``--kind`` names
another of ``synthetic.SCENE_KINDS``, e.g. ``mixed_fast_light_hard`` for a
window whose light changes.  Warp on 2 threads; kernels are compiled and
loaded first.
"""
from __future__ import annotations

import argparse
import time

import ivkernels as iv


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("label")
    ap.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--kind", default="objects_camera", choices=sorted(iv.synthetic.SCENE_KINDS),
                    help="the scene kind (training seed 1)")
    args = ap.parse_args(argv)
    seq = iv.synthetic.render_kind(args.kind, n_frames=args.frames, size=tuple(args.size), seed=1)
    iv.decompose(seq.frames[:2, :64, :80], threads=args.threads)        # compile and load the kernels
    t0 = time.perf_counter()
    video = iv.decompose(seq.frames, threads=args.threads)
    seconds = time.perf_counter() - t0
    stages = ", ".join(f"{k} {v:.1f}" for k, v in video.diagnostics["seconds"].items())
    print(f"{args.label}: {seconds:.1f} s ({stages})", flush=True)


if __name__ == "__main__":
    main()
