"""The step evidence of Eq. 9's local term per full-size pyramid level: host NumPy against the kernels.

Times, side by side in one run, the two ways the energy has built its local
shading gate's step weight (``WindowEnergy._local_shading_gate`` with the
default ``Params``: the cut at flow jumps times ``1 + gain' w evidence``):

* ``host``: the host NumPy code of ``--before`` (default ``eff9bf1``, read with
  ``git show``): ``grey_step_gate`` on ``be.numpy(I)``, Weiss's stability
  cue on the host, and the product with the cut gate on the host;
* ``kernels``: this checkout's :func:`ivkernels.solver.step_evidence.multiply_step_gate`,
  the kernels of the ``step_evidence`` family on the backend's arrays, with
  the whole video's chromatic share as the host way (``share_radius = 0``).

Both start from the same cut gate (built once, outside the timing), are run
in turn ``--repeat`` times, and the median seconds of each are printed with
their ratio and the largest difference between the two gates.

With ``--steps`` it then times each kernel of the ``kernels`` way alone,
``maps.shading_gate`` (Weiss's cue as the host way computes it), and the
share read around each pixel (host NumPy, and the kernels ``pixel_counts``
and ``share_weight`` that compute it now), min of ``--repeat``.

With ``--local-share`` it times instead :func:`multiply_step_gate` with the
default ``Params`` (the share read around each pixel, ``share_radius`` 0.3)
as of ``--share-before`` (default ``8800238``: that share on host NumPy,
read back from the backend) and as of this checkout (the kernels), side by
side in the same way, and prints the largest difference of the two gates.

    python perf/bench_step_evidence.py                          # 8 frames at 640x480, Warp, 2 threads
    python perf/bench_step_evidence.py --backend taichi --size 240 320
    python perf/bench_step_evidence.py --local-share            # the default share_radius, before / now
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import time
import types
from pathlib import Path

import numpy as np

import ivkernels as iv
from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.solver.motion_maps import shading_cut_gate
from ivkernels.solver.step_evidence import (DARK_OFFSET, SHARE_PRIOR_STEPS, STATIC_FLOW, local_chromatic_share,
                                            multiply_step_gate, share_radius_pixels)

ROOT = Path(__file__).resolve().parents[1]


def old_module(rev: str) -> types.ModuleType:
    """``ivkernels/solver/step_evidence.py`` of ``rev`` as a module."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:ivkernels/solver/step_evidence.py"],
                            capture_output=True, text=True, check=True).stdout
    module = types.ModuleType(f"step_evidence_{rev}")
    exec(compile(source, f"{rev}:ivkernels/solver/step_evidence.py", "exec"), module.__dict__)
    return module


def host_gate(old, be, I, flow, cut, p):
    """The step weight as ``WindowEnergy`` computed it on the host before the kernels."""
    T, h, w, _ = I.shape
    tau_chroma = p.shading_step_chroma if p.shading_step_chroma > 0 else np.inf
    steps = old.grey_step_gate(be.numpy(I), p.shading_step_gain, p.shading_step_tau, tau_chroma)
    stable = be.empty((T, h, w))
    be.maps.shading_gate(I, flow, stable, p.shading_step_stability)
    speed = np.sqrt((be.numpy(flow) ** 2).sum(axis=-1))
    moving = np.zeros((T, h, w), bool)
    moving[:-1] |= speed >= STATIC_FLOW
    moving[1:] |= speed >= STATIC_FLOW
    steps = 1.0 + (steps - 1.0) * np.where(moving, 1.0, be.numpy(stable)).astype(np.float32)
    return be.asarray(be.numpy(cut) * steps)


def kernel_gate(be, I, flow, cut, p):
    gate = be.empty(cut.shape)
    be.vecops.copy(cut.reshape((cut.size,)), gate.reshape((gate.size,)))
    multiply_step_gate(be, I, gate, p.shading_step_gain, p.shading_step_tau, p.shading_step_chroma,
                       flow=flow, stability=p.shading_step_stability, share_radius=0.0)     # as the host way
    return gate


def share_gate(multiply, be, I, flow, cut, p):
    """``cut`` times the step weight by ``multiply`` (a ``multiply_step_gate``) with the default ``Params``."""
    gate = be.empty(cut.shape)
    be.vecops.copy(cut.reshape((cut.size,)), gate.reshape((gate.size,)))
    multiply(be, I, gate, p.shading_step_gain, p.shading_step_tau, p.shading_step_chroma, flow=flow,
             stability=p.shading_step_stability, share_radius=p.shading_step_share_radius)
    return gate


