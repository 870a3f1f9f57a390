"""Argument checks shared by every backend (they look at host values only)."""
from __future__ import annotations

import math
import numbers

import numpy as np


def check_basis_rows(k: int, rows, coeffs=None):
    """Row indices into a ``(k, n)`` basis, and optionally one coefficient per row.

    rows : sequence of ints in ``[0, k)``, non-empty, or ``None`` for all rows.
    coeffs : ``None``, or a sequence of finite numbers of the same length.
    Returns ``rows`` as int32 and ``coeffs`` as float32 NumPy arrays (``None``
    when not given); raises ValueError with what was expected otherwise.
    """
    rows = np.arange(k) if rows is None else np.asarray(rows)
    if rows.ndim != 1 or len(rows) == 0 or not np.issubdtype(rows.dtype, np.integer):
        raise ValueError(f"rows must be a non-empty 1-D sequence of row indices, got {rows!r}")
    if rows.min() < 0 or rows.max() >= k:
        raise ValueError(f"rows must lie in [0, {k}) (the basis rows), got {rows.tolist()}")
    if coeffs is not None:
        coeffs = np.asarray(coeffs, np.float64)
        if coeffs.shape != rows.shape or not np.isfinite(coeffs).all():
            raise ValueError(f"coeffs must be {len(rows)} finite numbers (one per row), got {coeffs!r}")
        coeffs = coeffs.astype(np.float32)
    return rows.astype(np.int32), coeffs


def check_float(name: str, value, *, positive: bool = False) -> float:
    """``value`` as a float; raise unless it is a finite real number (``> 0`` if ``positive``).

    Python and NumPy ints and floats are accepted, ``bool`` is not.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value) or (positive and value <= 0):
        raise ValueError(f"{name} must be a finite float{' > 0' if positive else ''}, got {value!r}")
    return float(value)


def check_positive(name: str, value) -> float:
    """``float(value)``; raise unless it is ``> 0`` (``inf`` passes, ``nan`` does not)."""
    value = float(value)
    if not value > 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return value


def check_non_negative(name: str, value) -> float:
    """``float(value)``; raise unless it is ``>= 0`` (``inf`` passes, ``nan`` does not)."""
    value = float(value)
    if not value >= 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return value


def check_int(name: str, value, minimum: int, hint: str = "") -> int:
    """``value`` as an int; raise unless it is an integer (not ``bool``) ``>= minimum``.

    ``hint`` is appended to the message, e.g. ``" (2 for the paper's 5x5 window)"``.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}{hint}, got {value!r}")
    return int(value)


def check_separate(name_a: str, span_a, name_b: str, span_b, why: str) -> None:
    """Raise ValueError if two arrays share memory: the one aliasing rule of every backend.

    ``span_a``, ``span_b`` : ``(device, first byte, one past the last byte)``
    of each array's memory (see ``memory_span`` in each backend's checks), or
    ``None`` for an empty array, which overlaps nothing.  Arrays on different
    devices never overlap; on one device, any common byte is an overlap (a
    partial overlap is refused as firmly as the same array passed twice).
    ``why`` says in the message what the function needs the separation for.
    """
    if span_a is None or span_b is None or span_a[0] != span_b[0]:
        return
    if span_a[1] < span_b[2] and span_b[1] < span_a[2]:
        raise ValueError(f"{name_a} must not alias {name_b}: they must be different arrays "
                         f"sharing no memory ({why})")
