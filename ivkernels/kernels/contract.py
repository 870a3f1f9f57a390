"""The contract of every kernel host function, declared once as data and checked by one routine.

Each family's host functions are declared in its specification module
(``kernels/reference/<family>.py``, beside the NumPy reference of each
function) by :meth:`Family.declare`: the signature (names, kinds, defaults),
one line of what the function does, and a spec per argument::

    FAMILY.declare("data_term(I, A, S, w_lum, gA, gS, energy_rows, lam=10.0, eps=0.001)",
                   "Add Eq. 3 and its gradient.",
                   I="T H W 3", A="T H W 3", S="T H W", w_lum="T H W",
                   gA=Acc("T H W 3"), gS=Acc("T H W"), energy_rows=Acc("T*H", "float64"),
                   lam=Real, eps=Real)

(a string is a float32 input; :func:`Out` an output written in place,
:func:`Acc` one added into; :class:`Vector`, :class:`Scalar` (``Real``,
``Positive``, :func:`Int`, ...), :class:`Workspace`, :class:`Rule` for what
shapes cannot say, ``separate=`` for arrays that must not share memory).

Every backend reads the same declarations: its host functions are wrapped by
:func:`checked`, which checks the arguments with :func:`check_call` through
the backend's :class:`Frontend` (what a ``wp.array`` or a ``numpy.ndarray``
is), so a rule is written once for all backends;
:mod:`ivkernels.backends.protocols` builds the family protocols from them, and
the tests read them to generate bad arguments.

Shapes
------
An array's ``dims`` are its axes separated by spaces: an int (``3``), a name
(``T``, ``T'``, ``h``) bound by the first array that has it and compared in
every later one, an expression of bound names and scalar arguments (``T*H``,
``T-1``, ``3*C``, ``(H-1)//spacing+2``: ints, names, ``+ - * // **``;
negative values count as 0), ``[C]``: a last axis that may be missing (alike
in every array declaring it), or ``...`` alone: any shape, the same in every
array declared ``...``.  Arrays are checked in signature order (or the
``order`` given); one whose expression names a size bound only later is
checked again at the end.  Messages name the argument, the layout
(``(T, H, W, 3)``) and the sizes expected, with ``?`` for sizes not yet bound.

Order of the checks: the scalars, then the arrays (type, dtype, shape,
device, contiguity), each :class:`Rule` right after the array it follows,
then the aliasing rules (:attr:`HostFunction.separate`).
"""
from __future__ import annotations

import ast
import dataclasses
import functools
import importlib
import inspect
import re
from typing import Callable

from ivkernels.kernels import FAMILIES
from ivkernels.kernels.checks import check_float, check_int, check_non_negative, check_positive, check_separate
from ivkernels.kernels.workspace import check_workspace

_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*'?$")


# ----------------------------------------------------------------------------- argument specs

@dataclasses.dataclass(frozen=True)
class Array:
    """An array argument: ``dims`` (see the module docstring) and ``dtype`` ("float32", "float64", "int32").

    output : written in place (so never copied; a backend whose kernels need
        contiguous memory refuses a strided output).
    accumulate : an output the function adds into (``out += ...``), which its
        initial content therefore takes part in.
    contiguous : refused unless C-contiguous on every backend.
    optional : ``None`` is accepted (and not checked).
    layout : the axes as the messages write them (default: ``dims`` as a tuple).
    """

    dims: str
    dtype: str = "float32"
    output: bool = False
    accumulate: bool = False
    contiguous: bool = False
    optional: bool = False
    layout: str | None = None

    def __post_init__(self):
        axes = _parse_dims(self.dims)
        object.__setattr__(self, "_axes", axes)
        object.__setattr__(self, "_any", axes == (("any",),))
        object.__setattr__(self, "_optional", axes[-1][0] == "optional" if axes else False)
        object.__setattr__(self, "_exprs", any(a[0] == "expr" for a in axes))
        object.__setattr__(self, "_plain", all(a[0] in ("int", "name", "expr") for a in axes))
        object.__setattr__(self, "_template", tuple(a[1] if a[0] != "expr" else a[1:] for a in axes)
                           if self._plain else ())

    @property
    def axes(self) -> tuple:
        return self._axes

    def describe(self) -> str:
        """``(T, H, W, 3)``: the axes as the messages and the protocols write them."""
        if self.layout is not None:
            return self.layout
        if self.dims.strip() == "...":
            return "(any shape)"
        tokens = self.dims.split()
        return "(" + ", ".join(tokens) + ("," if len(tokens) == 1 else "") + ")"


