"""The backend contract: one ``typing.Protocol`` per kernel family, built from the
declared host functions, and one for the backend object.

A backend is an object satisfying :class:`BackendProtocol`; its attribute
named after a family (``be.sampling``) is a module whose host functions have
exactly the names, parameter names, kinds and defaults declared in the
family's specification module (``ivkernels/kernels/reference/<family>.py``,
see :mod:`ivkernels.kernels.contract`).  The protocols below are built from
those declarations, so each function's signature, shapes and dtypes are
written once; ``tests/test_backend_contract.py`` checks every registered
backend's every family module against them with :func:`inspect.signature`.

The protocol methods are declarations (``self`` aside, they are the module
functions' signatures; their docstrings give the declared shapes).  Shapes
follow the array convention of :mod:`ivkernels.kernels`: float32 backend
arrays, images ``(T, H, W[, C])``, flow ``(T, H, W, 2)`` in pixels (x then
y), energies added per row into a float64 ``energy_rows`` of length ``T*H``;
outputs are passed in and written (or added into where said); functions
return ``None`` unless documented.  The full documentation of each function
is in :mod:`ivkernels.kernels.warp`.
"""
from __future__ import annotations

import inspect
import types
from typing import Protocol

import numpy as np

from ivkernels.kernels import FAMILIES
from ivkernels.kernels.contract import Family, HostFunction, families


def _method(fn: HostFunction):
    """A protocol method with ``fn``'s signature (after ``self``) and docstring."""
    def method(self, *args, **kwargs):
        raise NotImplementedError
    method.__name__ = method.__qualname__ = fn.name
    method.__doc__ = fn.describe()
    self_param = inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)
    method.__signature__ = fn.signature.replace(parameters=[self_param, *fn.signature.parameters.values()])
    return method


def family_protocol(family: Family) -> type:
    """The ``typing.Protocol`` of one family: a method per declared host function."""
    name = "".join(part.capitalize() for part in family.name.split("_")) + "Family"
    namespace = {n: _method(fn) for n, fn in family.functions.items()}
    namespace["__doc__"] = f"``{family.name}``: {family.doc}"
    namespace["__module__"] = __name__
    return types.new_class(name, (Protocol,), {}, lambda ns: ns.update(namespace))


#: Family name -> its protocol; the families every backend provides (those of
#: :data:`ivkernels.kernels.FAMILIES`, in that order).
FAMILY_PROTOCOLS: dict[str, type] = {name: family_protocol(f) for name, f in families().items()}
assert tuple(FAMILY_PROTOCOLS) == FAMILIES


class BackendProtocol(Protocol):
    """The object the solver and the flow hold: arrays, and the families as attributes.

    ``name`` is the name it is registered under (:func:`ivkernels.backends.register_backend`),
    ``device`` the device it runs on ("cpu", "cuda:0").  Backend arrays are
    whatever its family modules take (``wp.array``, ``numpy.ndarray``); the
    methods below are the only way host code makes or reads them.  One
    attribute per family, typed by :data:`FAMILY_PROTOCOLS`.
    """

    name: str
    device: str

    def asarray(self, a: np.ndarray):
        """A backend array holding ``a`` (a view where the backend can, else a copy)."""

    def empty(self, shape, dtype=np.float32):
        """An uninitialised backend array of ``shape`` (int or tuple) and NumPy ``dtype``."""

    def zeros(self, shape, dtype=np.float32):
        """A zero-filled backend array of ``shape`` and ``dtype``."""

    def zero(self, a) -> None:
        """Set every element of backend array ``a`` (any shape) to 0, in place."""

    def numpy(self, a) -> np.ndarray:
        """A NumPy view (CPU) or copy (other devices) of backend array ``a``, after synchronising."""

    def synchronize(self) -> None:
        """Wait until all work launched on ``device`` has finished."""


BackendProtocol.__annotations__.update(FAMILY_PROTOCOLS)
