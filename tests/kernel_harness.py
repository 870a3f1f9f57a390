"""Shared harness of the kernel batteries: backends, finite differences, and the contract tests.

Every kernel family's battery (``tests/test_kernels_<family>.py``) gets the
generic checks of each host function from the case table
(:mod:`ivkernels.kernels.cases`) in one line, and keeps only the checks
specific to its family::

    from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

    TestContract = contract("median")
  The contract, for every
case (host function and variant) on every real backend:

* matches the NumPy reference on odd sizes, one row, one column and one frame;
* reads non-contiguous (strided) inputs, or refuses those the case names
  ``contiguous`` with a ValueError;
* refuses an output aliasing an input it must not alias (ValueError), and
  gives the reference's answer for the pairs that may alias;
* handles empty input (zero frames, zero rows): no crash, or a ValueError,
  the same on every backend;
* Warp on 1 and 2 CPU threads gives identical results;
* every pair of backends agrees;
* energy gradients match central differences of the float64 reference energy.

Real backends are those of :func:`ivkernels.backends.available_backends`
that are not the reference oracle (``getattr(be, "is_reference", False)``).
Known drifts of a kernel from the contract are listed in :data:`KNOWN_GAPS`
and run as strict xfails, so fixing one turns its test red until the entry
goes.
"""
from __future__ import annotations

import dataclasses
import fnmatch
import itertools

import numpy as np
import pytest

from ivkernels.backends import available_backends
from ivkernels.kernels.cases import Case, cases_of, run
from ivkernels.kernels.launch import threads

# (T, H, W) of the reference comparisons: odd sizes and the edge cases of rows, columns and frames.
REFERENCE_SIZES = {"odd": (2, 7, 11), "row": (2, 1, 11), "column": (2, 7, 1), "frame": (1, 7, 11),
                   "larger": (3, 23, 37)}
CONTRACT_SIZE = (2, 7, 11)       # strided, aliasing
PAIR_SIZE = (2, 19, 23)          # backends against each other
THREAD_SIZE = (3, 23, 37)        # 69 rows, split in two bands
EMPTY_SIZES = {"no-frames": (0, 7, 11), "no-rows": (2, 0, 11)}

# (check, backend name pattern, case key pattern) -> why the kernel does not meet the contract yet.
# Each runs as a strict xfail: when the kernel is fixed, its entry must go.
KNOWN_GAPS: dict = {}


# ----------------------------------------------------------------------------- backends

def real_backends() -> list:
    """The backends whose kernels are tested: every available one except the oracles built on
    the NumPy references (the ``numpy`` backend *is* the references the batteries compare with)."""
    return available_backends(oracles=False)


def backend_id(be) -> str:
    return f"{be.name}-{be.device}"


def parametrize_kernel_backends(metafunc) -> None:
    """``kernel_backend``: each real backend; ``backend_pair``: each unordered pair of them."""
    backends = real_backends()
    if "kernel_backend" in metafunc.fixturenames:
        metafunc.parametrize("kernel_backend", backends, ids=[backend_id(b) for b in backends])
    if "backend_pair" in metafunc.fixturenames:
        pairs = list(itertools.combinations(backends, 2))
        metafunc.parametrize("backend_pair", pairs, ids=[f"{backend_id(a)}-vs-{backend_id(b)}" for a, b in pairs])


def pytest_generate_tests(metafunc) -> None:
    """Module-level hook for the batteries: import it into a test module to get the fixtures."""
    parametrize_kernel_backends(metafunc)


# ----------------------------------------------------------------------------- checks

def call_host(be, family: str, name: str, inputs, outputs, *params):
    """Call ``be.<family>.<name>(*inputs, *outputs, *params)`` on float32 copies of the
    NumPy ``inputs`` and ``outputs``; return the outputs as NumPy (one array, or a list)."""
    args = [be.asarray(np.ascontiguousarray(a, np.float32)) for a in inputs]
    outs = [be.asarray(np.ascontiguousarray(o, np.float32).copy()) for o in outputs]
    getattr(getattr(be, family), name)(*args, *outs, *params)
    result = [be.numpy(o).copy() for o in outs]
    return result[0] if len(result) == 1 else result


def finite_differences(energy, x, h: float = 1e-6) -> np.ndarray:
    """Central differences ``(E(x + h e_i) - E(x - h e_i)) / 2h`` of a scalar ``energy`` at every entry of ``x``.

    ``x`` is taken in float64; returns an array of its shape.
    """
    x = np.array(x, np.float64)
    fd = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        keep = x[idx]
        x[idx] = keep + h
        up = energy(x)
        x[idx] = keep - h
        down = energy(x)
        x[idx] = keep
        fd[idx] = (up - down) / (2 * h)
    return fd


