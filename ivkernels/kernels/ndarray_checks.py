"""Argument checks of host functions that take NumPy arrays (the Taichi and
NumPy backends); the mirror of :mod:`ivkernels.kernels.warp._checks`.

Every host function checks its arguments up front, before any launch, and
raises a ``TypeError`` (not a ``numpy.ndarray``, wrong dtype) or a
``ValueError`` (wrong shape, bad scalar, non-contiguous output) naming the
argument, what was expected and what was given.  The kernels take
``ti.types.ndarray()`` arguments, which must be C-contiguous: array checks
return a C-contiguous array, copying an input if needed; outputs are written
in place and are refused unless already contiguous.  The rules that do not
depend on the array type (scalars, aliasing) live in
:mod:`ivkernels.kernels.checks`.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.checks import check_float, check_int, check_non_negative, check_positive, check_separate  # noqa: F401
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


def check_disjoint(name_a: str, a, name_b: str, b, why: str) -> None:
    """Raise ValueError if arrays ``a`` and ``b`` share memory (:func:`ivkernels.kernels.checks.check_separate`)."""
    check_separate(name_a, memory_span(a), name_b, memory_span(b), why)


def check_array(name: str, a, shape: tuple | None, layout: str, *, dtype=np.float32,
                output: bool = False, copy: bool = True) -> np.ndarray:
    """Raise unless ``a`` is a NumPy array of ``dtype`` and ``shape``; return it C-contiguous.

    ``shape`` is a tuple whose ``None`` entries match any size, or ``None`` for
    any shape; ``layout`` names the axes in the messages (``"(T, H, W, 3)"``).
    A non-contiguous ``a`` raises if ``output`` (it is written in place) or
    ``copy=False``, and is otherwise returned as a contiguous copy.
    """
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name} must be a numpy.ndarray of {np.dtype(dtype).name} {layout}, got {type(a).__name__}")
    if a.dtype != dtype:
        raise TypeError(f"{name} must have dtype {np.dtype(dtype).name}, got {a.dtype.name}")
    if shape is not None and (a.ndim != len(shape)
                              or any(e is not None and e != s for e, s in zip(shape, a.shape))):
        want = tuple("?" if e is None else e for e in shape)
        raise ValueError(f"{name} must have shape {layout} = {want}, got {a.shape}")
    if not a.flags.c_contiguous:
        if output:
            raise ValueError(f"{name} is written in place and must be C-contiguous")
        if not copy:
            raise ValueError(f"{name} must be C-contiguous")
        a = np.ascontiguousarray(a)
    return a


def check_vector(name: str, a, n: int | None = None, output: bool = False) -> np.ndarray:
    """Raise unless ``a`` is a non-empty 1-D float32 NumPy array (of length ``n``).

    Returns it C-contiguous (inputs copied if needed, outputs must already be).
    """
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name} must be a 1-D numpy.ndarray of float32, got {type(a).__name__}")
    if a.dtype != np.float32:
        raise TypeError(f"{name} must have dtype float32, got {a.dtype.name}")
    if a.ndim != 1 or a.shape[0] < 1:
        raise ValueError(f"{name} must be a non-empty 1-D vector (n,), got shape {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} must have the same length as the first vector ({n}), got {a.shape[0]}")
    if not a.flags.c_contiguous:
        if output:
            raise ValueError(f"{name} is written in place and must be C-contiguous")
        a = np.ascontiguousarray(a)
    return a


class NdarrayFrontend(Frontend):
    """``numpy.ndarray`` s for :func:`ivkernels.kernels.contract.check_call`: strided inputs are
    copied contiguous, strided outputs refused (kernels taking ``ti.types.ndarray()``)."""

    kind = "numpy.ndarray"
    copies_inputs = True

    def is_array(self, a) -> bool:
        return isinstance(a, np.ndarray)

    def has_dtype(self, a, dtype: str) -> bool:
        return a.dtype == dtype

    def dtype_name(self, a) -> str:
        return a.dtype.name

    def is_contiguous(self, a) -> bool:
        return a.flags.c_contiguous

    def contiguous(self, a):
        return np.ascontiguousarray(a)

    def span(self, a):
        return memory_span(a)


FRONT = NdarrayFrontend()