def Out(dims: str, dtype: str = "float32", **kw) -> Array:
    """An output array (written, or updated in place)."""
    return Array(dims, dtype, output=True, **kw)


def Acc(dims: str, dtype: str = "float32", **kw) -> Array:
    """An output array the function adds into (``out += ...``)."""
    return Array(dims, dtype, output=True, accumulate=True, **kw)


@dataclasses.dataclass(frozen=True)
class Vector:
    """A non-empty 1-D float32 vector; every vector of a call has the length of the first,
    bound as the size ``name`` (so that an :class:`Array` can be declared ``"k n"``)."""

    output: bool = False
    name: str = "n"
    accumulate = False


@dataclasses.dataclass(frozen=True)
class Scalar:
    """A number, converted before the call: ``kind`` one of

    ``"float"`` (``float(value)``), ``"finite"`` (a finite real, ``> 0`` with
    ``positive``), ``"positive"`` (``> 0``), ``"non_negative"`` (``>= 0``),
    ``"int"`` (an int ``>= minimum``, ``hint`` appended to the message),
    ``"choice"`` (an int among ``choices``).
    """

    kind: str = "float"
    positive: bool = False
    minimum: int = 0
    hint: str = ""
    choices: tuple = ()

    def check(self, name: str, value):
        if self.kind == "float":
            return float(value)
        return self._check(name, value)

    def _check(self, name: str, value):
        if self.kind == "finite":
            return check_float(name, value, positive=self.positive)
        if self.kind == "positive":
            return check_positive(name, value)
        if self.kind == "non_negative":
            return check_non_negative(name, value)
        if self.kind == "int":
            return check_int(name, value, self.minimum, self.hint)
        if self.kind == "choice":
            if isinstance(value, bool) or value not in self.choices:
                raise ValueError(f"{name} must be {' or '.join(map(str, self.choices))}, got {value!r}")
            return int(value)
        raise AssertionError(self.kind)


Real = Scalar("float")
Finite = Scalar("finite")
FinitePositive = Scalar("finite", positive=True)
Positive = Scalar("positive")
NonNegative = Scalar("non_negative")


def Int(minimum: int, hint: str = "") -> Scalar:
    """An int ``>= minimum``."""
    return Scalar("int", minimum=minimum, hint=hint)


def Choice(*choices) -> Scalar:
    """An int among ``choices``."""
    return Scalar("choice", choices=tuple(choices))


@dataclasses.dataclass(frozen=True)
class Workspace:
    """A :class:`ivkernels.kernels.workspace.Workspace` or ``None``."""


@dataclasses.dataclass(frozen=True)
class Rule:
    """A rule on sizes and values that shapes cannot state: ``check(sizes, args)`` raises
    ValueError (``sizes``: the bound dims, ``args``: the checked arguments by name), and
    may return a dict of arguments to replace (converted values).  Runs right after the
    array named ``after`` (``None``: after every array)."""

    check: Callable
    after: str | None = None


# ----------------------------------------------------------------------------- declarations

