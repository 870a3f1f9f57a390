"""Argument checks of the Taichi host functions: those of every backend taking
NumPy arrays (:mod:`ivkernels.kernels.ndarray_checks`).  Taichi kernels take
``ti.types.ndarray()`` arguments, which must be C-contiguous: inputs are
copied when they are not, outputs are refused."""
from ivkernels.kernels.ndarray_checks import (check_array, check_disjoint, check_float, check_int,  # noqa: F401
                                              check_non_negative, check_positive, check_separate, check_vector,
                                              memory_span)
