"""The Warp backend: ``wp.array`` on the CPU or a CUDA device."""
from __future__ import annotations

import os
import sys
import tempfile

import numpy as np

from ivkernels.backends.base import Backend, as_shape


#: What Warp's native library prints at start-up on a machine with no CUDA
#: driver.  It is no fault of a CPU run; a CUDA device asked for where there is
#: none is refused by the registry with its own message.
_NO_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"
_started = False


def start_warp():
    """Import and start Warp quietly (once; later calls return at once), and return it.

    Warp is imported here, not at the top: the Taichi and NumPy backends
    never load it.  Warp 1.19 prints a warning from C at ``wp.init()`` on a
    machine without a CUDA driver, whatever ``wp.config`` says; the standard
    error is caught while it starts and every other line passed on.
    """
    import warp as wp

    global _started
    wp.config.log_level = wp.LOG_WARNING
    if _started:
        return wp
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        caught.seek(0)
        for line in caught.read().decode(errors="replace").splitlines():
            if _NO_DRIVER_WARNING not in line:
                print(line, file=sys.stderr)
    _started = True
    return wp


class WarpBackend(Backend):
    """Warp arrays (``wp.array``) on ``device`` ("cpu" or "cuda[:N]"); kernels in :mod:`ivkernels.kernels.warp`."""

    name = "warp"
    kernel_package = "ivkernels.kernels.warp"

    def __init__(self, device: str = "cpu"):
        # ``device`` was checked by the registry (:func:`~ivkernels.backends.registry.check_device`).
        super().__init__(device)
        self._wp = start_warp()

    @property
    def overlaps_python_threads(self) -> bool:
        """Warp's CPU launches release the GIL; CUDA launches are left to the stream."""
        return self.device == "cpu"

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
    wp = start_warp()
    return ["cuda"] if wp.is_cuda_available() else []


def cuda_device_count() -> int:
    """Number of CUDA devices Warp can use (0 when none)."""
    wp = start_warp()
    return wp.get_cuda_device_count() if wp.is_cuda_available() else 0