@dataclasses.dataclass(frozen=True)
class HostFunction:
    """The declared contract of one host function (see :meth:`Family.declare`)."""

    family: str
    name: str
    signature: inspect.Signature
    doc: str
    specs: dict
    separate: tuple = ()
    rules: tuple = ()

    def __post_init__(self):
        after = {}
        for rule in self.rules:
            after.setdefault(rule.after, []).append(rule)
        object.__setattr__(self, "_after", after)
        object.__setattr__(self, "_scalars", tuple((n, s) for n, s in self.specs.items() if isinstance(s, Scalar)))
        object.__setattr__(self, "_workspaces", tuple(n for n, s in self.specs.items() if isinstance(s, Workspace)))
        object.__setattr__(self, "_arrays", tuple((n, s) for n, s in self.specs.items()
                                                  if isinstance(s, (Array, Vector))))

    @property
    def key(self) -> str:
        return f"{self.family}.{self.name}"

    def arrays(self) -> dict:
        """Name -> :class:`Array` or :class:`Vector` of the array arguments, in signature order."""
        return {n: s for n, s in self.specs.items() if isinstance(s, (Array, Vector))}

    def outputs(self) -> tuple:
        return tuple(n for n, s in self.arrays().items() if s.output)

    def describe(self) -> str:
        """The one-line doc followed by the declared shapes, as the protocols show them."""
        parts = []
        for name, spec in self.arrays().items():
            if isinstance(spec, Vector):
                parts.append(f"{name} (n,)")
            else:
                dtype = "" if spec.dtype == "float32" else f" {spec.dtype}"
                role = " added into" if spec.accumulate else " out" if spec.output else ""
                parts.append(f"{name} {spec.describe()}{dtype}{role}")
        return self.doc + ("\n\nArrays: " + ", ".join(parts) + "." if parts else "")


class Family:
    """The declared host functions of one kernel family, in declaration order."""

    def __init__(self, name: str, doc: str):
        self.name = name
        self.doc = doc
        self.functions: dict[str, HostFunction] = {}

    def declare(self, signature: str, doc: str, *, separate: tuple = (), rules: tuple = (), order: tuple = (),
                **specs) -> HostFunction:
        """Declare ``signature`` (``"name(a, b, c=1.0, *, workspace=None)"``, defaults literal).

        ``specs`` by argument name: an :class:`Array` (a string is an input
        float32 array with those dims), :class:`Vector`, :class:`Scalar`,
        :class:`Workspace`; arguments without a spec are passed unchecked.
        ``order``: arguments checked before the others (else signature order).
        ``separate``: ``(written, read, why)`` pairs that must not share memory, with
        an optional fourth entry ``when(args)``: the rule holds only where it is true.
        """
        name, sig = _parse_signature(signature)
        specs = {n: Array(s) if isinstance(s, str) else s for n, s in specs.items()}
        unknown = set(specs) - set(sig.parameters) | {n for pair in separate for n in pair[:2]} - set(sig.parameters)
        if unknown:
            raise ValueError(f"{self.name}.{name}: specs of arguments not in the signature: {sorted(unknown)}")
        ordered = {n: specs[n] for n in (*order, *sig.parameters) if n in specs}
        fn = HostFunction(self.name, name, sig, doc, ordered, tuple(separate), tuple(rules))
        self.functions[name] = fn
        return fn


def _parse_signature(text: str) -> tuple[str, inspect.Signature]:
    node = ast.parse(f"def {text}: pass").body[0]
    args = node.args
    params = []
    positional = args.args
    defaults = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
    for a, d in zip(positional, defaults):
        params.append(inspect.Parameter(a.arg, inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                        default=inspect.Parameter.empty if d is None else ast.literal_eval(d)))
    for a, d in zip(args.kwonlyargs, args.kw_defaults):
        params.append(inspect.Parameter(a.arg, inspect.Parameter.KEYWORD_ONLY,
                                        default=inspect.Parameter.empty if d is None else ast.literal_eval(d)))
    return node.name, inspect.Signature(params)


def _parse_dims(dims: str) -> tuple:
    """Axes of ``dims``: ``("int", n)``, ``("name", s)``, ``("expr", function, names)``, ``("optional", s)``
    (a last axis ``[C]`` that may be missing, in every array declaring it alike), or ``(("any",),)``."""
    if dims.strip() == "...":
        return (("any",),)
    axes = []
    for token in dims.split():
        if token.startswith("[") and token.endswith("]"):
            axes.append(("optional", token[1:-1]))
        elif token.isdigit():
            axes.append(("int", int(token)))
        elif _NAME.match(token):
            axes.append(("name", token))
        else:
            tree = ast.parse(token, mode="eval").body
            names = tuple(sorted({n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}))
            axes.append(("expr", _compile(tree), names))
    return tuple(axes)


