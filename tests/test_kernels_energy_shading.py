"""Shading terms (Eq. 9 local smoothness, Eq. 13 coupling): value and gradient
vs the NumPy reference, finite differences, threads, backends, bad input."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import energy_shading as ref


def buffers(backend, shape, g0, e0):
    t, h = shape[:2]
    gS = backend.asarray(np.zeros(shape, np.float32) if g0 is None else g0.copy())
    er = backend.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    return gS, er


def run_smoothness(backend, S, g0=None, e0=None, **kw):
    gS, er = buffers(backend, S.shape, g0, e0)
    backend.energy_shading.shading_smoothness(backend.asarray(S), gS, er, **kw)
    return backend.numpy(er).copy(), backend.numpy(gS).copy()


def run_coupling(backend, S, S_tilde, w_bnd, g0=None, e0=None, **kw):
    gS, er = buffers(backend, S.shape, g0, e0)
    backend.energy_shading.coupling_term(*(backend.asarray(a) for a in (S, S_tilde, w_bnd)), gS, er, **kw)
    return backend.numpy(er).copy(), backend.numpy(gS).copy()


def coupling_inputs(rng, t, h, w, t_flow):
    S = rng.normal(size=(t, h, w)).astype(np.float32)
    S_tilde = rng.normal(size=(t, h, w)).astype(np.float32)
    w_bnd = (rng.random((t_flow, h, w)) < 0.3).astype(np.float32)
    return S, S_tilde, w_bnd


def finite_differences(energy, x, h=1e-6):
    x = x.astype(np.float64)
    fd = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        xp, xm = x.copy(), x.copy()
        xp[idx] += h
        xm[idx] -= h
        fd[idx] = (energy(xp) - energy(xm)) / (2 * h)
    return fd


def test_smoothness_matches_reference_and_accumulates(backend, rng):
    S = rng.normal(size=(2, 37, 53)).astype(np.float32)
    g0 = rng.normal(size=S.shape).astype(np.float32)
    e0 = rng.normal(size=2 * 37)
    er, gS = run_smoothness(backend, S, g0, e0, lam=2.0, eps=0.01)
    r_er, r_gS = ref.shading_smoothness(S, lam=2.0, eps=0.01)
    np.testing.assert_allclose(er, e0 + r_er, rtol=1e-5)
    np.testing.assert_allclose(gS, g0 + r_gS, rtol=1e-5, atol=1e-4)


def test_smoothness_hand_computed_constant(backend):
    # 3x4 image: 4 corners x 3 + 6 edge pixels x 5 + 2 interior x 8 = 58 ordered pairs
    er, gS = run_smoothness(backend, np.full((1, 3, 4), 0.7, np.float32), lam=2.0, eps=0.001)
    np.testing.assert_allclose(er.sum(), 2.0 * 0.001 * 58, rtol=1e-5)
    np.testing.assert_allclose(er, 2.0 * 0.001 * np.array([3 + 5 + 5 + 3, 5 + 8 + 8 + 5, 3 + 5 + 5 + 3]),
                               rtol=1e-5)
    assert not gS.any()


def test_smoothness_gradient_matches_finite_differences(backend, rng):
    S = rng.normal(size=(2, 7, 9)).astype(np.float32)
    lam, eps = 2.0, 0.05
    _, gS = run_smoothness(backend, S, lam=lam, eps=eps)
    fd = finite_differences(lambda s: ref.shading_smoothness(s, lam, eps)[0].sum(), S)
    np.testing.assert_allclose(gS, fd, rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("t_flow", [3, 2])
def test_coupling_matches_reference_and_accumulates(backend, rng, t_flow):
    S, S_tilde, w_bnd = coupling_inputs(rng, 3, 37, 53, t_flow)
    g0 = rng.normal(size=S.shape).astype(np.float32)
    e0 = rng.normal(size=3 * 37)
    er, gS = run_coupling(backend, S, S_tilde, w_bnd, g0, e0, lam=10.0)
    r_er, r_gS = ref.coupling_term(S, S_tilde, w_bnd, lam=10.0)
    np.testing.assert_allclose(er, e0 + r_er, rtol=1e-5)
    np.testing.assert_allclose(gS, g0 + r_gS, rtol=1e-5, atol=1e-5)
    if t_flow < 3:
        np.testing.assert_array_equal(er[t_flow * 37:], e0[t_flow * 37:])
        np.testing.assert_array_equal(gS[t_flow:], g0[t_flow:])


def test_coupling_gradient_matches_finite_differences(backend, rng):
    S, S_tilde, w_bnd = coupling_inputs(rng, 2, 7, 9, 1)
    _, gS = run_coupling(backend, S, S_tilde, w_bnd, lam=10.0)
    fd = finite_differences(lambda s: ref.coupling_term(s, S_tilde, w_bnd, 10.0)[0].sum(), S)
    np.testing.assert_allclose(gS, fd, rtol=1e-4, atol=1e-4)


def test_one_and_two_threads_identical(rng):
    be = get_backend("warp", "cpu")
    S, S_tilde, w_bnd = coupling_inputs(rng, 3, 37, 53, 2)
    with threads(1):
        one = run_smoothness(be, S) + run_coupling(be, S, S_tilde, w_bnd)
    with threads(2):
        two = run_smoothness(be, S) + run_coupling(be, S, S_tilde, w_bnd)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_warp_matches_taichi(rng):
    S, S_tilde, w_bnd = coupling_inputs(rng, 3, 19, 23, 2)
    w = run_smoothness(get_backend("warp"), S) + run_coupling(get_backend("warp"), S, S_tilde, w_bnd)
    t = run_smoothness(get_backend("taichi"), S) + run_coupling(get_backend("taichi"), S, S_tilde, w_bnd)
    for a, b in zip(w, t):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-5)


def test_bad_input_raises(backend, rng):
    S, S_tilde, w_bnd = (backend.asarray(a) for a in coupling_inputs(rng, 2, 5, 6, 1))
    gS, er = backend.zeros((2, 5, 6)), backend.zeros((10,), np.float64)
    sm, cp = backend.energy_shading.shading_smoothness, backend.energy_shading.coupling_term
    with pytest.raises(ValueError, match="gS must have shape"):
        sm(S, backend.zeros((2, 5, 7)), er)
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        sm(S, gS, backend.zeros((10,), np.float32))
    with pytest.raises(ValueError, match="S must have shape"):
        sm(backend.zeros((2, 5, 6, 1)), gS, er)
    with pytest.raises(ValueError, match="expected T' <= T"):
        cp(S, S_tilde, backend.zeros((3, 5, 6)), gS, er)
    with pytest.raises(ValueError, match="S_tilde must have shape"):
        cp(S, backend.zeros((1, 5, 6)), w_bnd, gS, er)
    with pytest.raises(TypeError, match="w_bnd must have dtype float32"):
        cp(S, S_tilde, backend.zeros((1, 5, 6), np.float64), gS, er)
