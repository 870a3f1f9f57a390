"""Argument checks and output writes shared by the NumPy backend's adapters.

Inputs are checked for type and dtype (the references check nothing); each
output is checked against the shape of the reference's result before it is
written, so a mismatch is a ``ValueError`` naming the output.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.ndarray_checks import check_array, check_disjoint  # noqa: F401  (re-exported)


def arrays(dtype=np.float32, **named) -> None:
    """Raise TypeError unless every keyword argument is a ``numpy.ndarray`` of ``dtype``."""
    for name, a in named.items():
        check_array(name, a, None, "array", dtype=dtype, copy=True)


def write(name: str, out, value) -> None:
    """``out[...] = value`` (cast to ``out``'s dtype) after checking that the shapes agree."""
    _check_output(name, out, value)
    out[...] = value


def add(name: str, out, value) -> None:
    """``out += value`` (cast to ``out``'s dtype) after checking that the shapes agree."""
    _check_output(name, out, value)
    out += np.asarray(value).astype(out.dtype, copy=False)


def _check_output(name: str, out, value) -> None:
    if not isinstance(out, np.ndarray):
        raise TypeError(f"{name} must be a numpy.ndarray (written in place), got {type(out).__name__}")
    if out.shape != np.shape(value):
        raise ValueError(f"{name} must have shape {np.shape(value)} (from the inputs), got {out.shape}")