_OPERATORS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
              ast.FloorDiv: lambda a, b: a // b, ast.Pow: lambda a, b: a ** b}


def _compile(node) -> Callable:
    """A dims expression (ints, names, ``+ - * // **``, parentheses) as a function of the env
    (bound sizes and scalar arguments) returning its value; anything else is refused here."""
    if isinstance(node, ast.Constant) and isinstance(node.value, int):
        value = node.value
        return lambda env: value
    if isinstance(node, ast.Name):
        key = node.id
        return lambda env: env[key]
    if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
        op, left, right = _OPERATORS[type(node.op)], _compile(node.left), _compile(node.right)
        return lambda env: op(left(env), right(env))
    raise ValueError(f"dims expressions take ints, sizes, scalars and + - * // **, got {ast.unparse(node)!r}")


# ----------------------------------------------------------------------------- the one checking routine

class Frontend:
    """What a backend's arrays are: the few questions :func:`check_call` asks of them.

    kind : how messages name the array type ("wp.array", "numpy.ndarray").
    array_type, dtypes : the array class, and what its ``dtype`` is for each
        declared dtype name; ``shape`` must be a tuple of ints.
    copies_inputs : a strided input is replaced by a contiguous copy (kernels
        that take contiguous memory only), and a strided output refused.
    """

    kind = "array"
    copies_inputs = False
    #: the array class (``isinstance`` test) and dtype name -> the arrays' ``dtype`` value
    array_type: type = object
    dtypes: dict = {}

    def dtype_name(self, a) -> str:
        raise NotImplementedError

    def device(self, a):
        """The array's device, or ``None`` where there is one device only."""
        return None

    def is_contiguous(self, a) -> bool:
        raise NotImplementedError

    def contiguous(self, a):
        """A C-contiguous copy of ``a``."""
        raise NotImplementedError

    def span(self, a):
        """``(device, first byte, one past the last byte)`` of ``a``'s memory; ``None`` if empty."""
        raise NotImplementedError


def check_call(fn: HostFunction, front: Frontend, args: dict) -> dict:
    """Check ``args`` (argument name -> value, every parameter) against ``fn``'s declaration.

    Returns ``args``, updated with the values to call the implementation with:
    scalars converted, inputs made contiguous where ``front`` copies them.
    Raises TypeError (not an array of the front end, wrong dtype, not a
    workspace) or ValueError (wrong shape, device or value, aliasing) naming
    the argument.
    """
    separate = [(w, args[w], r, args[r], why, when) for w, r, why, *when in fn.separate]
    scalars = {}
    for name, spec in fn._scalars:
        scalars[name] = args[name] = spec.check(name, args[name])
    for name in fn._workspaces:
        check_workspace(args[name])
    sizes: dict = {}
    device = [None]
    deferred = []
    after = fn._after
    for name, spec in fn._arrays:
        value = args[name]
        if type(spec) is Vector:
            args[name] = _vector(front, name, value, spec, sizes, device)
        elif value is None and spec.optional:
            continue
        else:
            args[name], complete = _array(front, name, value, spec, sizes, scalars, device)
            if not complete:
                deferred.append(name)
        if name in after:
            for rule in after[name]:
                args.update(rule.check(sizes, args) or {})
    for name in deferred:
        _array(front, name, args[name], fn.specs[name], sizes, scalars, device, final=True)
    for rule in after.get(None, ()):
        args.update(rule.check(sizes, args) or {})
    for written, a, read, b, why, when in separate:
        if a is None or b is None or (when and not when[0](args)):
            continue
        check_separate(written, front.span(a), read, front.span(b), why)
    return args


