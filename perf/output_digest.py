"""Digests of ``decompose()`` and ``estimate_flow()`` outputs on every backend.

A refactor that must not change results prints the same lines before and
after::

    python perf/output_digest.py > before.txt     # on the old code
    python perf/output_digest.py > after.txt      # on the new code
    diff before.txt after.txt                     # empty: bitwise identical

Inputs are two small rendered sequences (a static scene under a moving light
and moving objects), 5 frames at 40x48, so the NumPy backend finishes in
seconds; each array's SHA-256 is printed with its shape and dtype.
"""
from __future__ import annotations

import argparse
import hashlib

import numpy as np

import ivkernels as iv
from ivkernels.backends import available_backends


def digest(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    return f"{a.dtype}{list(a.shape)} {hashlib.sha256(a.tobytes()).hexdigest()[:16]}"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backends", nargs="*", default=None, help="default: every available CPU backend")
    args = ap.parse_args(argv)
    backends = args.backends or [b.name for b in available_backends() if b.device == "cpu"]
    for kind in ("static_moving_light", "objects_camera"):
        seq = iv.synthetic.render_sequence(kind, n_frames=5, size=(40, 48), seed=3)
        for be in backends:
            flow = iv.estimate_flow(seq.frames, backend=be)
            print(kind, be, "estimate_flow", digest(flow), flush=True)
            video = iv.decompose(seq.frames, backend=be, threads=2)
            for name in ("albedo", "shading", "flow", "occlusion", "boundary"):
                print(kind, be, "decompose", name, digest(getattr(video, name)), flush=True)
            gt = iv.decompose(seq.frames, flow=seq.flow, backend=be, threads=2)
            print(kind, be, "decompose(gt flow)", "albedo", digest(gt.albedo), flush=True)


if __name__ == "__main__":
    main()
