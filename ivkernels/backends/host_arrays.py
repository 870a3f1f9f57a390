"""Backends whose arrays are plain NumPy arrays in host memory (Taichi, NumPy)."""
from __future__ import annotations

import numpy as np

from ivkernels.backends.base import Backend, as_shape


class HostArrayBackend(Backend):
    """Arrays are C-contiguous ``numpy.ndarray`` on the CPU; ``numpy()`` returns them as they are."""

    # ``device`` is checked by the registry (:func:`~ivkernels.backends.registry.check_device`):
    # these backends declare the device "cpu" only.

    def asarray(self, a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a)

    def empty(self, shape, dtype=np.float32) -> np.ndarray:
        return np.empty(as_shape(shape), dtype=dtype)

    def zeros(self, shape, dtype=np.float32) -> np.ndarray:
        return np.zeros(as_shape(shape), dtype=dtype)

    def zero(self, a) -> None:
        a.fill(0)

    def numpy(self, a) -> np.ndarray:
        return a

    def synchronize(self) -> None:
        pass
