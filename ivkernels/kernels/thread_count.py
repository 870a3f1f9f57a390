"""The process's CPU thread count for kernels, kept apart from any backend.

Warp host functions split their launches over this many threads
(:mod:`ivkernels.kernels.launch` sets and reads it); the Taichi backend starts
its runtime with it.  Nothing here imports Warp or Taichi, so every backend can
read the setting without loading another backend's runtime.

The count is per calling Python thread (``threading.local``); the default is
``IVKERNELS_THREADS`` from the environment, else the machine's CPU count,
capped to 2.
"""
from __future__ import annotations

import os
import threading

_state = threading.local()
_DEFAULT_THREADS = max(1, min(2, int(os.environ.get("IVKERNELS_THREADS", os.cpu_count() or 1))))


def get_threads() -> int:
    """Number of CPU threads Warp host functions launch on (1 or 2)."""
    return getattr(_state, "threads", _DEFAULT_THREADS)
