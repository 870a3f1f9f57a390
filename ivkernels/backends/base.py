"""What every backend object shares: its name and device, and its kernel
families resolved lazily from a package of family modules."""
from __future__ import annotations

import importlib

import numpy as np

from ivkernels.backends.protocols import FAMILIES


class Backend:
    """Common front of the backends (see :class:`ivkernels.backends.protocols.BackendProtocol`).

    Subclasses set ``name`` (the registered name) and ``kernel_package`` (the
    package holding one module per family, e.g. ``"ivkernels.kernels.warp"``).
    Attributes named after :data:`~ivkernels.backends.protocols.FAMILIES`
    resolve lazily to ``<kernel_package>.<family>``.
    """

    name = "base"
    kernel_package = ""

    def __init__(self, device: str = "cpu"):
        self.device = device

    #: Whether host functions called from two Python threads run at the same
    #: time on the CPU (their launches release the GIL): the solver then
    #: estimates the next window's flow on a second thread while it solves.
    overlaps_python_threads = False

    def use_threads(self, threads: int) -> None:
        """Make the next launches run on ``threads`` CPU threads.

        Warp and the NumPy references read the calling thread's count from
        :mod:`ivkernels.kernels.thread_count` at every launch, so the default
        does nothing; a backend whose runtime fixes its thread count when it
        starts (Taichi) restarts it here.
        """

    def __getattr__(self, family: str):
        if family in FAMILIES and self.kernel_package:
            module = importlib.import_module(f"{self.kernel_package}.{family}")
            setattr(self, family, module)
            return module
        raise AttributeError(f"{type(self).__name__} has no attribute {family!r}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(device={self.device!r})"


def as_shape(shape) -> tuple:
    """An int or a sequence of ints as a shape tuple."""
    return (int(shape),) if np.isscalar(shape) else tuple(int(n) for n in shape)
