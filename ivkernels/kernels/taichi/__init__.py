"""Taichi mirror of :mod:`ivkernels.kernels.warp`: same modules, same host
function names and signatures, NumPy arrays passed as ``ti.types.ndarray()``.

Taichi is initialised lazily by :func:`init` (never at import time); Taichi
threads the outermost loop of each kernel by itself, on the number of threads
fixed when it was initialised.
"""
from __future__ import annotations

import threading

from ivkernels.kernels.thread_count import check_threads, get_threads

_lock = threading.Lock()
_initialised_threads: int | None = None


def initialised_threads() -> int | None:
    """The thread count Taichi runs on now (``None`` before :func:`init`)."""
    return _initialised_threads


def init(threads: int | None = None) -> None:
    """Initialise Taichi on the CPU with ``threads`` worker threads.

    ``threads=None`` takes the launch thread count of the calling thread
    (:func:`ivkernels.kernels.thread_count.get_threads`: ``IVKERNELS_THREADS`` or
    the cores available, unless set otherwise).  Calling it again with the
    count Taichi already runs on does nothing.

    Taichi fixes its thread count at ``ti.init`` and its runtime is
    process-wide, so a call with *another* count re-initialises it: every
    compiled Taichi kernel is dropped and compiles again (from Taichi's
    offline cache) on its next call, which costs tens of milliseconds per
    kernel, and Taichi fields would be invalidated (ivkernels creates none:
    its kernels take NumPy arrays).  The new count then holds for every
    caller in the process; do not change it while another Python thread runs
    Taichi kernels.  ``decompose(..., backend="taichi", threads=N)`` and
    ``estimate_flow(..., backend="taichi", threads=N)`` call this with their N,
    so a program that keeps one thread count pays for initialisation once.
    """
    global _initialised_threads

    threads = get_threads() if threads is None else check_threads(threads)
    with _lock:
        if _initialised_threads == threads:
            return
        import taichi as ti

        ti.init(arch=ti.cpu, cpu_max_num_threads=threads, default_fp=ti.f32,
                log_level=ti.WARN, offline_cache=True)
        _initialised_threads = threads
