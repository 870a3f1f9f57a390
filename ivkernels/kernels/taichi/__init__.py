"""Taichi mirror of :mod:`ivkernels.kernels.warp`: same modules, same host
function names and signatures, NumPy arrays passed as ``ti.types.ndarray()``.

Taichi is initialised lazily by :func:`init` (never at import time); Taichi
threads the outermost loop of each kernel by itself.
"""
from __future__ import annotations

import threading

_lock = threading.Lock()
_initialised_threads: int | None = None


def init(threads: int = 2) -> None:
    """Initialise Taichi on the CPU with ``threads`` worker threads (idempotent).

    Taichi's runtime is process-wide: a later call with another thread count
    re-initialises it (all compiled kernels are dropped and recompile lazily).
    """
    global _initialised_threads
    import taichi as ti

    with _lock:
        if _initialised_threads == threads:
            return
        ti.init(arch=ti.cpu, cpu_max_num_threads=threads, default_fp=ti.f32,
                log_level=ti.WARN, offline_cache=True)
        _initialised_threads = threads
