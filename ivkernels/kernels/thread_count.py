"""The process's CPU thread count for kernels, kept apart from any backend.

Warp host functions split their launches over this many threads
(:mod:`ivkernels.kernels.launch`); the Taichi backend starts its runtime with
it.  Nothing here imports Warp or Taichi, so every backend can read the
setting without loading another backend's runtime.

The number of threads N:

* defaults to the cores this process may run on (:func:`available_cores`),
  or to the environment variable :data:`THREADS_ENV` (``IVKERNELS_THREADS``)
  when it is set;
* is overridden per calling thread by :func:`set_threads` or the
  :func:`threads` context manager (what ``decompose(..., threads=N)``,
  ``estimate_flow(..., threads=N)`` and ``ivkernels decompose --threads N``
  use), so that benchmarks can compare thread counts on one code path.
"""
from __future__ import annotations

import contextlib
import numbers
import os
import threading

#: Environment variable giving the default thread count.
THREADS_ENV = "IVKERNELS_THREADS"

_state = threading.local()
_default_threads: int | None = None


def check_threads(threads, name: str = "threads") -> int:
    """Refuse a CPU thread count that is not an integer >= 1; return it as an int."""
    if isinstance(threads, bool) or not isinstance(threads, numbers.Integral):
        raise TypeError(f"{name} must be an integer >= 1 (CPU threads), got {threads!r}")
    if threads < 1:
        raise ValueError(f"{name} must be an integer >= 1 (CPU threads), got {threads!r}")
    return int(threads)


def available_cores() -> int:
    """CPU cores this process may run on (its affinity mask where the OS has one)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def threads_from_environment(environ=None) -> int:
    """The default thread count: ``IVKERNELS_THREADS`` if set, else :func:`available_cores`.

    Raises ``ValueError`` if the variable is set to anything but an integer >= 1.
    """
    environ = os.environ if environ is None else environ
    text = environ.get(THREADS_ENV)
    if text is None or not text.strip():
        return available_cores()
    try:
        n = int(text.strip())
    except ValueError:
        raise ValueError(f"environment variable {THREADS_ENV} must be an integer >= 1, "
                         f"got {text!r}") from None
    return check_threads(n, name=f"environment variable {THREADS_ENV}")


def default_threads() -> int:
    """The process-wide default thread count, read once from the environment."""
    global _default_threads
    if _default_threads is None:
        _default_threads = threads_from_environment()
    return _default_threads


def get_threads() -> int:
    """Number of CPU threads Warp host functions launch on, for the calling thread."""
    n = getattr(_state, "threads", None)
    return default_threads() if n is None else n


def set_threads(n: int | None) -> None:
    """Set the number of CPU launch threads for the calling thread (``None``: the default)."""
    _state.threads = None if n is None else check_threads(n)


@contextlib.contextmanager
def threads(n: int | None):
    """Context manager: launch on ``n`` CPU threads inside the block (``None``: the default)."""
    old = getattr(_state, "threads", None)
    set_threads(n)
    try:
        yield
    finally:
        _state.threads = old


def iterate_with_threads(n: int | None, items):
    """Iterate ``items`` (an iterator, e.g. a generator) with the launch thread
    count set to ``n`` while it computes each item, and the caller's own count
    restored while the caller holds it; closing the result closes ``items``."""
    items = iter(items)
    try:
        while True:
            with threads(n):
                try:
                    item = next(items)
                except StopIteration:
                    return
            yield item
    finally:
        close = getattr(items, "close", None)
        if close is not None:
            with threads(n):
                close()
