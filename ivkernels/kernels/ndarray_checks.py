"""What a ``numpy.ndarray`` is, for the one argument check of every backend.

The host functions of the backends taking NumPy arrays (Taichi, NumPy) check
their arguments by their declarations (:mod:`ivkernels.kernels.contract`)
before any launch; :data:`FRONT` answers the few questions the check asks of
a NumPy array.  Taichi kernels take ``ti.types.ndarray()`` arguments, which
must be C-contiguous: a strided input is replaced by a contiguous copy, a
strided output (written in place) is refused.  :mod:`ivkernels.kernels.warp._checks`
is the same for ``wp.array``.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Frontend

try:
    from numpy.lib.array_utils import byte_bounds
except ImportError:             # NumPy < 2
    from numpy import byte_bounds


def memory_span(a: np.ndarray):
    """``("cpu", first byte, one past the last byte)`` of a NumPy array's memory; ``None`` if empty."""
    if a.size == 0:
        return None
    lo, hi = byte_bounds(a)
    return ("cpu", lo, hi)


class NdarrayFrontend(Frontend):
    """``numpy.ndarray`` s for :func:`ivkernels.kernels.contract.check_call`: strided inputs are
    copied contiguous, strided outputs refused (kernels taking ``ti.types.ndarray()``)."""

    kind = "numpy.ndarray"
    copies_inputs = True
    array_type = np.ndarray
    dtypes = {"float32": np.dtype(np.float32), "float64": np.dtype(np.float64), "int32": np.dtype(np.int32)}

    def dtype_name(self, a) -> str:
        return a.dtype.name

    def is_contiguous(self, a) -> bool:
        return a.flags.c_contiguous

    def contiguous(self, a):
        return np.ascontiguousarray(a)

    def span(self, a):
        return memory_span(a)


FRONT = NdarrayFrontend()
