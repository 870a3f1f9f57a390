"""Giving the C heap's free pages back to the OS when a call returns.

NumPy and Warp CPU arrays are allocated by the C library's ``malloc``.  glibc
serves a large block by ``mmap`` (returned to the OS when freed) only until a
block of that size has been freed: its mmap threshold then rises to the freed
block's size (up to 32 MiB), and later blocks of up to that size come from
its heap, which keeps freed memory for reuse rather than returning it (and
cannot return the part pinned below a live block).  So the arrays of a
``decompose()``, freed when it returns, stay resident as free heap: after a
warm-up, four calls on 60x80 to 240x320 frames left the process 32 to 67 MiB
larger than the arrays its caller held (three runs; 80 MiB with tracemalloc
on), and the heap's free bytes (mallinfo2 ``fordblks``) account for all of
it; live Warp arrays, Python objects, loaded Warp modules and the kernels'
caches did not grow (perf/RESULTS.md, "Resident memory after decompose()").

:func:`release_free_memory` asks the allocator to return its free pages
(glibc's ``malloc_trim(0)``, about a millisecond); :func:`ivkernels.decompose`
calls it as it returns, so the process keeps what is live and no more (at
most 1.1 MiB left in the same runs).  Where the C library has no such call
(not glibc) it does nothing.
"""
from __future__ import annotations

import ctypes
import sys


def _malloc_trim():
    """glibc's ``malloc_trim``, or ``None`` where the C library has none."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        trim = ctypes.CDLL(None).malloc_trim        # the symbol as this process resolves it
    except (OSError, AttributeError):
        return None
    trim.argtypes = [ctypes.c_size_t]
    trim.restype = ctypes.c_int
    return trim


_trim = _malloc_trim()


def can_release() -> bool:
    """Whether :func:`release_free_memory` reaches the allocator (glibc on Linux)."""
    return _trim is not None


def release_free_memory() -> bool:
    """Return the C heap's free pages to the OS; live memory is untouched.

    Returns ``True`` if the allocator released some memory, ``False`` if it
    had none to release or cannot release (see :func:`can_release`).
    """
    return bool(_trim(0)) if _trim is not None else False


def resident_bytes() -> int | None:
    """Resident set size of this process in bytes (``VmRSS``), ``None`` without ``/proc``."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None
