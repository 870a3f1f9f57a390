"""The Taichi backend: NumPy arrays passed to Taichi kernels as ``ti.types.ndarray()``."""
from __future__ import annotations

from ivkernels.backends.host_arrays import HostArrayBackend
from ivkernels.kernels.taichi import init
from ivkernels.kernels.thread_count import get_threads


class TaichiBackend(HostArrayBackend):
    """NumPy arrays on the CPU; kernels in :mod:`ivkernels.kernels.taichi`.

    Taichi threads its kernels itself; it starts with the thread count of
    :mod:`ivkernels.kernels.thread_count` at the time the backend is first
    made (nothing here imports Warp).
    """

    name = "taichi"
    kernel_package = "ivkernels.kernels.taichi"

    def __init__(self, device: str = "cpu", threads: int | None = None):
        super().__init__(device)
        init(get_threads() if threads is None else threads)

    def use_threads(self, threads: int) -> None:
        """Restart Taichi's runtime on ``threads`` threads (nothing if it already runs on them)."""
        init(threads)
