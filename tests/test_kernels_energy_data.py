"""Data term (Eq. 3) and the constraint A = I - S: the generic contract from the case table
(value and gradient vs the NumPy reference, finite differences), plus a hand-computed zero
residual, the chain rule of the constrained gradient, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import energy_data as ref
from kernel_harness import contract, finite_differences, pytest_generate_tests  # noqa: F401  (fixture)

TestContract = contract("energy_data")


def make_inputs(rng, t, h, w):
    I = rng.normal(0.0, 1.0, (t, h, w, 3)).astype(np.float32)
    A = rng.normal(0.0, 1.0, (t, h, w, 3)).astype(np.float32)
    S = rng.normal(0.0, 1.0, (t, h, w)).astype(np.float32)
    w_lum = rng.uniform(0.001, 1.0, (t, h, w)).astype(np.float32)
    return I, A, S, w_lum


def run(be, I, A, S, w_lum, gA0=None, gS0=None, e0=None, **kw):
    """Call data_term on ``be`` with gradient/energy buffers starting at gA0, gS0, e0."""
    t, h, w, _ = I.shape
    gA = be.asarray(np.zeros(A.shape, np.float32) if gA0 is None else gA0.copy())
    gS = be.asarray(np.zeros(S.shape, np.float32) if gS0 is None else gS0.copy())
    er = be.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    be.energy_data.data_term(*(be.asarray(a) for a in (I, A, S, w_lum)), gA, gS, er, **kw)
    return be.numpy(er).copy(), be.numpy(gA).copy(), be.numpy(gS).copy()


def test_hand_computed_zero_residual(kernel_backend):
    z = np.zeros((1, 3, 5, 3), np.float32)
    er, gA, gS = run(kernel_backend, z, z, z[..., 0], np.ones((1, 3, 5), np.float32), lam=10.0, eps=0.001)
    np.testing.assert_allclose(er, np.full(3, 10.0 * 0.001 * 15), rtol=1e-6)
    assert not gA.any() and not gS.any()


def test_bad_input_raises(kernel_backend, rng):
    I, A, S, w_lum = (kernel_backend.asarray(a) for a in make_inputs(rng, 2, 5, 6))
    gA, gS = kernel_backend.zeros((2, 5, 6, 3)), kernel_backend.zeros((2, 5, 6))
    er = kernel_backend.zeros((10,), np.float64)
    f = kernel_backend.energy_data.data_term
    with pytest.raises(ValueError, match="A must have shape"):
        f(I, kernel_backend.zeros((2, 5, 7, 3)), S, w_lum, gA, gS, er)
    with pytest.raises(ValueError, match="energy_rows"):
        f(I, A, S, w_lum, gA, gS, kernel_backend.zeros((11,), np.float64))
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        f(I, A, S, w_lum, gA, gS, kernel_backend.zeros((10,), np.float32))
    with pytest.raises(TypeError, match="S must have dtype float32"):
        f(I, A, kernel_backend.zeros((2, 5, 6), np.float64), w_lum, gA, gS, er)
    with pytest.raises(ValueError, match="I must have shape"):
        f(kernel_backend.zeros((2, 5, 6, 4)), A, S, w_lum, gA, gS, er)


def test_constrained_gradient_is_the_chain_rule(kernel_backend, rng):
    """d/dS of E(I - S, S) by finite differences of a quadratic E(A, S)."""
    t, h, w = 1, 5, 6
    I = rng.normal(size=(t, h, w, 3))
    S = rng.normal(size=(t, h, w))
    cA, cS = rng.normal(size=(t, h, w, 3)), rng.normal(size=(t, h, w))

    def energy(S_):
        A_ = ref.constrained_albedo(I, S_)
        return 0.5 * (cA * A_ * A_).sum() + 0.5 * (cS * S_ * S_).sum()

    A = ref.constrained_albedo(I, S)
    gA, gS = (cA * A).astype(np.float32), (cS * S).astype(np.float32)
    out = kernel_backend.asarray(np.zeros((t, h, w), np.float32))
    kernel_backend.energy_data.constrained_gradient(kernel_backend.asarray(gA), kernel_backend.asarray(gS), out)
    np.testing.assert_allclose(kernel_backend.numpy(out), finite_differences(energy, S), rtol=1e-4, atol=1e-4)


def test_constrained_bad_input(kernel_backend):
    I = kernel_backend.asarray(np.zeros((1, 4, 4, 3), np.float32))
    with pytest.raises(ValueError, match="S must have shape"):
        kernel_backend.energy_data.constrained_albedo(I, kernel_backend.asarray(np.zeros((1, 4, 5), np.float32)),
                                               kernel_backend.asarray(np.zeros((1, 4, 4, 3), np.float32)))
    with pytest.raises(ValueError, match="alias"):
        kernel_backend.energy_data.constrained_albedo(I, kernel_backend.asarray(np.zeros((1, 4, 4), np.float32)), I)
