"""Launching Warp kernels over rows, on one or two CPU threads.

Every image kernel in :mod:`ivkernels.kernels.warp` is launched with one Warp
thread per image row (``T * H`` rows for a frame stack) and loops over ``x``
inside; its first argument is ``row_begin: int`` and the thread handles row
``row_begin + wp.tid()``.  On the CPU a launch runs on a single thread and
releases the GIL, so :func:`launch_rows` splits the rows into two bands and
launches them from two Python threads.

Gather kernels (each output row written by the thread owning it) can be split
at any row.  Scatter kernels must be split where the halves write disjoint
memory; pass ``align=rows_per_frame`` to split only at frame boundaries.

The number of threads is a process-wide setting (:func:`set_threads`,
:func:`threads`) so that benchmarks can compare 1 and 2 threads on the same
code path.
"""
from __future__ import annotations

import contextlib
import threading
from concurrent.futures import ThreadPoolExecutor

import warp as wp

from ivkernels.kernels.thread_count import _state, get_threads  # noqa: F401  (get_threads re-exported)

_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()
_warm: set = set()
_warm_lock = threading.Lock()


def set_threads(n: int) -> None:
    """Set the number of CPU launch threads for the calling thread (1 or 2)."""
    if n not in (1, 2):
        raise ValueError(f"threads must be 1 or 2, got {n!r}")
    _state.threads = n


@contextlib.contextmanager
def threads(n: int):
    """Context manager: launch on ``n`` CPU threads inside the block."""
    old = get_threads()
    set_threads(n)
    try:
        yield
    finally:
        set_threads(old)


def _executor() -> ThreadPoolExecutor:
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ivkernels-launch")
        return _pool


def launch_rows(kernel, n_rows: int, inputs: list, device="cpu", *, align: int = 1) -> None:
    """Launch ``kernel(row_begin, *inputs)`` over ``n_rows`` rows.

    Parameters
    ----------
    kernel : warp kernel whose first argument is ``row_begin: int``.
    n_rows : total rows (``T * H`` for a frame stack, ``H`` for one image).
    inputs : the remaining kernel arguments.
    device : Warp device; on CUDA the whole domain is one launch.
    align : split only at multiples of ``align`` rows (use the frame height
        for kernels that scatter into other rows).  If no aligned split
        exists the launch runs on one thread.
    """
    if n_rows <= 0:
        return
    dev = wp.get_device(device)
    split = 0
    if dev.is_cpu and get_threads() == 2 and n_rows >= 2:
        units = n_rows // align
        if units >= 2:
            split = (units // 2) * align
    if split == 0:
        wp.launch(kernel, dim=n_rows, inputs=[0, *inputs], device=dev)
        return
    key = (kernel.key, kernel.module.name)
    with _warm_lock:
        first = key not in _warm
        _warm.add(key)
    if first:
        # Compile and load the module on this thread before two threads race to do it.
        wp.launch(kernel, dim=split, inputs=[0, *inputs], device=dev)
        wp.launch(kernel, dim=n_rows - split, inputs=[split, *inputs], device=dev)
        return
    other = _executor().submit(wp.launch, kernel, dim=split, inputs=[0, *inputs], device=dev)
    wp.launch(kernel, dim=n_rows - split, inputs=[split, *inputs], device=dev)
    other.result()
