"""What a ``wp.array`` is, for the one argument check of every backend.

The host functions of :mod:`ivkernels.kernels.warp` check their arguments by
their declarations (:mod:`ivkernels.kernels.contract`) before any launch;
:data:`FRONT` answers the few questions the check asks of a ``wp.array``.
Warp kernels read strided arrays, so nothing is copied; every array must be
on the device of the first one.  :mod:`ivkernels.kernels.ndarray_checks` is
the same for NumPy arrays.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import Frontend
from ivkernels.kernels.launch import gpu_layout


def memory_span(a):
    """``(device, first byte, one past the last byte)`` of a ``wp.array``'s memory; ``None`` if empty."""
    if a.size == 0 or a.ptr is None:
        return None
    extent = sum((n - 1) * s for n, s in zip(a.shape, a.strides)) + wp.types.type_size_in_bytes(a.dtype)
    return (str(a.device), a.ptr, a.ptr + extent)


class WarpFrontend(Frontend):
    """``wp.array`` s for :func:`ivkernels.kernels.contract.check_call`: read with their strides
    (never copied), on the device of the first array."""

    kind = "wp.array"
    array_type = wp.array
    dtypes = {"float32": wp.float32, "float64": wp.float64, "int32": wp.int32}

    def dtype_name(self, a) -> str:
        return wp.types.type_repr(a.dtype)

    def device(self, a):
        return a.device

    def is_contiguous(self, a) -> bool:
        return a.size == 0 or a.is_contiguous

    def contiguous(self, a):
        return a.contiguous()

    def span(self, a):
        return memory_span(a)


FRONT = WarpFrontend()


def native_rows(device, *arrays) -> bool:
    """Whether a host function takes its CPU-only native row loop: the device has the
    CPU's layout (not a GPU, nor the GPU layouts forced for the tests,
    :func:`ivkernels.kernels.launch.gpu_layout`) and the arrays' rows are contiguous
    (:func:`rows_contiguous`)."""
    return not gpu_layout(device) and rows_contiguous(*arrays)


def rows_contiguous(*arrays) -> bool:
    """Whether every array's rows are contiguous float32 runs: the last axis of a
    (T, H, W) array, the last two (x, channel) of a (T, H, W, C) one.  The CPU's
    native row loops read such rows with plain pointers; frames and rows may have
    any strides."""
    for a in arrays:
        if a.strides[-1] != 4 or (a.ndim == 4 and a.strides[2] != 4 * a.shape[3]):
            return False
    return True
