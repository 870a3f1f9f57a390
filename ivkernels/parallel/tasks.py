"""The work a task does, the same in this process and on a Ray worker.

A task is one video, or one chunk of a long video (:mod:`ivkernels.parallel.chunks`):
:func:`solve` runs :func:`ivkernels.decompose` on its frames.  The
functions here are plain Python; :mod:`ivkernels.parallel.engines` wraps them
as Ray tasks.  They are module-level so Ray ships them by reference (a worker
imports this module) rather than by value.

Per process, once (:func:`prepare_process`): the kernel launch thread count
is set to the task's ``threads`` (on a Ray worker the CPUs the task holds,
at least one) and, for the Taichi backend, Taichi is initialised with it (Taichi's
runtime is process-wide and must not be forked after ``ti.init``; Ray
starts its workers as fresh processes, so each initialises its own).
Per node, once (:func:`warm_up`): a tiny decomposition with the same
options compiles every kernel the call will use into Warp's (and Taichi's)
on-disk kernel cache, so the node's workers load kernels instead of each
compiling them at the same time.  On a local cluster that the call starts,
the same decomposition runs in the calling process instead
(:func:`warm_up_here`), while the cluster starts.
"""
from __future__ import annotations

import os
import time

import numpy as np

from ivkernels.decompose import IntrinsicVideo, decompose
from ivkernels.kernels import taichi as taichi_kernels
from ivkernels.kernels.thread_count import set_threads

#: Size of the clip :func:`warm_up` decomposes: (frames, height, width); two pyramid
#: levels at the default Params, so the resampling kernels compile too.
WARM_UP_SHAPE = (3, 48, 64)

# (backend, threads) this process was prepared for
_prepared: tuple | None = None


def prepare_process(backend: str, threads: int) -> None:
    """Set this process's kernel thread count and initialise Taichi once (see the module docstring)."""
    global _prepared
    if _prepared == (backend, threads):
        return
    set_threads(threads)
    if backend == "taichi":
        taichi_kernels.init(threads)
    _prepared = (backend, threads)


def solve(frames: np.ndarray, flow, options: dict) -> IntrinsicVideo:
    """Decompose one video or chunk.

    Parameters
    ----------
    frames : (T, H, W, 3) frames as :func:`ivkernels.decompose` takes them
        (read-only views into Ray's object store are fine: they are copied
        once into linear float32).
    flow : ``None``, a flow method name or a (T-1, H, W, 2) float array.
    options : the other keyword arguments of :func:`ivkernels.decompose`
        (``threads`` among them).

    Returns
    -------
    IntrinsicVideo; ``diagnostics["task"]`` adds the process id, the
    seconds the task took in it, the CPU seconds its process used
    meanwhile, when it started and finished (``time.time()``, seconds since
    the epoch, for a timeline across processes) and, on Ray, the node id.
    """
    started, t0, c0 = time.time(), time.perf_counter(), time.process_time()
    video = decompose(frames, flow=flow, **options)
    video.diagnostics["task"] = {"pid": os.getpid(), "seconds": time.perf_counter() - t0,
                                 "cpu_seconds": time.process_time() - c0,
                                 "started": started, "finished": time.time()}
    return video


def solve_in_worker(frames: np.ndarray, flow, options: dict) -> IntrinsicVideo:
    """:func:`solve` in a worker process of its own, prepared once by :func:`prepare_process`
    (never in the caller's process: it sets the process's thread count);
    ``diagnostics["task"]`` adds the node id, the kernel threads and the CPUs the task held."""
    import ray

    prepare_process(options.get("backend", "warp"), options["threads"])
    video = solve(frames, flow, options)
    context = ray.get_runtime_context()
    video.diagnostics["task"].update(node=context.get_node_id(), threads=options["threads"],
                                     cpus=context.get_assigned_resources().get("CPU"))
    return video


def _warm_up_clip(flow) -> tuple[np.ndarray, object]:
    """The tiny clip :func:`warm_up` decomposes, and its flow argument: the flow method
    named by ``flow``, or a zero flow when arrays are given."""
    T, H, W = WARM_UP_SHAPE
    y, x = np.mgrid[0:H, 0:W] / max(H, W)
    frame = np.stack([0.2 + 0.6 * x, 0.3 + 0.4 * y, 0.5 + 0.3 * x * y], axis=-1)
    frames = np.stack([np.roll(frame, t, axis=1) for t in range(T)]).astype(np.float32)
    if flow is not None and not isinstance(flow, str):
        flow = np.zeros((T - 1, H, W, 2), np.float32)
    return frames, flow


def warm_up(options: dict, flow) -> str:
    """Decompose a tiny clip with ``options`` (and the flow method, or a zero
    flow when arrays are given), so every kernel is compiled on this node;
    returns the Ray node id."""
    import ray

    solve_in_worker(*_warm_up_clip(flow), options)
    return ray.get_runtime_context().get_node_id()


def warm_up_here(options: dict, flow) -> None:
    """:func:`warm_up`'s decomposition in the calling process, on one thread for this
    call only (nothing process-wide is set) and without a progress bar: compiles the
    kernels into this machine's on-disk caches, which a local cluster's workers then load."""
    solve(*_warm_up_clip(flow), dict(options, threads=1, progress=False))
