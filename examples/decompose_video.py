"""Decompose a video of your own and look at the result.

    python examples/decompose_video.py clip.mp4 --out out/clip [--stop 16] [--scale 0.5]

Reads the video (or a folder of images), decomposes it with the default
settings, and writes the command line's outputs (albedo/, shading/, flow/,
occlusion/, boundary/, intrinsics.npz, preview.mp4, contact_sheet.png) under
``--out``.  Without an input it makes a short clip from the synthetic
renderer first, so the example runs anywhere.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ivkernels import cli
from ivkernels.evaluation import synthetic
from ivkernels.io import write_video


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input", nargs="?", help="video file or folder of images")
    parser.add_argument("--out", default="out/video")
    parser.add_argument("--start", type=int, default=0)
    parser.add_argument("--stop", type=int, default=None)
    parser.add_argument("--scale", type=float, default=1.0)
    parser.add_argument("--backend", default="warp", choices=["warp", "taichi"])
    args = parser.parse_args(argv)
    out = Path(args.out)
    source = args.input
    if source is None:
        out.parent.mkdir(parents=True, exist_ok=True)
        seq = synthetic.render_sequence("rotating_shadows", n_frames=6, size=(120, 160), seed=2)
        source = str(write_video(out.parent / (out.name + "_input.mp4"), seq.frames_srgb8(), fps=6))
        print(f"no input given: made {source}")
    cmd = ["decompose", source, "-o", str(out), "--force", "--start", str(args.start),
           "--scale", str(args.scale), "--backend", args.backend]
    if args.stop is not None:
        cmd += ["--stop", str(args.stop)]
    return cli.main(cmd)


if __name__ == "__main__":
    raise SystemExit(main())
