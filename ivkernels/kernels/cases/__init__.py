"""Case table of every kernel host function: inputs, outputs, NumPy reference, tolerances.

One :class:`Case` per host function (and per variant of its parameters) of
each kernel family, one module per family (``cases/<family>.py``, a tuple
``CASES``).  The tests generate their contract checks from this table (each
backend against the reference on odd sizes, non-contiguous inputs, aliasing,
empty input, gradients by finite differences) and the kernel benchmarks time
the same calls on realistic sizes.

A case is used in four steps::

    from ivkernels.kernels.cases import all_cases, run
    case = all_cases()[0]
    values = case.make(np.random.default_rng(0), 2, 7, 11)    # NumPy arrays and scalars by argument name
    got = run(case, backend, values)                          # {output name: numpy array}, "return" if any
    want = case.reference(values)                             # {output name: expected final value}

Sizes
-----
``make(rng, T, H, W)`` builds the inputs of a video of ``T`` frames of
``H x W`` pixels: frame-wise arrays have ``T`` frames, flow-wise arrays (a flow
and what is defined per pair of frames) have ``P = max(T - 1, 0)`` pairs, and
flat vectors (``vecops``) have ``4 T H W - 1`` elements (the solver's
unknowns, an odd length).  Ranges imitate the solver's data: log images
(``log`` of linear RGB in (0, 1]), flows of a few pixels with some samples
leaving the image, Lab colours, 0 / 1 masks.

Values
------
``values`` is a dict, in call order, of NumPy arrays (float32 unless an
argument is documented otherwise), Python scalars, and :class:`Allocate`
entries (an argument the backend must make itself, e.g. a scratch struct).
Outputs are in it with their shape and initial content: random where the
function accumulates or updates in place (``Case.updates``), NaN or zeros
where it overwrites.  Entries named in neither ``call`` nor ``keywords`` are
for the reference only.

The reference returns the *final* content of the outputs it predicts
(accumulated buffers include their initial content) and ``"return"`` for a
returned value; outputs it leaves out (scratch) are not compared.
"""
from __future__ import annotations

import dataclasses
import importlib
from typing import Callable, Mapping

import numpy as np

from ivkernels.kernels import FAMILIES



@dataclasses.dataclass(frozen=True)
class Tol:
    """Tolerance of one output: ``|got - want| <= atol + atol_rel * max|want| + rtol * |want|``."""

    rtol: float = 1e-5
    atol: float = 1e-6
    atol_rel: float = 0.0

    def absolute(self, want) -> float:
        """The absolute part of the bound for the expected value ``want``."""
        want = np.asarray(want)
        peak = float(np.abs(want).max()) if want.size and self.atol_rel else 0.0
        return self.atol + self.atol_rel * peak


EXACT = Tol(0.0, 0.0)


@dataclasses.dataclass(frozen=True)
class Allocate:
    """An argument the backend makes itself: ``make(be, values)`` returns it (e.g. a scratch struct)."""

    make: Callable


@dataclasses.dataclass(frozen=True)
class Gradient:
    """An energy and the gradient the same call accumulates, checked by finite differences.

    wrt : the input differentiated (float32 array).
    grad : the output accumulating ``dE/d wrt`` (starts at zero for the check).
    energy : the output accumulating the energy (summed over its entries).
    size : ``(T, H, W)`` of the check (every entry of ``wrt`` is perturbed).
    make : inputs for the check when the case's own do not suit (a smoother
        table, data away from kinks); ``None`` uses ``Case.make``.
    overrides : scalar arguments replaced for the check (e.g. a larger ``eps``).
    rtol, atol, atol_rel : kernel gradient vs central differences of the
        float64 reference energy, as in :class:`Tol`.
    min_peak : the largest |finite difference| must exceed this (the check
        must see a non-trivial gradient).
    """

    wrt: str
    grad: str
    energy: str = "energy_rows"
    size: tuple = (2, 7, 9)
    make: Callable | None = None
    overrides: Mapping = dataclasses.field(default_factory=dict)
    rtol: float = 1e-4
    atol: float = 1e-4
    atol_rel: float = 0.0
    min_peak: float = 0.0


