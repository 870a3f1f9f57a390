"""Temporal terms (Eq. 4, 5, 8): the generic contract from the case table (value and gradient
vs the NumPy reference, finite differences), plus the continuous Tukey, no motion giving
exactly zero, a single frame, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.workspace import Workspace
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("energy_temporal")


def make_inputs(rng, t, h, w, c, max_flow=4.0):
    """Random X, flow (partly pointing outside the image) and occ (0, 1 and fractions)."""
    shape = (t, h, w) if c is None else (t, h, w, c)
    X = rng.normal(0.0, 1.0, shape).astype(np.float32)
    flow = rng.uniform(-max_flow, max_flow, (t - 1, h, w, 2)).astype(np.float32)
    flow[:, :, :2, 0] -= 3.0  # left columns: some samples well outside the image
    occ = (rng.random((t - 1, h, w)) < 0.8).astype(np.float32)
    occ[:, ::4, ::3] = 0.5
    return X, flow, occ


def run(be, X, flow, occ, g0=None, e0=None, **kw):
    t, h = X.shape[:2]
    gX = be.asarray(np.zeros(X.shape, np.float32) if g0 is None else g0.copy())
    er = be.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    be.energy_temporal.temporal_term(*(be.asarray(a) for a in (X, flow, occ)), gX, er, **kw)
    return be.numpy(er).copy(), be.numpy(gX).copy()


def test_tukey_is_continuous_and_saturates(kernel_backend):
    """One pixel per row, zero flow: row energy = lam * rho(d) for d swept across alpha."""
    alpha, lam = 2.0, 3.0
    d = np.linspace(-3 * alpha, 3 * alpha, 601).astype(np.float32)
    X = np.zeros((2, d.size, 1), np.float32)
    X[1, :, 0] = d
    flow = np.zeros((1, d.size, 1, 2), np.float32)
    occ = np.ones((1, d.size, 1), np.float32)
    er, gX = run(kernel_backend, X, flow, occ, lam=lam, alpha=alpha)
    q = (d.astype(np.float64) / alpha) ** 2
    closed = np.where(q <= 1, q - q**2 + q**3 / 3, 1 / 3)
    np.testing.assert_allclose(er[: d.size], lam * closed, rtol=1e-5, atol=1e-6)
    assert np.abs(np.diff(er[: d.size])).max() < 0.05  # no jump at |d| = alpha
    np.testing.assert_allclose(er[: d.size][np.abs(d) >= alpha], lam / 3, rtol=1e-6)
    assert not gX[1][np.abs(d) >= alpha].any()
    deriv = np.where(q <= 1, 2 / alpha**2 * d * (1 - q) ** 2, 0.0)
    np.testing.assert_allclose(gX[1, :, 0], lam * deriv, rtol=1e-5, atol=1e-6)


def test_no_motion_constant_gives_exactly_zero(kernel_backend, rng):
    X = np.broadcast_to(rng.normal(size=(1, 11, 13, 3)), (3, 11, 13, 3)).astype(np.float32)
    flow = np.zeros((2, 11, 13, 2), np.float32)
    er, gX = run(kernel_backend, X, flow, np.ones((2, 11, 13), np.float32), lam=10.0)
    assert not er.any() and not gX.any()


def test_single_frame_adds_nothing(kernel_backend, rng):
    X = rng.normal(size=(1, 5, 6, 3)).astype(np.float32)
    er, gX = run(kernel_backend, X, np.zeros((0, 5, 6, 2), np.float32), np.zeros((0, 5, 6), np.float32), lam=10.0)
    assert not er.any() and not gX.any()


def test_bad_input_raises(kernel_backend, rng):
    X, flow, occ = (kernel_backend.asarray(a) for a in make_inputs(rng, 2, 5, 6, 3))
    gX = kernel_backend.zeros((2, 5, 6, 3))
    er = kernel_backend.zeros((10,), np.float64)
    f = kernel_backend.energy_temporal.temporal_term
    with pytest.raises(ValueError, match="flow must have shape"):
        f(X, kernel_backend.zeros((2, 5, 6, 2)), occ, gX, er, 10.0)
    with pytest.raises(ValueError, match="occ must have shape"):
        f(X, flow, kernel_backend.zeros((1, 5, 7)), gX, er, 10.0)
    with pytest.raises(ValueError, match="gX must have shape"):
        f(X, flow, occ, kernel_backend.zeros((2, 5, 6, 1)), er, 10.0)
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        f(X, flow, occ, gX, kernel_backend.zeros((10,), np.float32), 10.0)
    with pytest.raises(TypeError, match="workspace must be"):
        f(X, flow, occ, gX, er, 10.0, workspace={})
    with pytest.raises(TypeError, match="X must have dtype float32"):
        f(kernel_backend.zeros((2, 5, 6, 3), np.float64), flow, occ, gX, er, 10.0)


def test_workspace_reused_across_shapes_gives_the_same_result(kernel_backend, rng):
    a, b = make_inputs(rng, 3, 11, 13, 3), make_inputs(rng, 2, 11, 13, 3)
    fresh = [run(kernel_backend, *x, lam=10.0, alpha=1.5) for x in (a, b)]
    ws = Workspace()
    for _ in range(2):          # the second round finds the buffers left by the first
        for x, want in zip((a, b), fresh):
            for got, w in zip(run(kernel_backend, *x, lam=10.0, alpha=1.5, workspace=ws), want):
                np.testing.assert_array_equal(got, w)
    # Warp keeps one splat-weight buffer per shape; Taichi's single kernel needs none
    assert len(ws) == (2 if kernel_backend.name == "warp" else 0)


def test_both_terms_at_once_equal_the_two_terms(kernel_backend, rng):
    """temporal_terms(A, S) adds what temporal_term(A) then temporal_term(S) add (Warp: bitwise)."""
    be = kernel_backend
    A, flow, occ = make_inputs(rng, 4, 17, 23, 3)
    S = rng.normal(0.0, 1.0, (4, 17, 23)).astype(np.float32)
    e0 = rng.normal(size=4 * 17).astype(np.float64)
    gA0, gS0 = rng.normal(size=A.shape).astype(np.float32), rng.normal(size=S.shape).astype(np.float32)
    rows, gA = run(be, A, flow, occ, gA0, e0, lam=10.0, alpha=1.5)
    rows, gS = run(be, S, flow, occ, gS0, rows, lam=3.0, alpha=1.5)
    both_rows = be.asarray(e0.copy())
    both_gA, both_gS = be.asarray(gA0.copy()), be.asarray(gS0.copy())
    be.energy_temporal.temporal_terms(*(be.asarray(a) for a in (A, S, flow, occ)), both_gA, both_gS, both_rows,
                                      lam_albedo=10.0, lam_shading=3.0, alpha=1.5, workspace=Workspace())
    exact = be.name == "warp"          # same kernels' arithmetic; Taichi's atomics add in any order
    for got, want in ((be.numpy(both_gA), gA), (be.numpy(both_gS), gS), (be.numpy(both_rows), rows)):
        if exact:
            np.testing.assert_array_equal(got, want)
        else:
            np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)
