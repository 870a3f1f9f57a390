"""Accuracy on the synthetic sequences, as the paper's Fig. 6.

For every synthetic kind (8 frames at 320x240 by default, plus one kind at
640x480 with ``--large``), prints LMSE of albedo, shading and their mean
(Grosse et al.), and the temporal incoherence (EPE of a fixed flow method run
on the albedo sequence, against ground-truth flow) for:

    IV          intrinsic video with estimated flow (the default flow method)
    IV-noflow   the ablation without temporal terms and motion weights
    IV-gtflow   intrinsic video with ground-truth flow
    CRET        per-frame colour Retinex
    input       the input video taken as albedo
    GT          the ground-truth albedo (temporal incoherence only)

Evaluation uses seed 0 of every kind; weights were chosen on other seeds.

    python perf/accuracy.py [--frames 8] [--size 240 320] [--large] [--backend warp]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import ivkernels as iv
from ivkernels import metrics, synthetic
from ivkernels.baselines import color_retinex

EVAL_SEED = 0


def evaluate(kind: str, n_frames: int, size, backend: str, methods) -> dict:
    seq = synthetic.render_sequence(kind, n_frames=n_frames, size=tuple(size), seed=EVAL_SEED)
    rows = {}
    for name in methods:
        t0 = time.perf_counter()
        if name == "IV":
            video = iv.decompose(seq.frames, backend=backend)
            albedo, shading = video.albedo, video.shading
        elif name == "IV-noflow":
            video = iv.decompose(seq.frames, temporal=False, backend=backend)
            albedo, shading = video.albedo, video.shading
        elif name == "IV-gtflow":
            video = iv.decompose(seq.frames, flow=seq.flow, backend=backend)
            albedo, shading = video.albedo, video.shading
        elif name == "CRET":
            albedo, shading = color_retinex(seq.frames)
        elif name == "input":
            albedo, shading = seq.frames, np.ones(seq.frames.shape[:3], np.float32)
        elif name == "GT":
            albedo, shading = seq.albedo, seq.shading
        else:
            raise ValueError(name)
        seconds = time.perf_counter() - t0
        lmse = metrics.intrinsic_lmse(albedo, shading, seq.albedo, seq.shading)
        tin = metrics.temporal_incoherence(albedo, seq.flow, seq.visibility)
        rows[name] = dict(lmse, epe=tin["epe"], epe_visible=tin["epe_visible"], seconds=seconds)
    return rows


def print_table(title: str, rows: dict) -> None:
    print(f"\n{title}")
    print(f"{'method':<11} {'LMSE A':>8} {'LMSE S':>8} {'LMSE mean':>9} {'EPE':>7} {'EPE vis':>8} {'s':>6}")
    for name, r in rows.items():
        print(f"{name:<11} {r['albedo']:8.4f} {r['shading']:8.4f} {r['mean']:9.4f} "
              f"{r['epe']:7.3f} {r['epe_visible']:8.3f} {r['seconds']:6.1f}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(240, 320), metavar=("H", "W"))
    parser.add_argument("--large", action="store_true", help="also run one kind at 640x480")
    parser.add_argument("--backend", default="warp", choices=["warp", "taichi"])
    parser.add_argument("--kinds", nargs="*", default=list(synthetic.KINDS))
    args = parser.parse_args(argv)
    methods = ["IV", "IV-noflow", "IV-gtflow", "CRET", "input", "GT"]
    per_kind = {}
    for kind in args.kinds:
        per_kind[kind] = evaluate(kind, args.frames, args.size, args.backend, methods)
        print_table(f"{kind}: {args.frames} frames at {args.size[1]}x{args.size[0]}", per_kind[kind])
    mean = {m: {k: float(np.mean([per_kind[kind][m][k] for kind in per_kind]))
                for k in per_kind[args.kinds[0]][m]} for m in methods}
    print_table(f"mean over {len(per_kind)} kinds", mean)
    iv_mean, cret_mean = mean["IV"]["mean"], mean["CRET"]["mean"]
    print(f"\nIV / CRET mean LMSE = {iv_mean / cret_mean:.3f} (required <= 0.85); "
          f"IV {'<' if iv_mean < mean['IV-noflow']['mean'] else '>='} IV-noflow "
          f"(difference {iv_mean - mean['IV-noflow']['mean']:+.2e}); "
          f"IV albedo EPE {mean['IV']['epe']:.3f} vs input {mean['input']['epe']:.3f} "
          f"and CRET {mean['CRET']['epe']:.3f}")
    if args.large:
        kind = args.kinds[0]
        rows = evaluate(kind, args.frames, (480, 640), args.backend, methods)
        print_table(f"{kind}: {args.frames} frames at 640x480", rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
