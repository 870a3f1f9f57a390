"""The backend object the solver and the flow talk to.

The solver never imports Warp or Taichi: it asks :func:`get_backend` for an
object that allocates arrays and exposes the kernel families as attributes
(``be.sampling.warp_bilinear(...)``).  Both backends expose the same families
with the same host-function names and signatures.

>>> be = get_backend("warp")            # doctest: +SKIP
>>> a = be.asarray(np.zeros((2, 3, 4), np.float32))
"""
from __future__ import annotations

import importlib

import numpy as np

FAMILIES = (
    "colour", "sampling", "derivatives", "maps", "pyramid", "vecops", "median",
    "energy_data", "energy_temporal", "energy_shading", "energy_albedo_gsm",
    "energy_albedo_entropy", "flow_classic",
)
BACKENDS = ("warp", "taichi")


class Backend:
    """Common front of the Warp and Taichi backends.

    Attributes named after :data:`FAMILIES` resolve lazily to the backend's
    kernel module of that name.
    """

    name = "base"

    def __init__(self, device: str = "cpu"):
        self.device = device

    def __getattr__(self, family: str):
        if family in FAMILIES:
            module = importlib.import_module(f"ivkernels.kernels.{self.name}.{family}")
            setattr(self, family, module)
            return module
        raise AttributeError(f"{type(self).__name__} has no attribute {family!r}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(device={self.device!r})"


class WarpBackend(Backend):
    """Warp arrays (``wp.array``) on ``device`` ("cpu" or "cuda[:N]")."""

    name = "warp"

    def __init__(self, device: str = "cpu"):
        import warp as wp

        wp.config.log_level = wp.LOG_WARNING
        wp.init()
        if device.startswith("cuda") and not wp.is_cuda_available():
            raise RuntimeError(
                f"device={device!r} was asked for but Warp finds no CUDA device; use device='cpu'")
        if device != "cpu" and not device.startswith("cuda"):
            raise ValueError(f"device must be 'cpu' or 'cuda[:N]', got {device!r}")
        super().__init__(device)
        self._wp = wp

    def asarray(self, a: np.ndarray):
        """Backend array holding ``a`` (a zero-copy view on the CPU when possible)."""
        wp = self._wp
        a = np.ascontiguousarray(a)
        if self.device == "cpu":
            return wp.array(a, dtype=wp.dtype_from_numpy(a.dtype), copy=False, device="cpu")
        return wp.array(a, dtype=wp.dtype_from_numpy(a.dtype), device=self.device)

    def empty(self, shape, dtype=np.float32):
        return self._wp.empty(_shape(shape), dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device)

    def zeros(self, shape, dtype=np.float32):
        return self._wp.zeros(_shape(shape), dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device)

    def numpy(self, a) -> np.ndarray:
        """NumPy view (CPU) or copy (CUDA) of a backend array."""
        self._wp.synchronize_device(self.device)
        return a.numpy()

    def synchronize(self) -> None:
        self._wp.synchronize_device(self.device)


class TaichiBackend(Backend):
    """NumPy arrays passed to Taichi kernels as ``ti.types.ndarray()``.

    Taichi threads its kernels itself; it starts with the launch thread count
    of :mod:`ivkernels.kernels.launch` at the time the backend is first made.
    """

    name = "taichi"

    def __init__(self, device: str = "cpu", threads: int | None = None):
        if device != "cpu":
            raise ValueError(f"the taichi backend runs on device='cpu' only, got {device!r}")
        from ivkernels.kernels.launch import get_threads
        from ivkernels.kernels.taichi import init

        init(get_threads() if threads is None else threads)
        super().__init__(device)

    def asarray(self, a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a)

    def empty(self, shape, dtype=np.float32) -> np.ndarray:
        return np.empty(_shape(shape), dtype=dtype)

    def zeros(self, shape, dtype=np.float32) -> np.ndarray:
        return np.zeros(_shape(shape), dtype=dtype)

    def numpy(self, a) -> np.ndarray:
        return a

    def synchronize(self) -> None:
        pass


def _shape(shape) -> tuple:
    """An int or a sequence of ints as a shape tuple."""
    return (int(shape),) if np.isscalar(shape) else tuple(int(n) for n in shape)


_cache: dict = {}


def get_backend(name: str = "warp", device: str = "cpu") -> Backend:
    """Return the (cached) backend ``name`` ("warp" or "taichi") on ``device``."""
    if name not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {name!r}")
    key = (name, device)
    if key not in _cache:
        _cache[key] = WarpBackend(device) if name == "warp" else TaichiBackend(device)
    return _cache[key]


def available_backends() -> list[Backend]:
    """Every backend usable in this process (CPU Warp, Taichi, and CUDA Warp if present)."""
    out = [get_backend("warp", "cpu"), get_backend("taichi", "cpu")]
    import warp as wp

    if wp.is_cuda_available():
        out.append(get_backend("warp", "cuda"))
    return out
