"""Data term (Eq. 3): value and gradient vs the NumPy reference, finite
differences, threads, backends, bad input."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import energy_data as ref


def make_inputs(rng, t, h, w):
    I = rng.normal(0.0, 1.0, (t, h, w, 3)).astype(np.float32)
    A = rng.normal(0.0, 1.0, (t, h, w, 3)).astype(np.float32)
    S = rng.normal(0.0, 1.0, (t, h, w)).astype(np.float32)
    w_lum = rng.uniform(0.001, 1.0, (t, h, w)).astype(np.float32)
    return I, A, S, w_lum


def run(backend, I, A, S, w_lum, gA0=None, gS0=None, e0=None, **kw):
    """Call data_term on ``backend`` with gradient/energy buffers starting at gA0, gS0, e0."""
    t, h, w, _ = I.shape
    gA = backend.asarray(np.zeros(A.shape, np.float32) if gA0 is None else gA0.copy())
    gS = backend.asarray(np.zeros(S.shape, np.float32) if gS0 is None else gS0.copy())
    er = backend.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    backend.energy_data.data_term(*(backend.asarray(a) for a in (I, A, S, w_lum)), gA, gS, er, **kw)
    return backend.numpy(er).copy(), backend.numpy(gA).copy(), backend.numpy(gS).copy()


def test_matches_reference_and_accumulates(backend, rng):
    I, A, S, w_lum = make_inputs(rng, 2, 37, 53)
    gA0 = rng.normal(size=A.shape).astype(np.float32)
    gS0 = rng.normal(size=S.shape).astype(np.float32)
    e0 = rng.normal(size=2 * 37).astype(np.float64)
    er, gA, gS = run(backend, I, A, S, w_lum, gA0, gS0, e0, lam=7.0, eps=0.01)
    r_er, r_gA, r_gS = ref.data_term(I, A, S, w_lum, lam=7.0, eps=0.01)
    np.testing.assert_allclose(er, e0 + r_er, rtol=1e-5)
    np.testing.assert_allclose(gA, gA0 + r_gA, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(gS, gS0 + r_gS, rtol=1e-5, atol=1e-3)


def test_hand_computed_zero_residual(backend):
    z = np.zeros((1, 3, 5, 3), np.float32)
    er, gA, gS = run(backend, z, z, z[..., 0], np.ones((1, 3, 5), np.float32), lam=10.0, eps=0.001)
    np.testing.assert_allclose(er, np.full(3, 10.0 * 0.001 * 15), rtol=1e-6)
    assert not gA.any() and not gS.any()


def test_gradient_matches_finite_differences(backend, rng):
    I, A, S, w_lum = make_inputs(rng, 2, 7, 9)
    lam, eps = 10.0, 0.05
    _, gA, gS = run(backend, I, A, S, w_lum, lam=lam, eps=eps)
    A64, S64, h = A.astype(np.float64), S.astype(np.float64), 1e-6

    def energy(A_, S_):
        return ref.data_term(I, A_, S_, w_lum, lam, eps)[0].sum()

    fd_A = np.zeros_like(A64)
    for idx in np.ndindex(A.shape):
        ap, am = A64.copy(), A64.copy()
        ap[idx] += h
        am[idx] -= h
        fd_A[idx] = (energy(ap, S64) - energy(am, S64)) / (2 * h)
    fd_S = np.zeros_like(S64)
    for idx in np.ndindex(S.shape):
        sp, sm = S64.copy(), S64.copy()
        sp[idx] += h
        sm[idx] -= h
        fd_S[idx] = (energy(A64, sp) - energy(A64, sm)) / (2 * h)
    np.testing.assert_allclose(gA, fd_A, rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(gS, fd_S, rtol=1e-4, atol=1e-4)


def test_one_and_two_threads_identical(rng):
    be = get_backend("warp", "cpu")
    inputs = make_inputs(rng, 3, 37, 53)
    with threads(1):
        one = run(be, *inputs)
    with threads(2):
        two = run(be, *inputs)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_warp_matches_taichi(rng):
    inputs = make_inputs(rng, 2, 19, 23)
    w = run(get_backend("warp"), *inputs)
    t = run(get_backend("taichi"), *inputs)
    # d/dz of z / sqrt(z^2 + eps^2) is up to 1/eps: float32 rounding of z shows up scaled by lam/eps
    for a, b in zip(w, t):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-3)


def test_bad_input_raises(backend, rng):
    I, A, S, w_lum = (backend.asarray(a) for a in make_inputs(rng, 2, 5, 6))
    gA, gS = backend.zeros((2, 5, 6, 3)), backend.zeros((2, 5, 6))
    er = backend.zeros((10,), np.float64)
    f = backend.energy_data.data_term
    with pytest.raises(ValueError, match="A must have shape"):
        f(I, backend.zeros((2, 5, 7, 3)), S, w_lum, gA, gS, er)
    with pytest.raises(ValueError, match="energy_rows"):
        f(I, A, S, w_lum, gA, gS, backend.zeros((11,), np.float64))
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        f(I, A, S, w_lum, gA, gS, backend.zeros((10,), np.float32))
    with pytest.raises(TypeError, match="S must have dtype float32"):
        f(I, A, backend.zeros((2, 5, 6), np.float64), w_lum, gA, gS, er)
    with pytest.raises(ValueError, match="I must have shape"):
        f(backend.zeros((2, 5, 6, 4)), A, S, w_lum, gA, gS, er)


# --------------------------------------------------- Eq. 3 as the constraint A = I - S
def test_constrained_albedo_matches_reference(backend, rng):
    I = rng.normal(0.0, 1.0, (2, 13, 7, 3)).astype(np.float32)
    S = rng.normal(0.0, 1.0, (2, 13, 7)).astype(np.float32)
    A = backend.asarray(np.full(I.shape, np.nan, np.float32))
    backend.energy_data.constrained_albedo(backend.asarray(I), backend.asarray(S), A)
    np.testing.assert_allclose(backend.numpy(A), ref.constrained_albedo(I, S), atol=1e-6)


def test_constrained_gradient_is_the_chain_rule(backend, rng):
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
    out = backend.asarray(np.zeros((t, h, w), np.float32))
    backend.energy_data.constrained_gradient(backend.asarray(gA), backend.asarray(gS), out)
    fd = np.zeros_like(S)
    for idx in np.ndindex(S.shape):
        sp, sm = S.copy(), S.copy()
        sp[idx] += 1e-6
        sm[idx] -= 1e-6
        fd[idx] = (energy(sp) - energy(sm)) / 2e-6
    np.testing.assert_allclose(backend.numpy(out), fd, rtol=1e-4, atol=1e-4)


def test_constrained_gradient_in_place(backend, rng):
    gA = rng.normal(size=(2, 9, 4, 3)).astype(np.float32)
    gS = rng.normal(size=(2, 9, 4)).astype(np.float32)
    want = ref.constrained_gradient(gA, gS)
    gS_be = backend.asarray(gS.copy())
    backend.energy_data.constrained_gradient(backend.asarray(gA), gS_be, gS_be)
    np.testing.assert_allclose(backend.numpy(gS_be), want, rtol=1e-6, atol=1e-6)


def test_constrained_bad_input(backend):
    I = backend.asarray(np.zeros((1, 4, 4, 3), np.float32))
    with pytest.raises(ValueError, match="S must have shape"):
        backend.energy_data.constrained_albedo(I, backend.asarray(np.zeros((1, 4, 5), np.float32)),
                                               backend.asarray(np.zeros((1, 4, 4, 3), np.float32)))
    with pytest.raises(ValueError, match="alias"):
        backend.energy_data.constrained_albedo(I, backend.asarray(np.zeros((1, 4, 4), np.float32)), I)
