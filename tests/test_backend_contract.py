"""The backend contract: every registered backend against the declared protocols,
the registry as the one list of backends, the rules every backend shares, and the
declarations of the host functions (:mod:`ivkernels.kernels.contract`) that all of
them and the case table read."""
import inspect
import subprocess
import sys

import numpy as np
import pytest

from ivkernels import cli
from ivkernels.backends import (FAMILIES, FAMILY_PROTOCOLS, BackendProtocol, NumpyBackend, available_backends,
                                backend_names, backend_spec, get_backend, register_backend)
from ivkernels.backends import registry
from ivkernels.kernels.cases import all_cases, run
from ivkernels.kernels.contract import Array, Family, Int, check_call, families
from ivkernels.kernels.ndarray_checks import FRONT as NDARRAY


def _declared(protocol) -> dict:
    """Method name -> signature without ``self``, of a Protocol class."""
    out = {}
    for name, member in vars(protocol).items():
        if inspect.isfunction(member) and not name.startswith("_"):
            sig = inspect.signature(member)
            out[name] = sig.replace(parameters=list(sig.parameters.values())[1:])
    return out


def _shape(sig) -> list:
    """What must agree between declaration and implementation: names, kinds, defaults."""
    return [(p.name, p.kind, p.default) for p in sig.parameters.values()]


@pytest.mark.parametrize("name", backend_names())
@pytest.mark.parametrize("family", sorted(FAMILY_PROTOCOLS))
def test_every_family_module_implements_its_protocol(name, family):
    module = getattr(get_backend(name, "cpu"), family)
    for fn, declared in _declared(FAMILY_PROTOCOLS[family]).items():
        impl = getattr(module, fn, None)
        assert callable(impl), f"{name}.{family} lacks {fn}()"
        assert _shape(inspect.signature(impl)) == _shape(declared), \
            f"{name}.{family}.{fn}{inspect.signature(impl)} drifts from the protocol's {fn}{declared}"


@pytest.mark.parametrize("name", backend_names())
def test_every_backend_object_implements_the_backend_protocol(name):
    be = get_backend(name, "cpu")
    assert be.name == name and be.device == "cpu"
    for attr in BackendProtocol.__annotations__:
        assert getattr(be, attr) is not None, f"{name} lacks {attr}"
    for fn, declared in _declared(BackendProtocol).items():
        assert _shape(inspect.signature(getattr(be, fn))) == _shape(declared), f"{name}.{fn}"


def test_the_protocol_test_catches_a_drift():
    """A module whose signature differs from the protocol's is told apart."""
    def resize_flow(src, out, scale=1.0):
        pass

    declared = _declared(FAMILY_PROTOCOLS["pyramid"])["resize_flow"]
    assert _shape(inspect.signature(resize_flow)) != _shape(declared)


def test_backend_array_round_trip(any_backend):
    be = any_backend
    a = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    b = be.asarray(a)
    np.testing.assert_array_equal(be.numpy(b), a)
    z = be.zeros((2, 3))
    assert be.numpy(z).shape == (2, 3) and not be.numpy(z).any()
    e = be.empty(5, np.float64)
    assert be.numpy(e).shape == (5,) and be.numpy(e).dtype == np.float64
    be.zero(b)
    be.synchronize()
    assert not be.numpy(b).any()


def test_registry_lists_the_built_in_backends():
    assert backend_names()[:3] == ("warp", "taichi", "numpy")
    assert backend_spec("numpy").oracle and not backend_spec("warp").oracle
    assert backend_spec("warp").devices == ("cpu", "cuda")
    names = {b.name for b in available_backends()}
    assert names == set(backend_names())
    assert "numpy" not in {b.name for b in available_backends(oracles=False)}


def test_unknown_backend_is_a_clear_error():
    with pytest.raises(ValueError, match=r"backend must be one of \('warp', 'taichi', 'numpy'"):
        get_backend("torch")
    with pytest.raises(ValueError, match="numpy backend runs on device='cpu' only"):
        get_backend("numpy", "cuda")
    with pytest.raises(ValueError, match="devices must be"):
        register_backend("x", object, devices=("tpu",))
    with pytest.raises(ValueError, match="identifier"):
        register_backend("not a name", object)


