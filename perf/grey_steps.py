"""Grey albedo steps: intrinsic video against colour Retinex on colour and grey video.

Each sequence is run twice: as rendered (colour) and as grey video, the same
scene with its albedo replaced by its luminance (3 equal channels) and the
frames re-made as albedo times shading, so the grey version has exactly the
shading of the colour one and truth for both.  The synthetic kinds use their
ground-truth flow (6 frames at 160x120); the MIT-Berkeley training objects
their exact zero flow, at about 120 pixels on the shorter side.  Prints mean
LMSE (synthetic) or albedo LMSE in the mask (MIT) of tuned colour Retinex
(``CRET``, synthetic and MIT) and of IV with each ``--setting``.

    python perf/grey_steps.py --setting off shading_step_gain=0 --setting on
    python perf/grey_steps.py --mit apple paper1 --palettes grey --setting gain4 shading_step_gain=4

Training data only: synthetic seeds other than 0 (default 1) and the MIT
training objects.
"""
from __future__ import annotations

import argparse

import numpy as np

import ivkernels as iv
from ivkernels.evaluation import datasets, metrics, synthetic
from ivkernels.evaluation.baselines import TUNED_THRESHOLDS, color_retinex

from common import parse_value

#: Rec. 709 luminance weights of linear RGB.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)


def as_grey(albedo: np.ndarray, shading: np.ndarray):
    """(frames, albedo) of the grey version: albedo luminance in 3 equal channels, times shading."""
    a = np.repeat((albedo @ LUMINANCE)[..., None], 3, -1).astype(np.float32)
    return np.clip(a * shading[..., None], 0, 1).astype(np.float32), a


def synthetic_rows(kinds, seed, palettes, settings):
    for kind in kinds:
        seq = synthetic.render_sequence(kind, n_frames=6, size=(120, 160), seed=seed)
        for palette in palettes:
            frames, albedo = (seq.frames, seq.albedo) if palette == "colour" else as_grey(seq.albedo, seq.shading)
            a, s = color_retinex(frames, *TUNED_THRESHOLDS)
            row = {"CRET": metrics.intrinsic_lmse(a, s, albedo, seq.shading)["mean"]}
            for name, params in settings.items():
                video = iv.decompose(frames, flow=seq.flow, params=params)
                row[name] = metrics.intrinsic_lmse(video.albedo, video.shading, albedo, seq.shading)["mean"]
            yield f"{kind}/{seed}", palette, row


def mit_rows(names, palettes, settings):
    for name in names:
        obj = datasets.load_mit_object(name)
        t, h, w, _ = obj.frames.shape
        k = max(1, int(round(min(h, w) / 120)))
        frames, albedo = obj.frames[:, ::k, ::k], obj.albedo[::k, ::k]
        mask, shading = obj.mask[::k, ::k], obj.frame_shading[:, ::k, ::k]
        for palette in palettes:
            if palette == "grey":
                albedo_p = np.repeat((albedo @ LUMINANCE)[..., None], 3, -1)
                frames_p = np.repeat((frames @ LUMINANCE)[..., None], 3, -1).astype(np.float32)
            else:
                albedo_p, frames_p = albedo, np.ascontiguousarray(frames)
            truth = np.broadcast_to(albedo_p, frames_p.shape)
            a, s = color_retinex(frames_p, *TUNED_THRESHOLDS)
            row = {"CRET": metrics.intrinsic_lmse(a, s, truth, shading, mask=mask)["albedo"]}
            zero = np.zeros((t - 1,) + frames_p.shape[1:3] + (2,), np.float32)
            for label, params in settings.items():
                video = iv.decompose(frames_p, flow=zero, params=params)
                row[label] = metrics.intrinsic_lmse(video.albedo, video.shading, truth, shading, mask=mask)["albedo"]
            yield f"mit {name}", palette, row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--setting", nargs="+", action="append", metavar=("LABEL", "NAME=VALUE"),
                    help="a label and the Params fields it sets (repeatable); default: the defaults as 'IV'")
    ap.add_argument("--kinds", nargs="*", default=list(synthetic.KINDS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mit", nargs="*", default=[], help="MIT training objects to run (none by default)")
    ap.add_argument("--palettes", nargs="+", default=["colour", "grey"], choices=["colour", "grey"])
    args = ap.parse_args(argv)
    if args.seed == 0:
        ap.error("seed 0 is kept for reporting; choose on another seed")
    settings = {"IV": iv.Params()}
    if args.setting:
        settings = {}
        for label, *fields in args.setting:
            changes = {}
            for item in fields:
                name, _, value = item.partition("=")
                changes[name] = parse_value(value)
            settings[label] = iv.Params(**changes)
    rows = list(synthetic_rows(args.kinds, args.seed, args.palettes, settings))
    rows += list(mit_rows(args.mit, args.palettes, settings))
    for item, palette, row in rows:
        print(f"{item:24s} {palette:6s}", "  ".join(f"{k}={v:.4f}" for k, v in row.items()), flush=True)


if __name__ == "__main__":
    main()