@dataclasses.dataclass(frozen=True)
class Case:
    """One host function of a kernel family, called on generated inputs.

    family, function : the host function ``ivkernels.kernels.<backend>.<family>.<function>``.
    make : ``make(rng, T, H, W) -> values`` (see the module docstring).
    call : names of the positional arguments, in order.
    outputs : arrays the function writes (overwrites, accumulates or updates).
    reference : ``reference(values) -> {output: expected final value}`` by the NumPy reference.
    variant : a short name of the parameters when a function has several cases.
    keywords : names passed by keyword.
    updates : outputs whose initial content matters (accumulated ``+=`` or updated in place).
    scratch : outputs whose final content is unspecified (work buffers); never compared.
    returns : whether the function returns a value (compared as ``"return"``).
    tol : one :class:`Tol` for every output, or ``{output: Tol}`` (missing names: ``Tol()``).
    ignore : ``ignore(values) -> {output: bool mask}`` of entries where either
        answer is right (float ties on a threshold); ``None``: compare all.
    no_alias : ``(input, output)`` pairs the function must refuse to alias
        (it reads neighbours of the input, or scatters into the output).
    in_place : ``(input, output)`` pairs that may be the same array (the result
        is that of an output starting as a copy of the input).
    gradients : :class:`Gradient` checks of an energy's gradient.
    contiguous : inputs every backend requires C-contiguous (refused otherwise);
        any other array input may be a strided view.
    min_frames : the fewest frames ``T`` the function takes (fewer: a ValueError).
    """

    family: str
    function: str
    make: Callable
    call: tuple
    outputs: tuple
    reference: Callable
    variant: str = ""
    keywords: tuple = ()
    updates: tuple = ()
    scratch: tuple = ()
    returns: bool = False
    tol: Tol | Mapping = Tol()
    ignore: Callable | None = None
    no_alias: tuple = ()
    in_place: tuple = ()
    gradients: tuple = ()
    contiguous: tuple = ()
    min_frames: int = 1

    @property
    def key(self) -> str:
        """``family.function`` or ``family.function[variant]``: the id of the case."""
        return f"{self.family}.{self.function}" + (f"[{self.variant}]" if self.variant else "")

    def tolerance(self, output: str) -> Tol:
        return self.tol.get(output, Tol()) if isinstance(self.tol, Mapping) else self.tol

    def inputs(self, values: dict) -> tuple:
        """Names of the array arguments that are read only."""
        return tuple(n for n in (*self.call, *self.keywords)
                     if isinstance(values[n], np.ndarray) and n not in self.outputs)

    @property
    def compared(self) -> tuple:
        """Outputs whose final content is specified (``outputs`` less ``scratch``), and ``"return"``."""
        return tuple(n for n in self.outputs if n not in self.scratch) + (("return",) if self.returns else ())

    def host_function(self, be) -> Callable:
        return getattr(getattr(be, self.family), self.function)


def bind(case: Case, be, values: dict, arrays: Mapping | None = None) -> tuple[Callable[[], object], dict]:
    """A zero-argument call of ``case`` on backend ``be``, and the backend arrays it uses.

    Every NumPy array of ``values`` is copied into a backend array (so the call
    never writes into ``values``); ``arrays`` gives backend objects to use
    instead for some names (a strided view, an aliased output).  Returns
    ``(call, arrays)`` where ``arrays`` maps each argument name to what is passed.
    """
    given = dict(arrays or {})
    passed = {}
    for name in (*case.call, *case.keywords):
        v = values[name]
        if name in given:
            passed[name] = given[name]
        elif isinstance(v, np.ndarray):
            passed[name] = be.asarray(v.copy())
        elif isinstance(v, Allocate):
            passed[name] = v.make(be, values)
        else:
            passed[name] = v
    fn = case.host_function(be)
    args = [passed[n] for n in case.call]
    kwargs = {n: passed[n] for n in case.keywords}
    return (lambda: fn(*args, **kwargs)), passed


def read(case: Case, be, passed: Mapping, result=None) -> dict:
    """The outputs of a finished call as NumPy copies (and ``"return"``: ``result``)."""
    be.synchronize()
    out = {name: np.array(be.numpy(passed[name]), copy=True) for name in case.outputs}
    if case.returns:
        out["return"] = result
    return out


def run(case: Case, be, values: dict, arrays: Mapping | None = None) -> dict:
    """Call ``case`` on ``be`` with ``values``; return its outputs as NumPy arrays."""
    call, passed = bind(case, be, values, arrays)
    return read(case, be, passed, call())


def cases_of(family: str) -> tuple:
    """The cases of one family."""
    if family not in FAMILIES:
        raise ValueError(f"family must be one of {FAMILIES}, got {family!r}")
    return importlib.import_module(f"{__name__}.{family}").CASES


def all_cases() -> tuple:
    """Every case of every family, in the order of :data:`FAMILIES`."""
    return tuple(c for f in FAMILIES for c in cases_of(f))
