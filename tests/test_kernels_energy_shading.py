"""Shading terms (Eq. 9 local smoothness, Eq. 13 coupling): the generic contract from the case
table (value and gradient vs the NumPy reference, finite differences), plus a hand-computed
constant image, frames without flow left untouched, bad input."""
import numpy as np
import pytest

from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("energy_shading")


def buffers(be, shape, g0, e0):
    t, h = shape[:2]
    gS = be.asarray(np.zeros(shape, np.float32) if g0 is None else g0.copy())
    er = be.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    return gS, er


def run_smoothness(be, S, g0=None, e0=None, **kw):
    gS, er = buffers(be, S.shape, g0, e0)
    be.energy_shading.shading_smoothness(be.asarray(S), gS, er, **kw)
    return be.numpy(er).copy(), be.numpy(gS).copy()


def run_coupling(be, S, S_tilde, w_bnd, g0=None, e0=None, **kw):
    gS, er = buffers(be, S.shape, g0, e0)
    be.energy_shading.coupling_term(*(be.asarray(a) for a in (S, S_tilde, w_bnd)), gS, er, **kw)
    return be.numpy(er).copy(), be.numpy(gS).copy()


def coupling_inputs(rng, t, h, w, t_flow):
    S = rng.normal(size=(t, h, w)).astype(np.float32)
    S_tilde = rng.normal(size=(t, h, w)).astype(np.float32)
    w_bnd = (rng.random((t_flow, h, w)) < 0.3).astype(np.float32)
    return S, S_tilde, w_bnd


def test_smoothness_hand_computed_constant(kernel_backend):
    # 3x4 image: 4 corners x 3 + 6 edge pixels x 5 + 2 interior x 8 = 58 ordered pairs
    er, gS = run_smoothness(kernel_backend, np.full((1, 3, 4), 0.7, np.float32), lam=2.0, eps=0.001)
    np.testing.assert_allclose(er.sum(), 2.0 * 0.001 * 58, rtol=1e-5)
    np.testing.assert_allclose(er, 2.0 * 0.001 * np.array([3 + 5 + 5 + 3, 5 + 8 + 8 + 5, 3 + 5 + 5 + 3]),
                               rtol=1e-5)
    assert not gS.any()


def test_coupling_leaves_frames_without_flow_untouched(kernel_backend, rng):
    """w_bnd of T' < T frames: energy rows and gradient of the frames after T' keep their content."""
    S, S_tilde, w_bnd = coupling_inputs(rng, 3, 7, 9, 2)
    g0 = rng.normal(size=S.shape).astype(np.float32)
    e0 = rng.normal(size=3 * 7)
    er, gS = run_coupling(kernel_backend, S, S_tilde, w_bnd, g0, e0, lam=10.0)
    np.testing.assert_array_equal(er[2 * 7:], e0[2 * 7:])
    np.testing.assert_array_equal(gS[2:], g0[2:])
    assert (er[:2 * 7] != e0[:2 * 7]).any() and (gS[:2] != g0[:2]).any()


def test_bad_input_raises(kernel_backend, rng):
    S, S_tilde, w_bnd = (kernel_backend.asarray(a) for a in coupling_inputs(rng, 2, 5, 6, 1))
    gS, er = kernel_backend.zeros((2, 5, 6)), kernel_backend.zeros((10,), np.float64)
    sm, cp = kernel_backend.energy_shading.shading_smoothness, kernel_backend.energy_shading.coupling_term
    with pytest.raises(ValueError, match="gS must have shape"):
        sm(S, kernel_backend.zeros((2, 5, 7)), er)
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        sm(S, gS, kernel_backend.zeros((10,), np.float32))
    with pytest.raises(ValueError, match="S must have shape"):
        sm(kernel_backend.zeros((2, 5, 6, 1)), gS, er)
    with pytest.raises(ValueError, match="expected T' <= T"):
        cp(S, S_tilde, kernel_backend.zeros((3, 5, 6)), gS, er)
    with pytest.raises(ValueError, match="S_tilde must have shape"):
        cp(S, kernel_backend.zeros((1, 5, 6)), w_bnd, gS, er)
    with pytest.raises(TypeError, match="w_bnd must have dtype float32"):
        cp(S, S_tilde, kernel_backend.zeros((1, 5, 6), np.float64), gS, er)


def run_gated(be, S, gate, **kw):
    gS, er = buffers(be, S.shape, None, None)
    be.energy_shading.shading_smoothness_gated(be.asarray(S), be.asarray(gate), gS, er, **kw)
    return be.numpy(er).copy(), be.numpy(gS).copy()


def test_gated_smoothness_with_gate_one_is_the_plain_term(kernel_backend, rng):
    S = rng.normal(size=(2, 9, 13)).astype(np.float32)
    er, gS = run_gated(kernel_backend, S, np.ones_like(S), lam=3.0, eps=0.01)
    er0, gS0 = run_smoothness(kernel_backend, S, lam=3.0, eps=0.01)
    np.testing.assert_array_equal(er, er0)
    np.testing.assert_array_equal(gS, gS0)


def test_gated_smoothness_hand_computed_pair(kernel_backend):
    """1x2 image: one pair, counted twice, weighted by the mean of its two gates."""
    S = np.array([[[0.0, 0.3]]], np.float32)
    er, gS = run_gated(kernel_backend, S, np.array([[[0.2, 0.6]]], np.float32), lam=2.0, eps=0.4)
    rho = np.hypot(0.3, 0.4)                        # 0.5
    np.testing.assert_allclose(er.sum(), 2 * 2.0 * 0.4 * rho, rtol=1e-6)
    np.testing.assert_allclose(gS[0, 0], [-2 * 2.0 * 0.4 * 0.3 / rho, 2 * 2.0 * 0.4 * 0.3 / rho], rtol=1e-6)
    er, gS = run_gated(kernel_backend, S, np.zeros((1, 1, 2), np.float32), lam=2.0, eps=0.4)
    assert not er.any() and not gS.any()


def test_gated_smoothness_bad_input_raises(kernel_backend):
    S, gS = kernel_backend.zeros((2, 5, 6)), kernel_backend.zeros((2, 5, 6))
    er = kernel_backend.zeros((10,), np.float64)
    with pytest.raises(ValueError, match="gate must have shape"):
        kernel_backend.energy_shading.shading_smoothness_gated(S, kernel_backend.zeros((2, 5, 7)), gS, er)
    with pytest.raises(TypeError, match="gate must have dtype float32"):
        kernel_backend.energy_shading.shading_smoothness_gated(S, kernel_backend.zeros((2, 5, 6), np.float64),
                                                               gS, er)
