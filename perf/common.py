"""What the perf scripts share: the evaluation seed, command-line parsing of
``Params`` settings, and the one runner of every method on a sequence.

The scripts import it as ``from common import ...`` (they run as
``python perf/NAME.py``, so ``perf/`` is on the path) and never import each
other.

Methods (:data:`METHODS`), each returning ``(albedo, shading)``:

    IV            intrinsic video with estimated flow (the default flow method)
    IV-noflow     the ablation without temporal terms and motion weights
    IV-gtflow     intrinsic video with ground-truth flow (synthetic only)
    LRET          per-frame luminance Retinex, threshold chosen on training data
                  (``baselines.LUMINANCE_TUNED_THRESHOLD``, perf/tune_baselines.py)
    CRET          per-frame colour Retinex, Grosse et al.'s thresholds
    CRET-tuned    per-frame colour Retinex, thresholds chosen on training data
                  (``baselines.TUNED_THRESHOLDS``, perf/tune_baselines.py)
    Weiss         Weiss's temporal median of log-derivatives (static scenes;
                  on moving kinds it shows what ignoring the motion costs)
    Weiss-gtflow  Weiss along the ground-truth flow and visibility (synthetic only)
    Weiss-flow    Weiss along a cheap estimated flow (OpenCV DIS on the input,
                  ``args.weiss_flow_method``), no visibility (synthetic only)
    input         the input video taken as albedo
    GT            the ground truth
"""
from __future__ import annotations

import ast
import dataclasses
import importlib.util
import itertools
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import ivkernels as iv
from ivkernels.evaluation import metrics, synthetic
from ivkernels.evaluation.baselines import color_retinex, luminance_retinex, weiss, weiss_flow
from ivkernels.flow import ClassicNLSettings
from ivkernels.flowio import read_flo
from ivkernels.io import read_image
from ivkernels.kernels import launch

ROOT = Path(__file__).resolve().parents[1]


def load_revision(backend: str, family: str, rev: str, into: Path):
    """The module ``ivkernels/kernels/<backend>/<family>.py`` as of git revision ``rev``, imported
    from a copy in the folder ``into`` under a name of its own, beside this checkout's module
    (its imports resolve to this checkout's package)."""
    rel = f"ivkernels/kernels/{backend}/{family}.py"
    source = subprocess.run(["git", "show", f"{rev}:{rel}"], cwd=ROOT, check=True, capture_output=True,
                            text=True).stdout
    name = f"{backend}_{family}_at_{''.join(c if c.isalnum() else '_' for c in rev)}"
    path = Path(into) / f"{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


#: Seed 0 of every synthetic kind is for reporting only; choices are made on other seeds.
EVAL_SEED = 0
METHODS = ("IV", "IV-noflow", "IV-gtflow", "LRET", "CRET", "CRET-tuned", "Weiss", "Weiss-gtflow", "Weiss-flow",
           "input", "GT")
SYNTHETIC_ONLY = ("IV-gtflow", "Weiss-gtflow", "Weiss-flow")
IV_METHODS = ("IV", "IV-noflow", "IV-gtflow")
#: The per-frame baselines a method must beat on every kind (tuned on training data).
PER_FRAME_BASELINES = ("LRET", "CRET-tuned")


# --------------------------------------------------------------------------- #
# command-line values
# --------------------------------------------------------------------------- #
def parse_value(text: str):
    """A Params value from the command line: ``true`` / ``false``, an int, or a float."""
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    return int(text) if text.lstrip("-").isdigit() else float(text)


def parse_grid(items: list[str]) -> list[dict]:
    """``["a=1,2", "b=3", "c=false"]`` -> every combination as a dict (ints kept int, switches bool)."""
    axes = []
    for item in items:
        name, _, values = item.partition("=")
        if not values:
            raise SystemExit(f"--grid entries look like name=v1,v2; got {item!r}")
        axes.append([(name, parse_value(v)) for v in values.split(",")])
    return [dict(combo) for combo in itertools.product(*axes)] if axes else [{}]


