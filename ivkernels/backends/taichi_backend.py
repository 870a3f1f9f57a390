"""The Taichi backend: NumPy arrays passed to Taichi kernels as ``ti.types.ndarray()``."""
from __future__ import annotations

from ivkernels.backends.host_arrays import HostArrayBackend


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
        from ivkernels.kernels.taichi import init
        from ivkernels.kernels.thread_count import get_threads

        init(get_threads() if threads is None else threads)
