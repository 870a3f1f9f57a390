"""Where every second of the default decompose() goes: stages, kernel families, host steps, the roof.

Runs the default :func:`ivkernels.decompose` (estimated flow, two passes) on
a rendered sequence (``objects_camera``, training seed 1, as
``perf/bench_solver.py``) and prints, after a warm-up that compiles the
kernels:

1. **the machine's roof**, measured here: a STREAM-like triad
   (``a = b + s c``, 12 bytes per element) and the peak FLOP rate of a Warp
   CPU kernel (independent FMA chains, the scalar code our kernels compile
   to) on the launch threads, and of BLAS ``sgemm`` (SIMD, every core);
   plus the cost of one empty launch (8 array arguments) and of one launch
   split into row bands (:func:`ivkernels.kernels.launch.launch_rows`);
2. **seconds per stage**: flow pass 1, the guide solve, flow pass 2+, the
   backward flow of the forward-backward check (``Params.flow_round_trip_max``;
   on the calling thread here, on a second thread in a plain run), the
   motion maps (with the still-surface map of a still camera), the full
   solve and the rest (conversion, output); for each,
   the time inside kernel-family host functions, the estimated launch
   overhead (launches times the empty launch), host syncs and ``.numpy()``,
   allocations, and the host work between launches (the stage's time
   outside every family function and backend call: Python and NumPy), the
   number of launches and of energy evaluations;
3. **each kernel host function**: calls, seconds, share, launches, the bytes
   its array arguments hold (each read or written once: a lower bound of its
   memory traffic), the achieved GB/s against the STREAM rate, and, for the
   functions in :data:`FLOPS_PER_ELEMENT`, flops (counted from the kernel
   source per output element) against the FMA peak;
4. with ``--cprofile`` (default), a second run under :mod:`cProfile`: the
   host functions by own time, grouped (kernel execution on the calling
   thread, waits on the launch pool, Warp's launch packing, NumPy, the
   package's Python), and the top entries.

Instrumentation wraps the backend object's family modules
(``be.flow_classic``, ``be.median`` ...), its array methods and
``warp.launch``; no kernel is edited.  Timings of the first run carry the
wrappers' overhead only (a few microseconds per call, printed).

    python perf/profile.py                                  # 8 frames at 640x480, 2 threads
    python perf/profile.py --size 240 320 --frames 8 --no-cprofile
    python perf/profile.py --device cuda --no-cprofile      # on a GPU: every timed call waits for it

On a CUDA device the roof is the device's (a one-element-per-thread triad,
FMA chains, a launch with and without a wait), and a last table gives the
threads per launch of the most launched kernels against the threads the
device holds at once.

(``perf/profile.py`` runs this module's :func:`main`.)
"""
from __future__ import annotations

import argparse
import contextlib
import cProfile
import functools
import os
import pstats
import sys
import threading
import time
from collections import defaultdict

import numpy as np
import warp as wp

import ivkernels as iv
from ivkernels.evaluation import synthetic
from ivkernels.backends import get_backend
from ivkernels.backends.protocols import FAMILIES
from ivkernels.decompose import DEFAULT_FLOW_PASSES
from ivkernels.kernels.launch import launch_rows, set_threads

#: Flops per element of the launch's domain (the output's pixels, per frame
#: pair or frame), counted from the Warp kernel source of the hot functions:
#: adds, multiplies, divides, square roots and ``pow`` counted as one each
#: (a ``pow`` is tens of cycles: these are lower bounds of the work).
#: The element count is taken from the argument named in the second field.
FLOPS_PER_ELEMENT = {
    # red-black SOR, per pixel of one colour (half the pixels per call): 8 neighbour
    # products and sums (24), the 2x2 determinant and solve (13), the relaxation (8)
    ("flow_classic", "sor_sweep"): (0.5 * 45, "du/1"),
    # a full red-black sweep (sor_full_sweep): the same per pixel, every pixel once
    ("flow_classic", "sor_full_sweep"): (45, "du/1"),
    ("flow_classic", "assemble_system"): (40, "flow/1"),
    ("flow_classic", "smoothness_weights"): (4 * 8, "flow/1"),
    ("flow_classic", "data_coefficients_channels"): (2 * 3 * 22, "du/1"),
    ("sampling", "warp_bicubic"): (16 * 2 * 6 + 20, "flow/1"),
    ("median", "median5x5"): (2 * 25 * 5, "src/1"),
}


