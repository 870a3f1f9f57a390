#!/usr/bin/env python
"""Where the ground-truth flow loses to the estimated one: the flows swapped one object at a time.

For each training sequence (synthetic, seeds other than 0) this runs
``decompose()`` with its own estimated flow and with the ground-truth flow,
then once per object with the ground-truth flow everywhere except on that
object's pixels (``object_id`` of frame t), where the estimated flow takes
its place.  Per object it prints its share of the pixels, the true flow's
mean length and the estimated flow's endpoint error there, and the albedo
LMSE on that object for the three flows, beside the sequence's mean LMSE
(albedo and shading) with the swapped flow.  An object where the swap
brings the true flow's albedo error down to the estimated flow's is one
where the estimated flow, although wrong as a motion, gives the temporal
terms more to work with.

    python perf/flow_by_object.py --seeds 1 12
    python perf/flow_by_object.py --seeds 1 --kinds objects_camera --size 120 160
"""
from __future__ import annotations

import argparse

import numpy as np

import ivkernels as iv
from common import EVAL_SEED, parse_grid
from ivkernels.evaluation import metrics, synthetic


def swapped_flow(true_flow: np.ndarray, estimated: np.ndarray, object_id: np.ndarray, k: int) -> np.ndarray:
    """``true_flow`` (T-1, H, W, 2) with ``estimated`` on the pixels whose ``object_id``
    (T, H, W; frame t for pair t) is ``k``."""
    on = (object_id[:-1] == k)[..., None]
    return np.where(on, estimated, true_flow).astype(np.float32)


def object_lmse(albedo: np.ndarray, truth: np.ndarray, object_id: np.ndarray, k: int) -> float:
    """Albedo LMSE over the pixels of object ``k``."""
    return metrics.lmse(albedo, truth, mask=object_id == k)


def mean_lmse(video, seq) -> float:
    """LMSE mean (albedo and shading) of a decomposition against its sequence's truth."""
    return metrics.intrinsic_lmse(video.albedo, video.shading, seq.albedo, seq.shading)["mean"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1])
    parser.add_argument("--kinds", nargs="*", default=["rotating_shadows"], choices=synthetic.KINDS)
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=[240, 320], metavar=("H", "W"))
    parser.add_argument("--min-share", type=float, default=0.005,
                        help="objects covering less than this share of the pixels are skipped")
    parser.add_argument("--set", nargs="*", default=[], help="name=value Params fields")
    args = parser.parse_args(argv)
    if EVAL_SEED in args.seeds:
        raise SystemExit(f"seed {EVAL_SEED} is the evaluation seed; measure on other seeds")
    params = iv.Params().replace(**parse_grid(args.set)[0])

    for seed in args.seeds:
        for kind in args.kinds:
            seq = synthetic.render_sequence(kind, n_frames=args.frames, size=tuple(args.size), seed=seed)
            ids = seq.object_id
            estimated = iv.decompose(seq.frames, params=params)
            true = iv.decompose(seq.frames, flow=seq.flow, params=params)
            est_flow = np.asarray(estimated.flow, dtype=np.float32)

            print(f"\n{kind}/{seed}: LMSE mean, estimated flow {mean_lmse(estimated, seq):.4f}, "
                  f"ground-truth flow {mean_lmse(true, seq):.4f}")
            print(f"{'object':>6} {'share':>6} {'|u| px':>7} {'EPE px':>7} {'A est':>7} {'A true':>7} "
                  f"{'A swap':>7} {'mean swap':>9}")
            for k in np.unique(ids):
                share = float((ids == k).mean())
                if share < args.min_share:
                    continue
                on = ids[:-1] == k
                length = float(np.linalg.norm(seq.flow[on], axis=-1).mean()) if on.any() else 0.0
                epe = float(np.linalg.norm(est_flow[on] - seq.flow[on], axis=-1).mean()) if on.any() else 0.0
                swap = iv.decompose(seq.frames, flow=swapped_flow(seq.flow, est_flow, ids, k), params=params)
                cells = [object_lmse(v.albedo, seq.albedo, ids, k) for v in (estimated, true, swap)]
                print(f"{k:6d} {share:6.3f} {length:7.2f} {epe:7.2f} "
                      + " ".join(f"{c:7.4f}" for c in cells) + f" {mean_lmse(swap, seq):9.4f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
