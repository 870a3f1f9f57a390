#!/usr/bin/env python
"""Time every kernel on Warp (1 and 2 CPU threads), Taichi and the NumPy reference, in one run.

For each host function of every kernel family (``ivkernels.kernels.<backend>.<family>``)
this prints, from measurements taken in this one process:

* the median wall time of Warp on 1 thread, Warp on 2 threads (row bands,
  :mod:`ivkernels.kernels.launch`), Taichi (2 threads) and the NumPy
  reference, and the ratios between them;
* the first call of each host function on Warp and on Taichi (compile + load
  + one run, see "First call" below);
* the minimal bytes the kernel must move (every input read once, every output
  written once, every accumulated (``+=``) buffer read and written; scratch
  buffers and small tables not counted), the bandwidth achieved by Warp on 2
  threads, and its fraction of a memory-bandwidth roof measured at start;
* for the arithmetic-bound kernels, the cost per unit of work (pixel,
  pixel-neighbour) in ns and in core cycles, with an operation count.

Inputs imitate a real video (:func:`make_scene`): 8 frames of 640x480 linear
RGB, a piecewise-textured background panning by under a pixel per frame and
four elliptic objects moving by 2-4 pixels per frame, log albedo / log
shading / log input, the forward flow with a little noise, the occlusion map
of Eq. 6-7 and the motion-boundary map ``w_bnd`` (Sobel > 0.25, dilated by 3),
which covers ~5% of the pixels and is the mask of both weighted medians.
Frame-wise kernels get all T frames, flow-wise kernels the T-1 pairs, and the
``flow_classic`` kernels a single pair (T = 2 images, 1 flow).

Timing: after the first calls, ``--repeat`` rounds call Warp-1, Warp-2 and
Taichi in rotating order (so a load change on a shared machine hits all three
alike; a kernel stops after 3 rounds once it has used ``--case-budget``
seconds), and the median of each is reported.  Because wall time stretches
when other processes hold the cores, the CPU time of every Warp call is
recorded too: the 1-thread CPU time over the CPU time of the busier of the two
bands predicts the 2-thread speedup of an idle machine, and a pure-arithmetic
probe measures, at the start and the end, how much of a second core the
machine actually gave.

The NumPy reference is timed on crops (2 frames at 1/4 and 1/2 the size, then
the full input) for as long as the next crop is predicted to take under
``--ref-budget`` seconds; a time measured on a crop is scaled to the full
input by the ratio of work (pixels, or masked pixels for the weighted
medians) and printed with a ``~`` and the crop it was measured on.

First call: by default Warp and Taichi compile into fresh private cache
directories (``wp.config.kernel_cache_dir`` and ``TI_OFFLINE_CACHE_FILE_PATH``
point to a temporary directory; no global cache is touched), so the first
call of a host function includes compiling its kernels: for Warp the whole
module (one compile unit per family) is compiled by the first host function
of the family to run, for Taichi each kernel compiles on its own first call.
``--warm-cache`` uses the normal caches instead, and the first call then
measures loading the cached code.

    python perf/bench_kernels.py                          # 640x480, 8 frames, every family
    python perf/bench_kernels.py --only median energy_albedo_gsm --repeat 9
    python perf/bench_kernels.py --size 240 320 --frames 4 --json out.json
    python perf/bench_kernels.py --quick                  # 120x160, 3 frames: smoke run
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import platform
import statistics
import sys
import tempfile
import time
from typing import Callable

import numpy as np
import warp as wp

FAMILIES = (
    "colour", "sampling", "derivatives", "maps", "pyramid", "vecops", "median",
    "energy_data", "energy_temporal", "energy_shading", "energy_albedo_gsm",
    "energy_albedo_entropy", "flow_classic",
)
CONFIGS = ("warp1", "warp2", "taichi")
F32 = np.float32

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Memory-bandwidth roof: streaming kernels launched like the project's kernels
# ----------------------------------------------------------------------------

@wp.kernel
def stream_copy_chunks(row_begin: int, src: wp.array(dtype=float), dst: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        dst[i] = src[i]


@wp.kernel
def stream_copy_vec4_chunks(row_begin: int, src: wp.array(dtype=wp.vec4), dst: wp.array(dtype=wp.vec4),
                            chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        dst[i] = src[i]


@wp.kernel
def stream_triad_chunks(row_begin: int, a: wp.array(dtype=float), b: wp.array(dtype=float),
                        c: wp.array(dtype=float), s: float, chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, a.shape[0])
    for i in range(begin, end):
        a[i] = b[i] + s * c[i]


@wp.kernel
def spin_rows(row_begin: int, out: wp.array(dtype=float), iterations: int):
    r = row_begin + wp.tid()
    a = float(r) * 0.001
    for i in range(iterations):
        a = a * 0.999 + 0.001
    out[r] = a


def two_thread_capacity(rounds: int = 5) -> float:
    """Speedup of 2 threads over 1 on pure arithmetic (no memory traffic), rows launched like the kernels.

    Close to 2 on an idle 2-core machine; lower when other processes hold the cores.
    It bounds the 1-to-2-thread ratio any kernel can show in the same run.
    """
    from ivkernels.kernels.launch import launch_rows, threads

    out = wp.empty(256, dtype=wp.float32, device="cpu")
    fn = lambda: launch_rows(spin_rows, 256, [out, 40000])  # noqa: E731
    times = {1: [], 2: []}
    for nt in (1, 2):
        with threads(nt):
            fn()
    for r in range(rounds):
        for nt in ((1, 2) if r % 2 == 0 else (2, 1)):
            with threads(nt):
                times[nt].append(_timed(fn))
    return statistics.median(times[1]) / statistics.median(times[2])


def measure_roof(n: int, repeat: int) -> dict:
    """Best bandwidth (GB/s of bytes read + written, no write-allocate) of streaming copies.

    ``warp copy`` / ``warp triad`` (``a = b + s c``) are Warp kernels over
    float32 launched through :func:`launch_rows` on 1 and 2 threads, ``warp
    copy vec4`` the same copy over ``wp.vec4`` views (16 bytes per element),
    ``numpy copy`` is ``np.copyto`` (one thread).  Arrays of ``n`` float32, far
    larger than the last-level cache.  Each is timed by wall clock and by CPU
    time (for 2 threads: the busier band), best of ``repeat``; the roof is the
    best figure of all, i.e. what the memory system was seen to deliver.
    Returns ``{name: (wall GB/s, CPU GB/s)}`` plus ``"roof"``.
    """
    from ivkernels.kernels.launch import launch_rows, threads

    chunk = 1 << 16
    a, b, c = (np.full(n, 1.0, F32) for _ in range(3))
    wa, wb, wc = (wp.array(v, dtype=wp.float32, copy=False, device="cpu") for v in (a, b, c))
    va, vb = (wp.array(v.reshape(-1, 4), dtype=wp.vec4, copy=False, device="cpu") for v in (a, b))
    rows = (n + chunk - 1) // chunk
    tests = {
        "warp copy": (lambda: launch_rows(stream_copy_chunks, rows, [wb, wa, chunk]), 8, (1, 2)),
        "warp triad": (lambda: launch_rows(stream_triad_chunks, rows, [wa, wb, wc, 0.5, chunk]), 12, (1, 2)),
        "warp copy vec4": (lambda: launch_rows(stream_copy_vec4_chunks, rows, [vb, va, chunk // 4]), 8, (1, 2)),
        "numpy copy": (lambda: np.copyto(a, b), 8, (1,)),
    }
    out = {}
    for name, (fn, bytes_per, counts) in tests.items():
        for nt in counts:
            with threads(nt):
                fn()
                walls, cpus = [], []
                for _ in range(repeat):
                    c0, m0, t0 = time.process_time(), time.thread_time(), time.perf_counter()
                    fn()
                    walls.append(time.perf_counter() - t0)
                    main, total = time.thread_time() - m0, time.process_time() - c0
                    cpus.append(total if nt == 1 else max(main, total - main))
            out[f"{name} {nt}T"] = (bytes_per * n / min(walls) / 1e9, bytes_per * n / max(min(cpus), 1e-9) / 1e9)
    out["roof"] = max(max(v) for v in out.values())
    return out


def _cpu_timed(fn) -> float:
    c0 = time.process_time()
    fn()
    return time.process_time() - c0


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


# ----------------------------------------------------------------------------
# Inputs: a small synthetic video
# ----------------------------------------------------------------------------

@dataclasses.dataclass
class Scene:
    """Inputs shared by the cases; float32, C-contiguous, layouts of :mod:`ivkernels.kernels`."""

    T: int
    H: int
    W: int
    rgb: np.ndarray       # (T, H, W, 3) linear RGB in (0, 1]
    srgb: np.ndarray      # (T, H, W, 3) sRGB-encoded
    lab: np.ndarray       # (T, H, W, 3) CIE Lab
    A: np.ndarray         # (T, H, W, 3) log albedo
    S: np.ndarray         # (T, H, W) log shading
    I: np.ndarray         # (T, H, W, 3) log input = A + S
    w_lum: np.ndarray     # (T, H, W) luminance + 0.001
    grey: np.ndarray      # (T, H, W, 1) grey image in [-1, 1] (the flow's texture input)
    flow: np.ndarray      # (T-1, H, W, 2) forward flow, pixels
    div_neg: np.ndarray   # (T-1, H, W)
    sobel: np.ndarray     # (T-1, H, W) flow Sobel magnitude
    occ: np.ndarray       # (T-1, H, W) w_occ, 0 / 1
    w_bnd: np.ndarray     # (T-1, H, W) motion boundaries, 0 / 1

    @property
    def P(self) -> int:
        return self.T - 1


_OBJECTS = (  # centre (fraction of W, H), radii (px at 640 wide), velocity (px/frame)
    ((0.27, 0.30), (92, 70), (3.0, 1.5)),
    ((0.72, 0.28), (82, 62), (-2.5, 2.0)),
    ((0.30, 0.72), (100, 66), (3.5, -1.0)),
    ((0.73, 0.70), (86, 74), (-3.0, -2.0)),
)
_scene_cache: dict = {}


def make_scene(T: int, H: int, W: int, seed: int = 0) -> Scene:
    """A textured background panning slowly and four elliptic objects moving by 2-4 px/frame.

    Sizes scale with the width (so a smaller input is a crop-like copy of the
    same content); velocities are in pixels at every size.

    Albedo: Mondrian-like patches (40 px at 640 wide) of random colours times a
    fine sinusoidal texture, plus log-normal noise (sigma 0.02), carried by
    each layer's motion; shading: a smooth grey field drifting over time plus
    noise (sigma 0.01).  Flow: the motion of the top layer at each pixel plus
    a slight zoom of the background and Gaussian noise (sigma 0.03 px).
    Derived maps (Lab, divergence, occlusion, Sobel magnitude, ``w_bnd``)
    come from the NumPy references (so no kernel is compiled before it is
    timed).
    """
    key = (T, H, W, seed)
    if key in _scene_cache:
        return _scene_cache[key]
    from ivkernels.kernels.reference import colour as Rc, derivatives as Rd, maps as Rm

    rng = np.random.default_rng(seed)
    s = W / 640.0
    y, x = np.mgrid[0:H, 0:W].astype(F32)
    palette = rng.uniform(0.08, 0.9, (29, 3)).astype(F32)
    cell = 40.0 * s

    def texture(u, v, k):
        idx = (np.floor(u / cell).astype(np.int64) * 7 + np.floor(v / cell).astype(np.int64) * 13 + 5 * k) % 29
        fine = 1.0 + 0.08 * np.sin(u * (0.37 / s) + k) * np.cos(v * (0.29 / s))
        return palette[idx] * fine[..., None]

    bg_v = (0.8, 0.3)
    zoom = 0.002
    albedo = np.empty((T, H, W, 3), F32)
    vel = np.empty((T, H, W, 2), F32)
    for t in range(T):
        albedo[t] = texture(x - t * bg_v[0], y - t * bg_v[1], 0)
        vel[t, ..., 0] = bg_v[0] + zoom * (x - W / 2)
        vel[t, ..., 1] = bg_v[1] + zoom * (y - H / 2)
        for k, ((cx, cy), (rx, ry), (vx, vy)) in enumerate(_OBJECTS):
            ox, oy = cx * W + t * vx, cy * H + t * vy
            m = ((x - ox) / (rx * s)) ** 2 + ((y - oy) / (ry * s)) ** 2 <= 1.0
            albedo[t][m] = texture(x[m] - t * vx, y[m] - t * vy, k + 1)
            vel[t][m] = (vx, vy)
    albedo *= np.exp(0.02 * rng.standard_normal(albedo.shape, F32))
    t_axis = np.arange(T, dtype=F32)[:, None, None]
    shading = 0.35 + 0.6 * (0.5 + 0.5 * np.cos(2 * np.pi * (x / W * 0.8 + 0.05 * t_axis))
                            * np.sin(np.pi * (y / H * 0.9 + 0.1)))
    shading = np.clip(shading * np.exp(0.01 * rng.standard_normal(shading.shape, F32)), 0.05, 1.0)
    rgb = np.clip(albedo * shading[..., None], 1e-3, 1.0)
    A = np.log(np.maximum(albedo, 1e-3))
    S = np.log(shading)
    flow = vel[:-1] + 0.03 * rng.standard_normal(vel[:-1].shape, F32)
    lab = Rc.linear_rgb_to_lab(rgb)
    lum = Rc.luminance(rgb)
    div_neg = Rd.divergence_negative(flow)
    sobel = Rd.flow_sobel_magnitude(flow)
    occ = Rm.occlusion_binary(lab, flow, div_neg)
    w_bnd = Rm.motion_boundary(sobel, 0.25, 3)
    c = lambda a: np.ascontiguousarray(a, dtype=F32)  # noqa: E731
    scene = Scene(T, H, W, rgb=c(rgb), srgb=c(Rc.linear_to_srgb(rgb)), lab=c(lab), A=c(A), S=c(S),
                  I=c(A + S[..., None]), w_lum=c(lum + 0.001), grey=c(2.0 * lum[..., None] - 1.0),
                  flow=c(flow), div_neg=c(div_neg), sobel=c(sobel), occ=c(occ), w_bnd=c(w_bnd))
    _scene_cache[key] = scene
    return scene


# ----------------------------------------------------------------------------
# Cases
# ----------------------------------------------------------------------------

@dataclasses.dataclass
class Call:
    """A bound call and the arrays it must read, write, and read-and-write (accumulate)."""

    fn: Callable[[], object]
    reads: tuple = ()
    writes: tuple = ()
    updates: tuple = ()

    @property
    def nbytes(self) -> int:
        return (sum(a.nbytes for a in self.reads) + sum(a.nbytes for a in self.writes)
                + 2 * sum(a.nbytes for a in self.updates))


@dataclasses.dataclass
class Case:
    """One host function, built for a backend (``fast``) and for the NumPy reference (``ref``).

    unit : what the work is counted in for scaling reference crops:
        "frames" (T H W pixels), "pairs" ((T-1) H W), "pair" (H W, one pair),
        "vector" (4 T H W elements), "masked" (w_bnd pixels), "frames_only"
        (T; crops keep the full image).
    bound : "mem" (streaming: a few flops per pixel, no transcendental) or
        "compute"; ``ops`` says what each pixel costs.
    """

    family: str
    name: str
    fast: Callable        # fast(be, scene) -> Call
    ref: Callable | None  # ref(scene) -> zero-argument callable
    unit: str
    bound: str
    ops: str
    count: Callable | None = None   # count(scene) -> (units, label) for the compute table
    ops_per_unit: float | None = None
    split: Callable | None = None   # split(scene) -> best 2-thread speedup the row split allows

    @property
    def key(self) -> str:
        return f"{self.family}.{self.name}"


def _e(*shape, dtype=F32):
    return np.empty(shape, dtype)


def _z(*shape, dtype=F32):
    return np.zeros(shape, dtype)


def window_pairs(H: int, W: int, radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Per row / column: how many window rows / columns lie inside the image."""
    def per_axis(n):
        i = np.arange(n)
        return np.minimum(i + radius, n - 1) - np.maximum(i - radius, 0) + 1
    return per_axis(H), per_axis(W)


