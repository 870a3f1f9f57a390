"""The NumPy backend: the kernel families derived from the case table's NumPy references.

Slow and exact (float64 inside, float32 outputs); CPU only.  It proves that
the contract of :mod:`ivkernels.backends.protocols` is enough to run
:func:`ivkernels.decompose` end to end, and serves as an oracle next to the
compiled backends.  Its kernels are made by :func:`ivkernels.kernels.numpy.family`.
"""
from __future__ import annotations

from ivkernels.backends.host_arrays import HostArrayBackend
from ivkernels.kernels import FAMILIES
from ivkernels.kernels.numpy import family


class NumpyBackend(HostArrayBackend):
    """NumPy arrays on the CPU; kernels derived from the case table (:mod:`ivkernels.kernels.numpy`)."""

    name = "numpy"
    kernel_package = "ivkernels.kernels.numpy"

    def __getattr__(self, name: str):
        if name in FAMILIES:
            module = family(name)
            setattr(self, name, module)
            return module
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")
