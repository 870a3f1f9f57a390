"""Objects the kernels' host functions keep between calls, on every backend.

Scratch buffers (per-pixel intermediates of multi-pass kernels) are built
once per key and *calling thread*, so two CPU threads running host functions
at the same time never share one; small read-only tables are shared.  Keys
start with the calling module's name and include everything the object
depends on (device, shape, parameters).
"""
from __future__ import annotations

import threading

_cache: dict = {}
_lock = threading.Lock()


def cached(key: tuple, make):
    """The object ``make()`` returns, built on the first call with ``key`` and kept."""
    with _lock:
        obj = _cache.get(key)
        if obj is None:
            obj = make()
            _cache[key] = obj
    return obj


def scratch(key: tuple, make):
    """A scratch buffer built by ``make()`` once per ``key`` and calling thread."""
    return cached((*key, threading.get_ident()), make)