def neighbour_count(s: Scene, frames: int, radius: int) -> int:
    """Pixel-neighbour pairs of a (2r+1)^2 window over ``frames`` frames, centre excluded."""
    ny, nx = window_pairs(s.H, s.W, radius)
    return int(frames * (ny.sum() * nx.sum() - s.H * s.W))


def masked_window_count(s: Scene, mask: np.ndarray, radius: int) -> int:
    """Window pixels (centre included) visited over the masked pixels."""
    ny, nx = window_pairs(s.H, s.W, radius)
    t, y, x = np.nonzero(mask >= 0.5)
    return int((ny[y] * nx[x]).sum())


def build_cases() -> list[Case]:
    from ivkernels.kernels.reference import (colour as Rc, derivatives as Rd, energy_data as Red,
                                             energy_shading as Res, energy_temporal as Ret,
                                             flow_classic as Rf, maps as Rm, median as Rmed,
                                             pyramid as Rp, sampling as Rs, vecops as Rv)
    cases: list[Case] = []

    def add(family, name, fast, ref, unit, bound, ops, count=None, ops_per_unit=None, split=None):
        cases.append(Case(family, name, fast, ref, unit, bound, ops, count, ops_per_unit, split))

    def frames_split(n):
        """Bound of a launch split only at frame boundaries (``align=H``) over ``n(s)`` frames."""
        return lambda s: row_split_bound(np.ones(n(s)))

    def masked_split(frames):
        """Bound of an even row split when the work follows w_bnd (rows of ``frames(s)`` frames)."""
        def bound(s):
            rows = np.full(frames(s) * s.H, 0.002 * s.W)
            rows[: s.P * s.H] += (s.w_bnd >= 0.5).reshape(s.P * s.H, s.W).sum(1)
            return row_split_bound(rows)
        return bound

    # -- colour ---------------------------------------------------------------
    def elementwise(fn_name, src_attr, extra=()):
        def fast(be, s):
            src = getattr(s, src_attr)
            out = np.empty_like(src)
            a, o = be.asarray(src), be.asarray(out)
            fn = getattr(be.colour, fn_name)
            return Call(lambda: fn(a, o, *extra), (src,), (out,))
        return fast

    add("colour", "srgb_to_linear", elementwise("srgb_to_linear", "srgb"),
        lambda s: (lambda: Rc.srgb_to_linear(s.srgb)), "frames", "compute", "1 pow per element")
    add("colour", "linear_to_srgb", elementwise("linear_to_srgb", "rgb"),
        lambda s: (lambda: Rc.linear_to_srgb(s.rgb)), "frames", "compute", "1 pow per element")
    add("colour", "log_floor", elementwise("log_floor", "rgb", (1e-4,)),
        lambda s: (lambda: Rc.log_floor(s.rgb, 1e-4)), "frames", "compute", "1 log per element")
    add("colour", "linear_rgb_to_lab", elementwise("linear_rgb_to_lab", "rgb"),
        lambda s: (lambda: Rc.linear_rgb_to_lab(s.rgb)), "frames", "compute", "3 cube roots (pow) + 25 flops/px")

    def luminance(be, s):
        out = _e(s.T, s.H, s.W)
        a, o = be.asarray(s.rgb), be.asarray(out)
        return Call(lambda: be.colour.luminance(a, o), (s.rgb,), (out,))
    add("colour", "luminance", luminance, lambda s: (lambda: Rc.luminance(s.rgb)), "frames", "mem",
        "5 flops/px")

    # -- sampling -------------------------------------------------------------
    def warp_case(fn_name):
        def fast(be, s):
            src = s.A[1:]
            out, inside = np.empty_like(src), _e(s.P, s.H, s.W)
            args = [be.asarray(v) for v in (src, s.flow, out, inside)]
            fn = getattr(be.sampling, fn_name)
            return Call(lambda: fn(*args), (src, s.flow), (out, inside))
        return fast

    add("sampling", "warp_bilinear", warp_case("warp_bilinear"),
        lambda s: (lambda: Rs.warp_bilinear(s.A[1:], s.flow)), "pairs", "mem", "4 taps x 3 ch, ~45 flops/px")

    def splat(be, s):
        vals, out = s.A[:-1], _z(s.P, s.H, s.W, 3)
        args = [be.asarray(v) for v in (vals, s.flow, out)]
        return Call(lambda: be.sampling.splat_bilinear(*args), (vals, s.flow), (), (out,))
    add("sampling", "splat_bilinear", splat, lambda s: (lambda: Rs.splat_bilinear(s.A[:-1], s.flow)),
        "pairs", "mem", "12 scattered adds/px", split=frames_split(lambda s: s.P))
    add("sampling", "warp_bicubic", warp_case("warp_bicubic"),
        lambda s: (lambda: Rs.warp_bicubic(s.A[1:], s.flow)), "pairs", "compute",
        "16 taps x 3 ch + 60 Keys weights, ~350 flops/px")

    # -- derivatives ----------------------------------------------------------
    def gradient(be, s):
        gx, gy = np.empty_like(s.grey), np.empty_like(s.grey)
        args = [be.asarray(v) for v in (s.grey, gx, gy)]
        return Call(lambda: be.derivatives.image_gradient(*args), (s.grey,), (gx, gy))
    add("derivatives", "image_gradient", gradient, lambda s: (lambda: Rd.image_gradient(s.grey)),
        "frames", "mem", "2 x 5-tap stencil, 10 flops/px")

    def flow_map(fn_name):
        def fast(be, s):
            out = _e(s.P, s.H, s.W)
            a, o = be.asarray(s.flow), be.asarray(out)
            fn = getattr(be.derivatives, fn_name)
            return Call(lambda: fn(a, o), (s.flow,), (out,))
        return fast
    add("derivatives", "flow_sobel_magnitude", flow_map("flow_sobel_magnitude"),
        lambda s: (lambda: Rd.flow_sobel_magnitude(s.flow)), "pairs", "compute", "4 Sobel sums + sqrt, ~45 flops/px")
    add("derivatives", "divergence_negative", flow_map("divergence_negative"),
        lambda s: (lambda: Rd.divergence_negative(s.flow)), "pairs", "mem", "5 flops/px")

    # -- maps -----------------------------------------------------------------
    def occlusion(fn_name):
        def fast(be, s):
            out = _e(s.P, s.H, s.W)
            args = [be.asarray(v) for v in (s.lab, s.flow, s.div_neg, out)]
            fn = getattr(be.maps, fn_name)
            return Call(lambda: fn(*args), (s.lab, s.flow, s.div_neg), (out,))
        return fast
    add("maps", "occlusion_soft", occlusion("occlusion_soft"),
        lambda s: (lambda: Rm.occlusion_soft(s.lab, s.flow, s.div_neg)), "pairs", "compute",
        "bilinear Lab sample + exp, ~60 flops/px")
    add("maps", "occlusion_binary", occlusion("occlusion_binary"),
        lambda s: (lambda: Rm.occlusion_binary(s.lab, s.flow, s.div_neg)), "pairs", "compute",
        "bilinear Lab sample + exp, ~60 flops/px")

    def boundary(be, s):
        out = _e(s.P, s.H, s.W)
        a, o = be.asarray(s.sobel), be.asarray(out)
        return Call(lambda: be.maps.motion_boundary(a, o, 0.25, 3), (s.sobel,), (out,))
    add("maps", "motion_boundary", boundary, lambda s: (lambda: Rm.motion_boundary(s.sobel, 0.25, 3)),
        "pairs", "compute", "7x7 window search (<= 49 compares, early exit)")

    # -- pyramid --------------------------------------------------------------
    def blur(be, s):
        out, scratch = np.empty_like(s.rgb), np.empty_like(s.rgb)
        args = [be.asarray(v) for v in (s.rgb, out, scratch)]
        return Call(lambda: be.pyramid.gaussian_blur(*args, 1.0), (s.rgb,), (out,))
    add("pyramid", "gaussian_blur", blur, lambda s: (lambda: Rp.gaussian_blur(s.rgb, 1.0)), "frames",
        "compute", "sigma 1: 2 passes x 7 taps, 28 flops/element")

    def resize_down(be, s):
        out = _e(s.T, s.H // 2, s.W // 2, 3)
        a, o = be.asarray(s.rgb), be.asarray(out)
        return Call(lambda: be.pyramid.resize_bilinear(a, o), (s.rgb,), (out,))
    add("pyramid", "resize_bilinear", resize_down,
        lambda s: (lambda: Rp.resize_bilinear(s.rgb, (s.H // 2, s.W // 2))), "frames", "mem",
        "halve: 4 taps x 3 ch per output px")

    def resize_up(be, s):
        src = np.ascontiguousarray(s.flow[:, ::2, ::2])
        out = _e(s.P, s.H, s.W, 2)
        a, o = be.asarray(src), be.asarray(out)
        return Call(lambda: be.pyramid.resize_flow(a, o), (src,), (out,))
    add("pyramid", "resize_flow", resize_up,
        lambda s: (lambda: Rp.resize_flow(np.ascontiguousarray(s.flow[:, ::2, ::2]), (s.H, s.W))),
        "pairs", "mem", "double: 4 taps x 2 ch per output px")

    # -- vecops (the solver's unknowns: A and S of every frame, 4 T H W floats) --
    def vectors(s, k):
        n = 4 * s.T * s.H * s.W
        rng = np.random.default_rng(1)
        return [rng.standard_normal(n, dtype=F32) for _ in range(k)]

    def vec_case(name):
        def fast(be, s):
            x, y = vectors(s, 2)
            out = np.empty_like(x)
            X, Y, O = be.asarray(x), be.asarray(y), be.asarray(out)
            v = be.vecops
            table = {
                "dot": (lambda: v.dot(X, Y), (x, y), (), ()),
                "norm_inf": (lambda: v.norm_inf(X), (x,), (), ()),
                "axpy": (lambda: v.axpy(0.5, X, Y), (x,), (), (y,)),
                "scale": (lambda: v.scale(1.0, X), (), (), (x,)),
                "lincomb": (lambda: v.lincomb(O, 0.5, X, 0.25, Y), (x, y), (out,), ()),
                "copy": (lambda: v.copy(X, O), (x,), (out,), ()),
                "fill": (lambda: v.fill(O, 1.0), (), (out,), ()),
            }
            fn, r, w, u = table[name]
            return Call(fn, r, w, u)
        return fast

    def vec_ref(name):
        def ref(s):
            x, y = vectors(s, 2)
            return {"dot": lambda: Rv.dot(x, y), "norm_inf": lambda: Rv.norm_inf(x),
                    "axpy": lambda: Rv.axpy(0.5, x, y), "scale": lambda: Rv.scale(1.0, x),
                    "lincomb": lambda: Rv.lincomb(0.5, x, 0.25, y), "copy": lambda: Rv.copy(x),
                    "fill": lambda: Rv.fill(x, 1.0)}[name]
        return ref

    for name in ("dot", "norm_inf", "axpy", "scale", "lincomb", "copy", "fill"):
        add("vecops", name, vec_case(name), vec_ref(name), "vector", "mem", "<= 2 flops/element")

    # -- median ---------------------------------------------------------------
    def median5(be, s):
        out = np.empty_like(s.flow)
        a, o = be.asarray(s.flow), be.asarray(out)
        return Call(lambda: be.median.median5x5(a, o), (s.flow,), (out,))
    add("median", "median5x5", median5, lambda s: (lambda: Rmed.median5x5(s.flow)), "pairs", "compute",
        "25 loads + 113 compare-exchanges per channel",
        count=lambda s: (2 * s.P * s.H * s.W, "px-channels"), ops_per_unit=25 + 2 * 113)

    def wm_shading(be, s):
        out = np.empty_like(s.S)
        args = [be.asarray(v) for v in (s.S, s.flow, s.w_bnd, out)]
        return Call(lambda: be.median.weighted_median_shading(*args, radius=7, sigma_s=7.0, lam=0.001),
                    (s.S, s.flow, s.w_bnd), (out,))
    add("median", "weighted_median_shading", wm_shading,
        lambda s: (lambda: Rmed.weighted_median_shading(s.S, s.flow, s.w_bnd, 7, 7.0, 0.001)),
        "masked", "compute", "15x15: 2-means of 225 flow vectors + weighted selection",
        count=lambda s: (masked_window_count(s, s.w_bnd, 7), "px-neighbours"),
        split=masked_split(lambda s: s.T))

    def wm_flow(be, s):
        out = np.empty_like(s.flow)
        lab = s.lab[:-1]
        args = [be.asarray(v) for v in (s.flow, lab, s.occ, s.w_bnd, out)]
        return Call(lambda: be.median.weighted_median_flow(*args, 7, 7.0, 7.0 * math.sqrt(3.0)),
                    (s.flow, lab, s.occ, s.w_bnd), (out,))
    add("median", "weighted_median_flow", wm_flow,
        lambda s: (lambda: Rmed.weighted_median_flow(s.flow, s.lab[:-1], s.occ, s.w_bnd, 7, 7.0,
                                                     7.0 * math.sqrt(3.0))),
        "masked", "compute", "15x15: 225 weights (exp) + 2 weighted selections",
        count=lambda s: (masked_window_count(s, s.w_bnd, 7), "px-neighbours"),
        split=masked_split(lambda s: s.P))

    # -- energy terms ---------------------------------------------------------
    def data_term(be, s):
        gA, gS, er = _z(s.T, s.H, s.W, 3), _z(s.T, s.H, s.W), _z(s.T * s.H, dtype=np.float64)
        args = [be.asarray(v) for v in (s.I, s.A, s.S, s.w_lum, gA, gS, er)]
        return Call(lambda: be.energy_data.data_term(*args), (s.I, s.A, s.S, s.w_lum), (), (gA, gS, er))
    add("energy_data", "data_term", data_term, lambda s: (lambda: Red.data_term(s.I, s.A, s.S, s.w_lum)),
        "frames", "compute", "3 x (sqrt + div + 8 flops)/px")

    def temporal(attr, lam):
        def fast(be, s):
            X = getattr(s, attr)
            gX, er = np.zeros_like(X), _z(s.T * s.H, dtype=np.float64)
            args = [be.asarray(v) for v in (X, s.flow, s.occ, gX, er)]
            return Call(lambda: be.energy_temporal.temporal_term(*args, lam), (X, s.flow, s.occ), (), (gX, er))
        return fast
    add("energy_temporal", "temporal_term(A)", temporal("A", 10.0),
        lambda s: (lambda: Ret.temporal_term(s.A, s.flow, s.occ, 10.0)), "pairs", "compute",
        "gather + splat: 2 bilinear samples, 2 Tukey, 12 atomic adds per px (3 ch)",
        split=frames_split(lambda s: s.P))
    add("energy_temporal", "temporal_term(S)", temporal("S", 1.0),
        lambda s: (lambda: Ret.temporal_term(s.S, s.flow, s.occ, 1.0)), "pairs", "compute",
        "gather + splat: 2 bilinear samples, 2 Tukey, 4 atomic adds per px (1 ch)",
        split=frames_split(lambda s: s.P))

    def smooth(be, s):
        gS, er = _z(s.T, s.H, s.W), _z(s.T * s.H, dtype=np.float64)
        args = [be.asarray(v) for v in (s.S, gS, er)]
        return Call(lambda: be.energy_shading.shading_smoothness(*args), (s.S,), (), (gS, er))
    add("energy_shading", "shading_smoothness", smooth, lambda s: (lambda: Res.shading_smoothness(s.S)),
        "frames", "compute", "8 neighbours x (sqrt + div + 5 flops)",
        count=lambda s: (neighbour_count(s, s.T, 1), "px-neighbours"), ops_per_unit=5 + 2)

    def coupling(be, s):
        St = s.S + F32(0.01)
        gS, er = _z(s.T, s.H, s.W), _z(s.T * s.H, dtype=np.float64)
        args = [be.asarray(v) for v in (s.S, St, s.w_bnd, gS, er)]
        return Call(lambda: be.energy_shading.coupling_term(*args), (s.S[:-1], St[:-1], s.w_bnd), (),
                    (gS[:-1], er))
    add("energy_shading", "coupling_term", coupling,
        lambda s: (lambda: Res.coupling_term(s.S, s.S + 0.01, s.w_bnd)), "frames", "mem", "6 flops/px")

    # -- albedo priors --------------------------------------------------------
    def prior():
        from ivkernels.priors import load_albedo_prior
        return load_albedo_prior()

    def gsm_args(s):
        p = prior()
        f = lambda a: np.ascontiguousarray(a, F32)  # noqa: E731
        return p, f(p.sigma_inv), f(p.table_g), f(p.table_dg)

    def gsm(radius):
        def fast(be, s):
            p, P, tg, tdg = gsm_args(s)
            gA, er = _z(s.T, s.H, s.W, 3), _z(s.T * s.H, dtype=np.float64)
            args = [be.asarray(v) for v in (s.A, P, tg, tdg)]
            g, e = be.asarray(gA), be.asarray(er)
            return Call(lambda: be.energy_albedo_gsm.gsm_smoothness(*args, float(p.r2_max), g, e, 1.0, radius),
                        (s.A,), (), (gA, er))
        return fast

    def gsm_ref(s):
        from ivkernels.kernels.reference import energy_albedo_gsm as Rg
        p = prior()
        return lambda: Rg.gsm_smoothness(s.A, p.sigma_inv, p.table_g, p.table_dg, p.r2_max, 1.0, 2)
    # per pair (12 per pixel, each looked up once): forward d (3), r2 (5), sqrt, cell (3),
    # vec4 read, 2 multiply-adds (4), pair store, gradient + energy sums (7); backward: pair
    # read, d (3), sums (4): ~34 ops per pair = ~17 per pixel-neighbour (24 per pixel)
    add("energy_albedo_gsm", "gsm_smoothness", gsm(2), gsm_ref, "frames", "compute",
        "5x5: 12 pairs per pixel, each looked up once (sqrt, one vec4 cell read) and gathered once, ~17 ops per neighbour",
        count=lambda s: (neighbour_count(s, s.T, 2), "px-neighbours"), ops_per_unit=17)

    def entropy_setup(be, s):
        from ivkernels.priors import entropy_blur_weights
        p = prior()
        B = p.hist_bins
        taps = entropy_blur_weights(p.sigma_p, p.hist_bin_width)
        W = np.ascontiguousarray(p.whiten, F32)
        scratch = be.energy_albedo_entropy.allocate_entropy_scratch(s.T, B)
        return p, B, be.asarray(taps), taps, be.asarray(W), scratch

    def scratch_np(be, sc):
        return [be.numpy(a) for a in sc]

    def ent_hist(be, s):
        p, B, taps, _, Wm, sc = entropy_setup(be, s)
        A = be.asarray(s.A)
        hist, flags = scratch_np(be, sc)[:2]
        return Call(lambda: be.energy_albedo_entropy.entropy_histogram(A, Wm, p.hist_lo, p.hist_bin_width,
                                                                       sc.hist, sc.row_flags),
                    (s.A,), (hist, flags))

    def ent_blur(be, s):
        p, B, taps, _, Wm, sc = entropy_setup(be, s)
        E = be.energy_albedo_entropy
        E.entropy_histogram(be.asarray(s.A), Wm, p.hist_lo, p.hist_bin_width, sc.hist, sc.row_flags)
        hist, flags, tmp, blurred, _ = scratch_np(be, sc)
        return Call(lambda: E.entropy_blur(sc.hist, taps, sc.row_flags, sc.tmp, sc.blurred),
                    (hist, flags[0]), (blurred,))

    def ent_dot(be, s):
        p, B, taps, _, Wm, sc = entropy_setup(be, s)
        E = be.energy_albedo_entropy
        E.entropy_histogram(be.asarray(s.A), Wm, p.hist_lo, p.hist_bin_width, sc.hist, sc.row_flags)
        E.entropy_blur(sc.hist, taps, sc.row_flags, sc.tmp, sc.blurred)
        hist, _, _, blurred, dots = scratch_np(be, sc)
        return Call(lambda: E.entropy_dot(sc.hist, sc.blurred, sc.dots), (hist, blurred), (dots,))

    def ent_slice(be, s):
        p, B, taps, _, Wm, sc = entropy_setup(be, s)
        E = be.energy_albedo_entropy
        A = be.asarray(s.A)
        E.entropy_histogram(A, Wm, p.hist_lo, p.hist_bin_width, sc.hist, sc.row_flags)
        E.entropy_blur(sc.hist, taps, sc.row_flags, sc.tmp, sc.blurred)
        E.entropy_dot(sc.hist, sc.blurred, sc.dots)
        gA = _z(s.T, s.H, s.W, 3)
        g = be.asarray(gA)
        return Call(lambda: E.entropy_slice_gradient(A, Wm, p.hist_lo, p.hist_bin_width, sc.blurred,
                                                     sc.dots, g, 1.0),
                    (s.A,), (), (gA,))

    def ent_term(be, s):
        p, B, taps, _, Wm, sc = entropy_setup(be, s)
        E = be.energy_albedo_entropy
        A = be.asarray(s.A)
        gA, er = _z(s.T, s.H, s.W, 3), _z(s.T * s.H, dtype=np.float64)
        g, e = be.asarray(gA), be.asarray(er)
        return Call(lambda: E.entropy_term(A, Wm, p.hist_lo, p.hist_bin_width, taps, p.sigma_p, sc, g, e, 1.0),
                    (s.A,), (), (gA, er))

    def ent_ref(what):
        def ref(s):
            from ivkernels.kernels.reference import energy_albedo_entropy as Rent
            from ivkernels.priors import entropy_blur_weights
            p = prior()
            B = p.hist_bins
            taps = entropy_blur_weights(p.sigma_p, p.hist_bin_width)
            if what == "histogram":
                return lambda: Rent.entropy_histogram(s.A, p.whiten, p.hist_lo, p.hist_bin_width, B)
            if what == "blur":
                hist = Rent.entropy_histogram(s.A, p.whiten, p.hist_lo, p.hist_bin_width, B)
                return lambda: Rent.entropy_blur(hist, taps)
            return lambda: Rent.entropy_term(s.A, p.whiten, p.hist_lo, p.hist_bin_width, taps, p.sigma_p,
                                             1.0, B)
        return ref
    add("energy_albedo_entropy", "entropy_histogram", ent_hist, ent_ref("histogram"), "frames_only",
        "compute", "3x3 whitening + 8 trilinear atomic adds per px", split=frames_split(lambda s: s.T))
    add("energy_albedo_entropy", "entropy_blur", ent_blur, ent_ref("blur"), "frames_only", "compute",
        "3 separable passes x 21 taps over the B^3 histogram of each frame")
    add("energy_albedo_entropy", "entropy_dot", ent_dot, None, "frames_only", "mem", "1 fma per bin",
        split=frames_split(lambda s: s.T))
    add("energy_albedo_entropy", "entropy_slice_gradient", ent_slice, None, "frames_only", "compute",
        "3x3 whitening + 8-corner trilinear gradient per px")
    add("energy_albedo_entropy", "entropy_term", ent_term, ent_ref("term"), "frames_only", "compute",
        "histogram + blur + dot + slice gradient", split=frames_split(lambda s: s.T))

    # -- flow_classic (one pair: 2 images, 1 flow) ------------------------------
    def pair(s):
        """Arrays of one pair: first image's (grey, gradients), second image packed, flow, increment."""
        rng = np.random.default_rng(2)
        H, W = s.H, s.W
        i1 = np.ascontiguousarray(s.grey[0, ..., 0])[None]
        i1x = np.ascontiguousarray(np.gradient(i1, axis=2), F32)
        i1y = np.ascontiguousarray(np.gradient(i1, axis=1), F32)
        warped = np.ascontiguousarray(np.stack([s.grey[1, ..., 0], i1x[0], i1y[0]], -1)[None], F32)
        du = rng.normal(0.0, 0.05, (1, H, W, 2)).astype(F32)
        return dict(i1=i1, i1x=i1x, i1y=i1y, warped=warped, inside=s.occ[:1].copy(), flow=s.flow[:1].copy(),
                    du=du)

    def fc(name):
        def fast(be, s):
            F = be.flow_classic
            q = pair(s)
            A = be.asarray
            H, W = s.H, s.W
            if name == "srgb_grey":
                rgb, out = s.rgb[:2], _e(2, H, W)
                a, o = A(rgb), A(out)
                return Call(lambda: F.srgb_grey(a, o), (rgb,), (out,))
            if name == "row_min_max":
                src, out = s.grey[:2], _e(2 * H, 1, 2)
                a, o = A(src), A(out)
                return Call(lambda: F.row_min_max(a, o), (src,), (out,))
            if name == "scale_shift":
                src, out = s.grey[:2], np.empty_like(s.grey[:2])
                a, o, sc, sh = A(src), A(out), A(np.full(1, 2.0, F32)), A(np.full(1, -1.0, F32))
                return Call(lambda: F.scale_shift(a, o, sc, sh), (src,), (out,))
            if name in ("rof_dual_step", "rof_texture"):
                img = np.ascontiguousarray(s.grey[:2, ..., 0])
                p_in = np.random.default_rng(3).uniform(-0.5, 0.5, (2, H, W, 2)).astype(F32)
                out = np.empty_like(p_in) if name == "rof_dual_step" else np.empty_like(img)
                a, p, o = A(img), A(p_in), A(out)
                if name == "rof_dual_step":
                    return Call(lambda: F.rof_dual_step(a, p, o, 0.125, 2.0), (img, p_in), (out,))
                return Call(lambda: F.rof_texture(a, p, o, 0.125, 0.95), (img, p_in), (out,))
            if name == "pack_image_gradient":
                out = _e(1, H, W, 3)
                args = [A(v) for v in (q["i1"], q["i1x"], q["i1y"], out)]
                return Call(lambda: F.pack_image_gradient(*args), (q["i1"], q["i1x"], q["i1y"]), (out,))
            if name == "data_coefficients":
                out = _e(1, H, W, 5)
                ins = [q[k] for k in ("i1", "i1x", "i1y", "warped", "inside", "du")]
                args = [A(v) for v in (*ins, out)]
                return Call(lambda: F.data_coefficients(*args), tuple(ins), (out,))
            if name == "smoothness_weights":
                out = _e(1, H, W, 4)
                args = [A(v) for v in (q["flow"], q["du"], out)]
                return Call(lambda: F.smoothness_weights(*args), (q["flow"], q["du"]), (out,))
            if name in ("assemble_system", "sor_sweep (red+black)"):
                data, sm, system = _e(1, H, W, 5), _e(1, H, W, 4), _e(1, H, W, 5)
                F.data_coefficients(*[A(q[k]) for k in ("i1", "i1x", "i1y", "warped", "inside", "du")], A(data))
                F.smoothness_weights(A(q["flow"]), A(q["du"]), A(sm))
                fl, du, d, m, sy = A(q["flow"]), A(q["du"]), A(data), A(sm), A(system)
                if name == "assemble_system":
                    return Call(lambda: F.assemble_system(fl, d, m, 3.0, sy), (q["flow"], data, sm), (system,))
                F.assemble_system(fl, d, m, 3.0, sy)

                def sweep():
                    F.sor_sweep(du, sy, m, 3.0, 1.9, 0)
                    F.sor_sweep(du, sy, m, 3.0, 1.9, 1)
                return Call(sweep, (system, sm), (), (q["du"],))
            if name == "apply_update":
                out = np.empty_like(q["flow"])
                args = [A(v) for v in (q["flow"], q["du"], out)]
                return Call(lambda: F.apply_update(*args, 1.0), (q["flow"], q["du"]), (out,))
            if name == "select_masked":
                other, out = q["flow"] + F32(0.1), np.empty_like(q["flow"])
                args = [A(v) for v in (s.w_bnd[:1], q["flow"], other, out)]
                return Call(lambda: F.select_masked(*args), (s.w_bnd[:1], q["flow"], other), (out,))
            if name == "flow_sobel_components":
                out, energy = _e(1, H, W, 4), _e(H, 2)
                args = [A(v) for v in (q["flow"], out, energy)]
                return Call(lambda: F.flow_sobel_components(*args), (q["flow"],), (out, energy))
            if name == "thin_edges":
                sob, energy = _e(1, H, W, 4), _e(H, 2)
                F.flow_sobel_components(A(q["flow"]), A(sob), A(energy))
                cutoff = np.ascontiguousarray(4.0 * energy.sum(0)[None] / (H * W), F32)
                out = _e(1, H, W)
                args = [A(v) for v in (sob, cutoff, out)]
                return Call(lambda: F.thin_edges(*args), (sob,), (out,))
            raise KeyError(name)
        return fast

    def fc_ref(name):
        def ref(s):
            q = pair(s)
            if name == "srgb_grey":
                return lambda: Rf.srgb_grey(s.rgb[:2])
            if name == "row_min_max":
                return lambda: Rf.row_min_max(s.grey[:2])
            if name == "scale_shift":
                return lambda: Rf.scale_shift(s.grey[:2], np.full(1, 2.0), np.full(1, -1.0))
            if name in ("rof_dual_step", "rof_texture"):
                img = s.grey[:2, ..., 0]
                p = np.random.default_rng(3).uniform(-0.5, 0.5, (2, s.H, s.W, 2))
                if name == "rof_dual_step":
                    return lambda: Rf.rof_dual_step(img, p, 0.125, 2.0)
                return lambda: Rf.rof_texture(img, p, 0.125, 0.95)
            if name == "pack_image_gradient":
                return lambda: Rf.pack_image_gradient(q["i1"], q["i1x"], q["i1y"])
            if name == "data_coefficients":
                return lambda: Rf.data_coefficients(*[q[k] for k in ("i1", "i1x", "i1y", "warped", "inside", "du")])
            if name == "smoothness_weights":
                return lambda: Rf.smoothness_weights(q["flow"], q["du"])
            if name in ("assemble_system", "sor_sweep (red+black)"):
                data = Rf.data_coefficients(*[q[k] for k in ("i1", "i1x", "i1y", "warped", "inside", "du")])
                sm = Rf.smoothness_weights(q["flow"], q["du"])
                if name == "assemble_system":
                    return lambda: Rf.assemble_system(q["flow"], data, sm, 3.0)
                system = Rf.assemble_system(q["flow"], data, sm, 3.0)

                def sweep():
                    du = Rf.sor_sweep(q["du"], system, sm, 3.0, 1.9, 0)
                    Rf.sor_sweep(du, system, sm, 3.0, 1.9, 1)
                return sweep
            if name == "apply_update":
                return lambda: Rf.apply_update(q["flow"], q["du"], 1.0)
            if name == "select_masked":
                return lambda: Rf.select_masked(s.w_bnd[:1], q["flow"], q["flow"] + 0.1)
            if name == "flow_sobel_components":
                return lambda: Rf.flow_sobel_components(q["flow"])
            if name == "thin_edges":
                sob, energy = Rf.flow_sobel_components(q["flow"])
                cutoff = 4.0 * np.asarray(energy).reshape(-1, 2).sum(0)[None] / (s.H * s.W)
                return lambda: Rf.thin_edges(sob, cutoff)
            raise KeyError(name)
        return ref

    fc_table = (
        ("srgb_grey", "compute", "3 pow + 6 flops/px"),
        ("row_min_max", "mem", "2 compares/px"),
        ("scale_shift", "mem", "1 fma/px"),
        ("rof_dual_step", "compute", "3 divergences, sqrt, 2 div, ~35 flops/px"),
        ("rof_texture", "mem", "1 divergence, 6 flops/px"),
        ("pack_image_gradient", "mem", "copies only"),
        ("data_coefficients", "compute", "1 pow (generalised Charbonnier) + 20 flops/px"),
        ("smoothness_weights", "compute", "4 pow + 16 flops/px"),
        ("assemble_system", "mem", "4-neighbour sums, ~30 flops/px"),
        ("sor_sweep (red+black)", "compute", "4-neighbour sums + 2x2 solve: 2 div + ~30 flops/px"),
        ("apply_update", "mem", "2 clamps + 2 adds/px"),
        ("select_masked", "mem", "1 compare + 2 copies/px"),
        ("flow_sobel_components", "compute", "4 Sobel sums, ~40 flops/px"),
        ("thin_edges", "compute", "2 x (4-neighbour energy compare), ~30 flops/px"),
    )
    for name, bound, ops in fc_table:
        add("flow_classic", name, fc(name), fc_ref(name), "pair", bound, ops)
    return cases


# ----------------------------------------------------------------------------
# Measuring
# ----------------------------------------------------------------------------

def work(case: Case, s: Scene) -> float:
    """Work of ``case`` on ``s``, in the case's unit (for scaling reference crops)."""
    u = case.unit
    if u == "frames":
        return s.T * s.H * s.W
    if u == "pairs":
        return s.P * s.H * s.W
    if u == "pair":
        return s.H * s.W
    if u == "vector":
        return 4 * s.T * s.H * s.W
    if u == "masked":
        return float((s.w_bnd >= 0.5).sum())
    if u == "frames_only":
        return s.T
    raise ValueError(u)


def ref_ladder(case: Case, T: int, H: int, W: int) -> list[tuple[int, int, int]]:
    """Input sizes on which the reference is tried, smallest first, the full input last."""
    t2 = min(T, 2)
    if case.unit == "frames_only":
        sizes = [(t2, H, W), (T, H, W)]
    else:
        sizes = [(t2, max(H // 4, 8), max(W // 4, 8)), (t2, max(H // 2, 8), max(W // 2, 8)), (T, H, W)]
    out = []
    for size in sizes:
        if size not in out:
            out.append(size)
    return out


def time_reference(case: Case, full: Scene, budget: float, repeat: int) -> tuple[float | None, str]:
    """Reference seconds on the full input (measured, or scaled from the largest crop run) and the crop."""
    if case.ref is None:
        return None, "n/a"
    ladder = ref_ladder(case, full.T, full.H, full.W)
    best, where = None, ""
    prev = None
    for size in ladder:
        s = make_scene(*size)
        if work(case, s) <= 0:
            continue
        if prev is not None:
            t_prev, w_prev = prev
            if t_prev * work(case, s) / max(w_prev, 1e-9) > budget:
                break
        fn = case.ref(s)
        fn()  # warm-up (imports, first-touch of inputs)
        times = [_timed(fn)]
        while len(times) < repeat and sum(times) < 0.3 * budget:
            times.append(_timed(fn))
        t = statistics.median(times)
        prev = (t, work(case, s))
        best = t * work(case, full) / max(work(case, s), 1e-9)
        where = "full" if size == (full.T, full.H, full.W) else "x".join(map(str, size))
    return best, where


@dataclasses.dataclass
class Result:
    case: Case
    times: dict           # config -> list of seconds
    first: dict           # config -> seconds of the first call in the process
    ref: float | None
    ref_where: str
    nbytes: int
    count: tuple | None   # (units, label)
    cpu: dict             # "warp1": CPU seconds per call; "warp2": CPU seconds of the busier band

    def med(self, cfg) -> float | None:
        t = self.times.get(cfg)
        return statistics.median(t) if t else None

    def cpu_speedup(self) -> float | None:
        """2-thread speedup predicted from CPU time: 1-thread CPU / CPU of the busier band.

        Unlike wall time this does not stretch when other processes take the cores, so it
        shows what the split and its overheads allow on an idle machine (memory-bandwidth
        sharing between the two cores aside).
        """
        a, b = self.cpu.get("warp1"), self.cpu.get("warp2")
        if not a or not b or statistics.median(b) <= 0:
            return None
        return statistics.median(a) / statistics.median(b)


def run_case(case: Case, scene: Scene, backends: dict, repeat: int, budget_s: float,
             ref_budget: float, with_ref: bool) -> Result:
    from ivkernels.kernels.launch import threads

    warp_be, ti_be = backends["warp"], backends["taichi"]
    calls = {"warp": case.fast(warp_be, scene), "taichi": case.fast(ti_be, scene)}
    runners = {
        "warp1": (calls["warp"].fn, 1),
        "warp2": (calls["warp"].fn, 2),
        "taichi": (calls["taichi"].fn, None),
    }

    cpu = {"warp1": [], "warp2": []}

    def call(cfg, record=False):
        fn, nt = runners[cfg]
        if nt is None:
            return _timed(fn)
        with threads(nt):
            c0, m0, t0 = time.process_time(), time.thread_time(), time.perf_counter()
            fn()
            wall = time.perf_counter() - t0
            main, total = time.thread_time() - m0, time.process_time() - c0
        if record:
            # 1 thread: all CPU time; 2 threads: the busier band (this thread runs one band,
            # the pool thread the other, so total - main is the other band)
            cpu[cfg].append(total if nt == 1 else max(main, total - main))
        return wall

    # the first calls (compile, and launch_rows' sequential first 2-thread launch) warm up Warp-2 and
    # Taichi; Warp-1 gets one untimed call
    first = {"warp2": call("warp2"), "taichi": call("taichi")}
    call("warp1")
    times = {cfg: [] for cfg in CONFIGS}
    t_start = time.perf_counter()
    for r in range(repeat):
        order = CONFIGS[r % 3:] + CONFIGS[:r % 3]
        for cfg in order:
            times[cfg].append(call(cfg, record=True))
        if r >= 2 and time.perf_counter() - t_start > budget_s:
            break
    ref, where = time_reference(case, scene, ref_budget, repeat) if with_ref else (None, "skipped")
    count = case.count(scene) if case.count else None
    return Result(case, times, first, ref, where, calls["warp"].nbytes, count, cpu)


# ----------------------------------------------------------------------------
# Analysis of the arithmetic-bound kernels
# ----------------------------------------------------------------------------

def lloyd_iterations(flow_t: np.ndarray, y: int, x: int, radius: int = 7, iterations: int = 8,
                     min_separation: float = 0.5) -> tuple[int, int]:
    """(Lloyd passes run, window pixels kept) of the 2-means ``surf`` of one pixel, as the kernel does it."""
    h, w, _ = flow_t.shape
    y0, y1, x0, x1 = max(y - radius, 0), min(y + radius + 1, h), max(x - radius, 0), min(x + radius + 1, w)
    vec = flow_t[y0:y1, x0:x1].reshape(-1, 2).astype(np.float64)
    c0 = flow_t[y, x].astype(np.float64)
    c1 = vec[int(np.argmax(((vec - c0) ** 2).sum(-1)))].copy()
    passes = 0
    for _ in range(iterations):
        passes += 1
        near1 = ((vec - c1) ** 2).sum(-1) < ((vec - c0) ** 2).sum(-1)
        n0 = vec[~near1].mean(0) if (~near1).any() else c0
        n1 = vec[near1].mean(0) if near1.any() else c1
        moved = not (np.array_equal(n0, c0) and np.array_equal(n1, c1))
        c0, c1 = n0, n1
        if not moved:
            break
    if ((c0 - c1) ** 2).sum() < min_separation ** 2:
        return passes, len(vec)
    near1 = ((vec - c1) ** 2).sum(-1) < ((vec - c0) ** 2).sum(-1)
    own1 = ((flow_t[y, x] - c1) ** 2).sum() < ((flow_t[y, x] - c0) ** 2).sum()
    return passes, int((near1 == own1).sum())


def row_split_bound(row_work: np.ndarray, align: int = 1) -> float:
    """Best 2-thread speedup of :func:`launch_rows`' split of rows with this per-row work."""
    n = len(row_work)
    units = n // align
    if units < 2:
        return 1.0
    split = (units // 2) * align
    total = row_work.sum()
    return float(total / max(row_work[:split].sum(), row_work[split:].sum(), 1e-30))


def analyse(scene: Scene, backends: dict, results: dict, repeat: int) -> list[str]:
    """Measurements that explain the arithmetic-bound kernels; returns printable lines."""
    from ivkernels.kernels.launch import threads

    lines = []
    s = scene
    be = backends["warp"]

    def t1(call, n=repeat):
        """CPU seconds of one call on 1 thread (median; CPU time does not stretch under load)."""
        with threads(1):
            call.fn()
            return statistics.median(_cpu_timed(call.fn) for _ in range(max(3, n)))

    ghz = cpu_ghz()
    # 15x15 weighted median of the shading: 2-means passes, pairs kept, share of the clustering
    mask = s.w_bnd >= 0.5
    tt, yy, xx = np.nonzero(mask)
    pick = np.random.default_rng(0).choice(len(tt), min(400, len(tt)), replace=False) if len(tt) else []
    if len(tt):
        lines.append(f"w_bnd covers {mask.mean() * 100:.1f}% of the pixels of the {s.P} flow frames "
                     f"({mask.sum()} px).")
    if len(tt) and "median.weighted_median_shading" in results:
        stats = np.array([lloyd_iterations(s.flow[tt[i]], yy[i], xx[i]) for i in pick])
        passes, kept = stats[:, 0].mean(), stats[:, 1].mean()
        lines.append(f"weighted_median_shading: 2-means runs {passes:.2f} Lloyd passes on average "
                     f"(at most 8); x's surface keeps {kept:.0f} of ~225 window pixels (sample of {len(pick)}).")
        # op count per masked pixel (window of 225): farthest-vector pass 225 x 8, Lloyd passes
        # 225 x 16 each, surface test + pair copy 225 x 16, weighted quickselect ~3.4 n visits x 10
        ops = 225 * 8 + passes * 225 * 16 + 225 * 16 + 3.4 * kept * 10
        results["median.weighted_median_shading"].case.ops_per_unit = ops / 225
        from ivkernels.kernels.warp import median as wmed
        call = results["median.weighted_median_shading"].case.fast(be, s)
        full = t1(call)
        saved = wmed.KMEANS_ITERATIONS
        try:
            wmed.KMEANS_ITERATIONS = 0
            no_lloyd = t1(call)
        finally:
            wmed.KMEANS_ITERATIONS = saved
        share = 1.0 - no_lloyd / full
        lines.append(f"weighted_median_shading, Warp 1 thread (CPU time): {full * 1e3:.1f} ms; "
                     f"without the Lloyd passes "
                     f"{no_lloyd * 1e3:.1f} ms: the 2-means takes {share * 100:.0f}%, the farthest-vector pass, "
                     f"the pair copy and the selection the rest.")
        per_px = full / mask.sum()
        lines.append(f"  = {per_px * 1e9:.0f} ns per masked pixel = {per_px * 1e9 / 225:.1f} ns "
                     f"({per_px * 1e9 / 225 * ghz:.1f} cycles at {ghz:.2f} GHz) per pixel-neighbour, "
                     f"for ~{ops / 225:.0f} scalar ops per neighbour.")
        rows_sh = np.zeros(s.T * s.H)
        rows_sh[: s.P * s.H] = mask.reshape(s.P * s.H, s.W).sum(1)
        rows_sh += 0.002 * s.W  # the copy of S everywhere
        lines.append(f"  2-thread row split: at most {row_split_bound(rows_sh):.2f}x (the rows of all {s.T} "
                     f"frames are split in half; the last frame has no flow and only copies).")
    if len(tt) and "median.weighted_median_flow" in results:
        from ivkernels.kernels.reference import median as Rmed
        kept_flow = np.mean([(Rmed.flow_weights(s.lab[tt[i]], s.occ[tt[i]], yy[i], xx[i], 7, 7.0,
                                                7.0 * math.sqrt(3.0)) > 0).sum() for i in pick[:200]])
        ops_f = 225 * 35 + 2 * (225 * 5 + 3.4 * kept_flow * 10)
        results["median.weighted_median_flow"].case.ops_per_unit = ops_f / 225
        lines.append(f"weighted_median_flow: {kept_flow:.0f} of ~225 window pixels have a positive weight; "
                     f"~{ops_f / 225:.0f} ops per neighbour (an exp and ~15 flops for the weight, then two "
                     f"weighted quickselects); 2-thread row split: at most "
                     f"{row_split_bound(mask.reshape(s.P * s.H, s.W).sum(1) + 0.002 * s.W):.2f}x.")
    if "energy_albedo_entropy.entropy_histogram" in results:
        from ivkernels.priors import load_albedo_prior
        p = load_albedo_prior()
        E = be.energy_albedo_entropy
        sc = E.allocate_entropy_scratch(s.T, p.hist_bins)
        E.entropy_histogram(be.asarray(s.A), be.asarray(np.ascontiguousarray(p.whiten, F32)), p.hist_lo,
                            p.hist_bin_width, sc.hist, sc.row_flags)
        occupied = float(be.numpy(sc.row_flags)[0].mean())
        lines.append(f"entropy: {occupied * 100:.1f}% of the {s.T} x {p.hist_bins}^2 histogram rows hold mass "
                     f"({p.hist_bins}^3 bins per frame, {s.T * p.hist_bins ** 3 * 4 / 1e6:.0f} MB per cube); "
                     "the blur writes and the dot reads every row of the cube.")
    # GSM: cost per neighbour from radius 1 (8 neighbours) vs radius 2 (24)
    if "energy_albedo_gsm.gsm_smoothness" in results:
        t_r2 = t1(_gsm_call(be, s, 2))
        t_r1 = t1(_gsm_call(be, s, 1))
        n2, n1 = neighbour_count(s, s.T, 2), neighbour_count(s, s.T, 1)
        slope = (t_r2 - t_r1) / (n2 - n1)
        base = t_r2 - slope * n2
        lines.append(f"gsm_smoothness, Warp 1 thread (CPU time): radius 1 (8 neighbours) {t_r1 * 1e3:.0f} ms, radius 2 "
                     f"(24) {t_r2 * 1e3:.0f} ms: {slope * 1e9:.2f} ns ({slope * 1e9 * ghz:.1f} cycles) per "
                     f"pixel-neighbour, {base / (s.T * s.H * s.W) * 1e9:.1f} ns per pixel outside the window loop.")
    return lines


def _gsm_call(be, s: Scene, radius: int) -> Call:
    from ivkernels.priors import load_albedo_prior
    p = load_albedo_prior()
    f = lambda a: be.asarray(np.ascontiguousarray(a, F32))  # noqa: E731
    gA, er = _z(s.T, s.H, s.W, 3), _z(s.T * s.H, dtype=np.float64)
    args = [be.asarray(s.A), f(p.sigma_inv), f(p.table_g), f(p.table_dg)]
    g, e = be.asarray(gA), be.asarray(er)
    return Call(lambda: be.energy_albedo_gsm.gsm_smoothness(*args, float(p.r2_max), g, e, 1.0, radius))


# ----------------------------------------------------------------------------
# Report
# ----------------------------------------------------------------------------

def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def cpu_ghz() -> float:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("cpu MHz"):
                    return float(line.split(":", 1)[1]) / 1000.0
    except (OSError, ValueError):
        pass
    return 2.5


def table(headers: list[str], rows: list[list[str]], right: set | None = None) -> str:
    """A Markdown table with padded columns."""
    right = right if right is not None else set(range(1, len(headers)))
    widths = [max(len(str(r[i])) for r in [headers, *rows]) for i in range(len(headers))]

    def fmt(r):
        cells = [str(c).rjust(w) if i in right else str(c).ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        return "| " + " | ".join(cells) + " |"
    sep = "|" + "|".join(("-" * (w + 1) + ":") if i in right else ("-" * (w + 2)) for i, w in enumerate(widths)) + "|"
    return "\n".join([fmt(headers), sep, *(fmt(r) for r in rows)])


def ms(t: float | None, approx: bool = False) -> str:
    if t is None:
        return "-"
    v = t * 1e3
    s = f"{v:.0f}" if v >= 100 else f"{v:.1f}" if v >= 1 else f"{v:.2f}"
    return ("~" + s) if approx else s


def ratio(a: float | None, b: float | None) -> str:
    if a is None or b is None or b <= 0:
        return "-"
    r = a / b
    return f"{r:.0f}x" if r >= 100 else f"{r:.1f}x" if r >= 10 else f"{r:.2f}x"


def work_label(case: Case, s: Scene) -> str:
    return {"frames": f"{s.T}f", "pairs": f"{s.P}p", "pair": "1p", "masked": f"{s.P}p,mask",
            "vector": f"{4 * s.T * s.H * s.W / 1e6:.1f}M", "frames_only": f"{s.T}f"}[case.unit]


def report(results: list[Result], scene: Scene, roof: dict, tiny_ms: float, ghz: float) -> tuple[str, list]:
    rows, misses = [], []
    for r in results:
        c = r.case
        w1, w2, ti = r.med("warp1"), r.med("warp2"), r.med("taichi")
        gbs = r.nbytes / w2 / 1e9 if w2 else None
        frac = gbs / roof["roof"] if gbs else None
        band = statistics.median(r.cpu["warp2"]) if r.cpu.get("warp2") else None
        gbs_cpu = r.nbytes / band / 1e9 if band else None
        split = c.split(scene) if c.split else 2.0
        checks = []
        tiny = w1 is not None and w1 * 1e3 < tiny_ms
        if tiny:
            checks.append("tiny")
        elif w1 is not None and w2 is not None and w1 / w2 < 1.7:
            est = r.cpu_speedup()
            load_only = est is not None and est >= 1.7
            checks.append("2T<1.7" + ("(load)" if load_only else ""))
            misses.append({"kernel": c.key, "kind": "threads", "load_only": load_only,
                           "text": f"{w1 / w2:.2f}x wall, " + (f"{est:.2f}x from CPU time, " if est else "")
                                   + f"the row split allows {split:.2f}x"})
        if c.bound == "mem" and frac is not None and not tiny:
            if frac < 1 / 3:
                load_only = bool(gbs_cpu and gbs_cpu >= roof["roof"] / 3)
                checks.append("roof>3x" + ("(load)" if load_only else ""))
                misses.append({"kernel": c.key, "kind": "roof", "load_only": load_only,
                               "text": f"{gbs:.1f} GB/s wall = {frac * 100:.0f}% of the roof"
                                       + (f", {gbs_cpu:.1f} GB/s from CPU time = "
                                          f"{gbs_cpu / roof['roof'] * 100:.0f}%" if gbs_cpu else "")})
        rows.append([c.key, work_label(c, scene), ms(w1), ms(w2), ms(ti),
                     ms(r.ref, r.ref_where not in ("full",)), r.ref_where,
                     ratio(w1, w2), f"{r.cpu_speedup():.2f}x" if r.cpu_speedup() else "-", f"{split:.2f}",
                     ratio(ti, w2), ratio(r.ref, w2),
                     f"{r.nbytes / 1e6:.0f}", f"{gbs:.1f}" if gbs else "-", f"{gbs_cpu:.1f}" if gbs_cpu else "-",
                     f"{frac * 100:.0f}%" if frac else "-",
                     ms(r.first.get("warp2")), ms(r.first.get("taichi")), c.bound,
                     " ".join(checks) or "ok"])
    headers = ["kernel", "work", "W1 ms", "W2 ms", "TI ms", "NP ms", "NP on", "W1/W2", "cpu", "split",
               "TI/W2", "NP/W2", "MB", "GB/s", "GB/s cpu", "roof", "1st W ms", "1st TI ms", "bound", "check"]
    text = [table(headers, rows, right=set(range(2, 18)))]

    crows = []
    for r in results:
        c = r.case
        if c.bound != "compute":
            continue
        w1, w2 = r.med("warp1"), r.med("warp2")
        c1 = statistics.median(r.cpu["warp1"]) if r.cpu.get("warp1") else None
        if r.count:
            units, label = r.count
        elif c.unit == "frames_only":
            units, label = scene.T * scene.H * scene.W, "px"
        else:
            units, label = work(c, scene), "px"
        ns1 = w1 / units * 1e9 if w1 else None
        ns2 = w2 / units * 1e9 if w2 else None
        nsc = c1 / units * 1e9 if c1 else None
        cyc = nsc * ghz if nsc else None
        opc = f"{c.ops_per_unit / cyc:.2f}" if (c.ops_per_unit and cyc) else "-"
        crows.append([c.key, f"{units / 1e6:.2f}M {label}", f"{ns1:.2f}" if ns1 else "-",
                      f"{ns2:.2f}" if ns2 else "-", f"{nsc:.2f}" if nsc else "-", f"{cyc:.1f}" if cyc else "-",
                      f"{c.ops_per_unit:.0f}" if c.ops_per_unit else "-", opc, c.ops])
    if crows:
        text.append("Arithmetic-bound kernels: cost per unit of work. W1/W2 ns/unit: wall time / units; "
                    "W1 CPU ns/unit: 1-thread CPU time / units (unaffected by other processes); cycles/unit: "
                    f"CPU ns x {ghz:.2f} GHz; ops/unit: scalar operations per unit counted from the kernel "
                    "source (the weighted medians' counts use the measured Lloyd passes and kept pairs below); "
                    "ops/cycle: ops/unit / cycles/unit.")
        text.append(table(["kernel", "units", "W1 ns/unit", "W2 ns/unit", "W1 CPU ns/unit", "cycles/unit",
                           "ops/unit", "ops/cycle", "work per unit"], crows, right={1, 2, 3, 4, 5, 6, 7}))
    return "\n\n".join(text), misses


def compile_table(results: list[Result]) -> str:
    fams: dict = {}
    for r in results:
        f = fams.setdefault(r.case.family, [0.0, 0.0, 0])
        w2, ti = r.med("warp2"), r.med("taichi")
        f[0] += max(r.first["warp2"] - (w2 or 0.0), 0.0)
        f[1] += max(r.first["taichi"] - (ti or 0.0), 0.0)
        f[2] += 1
    rows = [[fam, str(n), f"{w:.2f}", f"{t:.2f}"] for fam, (w, t, n) in fams.items()]
    tot_w, tot_t = sum(v[0] for v in fams.values()), sum(v[1] for v in fams.values())
    rows.append(["total", str(sum(v[2] for v in fams.values())), f"{tot_w:.2f}", f"{tot_t:.2f}"])
    return table(["family", "host functions", "Warp s", "Taichi s"], rows)


# ----------------------------------------------------------------------------
# Main
# ----------------------------------------------------------------------------

def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--size", nargs=2, type=int, metavar=("H", "W"), default=None,
                   help="image size (default 480 640; 120 160 with --quick)")
    p.add_argument("--frames", type=int, default=None, help="frames T (default 8; 3 with --quick)")
    p.add_argument("--repeat", type=int, default=None, help="timed rounds per kernel (default 5; 2 with --quick)")
    p.add_argument("--only", nargs="+", metavar="FAMILY", default=None, help=f"families among {FAMILIES}")
    p.add_argument("--quick", action="store_true", help="small input, few repeats: a smoke run")
    p.add_argument("--ref-budget", type=float, default=None,
                   help="seconds the reference may take on one crop (default 2; 0.2 with --quick)")
    p.add_argument("--no-reference", action="store_true", help="skip the NumPy reference")
    p.add_argument("--no-analysis", action="store_true", help="skip the compute-bound breakdown")
    p.add_argument("--warm-cache", action="store_true",
                   help="use the normal Warp/Taichi kernel caches (first call = load, not compile)")
    p.add_argument("--tiny-ms", type=float, default=2.0,
                   help="kernels under this many ms on 1 thread are 'tiny' (no 2-thread expectation)")
    p.add_argument("--case-budget", type=float, default=6.0,
                   help="stop repeating a kernel after this many seconds (at least 3 rounds)")
    p.add_argument("--json", metavar="PATH", default=None, help="also write every measurement as JSON")
    args = p.parse_args(argv)
    if args.only:
        unknown = sorted(set(args.only) - set(FAMILIES))
        if unknown:
            p.error(f"unknown families {unknown}; choose among {', '.join(FAMILIES)}")
    H, W = args.size if args.size else ((120, 160) if args.quick else (480, 640))
    if H < 16 or W < 16:
        p.error(f"--size must be at least 16 x 16, got {H} x {W}")
    args.size = (H, W)
    args.frames = args.frames if args.frames is not None else (3 if args.quick else 8)
    if args.frames < 2:
        p.error(f"--frames must be >= 2 (the temporal kernels need a pair), got {args.frames}")
    args.repeat = args.repeat if args.repeat is not None else (2 if args.quick else 5)
    if args.repeat < 1:
        p.error(f"--repeat must be >= 1, got {args.repeat}")
    args.ref_budget = args.ref_budget if args.ref_budget is not None else (0.2 if args.quick else 2.0)
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    families = [f for f in FAMILIES if not args.only or f in args.only]
    t_total = time.perf_counter()
    cache_dir = None
    wp.config.log_level = wp.LOG_WARNING
    if hasattr(wp, "LOG_WARNING"):
        wp.config.log_level = wp.LOG_WARNING  # no greeting, no per-module load lines
    if not args.warm_cache:
        cache_dir = tempfile.TemporaryDirectory(prefix="ivkernels-bench-cache-")
        wp.config.kernel_cache_dir = os.path.join(cache_dir.name, "warp")
        os.environ["TI_OFFLINE_CACHE_FILE_PATH"] = os.path.join(cache_dir.name, "taichi")
    from ivkernels.backends import get_backend

    H, W = args.size
    T = args.frames
    print(f"# ivkernels kernel benchmark: {H}x{W}, {T} frames, {args.repeat} rounds", flush=True)
    print(f"machine: {os.cpu_count()} CPUs ({cpu_model()}, {cpu_ghz():.2f} GHz), "
          f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; python {platform.python_version()}, "
          f"numpy {np.__version__}, warp {wp.config.version}", flush=True)
    t0 = time.perf_counter()
    warp_be = get_backend("warp")
    t_warp_init = time.perf_counter() - t0
    from ivkernels.kernels.launch import threads
    from ivkernels.kernels.taichi import init as taichi_init

    t0 = time.perf_counter()
    with threads(2):
        ti_be = get_backend("taichi")
    taichi_init(threads=2)  # idempotent; Taichi runs on 2 threads whatever the launch setting was
    t_ti_init = time.perf_counter() - t0
    import taichi as ti
    ti.set_logging_level(ti.ERROR)  # compile-time warnings would interleave with the table
    print(f"taichi {'.'.join(map(str, ti.__version__))} (2 threads); init Warp {t_warp_init:.2f} s, "
          f"Taichi {t_ti_init:.2f} s; kernel caches: "
          f"{'normal (warm)' if args.warm_cache else 'fresh private directories (first calls compile)'}",
          flush=True)

    capacity = two_thread_capacity()
    print(f"2-thread capacity (a pure-arithmetic Warp kernel, 1 vs 2 threads): {capacity:.2f}x", flush=True)
    n_roof = (1 << 23) if args.quick else (1 << 25)
    roof = measure_roof(n_roof, 3 if args.quick else 10)
    print("\nmemory roof (best of repeated streaming runs, GB/s of bytes read + written, wall / CPU time, "
          f"{n_roof * 4 / 2**20:.0f} MiB per array): "
          + ", ".join(f"{k} {v[0]:.1f} / {v[1]:.1f}" for k, v in roof.items() if k != "roof")
          + f"; roof = {roof['roof']:.1f} GB/s", flush=True)

    t0 = time.perf_counter()
    scene = make_scene(T, H, W)
    print(f"inputs: {T} frames {H}x{W} made in {time.perf_counter() - t0:.1f} s; "
          f"w_bnd covers {scene.w_bnd.mean() * 100:.1f}% of the flow frames' pixels, "
          f"occluded {100 - scene.occ.mean() * 100:.1f}%, |flow| mean "
          f"{np.sqrt((scene.flow ** 2).sum(-1)).mean():.2f} px\n", flush=True)

    cases = [c for c in build_cases() if c.family in families]
    backends = {"warp": warp_be, "taichi": ti_be}
    results: dict = {}
    skipped = []
    for family in families:
        fam_cases = [c for c in cases if c.family == family]
        try:
            getattr(warp_be, family), getattr(ti_be, family)
        except Exception as exc:  # a family still being written
            skipped.append(f"{family}: {type(exc).__name__}: {exc}")
            print(f"skip {family}: {type(exc).__name__}: {exc}", flush=True)
            continue
        for case in fam_cases:
            try:
                r = run_case(case, scene, backends, args.repeat, args.case_budget, args.ref_budget,
                             not args.no_reference)
            except Exception as exc:
                skipped.append(f"{case.key}: {type(exc).__name__}: {exc}")
                print(f"skip {case.key}: {type(exc).__name__}: {exc}", flush=True)
                continue
            results[case.key] = r
            print(f"  {case.key:<42} W1 {ms(r.med('warp1')):>8}  W2 {ms(r.med('warp2')):>8}  "
                  f"TI {ms(r.med('taichi')):>8}  NP {ms(r.ref, r.ref_where != 'full'):>9} ({r.ref_where})  "
                  f"first W {ms(r.first['warp2'])} TI {ms(r.first['taichi'])}", flush=True)

    ghz = cpu_ghz()
    lines = []
    if not args.no_analysis and {"median", "energy_albedo_gsm", "energy_albedo_entropy"} & set(families):
        lines = analyse(scene, backends, results, args.repeat)
    ordered = list(results.values())
    text, misses = report(ordered, scene, roof, args.tiny_ms, ghz)
    print("\n## Kernels\n")
    print("W1/W2: Warp on 1/2 threads, TI: Taichi (2 threads), NP: NumPy reference ('~': scaled from the "
          "crop in 'NP on'); times are medians in ms; ratios X/W2 > 1 mean Warp-2 is faster; MB: minimal "
          "bytes moved; GB/s: MB / W2 time (GB/s cpu: MB / CPU time of the busier band); roof: GB/s as a "
          "fraction of the measured roof "
          f"({roof['roof']:.1f} GB/s); cpu: the 2-thread speedup predicted from CPU time (1-thread CPU "
          "time / CPU time of the busier band; what an idle machine would show); split: the best "
          "2-thread speedup the row split allows (work per band); 1st: first call (compile + load + one run); "
          "work: f frames, "
          "p pairs, M vector elements; check: 2T<1.7 = two threads under 1.7x on a kernel >= "
          f"{args.tiny_ms:g} ms ('(load)': the CPU-time prediction passes, the wall time lost to other "
          "processes), roof>3x = memory-bound kernel under a third of the roof ('(load)': GB/s cpu is "
          "within it).\n", flush=True)
    print(text)
    if lines:
        print("\n## Arithmetic-bound kernels, measured\n")
        for line in lines:
            print(("- " + line) if not line.startswith("  ") else line)
    print("\n## First-call cost per family (sum over host functions of first call - median call, s)\n")
    print(compile_table(ordered))
    print("\n## Expectations missed\n")
    for kind, title in (("threads", f"Warp 2 threads >= 1.7x Warp 1 thread (kernels >= {args.tiny_ms:g} ms)"),
                        ("roof", "memory-bound kernels within 3x of the roof")):
        these = [m for m in misses if m["kind"] == kind]
        print(f"{title}: {len(these)} missed by wall time", flush=True)
        load = [m["kernel"] for m in these if m["load_only"]]
        if load:
            print(f"- lost to other processes only (the CPU-time figure passes): {', '.join(load)}")
        for m in these:
            if not m["load_only"]:
                print(f"- {m['kernel']}: {m['text']}")
        print()
    if skipped:
        print("\n## Skipped\n")
        for s in skipped:
            print(f"- {s}")
    capacity_end = two_thread_capacity()
    elapsed = time.perf_counter() - t_total
    print(f"\n2-thread capacity at the end: {capacity_end:.2f}x (at the start {capacity:.2f}x)")
    print(f"load average at the end {' '.join(f'{v:.2f}' for v in os.getloadavg())}; total {elapsed:.0f} s")
    if args.json:
        payload = {
            "size": [H, W], "frames": T, "repeat": args.repeat, "roof": roof, "cpu": cpu_model(),
            "two_thread_capacity": [capacity, capacity_end],
            "nproc": os.cpu_count(), "warm_cache": args.warm_cache,
            "kernels": {k: {"times": r.times, "cpu": r.cpu, "first": r.first, "ref": r.ref, "ref_on": r.ref_where,
                            "bytes": r.nbytes, "bound": r.case.bound} for k, r in results.items()},
            "analysis": lines, "misses": misses, "skipped": skipped,
        }
        with open(args.json, "w") as f:
            json.dump(payload, f, indent=1)
    if cache_dir is not None:
        try:
            cache_dir.cleanup()
        except OSError:
            pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
