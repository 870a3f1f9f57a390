"""Launching Warp kernels over rows, in row bands on N CPU threads.

Every image kernel in :mod:`ivkernels.kernels.warp` is launched with one Warp
thread per image row (``T * H`` rows for a frame stack) and loops over ``x``
inside; its first argument is ``row_begin: int`` and the thread handles row
``row_begin + wp.tid()``.  On the CPU a launch runs on a single thread and
releases the GIL, so :func:`launch_rows` splits the rows into up to N bands
(:func:`row_bands`) and launches them from N Python threads: the calling
thread runs the last band, a shared pool the others.

Gather kernels (each output row written by the thread owning it) can be split
at any row.  Scatter kernels must be split where the bands write disjoint
memory; pass ``align=rows_per_frame`` to split only at frame boundaries.
Kernels whose rows differ in work by the data (the weighted medians, which
work only where a mask is set, often in one part of the image) pass
``balance=True``: their rows are cut into :data:`BALANCE_CHUNKS_PER_THREAD`
chunks per thread, which the threads take in turn as they finish, so that no
thread waits on another that drew the busy half of the image.

A band covers at least :data:`MIN_BAND_ELEMENTS` elements of the launch's
largest array (:func:`min_band_rows`), so small launches (coarse pyramid
levels, short vectors) stay on one thread, where handing a band to another
thread would cost more than it saves.  Rows differ widely in work (an image
row, a 4096-element chunk of a vector, a whole histogram frame), so the
minimum is counted in elements rather than rows.

The number of threads N is kept in :mod:`ivkernels.kernels.thread_count`
(re-exported here).

On a GPU one thread per row leaves all but a few thousand of the device's
threads idle, so the kernels whose pixels are independent also take a
``tiles`` argument (:func:`row_tiles`) and are launched over ``rows * tiles``
threads, each covering one tile of a row (``warp.row_tiles.row_span``): one
tile per row on the CPU (the same loops, the same results), one pixel per
tile on a GPU.  :func:`gpu_layout` says which layout a device gets; tests set
:data:`FORCE_GPU_LAYOUT_TILES` to run the GPU's layouts on the CPU.
"""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor, wait

import warp as wp

from ivkernels.kernels.thread_count import (THREADS_ENV, available_cores, default_threads,  # noqa: F401
                                            get_threads, iterate_with_threads, set_threads, threads,
                                            threads_from_environment)

#: Fewest array elements a band must cover (rows times the elements per row
#: of the launch's largest array argument) for a launch to be split.
MIN_BAND_ELEMENTS = 16384

#: Chunks per thread of a balanced launch (``launch_rows(..., balance=True)``).
#: ``perf/bench_balance.py`` (the weighted flow median of Classic+NL-fast on
#: Middlebury pairs, 2 threads): 1 thread / N threads 1.53 with one band per
#: thread, 1.73 / 1.76 / 1.81 / 1.79 with 2 / 4 / 8 / 16 chunks per thread.
BALANCE_CHUNKS_PER_THREAD = 8

#: Tests set this to run the GPU's layouts on the CPU: rows cut into this many
#: tiles (at most one per pixel), the other kernels' GPU forms (``gpu_layout``).
FORCE_GPU_LAYOUT_TILES: int | None = None


def gpu_layout(device) -> bool:
    """Whether kernels take their GPU layout on ``device``: on a CUDA device, or
    everywhere while :data:`FORCE_GPU_LAYOUT_TILES` is set."""
    return FORCE_GPU_LAYOUT_TILES is not None or not wp.get_device(device).is_cpu