def _array(front, name, a, spec: Array, sizes: dict, scalars: dict, device: list, final: bool = False):
    """Check one array argument (binding its sizes into ``sizes``); return it (or its contiguous copy)
    and whether its shape was checked in full (``False``: an expression names a size not bound yet)."""
    if not isinstance(a, front.array_type):
        raise TypeError(f"{name} must be a {front.kind} of {spec.dtype} {spec.describe()}, got {type(a).__name__}")
    if a.dtype != front.dtypes[spec.dtype]:
        raise TypeError(f"{name} must have dtype {spec.dtype}, got {front.dtype_name(a)}")
    shape = a.shape
    complete = True
    if not (spec._plain and _bind_plain(spec._template, shape, sizes, scalars)):
        complete = _bind(name, spec, shape, sizes, scalars)
    if not final:
        dev = front.device(a)
        if device[0] is None:
            device[0] = dev
        elif dev is not device[0] and dev != device[0]:
            raise ValueError(f"{name} is on device {dev}, expected {device[0]} (the device of the first array)")
        if not front.is_contiguous(a):
            if spec.output and (spec.contiguous or front.copies_inputs):
                raise ValueError(f"{name} is written in place and must be C-contiguous")
            if spec.contiguous:
                raise ValueError(f"{name} must be C-contiguous")
            if front.copies_inputs:
                a = front.contiguous(a)
    return a, complete


def _bind_plain(template: tuple, shape: tuple, sizes: dict, scalars: dict) -> bool:
    """The common case, fast: axes of ints, names and expressions (``template``: the ints, the
    names as strings, ``(function, names)`` for expressions).  Binds the new names and returns
    True if ``shape`` matches and every expression could be evaluated; else leaves ``sizes`` as
    it was and returns False (:func:`_bind` then words the error, or defers the array)."""
    if len(shape) != len(template):
        return False
    bound = None
    for x, n in zip(template, shape):
        kind = x.__class__
        if kind is int:
            if x != n:
                break
        elif kind is str:
            e = sizes.get(x)
            if e is None:
                sizes[x] = n
                bound = (bound or []) + [x]
            elif e != n:
                break
        else:
            env = {**scalars, **sizes}
            if not all(k in env for k in x[1]) or max(int(x[0](env)), 0) != n:
                break
    else:
        return True
    for x in bound or ():
        del sizes[x]
    return False


def _bind(name: str, spec: Array, shape: tuple, sizes: dict, scalars: dict) -> bool:
    """Every form of dims: bind the new sizes or raise the ValueError naming ``name``; return
    False if an expression could not be evaluated yet (the array is checked again at the end)."""
    complete = True
    if spec._any:
        want = sizes.get("...")
        if want is not None and shape != want:
            raise ValueError(f"{name} must have shape {spec.describe()} = {want}, got {shape}")
        sizes["..."] = shape
        return complete
    axes = spec._axes
    new = {}
    if spec._optional:
        key = f"[{axes[-1][1]}]"
        present = sizes.get(key, len(shape) == len(axes))
        new[key] = present
        axes = axes[:-1] + ((("name", axes[-1][1]),) if present else ())
    env = {**scalars, **sizes} if spec._exprs else None
    want = []
    for axis in axes:
        kind = axis[0]
        if kind == "int":
            want.append(axis[1])
        elif kind == "name":
            want.append(sizes.get(axis[1]))
        elif all(n in env for n in axis[2]):
            want.append(max(int(axis[1](env)), 0))
        else:
            want.append(None)
            complete = False
    bad = len(shape) != len(want)
    if not bad:
        for axis, e, n in zip(axes, want, shape):
            if e is None:
                if axis[0] == "name" and new.setdefault(axis[1], n) != n:
                    bad = True
            elif e != n:
                bad = True
    if bad:
        shown = tuple("?" if e is None else e for e in want)
        raise ValueError(f"{name} must have shape {spec.describe()} = {shown}, got {shape}")
    sizes.update(new)
    return complete


