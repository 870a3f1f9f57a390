"""Argument checks and output writes shared by the NumPy backend's adapters.

Inputs are checked for type and dtype (the references check nothing); each
output is checked against the shape of the reference's result before it is
written, so a mismatch is a ``ValueError`` naming the output.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels import ndarray_checks
from ivkernels.kernels.ndarray_checks import check_array


def arrays(dtype=np.float32, **named) -> None:
    """Raise TypeError unless every keyword argument is a ``numpy.ndarray`` of ``dtype``."""
    for name, a in named.items():
        check_array(name, a, None, "array", dtype=dtype, copy=True)


def check_disjoint(name_a: str, a, name_b: str, b, why: str) -> None:
    """Raise ValueError if arrays ``a`` and ``b`` share memory: the aliasing rule of every backend
    (:func:`ivkernels.kernels.checks.check_separate`); TypeError if either is not a ``numpy.ndarray``."""
    for name, x in ((name_a, a), (name_b, b)):
        if not isinstance(x, np.ndarray):
            raise TypeError(f"{name} must be a numpy.ndarray, got {type(x).__name__}")
    ndarray_checks.check_disjoint(name_a, a, name_b, b, why)


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
