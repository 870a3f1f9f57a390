"""Decompose a generated sequence and compare it with its ground truth.

Renders a synthetic Lambertian video (camera moving, light changing), writes
its frames as PNGs, runs the command line ``ivkernels decompose`` on them, and
writes a picture comparing the result with the exact ground truth::

    python examples/demo_synthetic.py --out out/demo

Look at ``out/demo/comparison.png`` (input / albedo / shading, estimated and
true) and ``out/demo/result/contact_sheet.png``; the full outputs of the
command line are under ``out/demo/result/``.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v2 as imageio
import numpy as np

from ivkernels import cli
from ivkernels.evaluation import metrics, synthetic
from ivkernels.evaluation.baselines import color_retinex
from ivkernels.io import write_png_sequence
from ivkernels.viz import albedo_to_srgb8, contact_sheet, shading_to_srgb8


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/demo", help="output folder")
    parser.add_argument("--kind", default="free_camera", choices=synthetic.KINDS)
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--backend", default="warp", choices=["warp", "taichi"])
    args = parser.parse_args(argv)

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    seq = synthetic.render_sequence(args.kind, n_frames=args.frames, size=tuple(args.size), seed=0)
    write_png_sequence(out / "input", seq.frames_srgb8())
    result = out / "result"
    status = cli.main(["decompose", str(out / "input"), "-o", str(result), "--force",
                       "--backend", args.backend])
    if status != 0:
        return status               # the command line has said what went wrong

    data = np.load(result / "intrinsics.npz")
    albedo, shading = data["albedo"], data["shading"]
    iv = metrics.intrinsic_lmse(albedo, shading, seq.albedo, seq.shading)
    cret_albedo, cret_shading = color_retinex(seq.frames)
    cret = metrics.intrinsic_lmse(cret_albedo, cret_shading, seq.albedo, seq.shading)
    print(f"{args.kind}, {args.frames} frames at {args.size[1]}x{args.size[0]}")
    print(f"  LMSE  intrinsic video: albedo {iv['albedo']:.4f}  shading {iv['shading']:.4f}"
          f"  mean {iv['mean']:.4f}")
    print(f"  LMSE  colour Retinex:  albedo {cret['albedo']:.4f}  shading {cret['shading']:.4f}"
          f"  mean {cret['mean']:.4f}")

    rows = [("input", albedo_to_srgb8(seq.frames)),
            ("albedo (ours)", albedo_to_srgb8(albedo)),
            ("albedo (true)", albedo_to_srgb8(seq.albedo / np.percentile(seq.albedo, 99))),
            ("shading (ours)", shading_to_srgb8(shading / np.percentile(shading, 99))),
            ("shading (true)", shading_to_srgb8(seq.shading / np.percentile(seq.shading, 99)))]
    imageio.imwrite(out / "comparison.png", contact_sheet(rows))
    print(f"wrote {out / 'comparison.png'} and {result}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
