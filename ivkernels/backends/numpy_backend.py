"""The NumPy backend: the kernel families as thin adapters over the NumPy references.

Slow and exact (float64 inside, float32 outputs); CPU only.  It proves that
the contract of :mod:`ivkernels.backends.protocols` is enough to run
:func:`ivkernels.decompose` end to end, and serves as an oracle next to the
compiled backends.  Its kernels are in :mod:`ivkernels.kernels.numpy`.
"""
from __future__ import annotations

from ivkernels.backends.host_arrays import HostArrayBackend


class NumpyBackend(HostArrayBackend):
    """NumPy arrays on the CPU; kernels in :mod:`ivkernels.kernels.numpy` (the references, adapted)."""

    name = "numpy"
    kernel_package = "ivkernels.kernels.numpy"