def _vector(front, name, a, spec: Vector, sizes: dict, device: list):
    if not isinstance(a, front.array_type):
        raise TypeError(f"{name} must be a 1-D {front.kind} of float32, got {type(a).__name__}")
    if a.dtype != front.dtypes["float32"]:
        raise TypeError(f"{name} must have dtype float32, got {front.dtype_name(a)}")
    shape = a.shape
    if len(shape) != 1 or shape[0] < 1:
        raise ValueError(f"{name} must be a non-empty 1-D vector (n,), got shape {shape}")
    n = sizes.setdefault(spec.name, shape[0])
    if shape[0] != n:
        raise ValueError(f"{name} must have the same length as the first vector ({n}), got {shape[0]}")
    dev = front.device(a)
    if device[0] is None:
        device[0] = dev
    elif dev is not device[0] and dev != device[0]:
        raise ValueError(f"{name} is on device {dev}, expected {device[0]} (the device of the first array)")
    if not front.is_contiguous(a) and front.copies_inputs:
        if spec.output:
            raise ValueError(f"{name} is written in place and must be C-contiguous")
        a = front.contiguous(a)
    return a


def checked(fn: HostFunction, front: Frontend) -> Callable:
    """Decorator: the implementation of ``fn`` on a backend, called with the arguments
    :func:`check_call` returns.  The implementation must have the declared signature
    (checked here, when the backend module is imported)."""
    def wrap(impl: Callable) -> Callable:
        have = [(p.name, p.kind, p.default) for p in inspect.signature(impl).parameters.values()]
        want = [(p.name, p.kind, p.default) for p in fn.signature.parameters.values()]
        if have != want:
            raise TypeError(f"{impl.__module__}.{impl.__name__}{inspect.signature(impl)} is not the declared "
                            f"{fn.key}{fn.signature}")
        params = list(fn.signature.parameters.values())
        positional = [p.name for p in params if p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD]
        keyword = [p.name for p in params if p.kind is inspect.Parameter.KEYWORD_ONLY]
        defaults = {p.name: p.default for p in params if p.default is not inspect.Parameter.empty}

        n_positional = len(positional)
        n_required = sum(1 for p in params if p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD
                         and p.default is inspect.Parameter.empty)
        required_keywords = any(p.kind is inspect.Parameter.KEYWORD_ONLY and p.default is inspect.Parameter.empty
                                for p in params)

        def bind(a: tuple, kw: dict) -> dict:
            if len(a) > n_positional:
                raise TypeError(f"{fn.name}() takes {n_positional} positional arguments, got {len(a)}")
            values = dict(defaults)
            values.update(zip(positional, a))
            for k, v in kw.items():
                if k not in fn.signature.parameters or (k in positional and positional.index(k) < len(a)):
                    raise TypeError(f"{fn.name}() got an unexpected or repeated argument {k!r}")
                values[k] = v
            missing = [n for n in (*positional, *keyword) if n not in values]
            if missing:
                raise TypeError(f"{fn.name}() missing arguments {missing}")
            return values

        @functools.wraps(impl)
        def host(*a, **kw):
            if kw or required_keywords or not n_required <= len(a) <= n_positional:
                values = bind(a, kw)
            else:
                values = dict(defaults)
                values.update(zip(positional, a))
            check_call(fn, front, values)
            if keyword:
                return impl(*[values[n] for n in positional], **{n: values[n] for n in keyword})
            return impl(*[values[n] for n in positional])

        host.contract = fn
        return host
    return wrap


def implements(family: Family, front: Frontend) -> Callable:
    """``implements(FAMILY, FRONT)("data_term")``: :func:`checked` by function name (the form each
    backend module uses: ``host = implements(spec.FAMILY, FRONT)`` then ``@host("data_term")``)."""
    def by_name(name: str) -> Callable:
        return checked(family.functions[name], front)
    return by_name


def families() -> dict:
    """Family name -> its :class:`Family`, for every family of :data:`ivkernels.kernels.FAMILIES`."""
    return {f: importlib.import_module(f"ivkernels.kernels.reference.{f}").FAMILY for f in FAMILIES}

