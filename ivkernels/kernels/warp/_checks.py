"""Argument checks of the Warp host functions.

Every host function checks its arguments up front, before any launch, and
raises a ``TypeError`` (not a ``wp.array``, wrong dtype) or a ``ValueError``
(wrong shape, wrong device, bad scalar) naming the argument, what was
expected and what was given.  :mod:`ivkernels.kernels.taichi._checks` holds
the same checks for NumPy arrays; the rules that do not depend on the array
type (scalars, aliasing) live in :mod:`ivkernels.kernels.checks`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.checks import check_float, check_int, check_non_negative, check_positive, check_separate  # noqa: F401


def memory_span(a):
    """``(device, first byte, one past the last byte)`` of a ``wp.array``'s memory; ``None`` if empty."""
    if a.size == 0 or a.ptr is None:
        return None
    extent = sum((n - 1) * s for n, s in zip(a.shape, a.strides)) + wp.types.type_size_in_bytes(a.dtype)
    return (str(a.device), a.ptr, a.ptr + extent)


def check_disjoint(name_a: str, a, name_b: str, b, why: str) -> None:
    """Raise ValueError if ``wp.array`` s ``a`` and ``b`` share memory (:func:`ivkernels.kernels.checks.check_separate`)."""
    check_separate(name_a, memory_span(a), name_b, memory_span(b), why)


def check_array(name: str, a, shape: tuple | None, layout: str, device=None, *, dtype=wp.float32) -> None:
    """Raise unless ``a`` is a ``wp.array`` of ``dtype`` and ``shape`` on ``device``.

    ``shape`` is a tuple whose ``None`` entries match any size, or ``None`` for
    any shape; ``layout`` names the axes in the messages (``"(T, H, W, 3)"``).
    ``device``: the device of the function's first array (``None``: any).
    """
    if not isinstance(a, wp.array):
        raise TypeError(f"{name} must be a wp.array of {wp.types.type_repr(dtype)} {layout}, "
                        f"got {type(a).__name__}")
    if a.dtype != dtype:
        raise TypeError(f"{name} must have dtype {wp.types.type_repr(dtype)}, got {wp.types.type_repr(a.dtype)}")
    if shape is not None and (len(a.shape) != len(shape)
                              or any(e is not None and e != s for e, s in zip(shape, a.shape))):
        want = tuple("?" if e is None else e for e in shape)
        raise ValueError(f"{name} must have shape {layout} = {want}, got {tuple(a.shape)}")
    if device is not None and a.device != device:
        raise ValueError(f"{name} is on device {a.device}, expected {device} (the device of the first array)")


def check_vector(name: str, a, n: int | None = None, device=None) -> int:
    """Raise unless ``a`` is a non-empty 1-D float32 ``wp.array`` (of length ``n``, on ``device``).

    Returns its length.
    """
    if not isinstance(a, wp.array):
        raise TypeError(f"{name} must be a 1-D wp.array of float32, got {type(a).__name__}")
    if a.dtype != wp.float32:
        raise TypeError(f"{name} must have dtype float32, got {wp.types.type_repr(a.dtype)}")
    if a.ndim != 1 or a.shape[0] < 1:
        raise ValueError(f"{name} must be a non-empty 1-D vector (n,), got shape {tuple(a.shape)}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} must have the same length as the first vector ({n}), got {a.shape[0]}")
    if device is not None and a.device != device:
        raise ValueError(f"{name} is on device {a.device}, expected {device} (the device of the first array)")
    return a.shape[0]