def assert_outputs(case: Case, got: dict, want: dict, values: dict, label: str = "") -> None:
    """Every output the reference predicts, within the case's tolerance (ignoring tied entries)."""
    ignore = case.ignore(values) if case.ignore else {}
    for name, expected in want.items():
        tol = case.tolerance(name)
        actual = got[name]
        expected = np.asarray(expected)
        if name in ignore:
            keep = ~np.asarray(ignore[name])
            actual, expected = np.asarray(actual)[keep], expected[keep]
        np.testing.assert_allclose(np.asarray(actual, np.float64), expected.astype(np.float64), rtol=tol.rtol,
                                   atol=tol.absolute(expected), err_msg=f"{case.key} {label}: {name}")


def strided_view(be, a: np.ndarray):
    """A non-contiguous backend view holding ``a`` (every stride doubled).

    The last axis is stored twice as long and read with a step of two, so the
    view has ``a``'s number of axes (Warp's CUDA arrays hold at most four)."""
    big = np.zeros(a.shape[:-1] + (2 * a.shape[-1],), a.dtype)
    big[..., ::2] = a
    return be.asarray(big)[(slice(None),) * (a.ndim - 1) + (slice(None, None, 2),)]


def known_gap(check: str, be, case: Case) -> str | None:
    for (c, backend, key), reason in KNOWN_GAPS.items():
        if c == check and fnmatch.fnmatch(be.name if be is not None else "", backend) \
                and (case.key == key or fnmatch.fnmatch(case.key, key)):
            return reason
    return None


def mark_gap(request, check: str, be, case: Case) -> None:
    reason = known_gap(check, be, case)
    if reason:
        request.applymarker(pytest.mark.xfail(reason=reason, strict=True))


def make_values(case: Case, size, seed: int = 0) -> dict:
    return case.make(np.random.default_rng(seed), *size)


# ----------------------------------------------------------------------------- generated tests

def _case_id(case: Case) -> str:
    return case.function + (f"-{case.variant}" if case.variant else "")


@dataclasses.dataclass(frozen=True)
class _Param:
    """One parameter set of a contract test (names of its arguments and an id)."""

    values: tuple
    id: str


def _params(test: str, cases) -> tuple[str, list]:
    if test in ("test_matches_reference",):
        return "case,size", [_Param((c, s), f"{_case_id(c)}-{k}") for c in cases for k, s in REFERENCE_SIZES.items()]
    if test == "test_refuses_aliased_output":
        return "case,pair", [_Param((c, p), f"{_case_id(c)}-{p[1]}={p[0]}") for c in cases for p in c.no_alias]
    if test == "test_in_place":
        return "case,pair", [_Param((c, p), f"{_case_id(c)}-{p[1]}={p[0]}") for c in cases for p in c.in_place]
    if test == "test_empty_input":
        return "case,size", [_Param((c, s), f"{_case_id(c)}-{k}") for c in cases for k, s in EMPTY_SIZES.items()]
    if test == "test_gradient_matches_finite_differences":
        return "case,gradient", [_Param((c, g), f"{_case_id(c)}-d{g.energy}/d{g.wrt}") for c in cases
                                 for g in c.gradients]
    return "case", [_Param((c,), _case_id(c)) for c in cases]


