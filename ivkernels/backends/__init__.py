"""The backend object the solver and the flow talk to, and the registry of backends.

The solver never imports Warp or Taichi: it asks :func:`get_backend` for an
object that allocates arrays and exposes the kernel families as attributes
(``be.sampling.warp_bilinear(...)``).  What that object must provide is
declared in :mod:`ivkernels.backends.protocols` (one ``Protocol`` per kernel
family, one for the object) and checked for every registered backend by
``tests/test_backend_contract.py``.

Registered here:

``"warp"``
    Warp kernels (:mod:`ivkernels.kernels.warp`) on "cpu" or "cuda[:N]".
``"taichi"``
    The same host functions in Taichi (:mod:`ivkernels.kernels.taichi`), "cpu".
``"numpy"``
    The NumPy references adapted to the same host functions
    (:mod:`ivkernels.kernels.numpy`): slow, exact, "cpu"; an oracle.

Another backend joins with :func:`register_backend`; the public API, the
command line's ``--backend``, the validation and the tests read the registry.

>>> be = get_backend("warp")            # doctest: +SKIP
>>> a = be.asarray(np.zeros((2, 3, 4), np.float32))
"""
from __future__ import annotations

from ivkernels.backends.base import Backend
from ivkernels.backends.numpy_backend import NumpyBackend
from ivkernels.backends.protocols import FAMILIES, FAMILY_PROTOCOLS, BackendProtocol
from ivkernels.backends.registry import (BackendSpec, available_backends, backend_names, backend_spec,
                                         check_device, get_backend, register_backend)
from ivkernels.backends.taichi_backend import TaichiBackend
from ivkernels.backends.warp_backend import WarpBackend, cuda_device_count, cuda_devices, start_warp

__all__ = [
    "Backend", "BackendProtocol", "BackendSpec", "FAMILIES", "FAMILY_PROTOCOLS", "NumpyBackend",
    "TaichiBackend", "WarpBackend", "available_backends", "backend_names", "backend_spec", "check_device",
    "cuda_device_count", "get_backend", "register_backend", "start_warp",
]

register_backend("warp", WarpBackend, devices=("cpu", "cuda"), present=cuda_devices,
                 device_count=lambda kind: cuda_device_count())
register_backend("taichi", TaichiBackend, devices=("cpu",))
register_backend("numpy", NumpyBackend, devices=("cpu",), oracle=True)