# --------------------------------------------------------------------- the roof

@wp.kernel
def _triad(row_begin: int, a: wp.array(dtype=wp.float32), b: wp.array(dtype=wp.float32),
           c: wp.array(dtype=wp.float32), s: float, width: int):
    r = row_begin + wp.tid()
    for x in range(width):
        i = r * width + x
        a[i] = b[i] + s * c[i]


@wp.kernel
def _fma_chains(row_begin: int, out: wp.array(dtype=wp.float32), n_iter: int):
    r = row_begin + wp.tid()
    x0 = float(r) * 1.0e-7
    x1 = x0 + 0.1
    x2 = x0 + 0.2
    x3 = x0 + 0.3
    x4 = x0 + 0.4
    x5 = x0 + 0.5
    x6 = x0 + 0.6
    x7 = x0 + 0.7
    for _ in range(n_iter):
        x0 = x0 * 0.999 + 0.001
        x1 = x1 * 0.999 + 0.001
        x2 = x2 * 0.999 + 0.001
        x3 = x3 * 0.999 + 0.001
        x4 = x4 * 0.999 + 0.001
        x5 = x5 * 0.999 + 0.001
        x6 = x6 * 0.999 + 0.001
        x7 = x7 * 0.999 + 0.001
    out[r] = x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7


@wp.kernel
def _empty8(row_begin: int, a0: wp.array(dtype=wp.float32), a1: wp.array(dtype=wp.float32),
            a2: wp.array(dtype=wp.float32), a3: wp.array(dtype=wp.float32), a4: wp.array(dtype=wp.float32),
            a5: wp.array(dtype=wp.float32), a6: wp.array(dtype=wp.float32), a7: wp.array(dtype=wp.float32),
            s: float):
    r = row_begin + wp.tid()
    if r < 0:
        a0[0] = s


def _best(fn, repeats: int) -> float:
    fn()
    return min(_timed(fn) for _ in range(repeats))


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


@wp.kernel
def _triad_flat(a: wp.array(dtype=wp.float32), b: wp.array(dtype=wp.float32),
                c: wp.array(dtype=wp.float32), s: float):
    i = wp.tid()
    a[i] = b[i] + s * c[i]