class KernelContract:
    """The generic checks of every host function of ``family`` (set by the subclass)."""

    family: str = ""

    def pytest_generate_tests(self, metafunc) -> None:
        if "case" not in metafunc.fixturenames:
            return
        names, params = _params(metafunc.function.__name__, cases_of(self.family))
        metafunc.parametrize(names, [p.values if len(p.values) > 1 else p.values[0] for p in params],
                             ids=[p.id for p in params])

    def test_matches_reference(self, request, case, size, kernel_backend):
        mark_gap(request, "reference", kernel_backend, case)
        values = make_values(case, size)
        if size[0] < case.min_frames:
            with pytest.raises(ValueError):
                run(case, kernel_backend, values)
            return
        assert_outputs(case, run(case, kernel_backend, values), case.reference(values), values, f"{size}")

    def test_strided_inputs(self, request, case, kernel_backend):
        mark_gap(request, "strided", kernel_backend, case)
        values = make_values(case, CONTRACT_SIZE)
        names = case.inputs(values)
        for name in case.contiguous:
            with pytest.raises(ValueError, match=f"{name}.*contiguous"):
                run(case, kernel_backend, values, {name: strided_view(kernel_backend, values[name])})
        views = {n: strided_view(kernel_backend, values[n]) for n in names if n not in case.contiguous}
        assert_outputs(case, run(case, kernel_backend, values, views), case.reference(values), values, "strided")

    def test_refuses_aliased_output(self, request, case, pair, kernel_backend):
        mark_gap(request, "alias", kernel_backend, case)
        source, output = pair
        values = make_values(case, CONTRACT_SIZE)
        shared = kernel_backend.asarray(values[source].copy())
        with pytest.raises(ValueError, match=rf"(?i)alias|different arrays|separate|overlap"):
            run(case, kernel_backend, values, {source: shared, output: shared})

    def test_in_place(self, request, case, pair, kernel_backend):
        mark_gap(request, "in_place", kernel_backend, case)
        source, output = pair
        values = make_values(case, CONTRACT_SIZE)
        shared = kernel_backend.asarray(values[source].copy())
        got = run(case, kernel_backend, values, {source: shared, output: shared})
        assert_outputs(case, got, case.reference({**values, output: values[source]}), values, "in place")

    def test_empty_input(self, request, case, size):
        """Every real backend succeeds (and they agree), or every one raises a ValueError."""
        mark_gap(request, "empty", None, case)
        values = make_values(case, size)
        outcomes = []
        for be in real_backends():
            try:
                outcomes.append((be, run(case, be, values)))
            except ValueError as err:
                outcomes.append((be, err))
        kinds = {type(o).__name__ for _, o in outcomes}
        assert len(kinds) == 1, f"{case.key} on {size}: " + ", ".join(
            f"{backend_id(be)}: {o!r}" if isinstance(o, Exception) else f"{backend_id(be)}: ran" for be, o in outcomes)
        first = outcomes[0][1]
        if isinstance(first, Exception):
            assert str(first), "the error must say what is wrong"
            return
        for be, got in outcomes[1:]:
            for name in case.compared:
                np.testing.assert_array_equal(np.shape(got[name]), np.shape(first[name]))
                np.testing.assert_allclose(got[name], first[name], rtol=case.tolerance(name).rtol,
                                           atol=case.tolerance(name).atol, err_msg=f"{case.key}: {name}")

    def test_one_and_two_threads_identical(self, request, case):
        warp_cpu = [b for b in real_backends() if b.name == "warp" and b.device == "cpu"]
        if not warp_cpu:
            pytest.skip("no Warp CPU backend")
        values = make_values(case, THREAD_SIZE)
        results = []
        for n in (1, 2):
            with threads(n):
                results.append(run(case, warp_cpu[0], values))
        for name in results[0]:
            np.testing.assert_array_equal(results[0][name], results[1][name], err_msg=f"{case.key}: {name}")

    def test_backends_agree(self, request, case, backend_pair):
        a, b = backend_pair
        mark_gap(request, "pair", b, case)
        values = make_values(case, PAIR_SIZE)
        got_a = run(case, a, values)
        assert_outputs(case, run(case, b, values), {k: got_a[k] for k in case.compared}, values,
                       f"{backend_id(b)} vs {backend_id(a)}")

    def test_gradient_matches_finite_differences(self, request, case, gradient, kernel_backend):
        """The kernel's float32 gradient against central differences of the float64 reference energy."""
        mark_gap(request, "gradient", kernel_backend, case)
        make = gradient.make or case.make
        values = {**make(np.random.default_rng(1), *gradient.size), **gradient.overrides}
        values[gradient.grad] = np.zeros_like(values[gradient.grad])
        values[gradient.energy] = np.zeros_like(values[gradient.energy])
        got = run(case, kernel_backend, values)[gradient.grad]

        def energy(x):
            return float(np.sum(case.reference({**values, gradient.wrt: x})[gradient.energy]))

        fd = finite_differences(energy, values[gradient.wrt])
        assert np.abs(fd).max() > gradient.min_peak
        np.testing.assert_allclose(got, fd, rtol=gradient.rtol,
                                   atol=gradient.atol + gradient.atol_rel * np.abs(fd).max())


def contract(family: str) -> type:
    """The :class:`KernelContract` of ``family``, without the checks none of its cases has
    (no aliasing pair, no gradient), so that nothing is collected only to be skipped."""
    cases = cases_of(family)
    absent = {name: None for name in dir(KernelContract)
              if name.startswith("test_") and not _params(name, cases)[1]}
    return type(f"TestContract_{family}", (KernelContract,), {"family": family, **absent})
