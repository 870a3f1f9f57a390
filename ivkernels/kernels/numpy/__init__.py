"""The NumPy backend's kernel families, derived from the case table.

Each host function of :mod:`ivkernels.kernels.warp` (same name, same
declared signature, same argument checks through
:func:`ivkernels.kernels.contract.checked`) is made here from its first case
in :mod:`ivkernels.kernels.cases`: the case's reference, run on the call's
arguments, gives the outputs' final content, which is written into them; an
output declared as added into (:func:`ivkernels.kernels.contract.Acc`) gets
the reference's increment added, ``out += increment`` (the reference is run
with that output at zero).  Returned values are returned.  Declared
functions without arguments to check and without a case (the Gaussian taps,
the medians' scratch shapes) are those of :mod:`ivkernels.kernels.host`,
shared by every backend.

A family whose cases do not state its functions as functions of their
arguments writes them out in a module of this package named after it, whose
functions take precedence: ``energy_albedo_entropy``, whose cases check each
step against the whole chain from the albedo.

Slow and exact (the references compute in float64); CPU only; arrays are
``numpy.ndarray``.  Used as ``get_backend("numpy")``: an oracle that runs
:func:`ivkernels.decompose` end to end through nothing but the backend
contract.
"""
from __future__ import annotations

import functools
import importlib
import importlib.util
import inspect
import types

import numpy as np

from ivkernels.kernels import host
from ivkernels.kernels.cases import Case, cases_of
from ivkernels.kernels.contract import HostFunction, checked, families
from ivkernels.kernels.ndarray_checks import FRONT


def derive(fn: HostFunction, case: Case):
    """``fn`` on NumPy arrays, by ``case``'s reference (see the module docstring)."""
    params = fn.signature.parameters
    positional = [n for n, p in params.items() if p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD]
    added = tuple(n for n, spec in fn.arrays().items() if spec.accumulate)

    def run(*args, **kwargs):
        values = {**dict(zip(positional, args)), **kwargs}
        want = case.reference({**values, **{n: np.zeros_like(values[n]) for n in added}})
        for name, value in want.items():
            if name == "return":
                continue
            out = values[name]
            if name in added:
                out += np.asarray(value).astype(out.dtype, copy=False)
            else:
                out[...] = value
        return want.get("return")

    run.__name__ = run.__qualname__ = fn.name
    run.__doc__ = f"{fn.doc}  (NumPy: the reference of case ``{case.key}``.)"
    run.__signature__ = fn.signature
    return checked(fn, FRONT)(run)


@functools.lru_cache(maxsize=None)
def family(name: str) -> types.ModuleType:
    """The NumPy backend's module of family ``name``: a host function per declared one."""
    declared = families()[name]
    module = types.ModuleType(f"{__name__}.{name}", f"``{name}`` on the NumPy backend: {declared.doc}")
    written = importlib.import_module(f"{__name__}.{name}") \
        if importlib.util.find_spec(f"{__name__}.{name}") is not None else None
    first_case = {}
    for case in cases_of(name):
        first_case.setdefault(case.function, case)
    for function, fn in declared.functions.items():
        if written is not None and hasattr(written, function):
            impl = getattr(written, function)
        elif function in first_case:
            impl = derive(fn, first_case[function])
        else:
            impl = getattr(host, function)
        setattr(module, function, impl)
    return module