def row_tiles(width: int, device, pixels_per_tile: int = 1) -> int:
    """Tiles per row of ``width`` pixels on ``device``: 1 on the CPU, on a GPU one
    per ``pixels_per_tile`` pixels (more than 1 where each thread needs scratch of
    its own); ``FORCE_GPU_LAYOUT_TILES`` (at most ``width``) when set."""
    if FORCE_GPU_LAYOUT_TILES is not None:
        return max(1, min(int(FORCE_GPU_LAYOUT_TILES), int(width)))
    if wp.get_device(device).is_cpu:
        return 1
    return max(1, -(-int(width) // int(pixels_per_tile)))


_pool: ThreadPoolExecutor | None = None
_pool_workers = 0
_pool_lock = threading.Lock()
_warm: set = set()
_warm_lock = threading.Lock()


def min_band_rows(n_rows: int, inputs: list, min_elements: int | None = None) -> int:
    """Fewest rows a band of this launch may have: ``min_elements`` (default
    :data:`MIN_BAND_ELEMENTS`) divided by the elements per row of the largest
    Warp array in ``inputs`` (its size over ``n_rows``); 1 if there is none."""
    min_elements = MIN_BAND_ELEMENTS if min_elements is None else min_elements
    largest = max((a.size for a in inputs if isinstance(a, wp.array)), default=0)
    if largest <= 0 or n_rows <= 0:
        return 1
    return max(1, -(-min_elements * n_rows // largest))


def row_bands(n_rows: int, n_bands: int, align: int = 1, min_rows: int = 1) -> list[tuple[int, int]]:
    """Split rows ``[0, n_rows)`` into at most ``n_bands`` contiguous bands.

    Bands start at multiples of ``align`` and hold as equal a number of
    ``align``-row units as possible (the first ones one unit more); the last
    band also takes the ``n_rows % align`` rows past the last whole unit.
    Every band but possibly a lone one has at least ``min_rows`` rows.

    Returns ``[(row_begin, row_count), ...]`` in row order, covering every row
    exactly once (empty for ``n_rows <= 0``).
    """
    if n_rows <= 0:
        return []
    if align < 1 or min_rows < 1 or n_bands < 1:
        raise ValueError(f"align, min_rows and n_bands must be >= 1, got {align}, {min_rows}, {n_bands}")
    units = n_rows // align
    units_per_band = -(-min_rows // align)          # fewest whole units holding min_rows rows
    k = max(1, min(n_bands, units // units_per_band))
    if k == 1:
        return [(0, n_rows)]
    base, extra = divmod(units, k)
    bands, begin = [], 0
    for i in range(k):
        count = (base + (i < extra)) * align
        bands.append((begin, count))
        begin += count
    last_begin, last_count = bands[-1]
    bands[-1] = (last_begin, n_rows - last_begin)
    return bands


def _executor(workers: int) -> ThreadPoolExecutor:
    """The shared launch pool, grown to at least ``workers`` threads."""
    global _pool, _pool_workers
    with _pool_lock:
        if _pool is None or _pool_workers < workers:
            # A replaced pool is not shut down: a caller may still be submitting to it;
            # its idle threads exit once it is collected.
            _pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="ivkernels-launch")
            _pool_workers = workers
        return _pool


def launch_rows(kernel, n_rows: int, inputs: list, device="cpu", *, align: int = 1,
                balance: bool = False) -> None:
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
    balance : cut the rows into :data:`BALANCE_CHUNKS_PER_THREAD` chunks per
        thread, handed out one at a time to whichever thread is free (for
        kernels whose work per row depends on the data).

    The rows are split by :func:`row_bands` into at most :func:`get_threads`
    bands (chunks) of at least :func:`min_band_rows` rows each.
    """
    if n_rows <= 0:
        return
    dev = wp.get_device(device)
    n_threads = get_threads() if dev.is_cpu else 1
    bands = [(0, n_rows)]
    if n_threads > 1:
        n_bands = n_threads * BALANCE_CHUNKS_PER_THREAD if balance else n_threads
        bands = row_bands(n_rows, n_bands, align, min_band_rows(n_rows, inputs))
    if len(bands) == 1:
        wp.launch(kernel, dim=n_rows, inputs=[0, *inputs], device=dev)
        return
    key = (kernel.key, kernel.module.name)
    with _warm_lock:
        first = key not in _warm
        _warm.add(key)
    if first:
        # Compile and load the module on this thread before several threads race to do it.
        for begin, count in bands:
            wp.launch(kernel, dim=count, inputs=[begin, *inputs], device=dev)
        return
    _launch_chunks(kernel, bands, inputs, dev, min(n_threads, len(bands)))


def _launch_chunks(kernel, chunks: list[tuple[int, int]], inputs: list, dev, n_threads: int) -> None:
    """Launch ``chunks`` on ``n_threads`` threads (the caller's and ``n_threads - 1``
    of the pool), each taking the next chunk not yet taken until none is left
    (one band per thread when there are as many chunks as threads)."""
    pending = iter(chunks)
    lock = threading.Lock()

    def work() -> None:
        while True:
            with lock:
                chunk = next(pending, None)
            if chunk is None:
                return
            begin, count = chunk
            wp.launch(kernel, dim=count, inputs=[begin, *inputs], device=dev)

    pool = _executor(n_threads - 1)
    others = [pool.submit(work) for _ in range(n_threads - 1)]
    try:
        work()
    finally:
        wait(others)
    for other in others:
        other.result()
