"""Choose Params settings by how they generalise: leave one kind out, judge by the worst.

For every setting of a grid (``--grid NAME=v1,v2 ...``, fields of
:class:`ivkernels.Params`) the script decomposes training sequences only:
every synthetic kind of ``synthetic.SCENE_KINDS`` at the training seeds
(never seed 0), and, with ``--mit``, the MIT-Berkeley training objects in
colour and as greyscale footage (luminance in, luminance reflectance as
truth).  Each item is scored against the strongest baseline *for that item*,
tuned on training data as IV is: luminance and colour Retinex with their tuned
thresholds, and Weiss's median where the scene is static (the static-scene
kinds and the MIT objects).  The score of a setting on a kind is
``IV LMSE / best baseline LMSE`` (mean over seeds; the MIT groups: albedo
LMSE in the mask, mean over objects), so 1 means "no better than the best
per-frame or Weiss baseline".

Then, for each kind in turn (the MIT colour and grey sets count as two kinds),
the kind is held out and the setting chosen on the others (the smallest worst
ratio, ties broken by the mean); the held-out kind's ratio at that choice is
what the choice generalises to.  The table ends with the worst held-out ratio
and the per-seed spread of every kind at the setting chosen on all kinds.

IV runs with estimated flow (the default path) unless ``--gt-flow`` (synthetic)
or ``--mit-flow zero`` (MIT: the objects are still, their exact flow is zero).  Rows are
saved to ``--save`` after every item and read back with ``--load`` (several
files; rows of the same setting and item are taken from the last file), so
a grid can be split over processes and resumed.

    python perf/hold_out.py --seeds 1 2 --grid shading_step_share_radius=0,0.1 --mit --save ho.json
    python perf/hold_out.py --load ho.json ho2.json
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import ivkernels as iv
from common import EVAL_SEED, parse_grid, run_method
from ivkernels.evaluation import datasets, metrics, synthetic

BASELINES = ("LRET", "CRET-tuned", "Weiss")
MIT_KINDS = ("MIT colour", "MIT grey")


def synthetic_item(kind: str, seed: int, args):
    seq = synthetic.render_kind(kind, n_frames=args.frames, size=tuple(args.size), seed=seed)
    return dict(frames=seq.frames, albedo=seq.albedo, shading=seq.shading, flow=seq.flow, mask=None,
                static=synthetic.SCENE_KINDS[kind].static_scene, score="mean")


def mit_item(name: str, achromatic: bool, args):
    obj = datasets.load_mit_object(name, scale=args.mit_scale, achromatic=achromatic)
    t, h, w, _ = obj.frames.shape
    return dict(frames=obj.frames, albedo=np.broadcast_to(obj.albedo, obj.frames.shape),
                shading=obj.frame_shading, flow=np.zeros((t - 1, h, w, 2), np.float32), mask=obj.mask,
                static=True, score="albedo")


def lmse(item: dict, albedo, shading) -> float:
    albedo = np.broadcast_to(albedo, item["frames"].shape)
    return float(metrics.intrinsic_lmse(albedo, shading, item["albedo"], item["shading"],
                                        mask=item["mask"])[item["score"]])


def items(args):
    """``(kind, key, loader)`` of every training item: synthetic kinds at the seeds, MIT groups."""
    for kind in args.kinds:
        for seed in args.seeds:
            yield kind, f"{kind}/{seed}", (lambda k=kind, s=seed: synthetic_item(k, s, args))
    if args.mit:
        for achromatic, group in zip((False, True), MIT_KINDS):
            if ("grey" if achromatic else "colour") not in args.mit_modes:
                continue
            for name in args.mit_objects or datasets.available_mit_objects():
                yield group, f"{group}/{name}", (lambda n=name, a=achromatic: mit_item(n, a, args))


def run(args, rows: dict) -> None:
    """Fill ``rows[label][key]`` (IV) and ``rows['baselines'][key]`` for every item and setting."""
    settings = {(", ".join(f"{k}={v}" for k, v in cfg.items()) or "defaults"): cfg
                for cfg in parse_grid(args.grid)}
    base = parse_grid(args.base)[0]
    for kind, key, load in items(args):
        item = None
        todo = [label for label in settings if key not in rows.get(label, {})]
        if key not in rows.get("baselines", {}) or todo:
            item = load()
        if key not in rows.setdefault("baselines", {}):
            names = BASELINES if item["static"] else BASELINES[:2]
            # the baselines read only the frames (common.run_method)
            rows["baselines"][key] = {n: lmse(item, *run_method(n, item["frames"], {}, None)) for n in names}
            save(args, rows)
        for label in todo:
            params = iv.Params().replace(**base, **settings[label])
            t0 = time.perf_counter()
            exact = args.gt_flow if item["mask"] is None else args.mit_flow == "zero"
            video = iv.decompose(item["frames"], flow=item["flow"] if exact else None, params=params)
            rows.setdefault(label, {})[key] = lmse(item, video.albedo, video.shading)
            save(args, rows)
            print(f"  {key:40s} {label:50s} {rows[label][key]:.4f} "
                  f"(best baseline {min(rows['baselines'][key].values()):.4f}, "
                  f"{time.perf_counter() - t0:.0f} s)", flush=True)


def save(args, rows: dict) -> None:
    if args.save:
        Path(args.save).write_text(json.dumps(rows, indent=1, sort_keys=True))


def kind_of(key: str) -> str:
    return key.rsplit("/", 1)[0]


def ratios(rows: dict, label: str) -> dict:
    """``{kind: (ratio of means, [per-seed or per-object ratios])}`` of one setting."""
    by_kind: dict = {}
    for key, value in rows[label].items():
        best = min(rows["baselines"][key].values())
        by_kind.setdefault(kind_of(key), []).append((value, best))
    return {k: (np.mean([v for v, _ in p]) / np.mean([b for _, b in p]), [v / b for v, b in p])
            for k, p in by_kind.items()}


def choose(table: dict, kinds) -> str:
    """The setting with the smallest worst ratio over ``kinds`` (ties: the smallest mean)."""
    return min(table, key=lambda s: (round(max(table[s][k][0] for k in kinds), 3),
                                     np.mean([table[s][k][0] for k in kinds])))


def report(rows: dict) -> None:
    labels = [label for label in rows if label != "baselines"]
    if not labels:
        return
    # every kind any setting was run on; a setting missing some of them is left out
    kinds = sorted(set.union(*(set(kind_of(k) for k in rows[label]) for label in labels)))
    missing = [label for label in labels if {kind_of(k) for k in rows[label]} != set(kinds)]
    for label in missing:
        print(f"left out (not run on every kind): {label}")
    labels = [label for label in labels if label not in missing]
    if not labels:
        return
    table = {label: ratios({"baselines": rows["baselines"],
                            label: {k: v for k, v in rows[label].items() if kind_of(k) in kinds}}, label)
             for label in labels}
    print("\nIV LMSE / best baseline (LRET, CRET-tuned; Weiss on static scenes), mean over seeds or objects")
    width = max(len(label) for label in labels)
    print(f"{'kind':32s} " + " ".join(f"{i:>7d}" for i in range(len(labels))))
    for k in kinds:
        print(f"{k:32s} " + " ".join(f"{table[label][k][0]:7.3f}" for label in labels))
    print(f"{'worst':32s} " + " ".join(f"{max(table[lb][k][0] for k in kinds):7.3f}" for lb in labels))
    print(f"{'mean':32s} " + " ".join(f"{np.mean([table[lb][k][0] for k in kinds]):7.3f}" for lb in labels))
    for i, label in enumerate(labels):
        print(f"  {i}: {label:{width}s}")

    if len(kinds) < 2:
        print("\nOne kind only: nothing to hold out.")
        return
    print("\nLeave one kind out: the setting chosen on the other kinds, and the held-out kind's ratio")
    held = {}
    for k in kinds:
        others = [o for o in kinds if o != k]
        chosen = choose(table, others)
        held[k] = table[chosen][k][0]
        print(f"  {k:32s} chosen {labels.index(chosen):3d}   held-out ratio {held[k]:6.3f}")
    worst = max(held, key=held.get)
    print(f"  worst held-out kind: {worst} at {held[worst]:.3f}; mean held-out ratio {np.mean(list(held.values())):.3f}")

    best = choose(table, kinds)
    print(f"\nChosen on all kinds: {labels.index(best)} ({best}); per-seed / per-object ratios:")
    for k in kinds:
        ratio, spread = table[best][k]
        print(f"  {k:32s} {ratio:6.3f}   [{min(spread):.3f} .. {max(spread):.3f}] over {len(spread)}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    parser.add_argument("--kinds", nargs="*", default=None, choices=list(synthetic.SCENE_KINDS), metavar="KIND",
                        help="names of synthetic.SCENE_KINDS (default: every one); none for MIT only")
    parser.add_argument("--grid", nargs="*", default=[], help="name=v1,v2 ... (Params fields)")
    parser.add_argument("--base", nargs="*", default=[], help="name=v fields fixed for every setting")
    parser.add_argument("--gt-flow", action="store_true", help="IV with the ground-truth flow")
    parser.add_argument("--mit", action="store_true", help="also the MIT objects, colour and grey")
    parser.add_argument("--mit-modes", nargs="+", default=["colour", "grey"], choices=["colour", "grey"])
    parser.add_argument("--mit-scale", type=float, default=0.5)
    parser.add_argument("--mit-flow", default="estimated", choices=["estimated", "zero"],
                        help="the MIT objects with the estimated flow (the default path) or their exact zero flow")
    parser.add_argument("--mit-objects", nargs="+", default=None, metavar="NAME")
    parser.add_argument("--save", help="JSON file the rows are written to after every item")
    parser.add_argument("--load", nargs="*", default=[], help="JSON files of earlier runs (merged)")
    args = parser.parse_args(argv)
    if EVAL_SEED in args.seeds:
        raise SystemExit(f"seed {EVAL_SEED} is the evaluation seed; choose settings on other seeds")
    args.kinds = list(synthetic.SCENE_KINDS) if args.kinds is None else args.kinds
    rows: dict = {}
    for path in args.load:
        for label, values in json.loads(Path(path).read_text()).items():
            rows.setdefault(label, {}).update(values)
    if args.grid or not args.load:
        run(args, rows)
    report(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