def side_by_side(be, ways: dict, repeat: int) -> tuple[dict, dict]:
    """Run each way once (compile, load, touch), then ``repeat`` times in alternating order:
    ``(gates, median seconds)`` by name."""
    gates = {name: be.numpy(way()).copy() for name, way in ways.items()}
    seconds = {name: [] for name in ways}
    for r in range(repeat):
        for name in (list(ways) if r % 2 == 0 else list(ways)[::-1]):
            t0 = time.perf_counter()
            ways[name]()
            be.synchronize()
            seconds[name].append(time.perf_counter() - t0)
    return gates, {name: statistics.median(s) for name, s in seconds.items()}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--backend", default="warp")
    ap.add_argument("--before", default="eff9bf1", help="commit whose host NumPy code is timed")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--steps", action="store_true", help="time each kernel of the kernels' way too")
    ap.add_argument("--local-share", action="store_true",
                    help="time multiply_step_gate with the default share_radius, --share-before against now")
    ap.add_argument("--share-before", default="8800238",
                    help="commit whose multiply_step_gate reads the local share on the host")
    args = ap.parse_args(argv)
    p = iv.Params()
    be = get_backend(args.backend)
    be.use_threads(args.threads)
    seq = iv.synthetic.render_sequence("objects_camera", n_frames=args.frames, size=tuple(args.size), seed=1)
    I = be.asarray(np.log(np.maximum(seq.frames, 1e-4)).astype(np.float32))
    flow = be.asarray(seq.flow.astype(np.float32))
    if args.local_share:
        old = old_module(args.share_before)
        with threads(args.threads):
            cut = shading_cut_gate(be, flow, p.shading_cut_threshold, args.frames)
            gates, seconds = side_by_side(be, {
                "before": lambda: share_gate(old.multiply_step_gate, be, I, flow, cut, p),
                "now": lambda: share_gate(multiply_step_gate, be, I, flow, cut, p)}, args.repeat)
        diff = np.abs(gates["before"].astype(np.float64) - gates["now"])
        print(f"{args.frames}x{args.size[0]}x{args.size[1]}, {args.backend} on {args.threads} threads, "
              f"multiply_step_gate with share_radius {p.shading_step_share_radius:g}, median of {args.repeat}: "
              f"before ({args.share_before}, host share) {seconds['before']:.3f} s, now (kernels) "
              f"{seconds['now']:.3f} s, ratio {seconds['now'] / seconds['before']:.3f}; "
              f"largest difference {diff.max():.2e}, bitwise equal {np.array_equal(gates['before'], gates['now'])}",
              flush=True)
        return
    old = old_module(args.before)
    with threads(args.threads):
        cut = shading_cut_gate(be, flow, p.shading_cut_threshold, args.frames)
        ways = {"host": lambda: host_gate(old, be, I, flow, cut, p), "kernels": lambda: kernel_gate(be, I, flow, cut, p)}
        gates, seconds = side_by_side(be, ways, args.repeat)
    host, kern = seconds["host"], seconds["kernels"]
    diff = np.abs(gates["host"].astype(np.float64) - gates["kernels"])
    print(f"{args.frames}x{args.size[0]}x{args.size[1]}, {args.backend} on {args.threads} threads, "
          f"median of {args.repeat}: host ({args.before}) {host:.3f} s, kernels {kern:.3f} s, "
          f"ratio {kern / host:.3f}; gate {gates['host'].min():.3f}..{gates['host'].max():.3f}, "
          f"largest difference {diff.max():.2e}", flush=True)
    if args.steps:
        with threads(args.threads):
            print_steps(be, I, flow, p, args.repeat)


def print_steps(be, I, flow, p, repeat: int) -> None:
    """Seconds of each kernel of :func:`multiply_step_gate` (and of ``maps.shading_gate``), min of ``repeat``."""
    T, h, w, _ = I.shape
    k = be.step_evidence
    offset, counts = be.empty((T, h, w, 3)), be.empty((T * h, 2), np.int32)
    weight, gate = be.empty((T, h, w)), be.zeros((T, h, w))
    pixel = be.empty((T, h, w, 2), np.int32)
    steps = {
        "offset_log": lambda: k.offset_log(I, offset, DARK_OFFSET),
        "step_counts": lambda: k.step_counts(offset, counts, p.shading_step_tau, p.shading_step_chroma),
        "still_stability": lambda: k.still_stability(I, flow, weight, p.shading_step_stability, STATIC_FLOW),
        "step_gate": lambda: k.step_gate(offset, counts, weight, gate, p.shading_step_gain, p.shading_step_tau,
                                         p.shading_step_chroma),
        "maps.shading_gate": lambda: be.maps.shading_gate(I, flow, weight, p.shading_step_stability),
        "local share (host NumPy, share_radius 0.3)": lambda: local_chromatic_share(
            be.numpy(I), p.shading_step_tau, p.shading_step_chroma, 0.3),
        "pixel_counts": lambda: k.pixel_counts(I, pixel, DARK_OFFSET, p.shading_step_tau, p.shading_step_chroma),
        "share_weight (share_radius 0.3)": lambda: k.share_weight(pixel, weight, share_radius_pixels(0.3, h, w),
                                                                  SHARE_PRIOR_STEPS),
    }
    for name, step in steps.items():
        step()
        be.synchronize()
        seconds = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            step()
            be.synchronize()
            seconds.append(time.perf_counter() - t0)
        print(f"  {name}: {min(seconds):.3f} s", flush=True)


if __name__ == "__main__":
    main()
