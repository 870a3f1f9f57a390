"""A dark grey disc on a grey floor, still, under a camera's noise: does the albedo keep it?

The smallest case of dark materials going into the shading.  ``--frames``
still frames of a disc of albedo ``--dark`` (radius ``--radius`` px) on a
floor of 0.5 under a smooth static light, with Gaussian noise (linear
units) drawn per colour channel (a colour camera) or shared by the channels
(greyscale footage), decomposed with the given ``Params`` settings (no
flow: the scene holds still).  Prints, per noise level and setting, the
median albedo inside the disc over the floor's, against the truth.

    python perf/dark_disc.py
    python perf/dark_disc.py --noise 0 0.003 0.01 --grid shading_step_noise=0,2.5
"""
from __future__ import annotations

import argparse

import numpy as np

import ivkernels as iv
from common import parse_grid
from ivkernels.evaluation.synthetic import DISC_FLOOR_ALBEDO, dark_disc


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--radius", type=int, default=20)
    parser.add_argument("--dark", type=float, default=0.08, help="the disc's albedo (the floor's is 0.5)")
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.003], help="std, linear units")
    parser.add_argument("--grid", nargs="*", default=["shading_step_noise=0,2.5"], help="name=v1,v2 Params fields")
    args = parser.parse_args(argv)
    if not 2 < args.radius < min(args.size) // 2 - 2:
        raise SystemExit(f"--radius must leave the disc and a floor around it inside the frame; got {args.radius}")
    truth = args.dark / DISC_FLOOR_ALBEDO
    print(f"dark disc (albedo {args.dark:g}, radius {args.radius} px) on a floor of {DISC_FLOOR_ALBEDO:g}, "
          f"{args.frames} still frames at {args.size[1]}x{args.size[0]}; albedo ratio inside / floor, truth {truth:.3f}")
    print(f"{'noise':>7} {'channels':>9} {'setting':<32} {'ratio':>7}")
    for noise in args.noise:
        for per_channel in (True, False):
            if noise == 0 and not per_channel:
                continue
            frames, inside, floor = dark_disc(tuple(args.size), args.frames, args.radius, args.dark, noise,
                                              per_channel)
            flow = np.zeros((args.frames - 1, *args.size, 2), np.float32)
            for fields in parse_grid(args.grid):
                albedo = iv.decompose(frames, flow=flow, params=iv.Params(**fields)).albedo.mean(axis=-1)
                ratio = float(np.median(albedo[:, inside]) / np.median(albedo[:, floor]))
                setting = ", ".join(f"{k}={v}" for k, v in fields.items()) or "default"
                channels = "-" if noise == 0 else "per" if per_channel else "shared"
                print(f"{noise:7.4f} {channels:>9} {setting:<32} {ratio:7.3f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