def key_values(items, name: str) -> dict:
    """``["a=1", "b=x"]`` -> ``{"a": 1, "b": "x"}`` (Python literals where they parse)."""
    out = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"{name}: expected NAME=VALUE, got {item!r}")
        try:
            out[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            out[key] = value
    return out


def iv_params_from(parser, items):
    """``ivkernels.Params`` with the ``--iv-param NAME=VALUE`` settings, or None without any;
    a bad name or value ends in ``parser.error``."""
    changes = key_values(items, "--iv-param")
    try:
        return iv.Params().replace(**changes) if changes else None
    except (TypeError, ValueError) as exc:
        parser.error(f"--iv-param: {exc}")


# --------------------------------------------------------------------------- #
# running the methods
# --------------------------------------------------------------------------- #
def run_iv(frames, variant: str, flow_gt=None, backend: str = "warp", params=None, **options):
    """The one call of :func:`ivkernels.decompose` behind every IV row.

    ``variant``: ``"IV"`` (estimated flow), ``"IV-noflow"`` (``temporal=False``)
    or ``"IV-gtflow"`` (``flow=flow_gt``).  ``params`` (an
    :class:`ivkernels.Params`) and ``options`` (further keyword arguments of
    ``decompose``) apply to all three.  Returns ``(albedo, shading)``.
    """
    if variant == "IV":
        video = iv.decompose(frames, backend=backend, params=params, **options)
    elif variant == "IV-noflow":
        video = iv.decompose(frames, temporal=False, backend=backend, params=params, **options)
    elif variant == "IV-gtflow":
        if flow_gt is None:
            raise ValueError("IV-gtflow needs the ground-truth flow")
        video = iv.decompose(frames, flow=flow_gt, backend=backend, params=params, **options)
    else:
        raise ValueError(f"unknown IV variant {variant!r}")
    return video.albedo, video.shading


def run_method(name: str, frames, truth: dict, args):
    """``(albedo, shading)`` of one method; ``truth`` holds albedo, shading, flow, visibility
    (the flow only for the methods that read it).  ``args`` gives ``backend``,
    ``iv_params``, ``iv_options`` and ``weiss_flow_method``."""
    if name in IV_METHODS:
        return run_iv(frames, name, truth.get("flow"), backend=args.backend, params=args.iv_params,
                      **args.iv_options)
    if name == "LRET":
        return luminance_retinex(frames)
    if name == "CRET":
        return color_retinex(frames, thresholds="grosse")
    if name == "CRET-tuned":
        return color_retinex(frames, thresholds="tuned")
    if name == "Weiss":
        return weiss(frames)
    if name == "Weiss-gtflow":
        return weiss_flow(frames, truth["flow"], truth["visibility"])
    if name == "Weiss-flow":
        flow = iv.estimate_flow(np.clip(frames, 0.0, 1.0), method=args.weiss_flow_method, backend=args.backend)
        return weiss_flow(frames, flow)
    if name == "input":
        return frames, np.ones(frames.shape[:3], np.float32)
    if name == "GT":
        return truth["albedo"], truth["shading"]
    raise ValueError(f"unknown method {name!r}")


def measure(frames, truth: dict, methods, args, mask=None) -> dict:
    """``{method: row}``: LMSE (albedo, shading, mean), albedo EPE (all / visible),
    flicker and seconds of every method on one sequence."""
    rows = {}
    for name in methods:
        t0 = time.perf_counter()
        albedo, shading = run_method(name, frames, truth, args)
        seconds = time.perf_counter() - t0
        albedo = np.broadcast_to(albedo, frames.shape)
        lmse = metrics.intrinsic_lmse(albedo, shading, truth["albedo"], truth["shading"], mask=mask)
        tin = metrics.temporal_incoherence(albedo, truth["flow"], truth["visibility"])
        flow = truth["flow"] if np.any(truth["flow"]) else None
        vis = truth["visibility"] if flow is not None else None
        flicker = metrics.albedo_flicker(albedo, flow, vis, mask=mask)
        rows[name] = dict(lmse, epe=tin["epe"], epe_visible=tin["epe_visible"], flicker=flicker, seconds=seconds)
    return rows


def evaluate_kind(kind: str, n_frames: int, size, seed: int, methods, args) -> dict:
    """:func:`measure` on ``synthetic.render_kind(kind, n_frames, size, seed)``
    (``kind``: a name of ``synthetic.SCENE_KINDS``, the four classic kinds included)."""
    seq = synthetic.render_kind(kind, n_frames=n_frames, size=tuple(size), seed=seed)
    truth = dict(albedo=seq.albedo, shading=seq.shading, flow=seq.flow, visibility=seq.visibility)
    return measure(seq.frames, truth, methods, args)


def mean_rows(per_item: dict) -> dict:
    """Mean of every column over the items, for the methods every item has."""
    items = list(per_item.values())
    names = [m for m in items[0] if all(m in rows for rows in items)]
    return {m: {k: float(np.mean([rows[m][k] for rows in items])) for k in items[0][m]} for m in names}


def parse_settings(items) -> dict:
    """``["lam=3", "data_term=gradient"]`` -> typed fields of :class:`ClassicNLSettings`."""
    types = {f.name: f.type for f in dataclasses.fields(ClassicNLSettings)}
    out = {}
    for item in items:
        key, _, value = item.partition("=")
        if key not in types:
            raise SystemExit(f"unknown Classic+NL setting {key!r}")
        typ = types[key]
        out[key] = (int(value) if typ == "int" else float(value) if typ == "float"
                    else value.lower() in ("1", "true", "yes") if typ == "bool" else value)
    return out


# ---------------------------------------------------------------- Middlebury pairs (eval_flow, bench_balance)

SEQUENCES = ("Dimetrodon", "Grove2", "Grove3", "Hydrangea", "RubberWhale", "Urban2", "Urban3", "Venus")


def default_data_dir() -> Path:
    here = Path(__file__).resolve()
    for base in (here.parents[1], *here.parents[2:4]):
        for cand in (base / "shared" / "data" / "middlebury", base / "data" / "middlebury"):
            if cand.is_dir():
                return cand
    return Path("/work/shared/data/middlebury")


def middlebury_pairs(root: Path, names):
    for name in names:
        d = root / name
        frames = np.stack([read_image(d / "frame10.png"), read_image(d / "frame11.png")])
        yield name, frames, read_flo(d / "flow10.flo")[None]


# ---------------------------------------------------------------- timing launch configurations (bench_launch, bench_balance)

def largest_input_elements(values: dict) -> int:
    """Elements of the largest array among a case's values."""
    return max((v.size for v in values.values() if isinstance(v, np.ndarray)), default=0)


def time_configs(call, be, configs: dict, repeat: int, budget_s: float,
                 setting: str = "MIN_BAND_ELEMENTS") -> dict:
    """Median seconds of ``call`` under each ``{name: (threads, value)}`` configuration,
    ``value`` given to the launch setting ``setting`` (an attribute of
    :mod:`ivkernels.kernels.launch`, restored afterwards), in rotating order."""
    default = getattr(launch, setting)
    times = {name: [] for name in configs}
    names = list(configs)
    t_start = time.perf_counter()
    try:
        for r in range(-1, repeat):                      # round -1 warms every configuration
            for name in names[r % len(names):] + names[:r % len(names)]:
                n, value = configs[name]
                setattr(launch, setting, value)
                with launch.threads(n):
                    t0 = time.perf_counter()
                    call()
                    be.synchronize()
                    if r >= 0:
                        times[name].append(time.perf_counter() - t0)
            if r >= 4 and time.perf_counter() - t_start > budget_s:
                break
    finally:
        setattr(launch, setting, default)
    return {name: statistics.median(v) for name, v in times.items()}