def measure_roof_cuda(device: str) -> dict:
    """The same roof on a CUDA device: a one-element-per-thread triad (coalesced), FMA
    chains on 2^20 threads, the host cost of one empty launch (no wait), and one
    launch followed by a wait (a round trip, as a ``.numpy()`` after a launch costs)."""
    n = 1 << 26                                    # 64 Mi floats, 256 MiB per array
    a = wp.zeros(n, dtype=wp.float32, device=device)
    b = wp.ones(n, dtype=wp.float32, device=device)
    c = wp.ones(n, dtype=wp.float32, device=device)

    def synced(fn):
        def inner():
            fn()
            wp.synchronize_device(device)
        return inner
    t = _best(synced(lambda: wp.launch(_triad_flat, dim=n, inputs=[a, b, c, 2.0], device=device)), 5)
    stream = 12.0 * n / t
    n_iter, frows = 2000, 1 << 20
    out = wp.zeros(frows, dtype=wp.float32, device=device)
    t = _best(synced(lambda: wp.launch(_fma_chains, dim=frows, inputs=[0, out, n_iter], device=device)), 3)
    fma_peak = 2.0 * 8 * n_iter * frows / t
    small = [wp.zeros(4, dtype=wp.float32, device=device) for _ in range(8)]
    reps = 2000
    synced(lambda: wp.launch(_empty8, dim=1, inputs=[0, *small, 1.0], device=device))()
    t0 = time.perf_counter()
    for _ in range(reps):
        wp.launch(_empty8, dim=1, inputs=[0, *small, 1.0], device=device)
    launch_s = (time.perf_counter() - t0) / reps
    wp.synchronize_device(device)
    t0 = time.perf_counter()
    for _ in range(reps // 4):
        wp.launch(_empty8, dim=1, inputs=[0, *small, 1.0], device=device)
        wp.synchronize_device(device)
    round_trip = (time.perf_counter() - t0) / (reps // 4)
    return {"stream_Bps": stream, "fma_flops": fma_peak, "blas_flops": 0.0,
            "launch_s": launch_s, "split_launch_s": round_trip, "threads": 1, "device": device}


def measure_roof(threads: int, device: str = "cpu") -> dict:
    """STREAM-like triad bandwidth, FMA peaks and launch costs on this machine
    (on a CUDA ``device``: :func:`measure_roof_cuda`)."""
    if device != "cpu":
        return measure_roof_cuda(device)
    width, rows = 4096, 4096                      # 16 Mi floats, 64 MiB per array
    n = width * rows
    a = wp.zeros(n, dtype=wp.float32, device="cpu")
    b = wp.array(np.ones(n, np.float32), device="cpu")
    c = wp.array(np.ones(n, np.float32), device="cpu")
    t = _best(lambda: launch_rows(_triad, rows, [a, b, c, 2.0, width]), 5)
    stream = 12.0 * n / t
    n_iter, frows = 20000, 4096
    out = wp.zeros(frows, dtype=wp.float32, device="cpu")
    t = _best(lambda: launch_rows(_fma_chains, frows, [out, n_iter]), 3)
    fma_peak = 2.0 * 8 * n_iter * frows / t
    m = np.random.default_rng(0).random((2048, 2048), dtype=np.float32)
    t = _best(lambda: m @ m, 3)
    blas_peak = 2.0 * 2048 ** 3 / t
    small = [wp.zeros(4, dtype=wp.float32, device="cpu") for _ in range(8)]
    wp.launch(_empty8, dim=1, inputs=[0, *small, 1.0], device="cpu")
    reps = 2000
    t0 = time.perf_counter()
    for _ in range(reps):
        wp.launch(_empty8, dim=1, inputs=[0, *small, 1.0], device="cpu")
    launch_s = (time.perf_counter() - t0) / reps
    big = [wp.zeros(480 * 640, dtype=wp.float32, device="cpu") for _ in range(8)]
    launch_rows(_empty8, 480, [*big, 1.0])
    t0 = time.perf_counter()
    for _ in range(reps // 4):
        launch_rows(_empty8, 480, [*big, 1.0])
    split_s = (time.perf_counter() - t0) / (reps // 4)
    return {"stream_Bps": stream, "fma_flops": fma_peak, "blas_flops": blas_peak,
            "launch_s": launch_s, "split_launch_s": split_s, "threads": threads, "device": "cpu"}


# --------------------------------------------------------------- instrumentation

def _nbytes(a) -> int:
    if isinstance(a, wp.array):
        return int(a.size) * wp.types.type_size_in_bytes(a.dtype)
    if isinstance(a, np.ndarray):
        return int(a.nbytes)
    return 0


def _elements(args, kwargs, names, spec: str) -> int:
    """Element count of ``spec`` = ``"<argument>/<trailing dims to drop>"`` (``"du/1"``:
    the pixels of a (T, H, W, 2) ``du``)."""
    name, _, drop = spec.partition("/")
    value = kwargs.get(name)
    if value is None and name in names:
        i = names.index(name)
        value = args[i] if i < len(args) else None
    if value is None or not hasattr(value, "shape"):
        return 0
    shape = tuple(value.shape)
    shape = shape[: len(shape) - int(drop or 0)] if int(drop or 0) else shape
    return int(np.prod(shape)) if shape else 0


class Recorder:
    """Counts and times of one decomposition, keyed by stage."""

    STAGES = ("flow pass 1", "guide solve", "flow pass 2+", "back flow", "maps", "full solve", "other")

    def __init__(self, device: str = "cpu"):
        #: a CUDA device to wait on around every timed call (launches there return at once)
        self.sync_device = None if device == "cpu" else device
        self.stack: list[str] = []
        self.stage_s = defaultdict(float)
        self.kernels = defaultdict(lambda: [0, 0.0, 0, 0, 0.0])   # calls, s, launches, bytes, flops
        self.host = defaultdict(lambda: [0, 0.0])                 # (stage, step) -> calls, s
        self.launches = defaultdict(int)                          # stage -> launches
        self.pool_launches = defaultdict(int)
        self.evaluations = defaultdict(int)
        self.launch_dims = defaultdict(lambda: [0, 0])            # kernel name -> launches, threads
        self.depth = threading.local()
        self.main = threading.get_ident()
        self.lock = threading.Lock()

    def stage(self) -> str:
        return self.stack[0] if self.stack else "other"

    @contextlib.contextmanager
    def in_stage(self, name: str):
        if self.stack:                     # an outer stage owns the time
            self.stack.append(name)
            try:
                yield
            finally:
                self.stack.pop()
            return
        self.stack.append(name)
        self.wait()
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.wait()
            self.stage_s[name] += time.perf_counter() - t0
            self.stack.pop()

    def wait(self) -> None:
        """On a CUDA device, wait for the queued kernels (so their time lands where they ran)."""
        if self.sync_device is not None:
            wp.synchronize_device(self.sync_device)


def _wrap_family(rec: Recorder, family: str, module):
    """A stand-in for a family module whose host functions record their calls."""
    import inspect

    class Proxy:
        def __getattr__(self, name):
            return getattr(module, name)

    proxy = Proxy()
    for name, fn in vars(module).items():
        home = getattr(fn, "__module__", None) or ""
        # the family's own functions, also when the family is a package of modules
        if name.startswith("_") or not inspect.isfunction(fn) or \
                not (home == module.__name__ or home.startswith(module.__name__ + ".")):
            continue
        try:
            names = list(inspect.signature(fn).parameters)
        except (TypeError, ValueError):
            names = []
        flops_spec = FLOPS_PER_ELEMENT.get((family, name))

        def wrapped(*args, __fn=fn, __name=name, __names=names, __spec=flops_spec, **kwargs):
            depth = getattr(rec.depth, "n", 0)
            if depth or threading.get_ident() != rec.main:
                return __fn(*args, **kwargs)
            rec.depth.n = 1
            stage = rec.stage()
            before = rec.launches[stage]
            rec.wait()
            t0 = time.perf_counter()
            try:
                return __fn(*args, **kwargs)
            finally:
                rec.wait()
                dt = time.perf_counter() - t0
                rec.depth.n = 0
                row = rec.kernels[(stage, family, __name)]
                row[0] += 1
                row[1] += dt
                row[2] += rec.launches[stage] - before
                row[3] += sum(_nbytes(a) for a in args) + sum(_nbytes(a) for a in kwargs.values())
                if __spec is not None:
                    row[4] += __spec[0] * _elements(args, kwargs, __names, __spec[1])

        functools.update_wrapper(wrapped, fn)
        setattr(proxy, name, wrapped)
    return proxy


HOST_METHODS = {"numpy": "sync + .numpy()", "synchronize": "sync + .numpy()", "asarray": "allocate / upload",
                "empty": "allocate / upload", "zeros": "allocate / upload", "zero": "allocate / upload"}


@contextlib.contextmanager
def instrumented(rec: Recorder, be):
    """Wrap ``be``'s families and array methods, ``warp.launch`` and the stage entry points."""
    import importlib

    undo = []

    def patch(owner, name, value):
        undo.append((owner, name, owner.__dict__.get(name, _MISSING) if isinstance(owner, type)
                     else getattr(owner, name, _MISSING)))
        setattr(owner, name, value)

    for family in FAMILIES:
        patch(be, family, _wrap_family(rec, family, getattr(be, family)))
    for method, step in HOST_METHODS.items():
        original = getattr(be, method)

        def host(*args, __orig=original, __step=step, **kwargs):
            if threading.get_ident() != rec.main or getattr(rec.depth, "n", 0):
                return __orig(*args, **kwargs)
            t0 = time.perf_counter()
            try:
                return __orig(*args, **kwargs)
            finally:
                row = rec.host[(rec.stage(), __step)]
                row[0] += 1
                row[1] += time.perf_counter() - t0
        patch(be, method, host)

    original_launch = wp.launch

    def launch(*args, **kwargs):
        stage = rec.stage()
        dim = kwargs.get("dim", args[1] if len(args) > 1 else 1)
        kernel = kwargs.get("kernel", args[0] if args else None)
        with rec.lock:
            rec.launches[stage] += 1
            row = rec.launch_dims[getattr(kernel, "key", "?")]
            row[0] += 1
            row[1] += int(np.prod(dim)) if not isinstance(dim, int) else dim
            if threading.get_ident() != rec.main:
                rec.pool_launches[stage] += 1
        return original_launch(*args, **kwargs)
    patch(wp, "launch", launch)

    from ivkernels.solver.energy import WindowEnergy

    original_evaluate = WindowEnergy.evaluate

    def evaluate(self, terms=None):
        rec.evaluations[rec.stage()] += 1
        return original_evaluate(self, terms)
    patch(WindowEnergy, "evaluate", evaluate)

    def staged(fn, label):
        @functools.wraps(fn)
        def inner(*args, **kwargs):
            if threading.get_ident() != rec.main:         # the stage stack is the calling thread's
                return fn(*args, **kwargs)
            name = label(args, kwargs) if callable(label) else label
            with rec.in_stage(name):
                return fn(*args, **kwargs)
        return inner

    dec = importlib.import_module("ivkernels.decompose")     # the module, not the function
    patch(dec._Decomposer, "_first_pass_flow", staged(dec._Decomposer._first_pass_flow, "flow pass 1"))
    patch(dec._Decomposer, "_back_flow_for", staged(dec._Decomposer._back_flow_for, "back flow"))
    # the second thread's flows (the next window's, the backward flow) run on the calling
    # thread here, so that every second has its stage
    patch(dec, "FLOW_AHEAD", False)

    def patch_everywhere(name, original, replacement):
        """Replace ``original`` under ``name`` in every module of the package that holds it
        (the modules import their entry points at their tops)."""
        for modname, module in list(sys.modules.items()):
            if (modname == "ivkernels" or modname.startswith("ivkernels.")) \
                    and getattr(module, name, None) is original:
                patch(module, name, replacement)

    flow_pkg = importlib.import_module("ivkernels.flow")
    patch_everywhere("estimate_flow", flow_pkg.estimate_flow,
                     staged(flow_pkg.estimate_flow,
                            lambda a, k: "flow pass 2+" if k.get("init") is not None else "flow pass 1"))
    guide = importlib.import_module("ivkernels.solver.guide")
    patch_everywhere("guide_solve", guide.guide_solve, staged(guide.guide_solve, "guide solve"))
    maps_mod = importlib.import_module("ivkernels.solver.motion_maps")
    patch_everywhere("motion_maps", maps_mod.motion_maps, staged(maps_mod.motion_maps, "maps"))
    still = importlib.import_module("ivkernels.solver.still_flow")
    patch_everywhere("still_surface_mask", still.still_surface_mask, staged(still.still_surface_mask, "maps"))
    ws = importlib.import_module("ivkernels.solver.window_solver")
    patch_everywhere("solve_window", ws.solve_window, staged(ws.solve_window, "full solve"))
    try:
        yield rec
    finally:
        for owner, name, old in reversed(undo):
            if old is _MISSING:
                delattr(owner, name)
            else:
                setattr(owner, name, old)


_MISSING = object()


# --------------------------------------------------------------------- running

def run(args, params, rec: Recorder | None = None, profiler=None) -> tuple[float, object]:
    seq = synthetic.render_sequence(args.kind, n_frames=args.frames, size=tuple(args.size), seed=args.seed)
    be = get_backend(args.backend, args.device)
    ctx = instrumented(rec, be) if rec is not None else contextlib.nullcontext()
    with ctx:
        if profiler is not None:
            profiler.enable()
        t0 = time.perf_counter()
        video = iv.decompose(seq.frames, backend=args.backend, params=params, threads=args.threads,
                             flow_passes=args.flow_passes, device=args.device)
        total = time.perf_counter() - t0
        if profiler is not None:
            profiler.disable()
    return total, video


def run_flow(args, rec: Recorder | None = None, profiler=None) -> tuple[float, object]:
    """``estimate_flow`` (``--flow METHOD``) on the Middlebury pairs ``--pairs``, one call per pair."""
    import importlib

    from eval_flow import default_data_dir, middlebury_pairs, parse_settings

    flow_pkg = importlib.import_module("ivkernels.flow")
    options = parse_settings(args.flow_set)
    pairs = list(middlebury_pairs(default_data_dir(), args.pairs))
    be = get_backend(args.backend, args.device)
    ctx = instrumented(rec, be) if rec is not None else contextlib.nullcontext()
    total = 0.0
    with ctx:
        for _, frames, _ in pairs:
            if profiler is not None:
                profiler.enable()
            t0 = time.perf_counter()
            flow_pkg.estimate_flow(frames, method=args.flow, backend=args.backend, threads=args.threads,
                                   device=args.device, **options)
            total += time.perf_counter() - t0
            if profiler is not None:
                profiler.disable()
    return total, None


def wrapper_overhead() -> float:
    """Seconds one wrapped family call adds (measured on a no-op)."""
    import types

    rec = Recorder()
    mod = types.ModuleType("fake_family")

    def noop(a, b):
        return None
    noop.__module__ = mod.__name__
    mod.noop = noop
    proxy = _wrap_family(rec, "fake", mod)
    n = 20000
    t0 = time.perf_counter()
    for _ in range(n):
        proxy.noop(1, 2)
    wrapped = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(n):
        noop(1, 2)
    return (wrapped - (time.perf_counter() - t0)) / n


def print_roof(roof: dict) -> None:
    if roof["device"] != "cpu":
        print(f"\n== device roof ({roof['device']}: {wp.get_device(roof['device']).name}, "
              f"{wp.get_device(roof['device']).sm_count} SMs)")
        print(f"  triad, one element per thread          {roof['stream_Bps'] / 1e9:8.1f} GB/s")
        print(f"  FMA chains, 2^20 threads               {roof['fma_flops'] / 1e9:8.1f} GFLOP/s")
        print(f"  one empty launch, host side (no wait)  {roof['launch_s'] * 1e6:8.1f} us")
        print(f"  one launch and a wait (round trip)     {roof['split_launch_s'] * 1e6:8.1f} us")
        return
    print(f"\n== machine roof ({roof['threads']} launch threads, cores {os.cpu_count()}, "
          f"load {os.getloadavg()[0]:.2f})")
    print(f"  STREAM-like triad (Warp kernel)        {roof['stream_Bps'] / 1e9:8.2f} GB/s")
    print(f"  FMA peak, Warp CPU kernel (scalar)     {roof['fma_flops'] / 1e9:8.2f} GFLOP/s")
    print(f"  FMA peak, BLAS sgemm (SIMD)            {roof['blas_flops'] / 1e9:8.2f} GFLOP/s")
    print(f"  one empty launch (8 arrays)            {roof['launch_s'] * 1e6:8.1f} us")
    print(f"  one launch in row bands (480 rows)     {roof['split_launch_s'] * 1e6:8.1f} us")


def print_stages(rec: Recorder, total: float, roof: dict, diag_seconds: dict, plain_total) -> None:
    stages = [s for s in Recorder.STAGES if s in rec.stage_s or s == "other"]
    stage_s = dict(rec.stage_s)
    stage_s["other"] = total - sum(rec.stage_s.values())
    fam_s = defaultdict(float)
    for (stage, _, _), row in rec.kernels.items():
        fam_s[stage] += row[1]
    host_s = defaultdict(float)
    for (stage, step), row in rec.host.items():
        host_s[(stage, step)] += row[1]
    print(f"\n== seconds per stage (instrumented run {total:.1f} s"
          + (f"; plain run {plain_total:.1f} s" if plain_total else "") + ")")
    head = (f"  {'stage':<13}{'s':>8}{'share':>7}{'in kernels':>11}{'launch ovh':>11}{'sync/.np':>9}"
            f"{'alloc':>7}{'host py/np':>11}{'launches':>9}{'evals':>7}")
    print(head)
    print("  " + "-" * (len(head) - 2))
    sums = defaultdict(float)
    for s in stages:
        sec = stage_s.get(s, 0.0)
        n_launch = rec.launches.get(s, 0)
        ovh = n_launch * roof["launch_s"]
        sync = host_s.get((s, "sync + .numpy()"), 0.0)
        alloc = host_s.get((s, "allocate / upload"), 0.0)
        hostwork = sec - fam_s.get(s, 0.0) - sync - alloc
        row = (sec, fam_s.get(s, 0.0), ovh, sync, alloc, hostwork, n_launch, rec.evaluations.get(s, 0))
        for k, v in zip(("s", "k", "o", "sy", "a", "h", "l", "e"), row):
            sums[k] += v
        print(f"  {s:<13}{sec:8.2f}{100 * sec / total:6.1f}%{row[1]:11.2f}{ovh:11.2f}{sync:9.2f}{alloc:7.2f}"
              f"{hostwork:11.2f}{n_launch:9d}{row[7]:7d}")
    print("  " + "-" * (len(head) - 2))
    print(f"  {'total':<13}{sums['s']:8.2f}{100.0:6.1f}%{sums['k']:11.2f}{sums['o']:11.2f}{sums['sy']:9.2f}"
          f"{sums['a']:7.2f}{sums['h']:11.2f}{int(sums['l']):9d}{int(sums['e']):7d}")
    print("  'in kernels': inside family host functions (kernels, their launches, their own host code);\n"
          "  'launch ovh': launches x one empty launch (part of 'in kernels'); 'host py/np': the stage's\n"
          "  time outside family functions and backend calls (Python, NumPy, L-BFGS vector algebra).")
    print("  decompose()'s own diagnostics['seconds']: "
          + ", ".join(f"{k} {v:.2f}" for k, v in diag_seconds.items()))


def print_families(rec: Recorder, total: float) -> None:
    fam = defaultdict(lambda: [0, 0.0, 0])
    by_stage = defaultdict(float)
    for (stage, family, _), row in rec.kernels.items():
        f = fam[family]
        f[0] += row[0]
        f[1] += row[1]
        f[2] += row[2]
        by_stage[(family, stage)] += row[1]
    stages = [s for s in Recorder.STAGES if any(k[1] == s for k in by_stage)]
    print("\n== seconds per kernel family, by stage")
    print(f"  {'family':<22}{'calls':>8}{'s':>8}{'share':>7}{'launches':>9}"
          + "".join(f"{s[:12]:>13}" for s in stages))
    for family, (calls, sec, launches) in sorted(fam.items(), key=lambda kv: -kv[1][1]):
        print(f"  {family:<22}{calls:8d}{sec:8.2f}{100 * sec / total:6.1f}%{launches:9d}"
              + "".join(f"{by_stage.get((family, s), 0.0):13.2f}" for s in stages))


def print_kernels(rec: Recorder, total: float, roof: dict, top: int) -> None:
    agg = defaultdict(lambda: [0, 0.0, 0, 0, 0.0])
    for (stage, family, name), row in rec.kernels.items():
        a = agg[(family, name)]
        for i in range(5):
            a[i] += row[i]
    print(f"\n== kernel host functions (top {top} by time) against the roof")
    print(f"  {'family.function':<46}{'calls':>7}{'s':>8}{'share':>7}{'ms/call':>8}{'launch':>7}"
          f"{'GB':>8}{'GB/s':>7}{'%STRM':>6}{'GFLOP':>7}{'GF/s':>6}{'%FMA':>5}")
    for (family, name), (calls, sec, launches, nbytes, flops) in \
            sorted(agg.items(), key=lambda kv: -kv[1][1])[:top]:
        bw = nbytes / sec if sec > 0 else 0.0
        fl = f"{flops / 1e9:7.2f}{flops / sec / 1e9:6.2f}{100 * flops / sec / roof['fma_flops']:5.0f}" \
            if flops else f"{'':7}{'':6}{'':5}"
        print(f"  {family + '.' + name:<46}{calls:7d}{sec:8.2f}{100 * sec / total:6.1f}%"
              f"{1e3 * sec / max(calls, 1):8.2f}{launches:7d}{nbytes / 1e9:8.2f}{bw / 1e9:7.2f}"
              f"{100 * bw / roof['stream_Bps']:5.0f}%" + fl)
    print("  GB: bytes of the array arguments (each touched once, a lower bound of the traffic);\n"
          "  GFLOP: counted per element from the kernel source (perf/profile.py FLOPS_PER_ELEMENT).")


def print_launch_widths(rec: Recorder, roof: dict, top: int) -> None:
    """Threads per launch of the most launched kernels, against what the device holds at once."""
    if roof["device"] == "cpu":
        return
    dev = wp.get_device(roof["device"])
    resident = dev.sm_count * 2048
    print(f"\n== threads per launch (top {top} kernels by launches; {dev.sm_count} SMs hold "
          f"{resident} threads at once)")
    print(f"  {'kernel':<44}{'launches':>9}{'threads/launch':>15}{'of resident':>12}")
    for key, (n, threads) in sorted(rec.launch_dims.items(), key=lambda kv: -kv[1][0])[:top]:
        mean = threads / max(n, 1)
        print(f"  {str(key)[:44]:<44}{n:9d}{mean:15.0f}{100 * mean / resident:11.1f}%")


def _category(key) -> str:
    filename, _, func = key
    if filename == "~":
        if "acquire" in func or "wait" in func:
            return "waiting on launch threads (lock / wait)"
        if "numpy" in func or "ufunc" in func or "ndarray" in func or func.startswith("<method 'reduce'"):
            return "NumPy (C)"
        return "other built-ins"
    if "/warp/" in filename and func == "invoke":
        return "kernel execution on the calling thread (Warp invoke)"
    if "/numpy/" in filename:
        return "NumPy (Python)"
    if "/warp/" in filename:
        return "Warp launch packing (Python)"
    if "/ivkernels/" in filename or filename.endswith("profile.py"):
        return "ivkernels host code (Python)"
    if "/threading.py" in filename or "concurrent/futures" in filename:
        return "thread pool (Python)"
    return "other Python"


def print_cprofile(profiler, total: float, top: int) -> None:
    stats = pstats.Stats(profiler)
    cats = defaultdict(float)
    rows = []
    for key, (cc, nc, tt, ct, _) in stats.stats.items():
        cats[_category(key)] += tt
        rows.append((tt, nc, ct, key))
    print(f"\n== host steps under cProfile (own time of the calling thread; run {total:.1f} s)")
    for cat, sec in sorted(cats.items(), key=lambda kv: -kv[1]):
        print(f"  {cat:<50}{sec:8.2f} s {100 * sec / total:5.1f}%")
    print(f"\n  top {top} functions by own time")
    print(f"  {'own s':>8}{'calls':>9}{'cum s':>8}  function")
    for tt, nc, ct, (fn, line, func) in sorted(rows, key=lambda r: -r[0])[:top]:
        where = f"{os.path.basename(fn)}:{line}" if fn != "~" else ""
        print(f"  {tt:8.2f}{nc:9d}{ct:8.2f}  {func} {where}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, nargs=2, default=(480, 640), metavar=("H", "W"))
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--backend", default="warp", choices=("warp",))
    ap.add_argument("--device", default="cpu",
                    help="'cpu' or 'cuda[:N]': on CUDA every timed call waits for its kernels")
    ap.add_argument("--kind", default="objects_camera")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--flow-passes", type=int, default=DEFAULT_FLOW_PASSES)
    ap.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="Params fields")
    ap.add_argument("--plain", action="store_true", help="also time one run without instrumentation")
    ap.add_argument("--no-cprofile", dest="cprofile", action="store_false")
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--flow", default=None, metavar="METHOD",
                    help="profile estimate_flow(METHOD) on Middlebury pairs instead of decompose()")
    ap.add_argument("--pairs", nargs="+", default=["RubberWhale", "Urban3"], help="Middlebury pairs of --flow")
    ap.add_argument("--flow-set", nargs="*", default=[], metavar="FIELD=VALUE",
                    help="ClassicNLSettings fields of --flow")
    args = ap.parse_args(argv)
    import ast

    fields = {}
    for item in args.set:
        name, _, value = item.partition("=")
        try:
            fields[name] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            fields[name] = value
    params = iv.Params(**fields)
    set_threads(args.threads)
    H, W = args.size
    if args.flow:
        print(f"estimate_flow({args.flow!r}) on Middlebury {args.pairs}, {args.threads} threads"
              + (f", {args.flow_set}" if args.flow_set else ""))
    else:
        print(f"decompose(): {args.frames} frames at {W}x{H}, {args.kind} seed {args.seed}, backend {args.backend}, "
          f"{args.threads} threads, flow_passes {args.flow_passes}" + (f", {fields}" if fields else ""))
    tiny = synthetic.render_sequence("objects_camera", n_frames=3, size=(32, 40), seed=1)
    t0 = time.perf_counter()
    iv.decompose(tiny.frames, backend=args.backend, threads=args.threads, device=args.device)
    wp.force_load(device=args.device)       # every module the package imported, also those tiny frames skip
    print(f"warm-up (kernel compile / load) {time.perf_counter() - t0:.1f} s")
    roof = measure_roof(args.threads, args.device)
    print_roof(roof)
    print(f"  wrapper overhead per family call       {wrapper_overhead() * 1e6:8.1f} us")
    plain = None
    job = (lambda rec=None, profiler=None: run_flow(args, rec, profiler)) if args.flow else \
        (lambda rec=None, profiler=None: run(args, params, rec, profiler))
    if args.plain:
        plain, _ = job()
    rec = Recorder(args.device)
    total, video = job(rec)
    print_stages(rec, total, roof, video.diagnostics["seconds"] if video is not None else {}, plain)
    print_families(rec, total)
    print_kernels(rec, total, roof, args.top)
    print_launch_widths(rec, roof, args.top)
    if args.cprofile:
        profiler = cProfile.Profile()
        ptotal, _ = job(None, profiler)
        print_cprofile(profiler, ptotal, args.top)


if __name__ == "__main__":
    main()
