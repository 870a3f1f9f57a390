"""Small read-only tables the kernels' host functions share between calls.

A table here depends on parameters only (a window radius and a sigma, never
an image size): e.g. the spatial weights of the weighted median, (2r+1)^2
floats.  The store is a process-wide LRU of at most :data:`MAX_TABLES`
entries, so it stays a few kilobytes whatever is decomposed.  Per-pixel
scratch buffers never go here: they live in a
:class:`ivkernels.kernels.workspace.Workspace` owned by the caller.
"""
from __future__ import annotations

import threading
from collections import OrderedDict

#: Entries kept; the least recently used one goes first.
MAX_TABLES = 32

_tables: OrderedDict = OrderedDict()
_lock = threading.Lock()


def cached(key: tuple, make):
    """The table ``make()`` returns for ``key``, built on first use and kept in the LRU.

    ``key`` starts with the calling module's name and holds every parameter the
    table depends on (and the device); the table must not be written to.
    """
    with _lock:
        obj = _tables.get(key)
        if obj is not None:
            _tables.move_to_end(key)
            return obj
    obj = make()
    with _lock:
        obj = _tables.setdefault(key, obj)
        _tables.move_to_end(key)
        while len(_tables) > MAX_TABLES:
            _tables.popitem(last=False)
    return obj


def cached_count() -> int:
    """Number of tables held (at most :data:`MAX_TABLES`)."""
    return len(_tables)
