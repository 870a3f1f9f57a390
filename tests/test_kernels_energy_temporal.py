"""Temporal terms (Eq. 4, 5, 8): value and gradient vs the NumPy reference,
finite differences, the continuous Tukey, threads, backends, bad input."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import energy_temporal as ref
from ivkernels.kernels.workspace import Workspace


def make_inputs(rng, t, h, w, c, max_flow=4.0):
    """Random X, flow (partly pointing outside the image) and occ (0, 1 and fractions)."""
    shape = (t, h, w) if c is None else (t, h, w, c)
    X = rng.normal(0.0, 1.0, shape).astype(np.float32)
    flow = rng.uniform(-max_flow, max_flow, (t - 1, h, w, 2)).astype(np.float32)
    flow[:, :, :2, 0] -= 3.0  # left columns: some samples well outside the image
    occ = (rng.random((t - 1, h, w)) < 0.8).astype(np.float32)
    occ[:, ::4, ::3] = 0.5
    return X, flow, occ


def run(backend, X, flow, occ, g0=None, e0=None, **kw):
    t, h = X.shape[:2]
    gX = backend.asarray(np.zeros(X.shape, np.float32) if g0 is None else g0.copy())
    er = backend.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    backend.energy_temporal.temporal_term(*(backend.asarray(a) for a in (X, flow, occ)), gX, er, **kw)
    return backend.numpy(er).copy(), backend.numpy(gX).copy()


@pytest.mark.parametrize("channels", [3, 1, None], ids=["C3", "C1", "HW"])
def test_matches_reference_and_accumulates(backend, rng, channels):
    X, flow, occ = make_inputs(rng, 3, 37, 53, channels)
    g0 = rng.normal(size=X.shape).astype(np.float32)
    e0 = rng.normal(size=3 * 37)
    er, gX = run(backend, X, flow, occ, g0, e0, lam=10.0, alpha=1.5)
    r_er, r_gX = ref.temporal_term(X, flow, occ, lam=10.0, alpha=1.5)
    assert not r_er[2 * 37:].any()  # the last frame has no pair
    np.testing.assert_allclose(er, e0 + r_er, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(gX, g0 + r_gX, rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("channels", [3, 1])
def test_gradient_matches_finite_differences(backend, rng, channels):
    X, flow, occ = make_inputs(rng, 2, 7, 9, channels)
    lam, alpha = 10.0, 1.5  # |d| spans both sides of alpha
    _, gX = run(backend, X, flow, occ, lam=lam, alpha=alpha)
    X64, h = X.astype(np.float64), 1e-6
    fd = np.zeros_like(X64)
    for idx in np.ndindex(X.shape):
        xp, xm = X64.copy(), X64.copy()
        xp[idx] += h
        xm[idx] -= h
        fd[idx] = (ref.temporal_term(xp, flow, occ, lam, alpha)[0].sum()
                   - ref.temporal_term(xm, flow, occ, lam, alpha)[0].sum()) / (2 * h)
    assert np.abs(fd).max() > 1.0
    np.testing.assert_allclose(gX, fd, rtol=1e-4, atol=1e-4)


def test_tukey_is_continuous_and_saturates(backend):
    """One pixel per row, zero flow: row energy = lam * rho(d) for d swept across alpha."""
    alpha, lam = 2.0, 3.0
    d = np.linspace(-3 * alpha, 3 * alpha, 601).astype(np.float32)
    X = np.zeros((2, d.size, 1), np.float32)
    X[1, :, 0] = d
    flow = np.zeros((1, d.size, 1, 2), np.float32)
    occ = np.ones((1, d.size, 1), np.float32)
    er, gX = run(backend, X, flow, occ, lam=lam, alpha=alpha)
    q = (d.astype(np.float64) / alpha) ** 2
    closed = np.where(q <= 1, q - q**2 + q**3 / 3, 1 / 3)
    np.testing.assert_allclose(er[: d.size], lam * closed, rtol=1e-5, atol=1e-6)
    assert np.abs(np.diff(er[: d.size])).max() < 0.05  # no jump at |d| = alpha
    np.testing.assert_allclose(er[: d.size][np.abs(d) >= alpha], lam / 3, rtol=1e-6)
    assert not gX[1][np.abs(d) >= alpha].any()
    deriv = np.where(q <= 1, 2 / alpha**2 * d * (1 - q) ** 2, 0.0)
    np.testing.assert_allclose(gX[1, :, 0], lam * deriv, rtol=1e-5, atol=1e-6)


def test_no_motion_constant_gives_exactly_zero(backend, rng):
    X = np.broadcast_to(rng.normal(size=(1, 11, 13, 3)), (3, 11, 13, 3)).astype(np.float32)
    flow = np.zeros((2, 11, 13, 2), np.float32)
    er, gX = run(backend, X, flow, np.ones((2, 11, 13), np.float32), lam=10.0)
    assert not er.any() and not gX.any()


def test_single_frame_adds_nothing(backend, rng):
    X = rng.normal(size=(1, 5, 6, 3)).astype(np.float32)
    er, gX = run(backend, X, np.zeros((0, 5, 6, 2), np.float32), np.zeros((0, 5, 6), np.float32), lam=10.0)
    assert not er.any() and not gX.any()


def test_workspace_reused_across_shapes_gives_the_same_result(backend, rng):
    a, b = make_inputs(rng, 3, 11, 13, 3), make_inputs(rng, 2, 11, 13, 3)
    fresh = [run(backend, *x, lam=10.0, alpha=1.5) for x in (a, b)]
    ws = Workspace()
    for _ in range(2):          # the second round finds the buffers left by the first
        for x, want in zip((a, b), fresh):
            for got, w in zip(run(backend, *x, lam=10.0, alpha=1.5, workspace=ws), want):
                np.testing.assert_array_equal(got, w)
    # Warp keeps one splat-weight buffer per shape; Taichi's single kernel needs none
    assert len(ws) == (2 if backend.name == "warp" else 0)


def test_one_and_two_threads_identical(rng):
    be = get_backend("warp", "cpu")
    X, flow, occ = make_inputs(rng, 5, 37, 53, 3, max_flow=8.0)
    with threads(1):
        one = run(be, X, flow, occ, lam=10.0)
    with threads(2):
        two = run(be, X, flow, occ, lam=10.0)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_warp_matches_taichi(rng):
    X, flow, occ = make_inputs(rng, 3, 19, 23, 3)
    w = run(get_backend("warp"), X, flow, occ, lam=10.0, alpha=1.0)
    t = run(get_backend("taichi"), X, flow, occ, lam=10.0, alpha=1.0)
    for a, b in zip(w, t):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-5)


def test_bad_input_raises(backend, rng):
    X, flow, occ = (backend.asarray(a) for a in make_inputs(rng, 2, 5, 6, 3))
    gX = backend.zeros((2, 5, 6, 3))
    er = backend.zeros((10,), np.float64)
    f = backend.energy_temporal.temporal_term
    with pytest.raises(ValueError, match="flow must have shape"):
        f(X, backend.zeros((2, 5, 6, 2)), occ, gX, er, 10.0)
    with pytest.raises(ValueError, match="occ must have shape"):
        f(X, flow, backend.zeros((1, 5, 7)), gX, er, 10.0)
    with pytest.raises(ValueError, match="gX must have shape"):
        f(X, flow, occ, backend.zeros((2, 5, 6, 1)), er, 10.0)
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        f(X, flow, occ, gX, backend.zeros((10,), np.float32), 10.0)
    with pytest.raises(TypeError, match="X must have dtype float32"):
        f(backend.zeros((2, 5, 6, 3), np.float64), flow, occ, gX, er, 10.0)
    with pytest.raises(TypeError, match="workspace must be"):
        f(X, flow, occ, gX, er, 10.0, workspace={})