def test_a_registered_backend_reaches_every_reader(monkeypatch):
    """get_backend, the CLI's --backend choices and the validation all read the registry."""
    monkeypatch.setattr(registry, "_specs", dict(registry._specs))
    monkeypatch.setattr(registry, "_made", {})

    class Echo(NumpyBackend):
        name = "echo"

    register_backend("echo", Echo)
    assert isinstance(get_backend("echo"), Echo)
    registry.check_device("echo", "cpu")
    with pytest.raises(ValueError, match="echo backend runs on device='cpu' only"):
        registry.check_device("echo", "cuda")
    assert cli._parser().parse_args(["decompose", "in", "-o", "out", "--backend", "echo"]).backend == "echo"


def _modules_loaded_by(backend: str) -> str:
    """``sys.modules`` membership of warp and taichi after loading every family of ``backend``,
    in a fresh interpreter."""
    code = ("import sys; from ivkernels.backends import get_backend, FAMILIES; "
            f"be = get_backend({backend!r}); [getattr(be, f) for f in FAMILIES]; "
            "print('warp' in sys.modules, 'taichi' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.strip().splitlines()[-1]


def test_taichi_backend_does_not_load_warp():
    assert _modules_loaded_by("taichi") == "False True"


def test_numpy_backend_loads_neither_warp_nor_taichi():
    assert _modules_loaded_by("numpy") == "False False"


# ----------------------------------------------------------------------------- rules every backend shares

def test_aliasing_is_refused_alike(any_backend):
    """One rule (kernels.checks.check_separate): the same array, or a view overlapping it, is refused."""
    be = any_backend
    I = be.asarray(np.zeros((2, 4, 5, 3), np.float32))
    S = be.zeros((2, 4, 5))
    with pytest.raises(ValueError, match="A must not alias I"):
        be.energy_data.constrained_albedo(I, S, I)
    buf = be.zeros(100)                                    # two (2, 4, 5, 2) fields, 10 floats apart
    with pytest.raises(ValueError, match="p_in must not alias p_out"):
        be.flow_classic.rof_dual_step(S, buf[:80].reshape((2, 4, 5, 2)), buf[10:90].reshape((2, 4, 5, 2)), 0.25, 0.5)
    src = be.zeros((1, 6, 7, 1))
    with pytest.raises(ValueError, match="scratch must not alias src"):
        be.pyramid.gaussian_blur(src, be.zeros((1, 6, 7, 1)), src, 1.0)
    flow = be.zeros((1, 6, 7, 2))
    with pytest.raises(ValueError, match="out must not alias src"):
        be.median.median5x5(flow, flow)
    X = be.zeros((2, 4, 5))                                # (T, H, W): viewed as (T, H, W, 1) on Warp
    with pytest.raises(ValueError, match="gX must not alias X"):
        be.energy_temporal.temporal_term(X, be.zeros((1, 4, 5, 2)), be.zeros((1, 4, 5)), X,
                                         be.zeros(8, np.float64), 1.0)
    # disjoint halves of one buffer are separate
    be.flow_classic.rof_dual_step(be.zeros((1, 4, 5)), buf[:40].reshape((1, 4, 5, 2)),
                                  buf[40:80].reshape((1, 4, 5, 2)), 0.25, 0.5)


def test_flow_classic_reads_non_contiguous_input_alike(any_backend, rng):
    """Every backend reads a strided view as its contiguous copy (Taichi copies it, Warp reads the strides)."""
    from ivkernels.kernels.reference import flow_classic as ref

    be = any_backend
    rgb = rng.uniform(0.0, 1.0, (2, 5, 14, 3)).astype(np.float32)
    view = be.asarray(rgb)[:, :, ::2]
    out = be.empty((2, 5, 7))
    be.flow_classic.srgb_grey(view, out)
    np.testing.assert_allclose(be.numpy(out), ref.srgb_grey(rgb[:, :, ::2]), rtol=1e-5, atol=1e-4)
    flow = rng.normal(size=(2, 5, 14, 2)).astype(np.float32)
    sobel, energy = be.empty((2, 5, 7, 4)), be.empty((10, 2))
    be.flow_classic.flow_sobel_components(be.asarray(flow)[:, :, ::2], sobel, energy)
    want, want_energy = ref.flow_sobel_components(flow[:, :, ::2])
    np.testing.assert_allclose(be.numpy(sobel), want, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(be.numpy(energy), want_energy, rtol=1e-4, atol=1e-4)


def test_median_spatial_table_is_built_once(monkeypatch):
    """Taichi keeps the shading median's spatial table between calls, as Warp does."""
    from ivkernels.kernels.taichi import median

    calls = []
    real = median.spatial_weights
    monkeypatch.setattr(median, "spatial_weights", lambda r, s: calls.append((r, s)) or real(r, s))
    be = get_backend("taichi")
    S = np.zeros((1, 6, 7), np.float32)
    for _ in range(3):
        be.median.weighted_median_shading(S, np.zeros((1, 6, 7, 2), np.float32), np.ones((1, 6, 7), np.float32),
                                          np.empty_like(S), radius=2, sigma_s=3.25)
    assert calls.count((2, 3.25)) <= 1


# ----------------------------------------------------------------------------- the declared contract

def _declared_functions():
    return [fn for family in families().values() for fn in family.functions.values()]


def _bound(case, values) -> dict:
    """Every parameter of ``case``'s host function: the case's values, defaults for the rest."""
    fn = families()[case.family].functions[case.function]
    args = {n: p.default for n, p in fn.signature.parameters.items() if p.default is not inspect.Parameter.empty}
    args.update({n: values[n] for n in (*case.call, *case.keywords)})
    return args


def test_every_family_is_declared_once_in_order():
    assert tuple(families()) == FAMILIES == tuple(FAMILY_PROTOCOLS)
    for name, family in families().items():
        assert family.name == name
        assert set(_declared(FAMILY_PROTOCOLS[name])) == set(family.functions)


@pytest.mark.parametrize("name", backend_names())
def test_every_backend_checks_through_the_declaration(name):
    """Each host function with declared arguments runs the one shared check (kernels.contract.checked)."""
    be = get_backend(name, "cpu")
    for fn in _declared_functions():
        impl = getattr(getattr(be, fn.family), fn.name)
        if fn.specs:
            assert getattr(impl, "contract", None) is fn, f"{name}.{fn.key} does not check through its declaration"


@pytest.mark.parametrize("case", all_cases(), ids=lambda c: c.key)
def test_case_inputs_meet_the_declaration(case):
    """The case table and the declarations agree: every case's inputs pass the declared checks."""
    fn = families()[case.family].functions[case.function]
    values = case.make(np.random.default_rng(0), *(max(case.min_frames, 2), 7, 11))
    check_call(fn, NDARRAY, _bound(case, values))


def _bad_arguments():
    """(case, argument) for every declared array argument of every case (one case per function)."""
    seen, out = set(), []
    for case in all_cases():
        if case.key.split("[")[0] in seen:
            continue
        seen.add(case.key.split("[")[0])
        fn = families()[case.family].functions[case.function]
        for name, spec in fn.arrays().items():
            if name in (*case.call, *case.keywords) and getattr(spec, "dims", "") != "...":
                out.append(pytest.param(case, name, id=f"{case.key}-{name}"))
    return out


@pytest.mark.parametrize("case,name", _bad_arguments())
def test_a_misshapen_or_mistyped_argument_is_named(any_backend, case, name):
    """Generated from the declarations: an array with one axis too many, or of another dtype, is
    refused before any launch with a message naming the argument."""
    be = any_backend
    values = case.make(np.random.default_rng(0), *(max(case.min_frames, 2), 7, 11))
    good = values[name]
    with pytest.raises(ValueError, match=rf"^{name} must (have shape|be a non-empty 1-D vector)"):
        run(case, be, values, {name: be.asarray(np.zeros(good.shape + (1,), good.dtype))})
    other = np.float64 if good.dtype == np.float32 else np.float32
    with pytest.raises(TypeError, match=rf"^{name} must have dtype"):
        run(case, be, values, {name: be.asarray(good.astype(other))})


@pytest.mark.parametrize("case", all_cases(), ids=lambda c: c.key)
def test_numpy_backend_is_its_cases_reference(case):
    """The NumPy backend, made from the case table, gives each case's reference on odd sizes."""
    be = get_backend("numpy")
    values = case.make(np.random.default_rng(0), max(case.min_frames, 2), 5, 7)
    got, want = run(case, be, values), case.reference(values)
    for name, expected in want.items():
        np.testing.assert_allclose(np.asarray(got[name], np.float64), np.asarray(expected, np.float64),
                                   rtol=1e-6, atol=1e-6, err_msg=f"{case.key}: {name}")


def test_declared_shapes_bind_and_compare():
    """The one checking routine: sizes bound by the first array, compared in the next, expressions
    of bound sizes and scalars, an optional last axis, and messages with the sizes expected."""
    family = Family("demo", "for the test")
    fn = family.declare("f(a, b, c, n=1, *, d=None)", "demo", a="T H W [C]", b=Array("T-1 H (W-1)//n+2"),
                        c=Array("T*H", "float64", output=True), d=Array("T H W [C]", optional=True), n=Int(1))
    ok = {"a": np.zeros((3, 4, 5), np.float32), "b": np.zeros((2, 4, 4), np.float32),
          "c": np.zeros(12, np.float64), "n": 2, "d": None}
    assert check_call(fn, NDARRAY, ok)["n"] == 2
    with pytest.raises(ValueError,
                       match=r"^b must have shape \(T-1, H, \(W-1\)//n\+2\) = \(2, 4, 6\), got \(2, 4, 4\)"):
        check_call(fn, NDARRAY, {**ok, "n": 1})
    with pytest.raises(ValueError, match=r"^c must have shape \(T\*H,\) = \(12,\), got \(11,\)"):
        check_call(fn, NDARRAY, {**ok, "c": np.zeros(11, np.float64)})
    with pytest.raises(ValueError, match=r"^d must have shape \(T, H, W, \[C\]\) = \(3, 4, 5\)"):
        check_call(fn, NDARRAY, {**ok, "d": np.zeros((3, 4, 5, 1), np.float32)})
    with pytest.raises(TypeError, match="^c must have dtype float64, got float32"):
        check_call(fn, NDARRAY, {**ok, "c": np.zeros(12, np.float32)})
    with pytest.raises(ValueError, match=r"^n must be an int >= 1, got 0"):
        check_call(fn, NDARRAY, {**ok, "n": 0})
    strided = np.zeros(24, np.float64)[::2]
    with pytest.raises(ValueError, match="^c is written in place and must be C-contiguous"):
        check_call(fn, NDARRAY, {**ok, "c": strided})
    assert check_call(fn, NDARRAY, {**ok, "a": np.zeros((3, 4, 10), np.float32)[:, :, ::2]})["a"].flags.c_contiguous


class _Reads(dict):
    """A dict recording the keys read from it."""

    def __init__(self, *args):
        super().__init__(*args)
        self.read = set()

    def __getitem__(self, key):
        self.read.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.read.add(key)
        return super().get(key, default)


def _first_cases() -> list:
    """The case each function of the NumPy backend is made from (its family's first of that function)."""
    first = {}
    for case in all_cases():
        first.setdefault((case.family, case.function), case)
    return [c for c in first.values() if c.family not in ("energy_albedo_entropy",)]


@pytest.mark.parametrize("case", _first_cases(), ids=lambda c: c.key)
def test_case_reference_is_a_function_of_the_arguments(case):
    """The NumPy backend is made from the case references, so the reference of each function's
    first case reads every argument (outputs added into or updated included) and nothing else."""
    fn = families()[case.family].functions[case.function]
    values = _Reads(case.make(np.random.default_rng(0), 2, 5, 7))
    case.reference(values)
    wanted = {n for n in fn.signature.parameters if n != "workspace"} - \
        {n for n in fn.outputs() if not fn.specs[n].accumulate and n not in case.updates}
    assert wanted <= values.read <= set(fn.signature.parameters), (wanted - values.read, values.read - wanted)
