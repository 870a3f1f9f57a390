"""The Warp backend: ``wp.array`` on the CPU or a CUDA device."""
from __future__ import annotations

import numpy as np

from ivkernels.backends.base import Backend, as_shape


def _init_warp():
    """Import and start Warp quietly (once; later calls return at once), and return it.

    Warp is imported here, not at the top: the Taichi and NumPy backends
    never load it.
    """
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    wp.init()
    return wp


class WarpBackend(Backend):
    """Warp arrays (``wp.array``) on ``device`` ("cpu" or "cuda[:N]"); kernels in :mod:`ivkernels.kernels.warp`."""

    name = "warp"
    kernel_package = "ivkernels.kernels.warp"

    def __init__(self, device: str = "cpu"):
        # ``device`` was checked by the registry (:func:`~ivkernels.backends.registry.check_device`).
        super().__init__(device)
        self._wp = _init_warp()

    def asarray(self, a: np.ndarray):
        """Backend array holding ``a`` (a zero-copy view on the CPU when possible)."""
        wp = self._wp
        a = np.ascontiguousarray(a)
        if self.device == "cpu":
            return wp.array(a, dtype=wp.dtype_from_numpy(a.dtype), copy=False, device="cpu")
        return wp.array(a, dtype=wp.dtype_from_numpy(a.dtype), device=self.device)

    def empty(self, shape, dtype=np.float32):
        return self._wp.empty(as_shape(shape), dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device)

    def zeros(self, shape, dtype=np.float32):
        return self._wp.zeros(as_shape(shape), dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device)

    def zero(self, a) -> None:
        a.zero_()

    def numpy(self, a) -> np.ndarray:
        """NumPy view (CPU) or copy (CUDA) of a backend array."""
        self._wp.synchronize_device(self.device)
        return a.numpy()

    def synchronize(self) -> None:
        self._wp.synchronize_device(self.device)


def cuda_devices() -> list[str]:
    """``["cuda"]`` when Warp finds a CUDA device, else ``[]`` (the devices beyond the CPU)."""
    wp = _init_warp()
    return ["cuda"] if wp.is_cuda_available() else []


def cuda_device_count() -> int:
    """Number of CUDA devices Warp can use (0 when none)."""
    wp = _init_warp()
    return wp.get_cuda_device_count() if wp.is_cuda_available() else 0
