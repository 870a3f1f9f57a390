"""Albedo global sparsity (Eq. 12) by histogram: the generic contract from the case table (each
step and the whole term vs the NumPy reference, gradient vs finite differences), plus the
energy vs the direct O(N^2) double sum as the bins shrink, the exact gradient of the
discrete energy, lattice shifts, clamping outside the cube, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.cases.energy_albedo_entropy import clustered_albedo
from ivkernels.kernels.reference import energy_albedo_entropy as ref
from ivkernels.priors import entropy_blur_weights, load_albedo_prior
from kernel_harness import contract, finite_differences, pytest_generate_tests  # noqa: F401  (fixture)

TestContract = contract("energy_albedo_entropy")

LO, H_BIN = -4.0, 0.06


@pytest.fixture(scope="module")
def prior():
    return load_albedo_prior()


make_albedo = clustered_albedo          # log albedo of a few materials (the case table's input)


def bins_for(h_bin, lo=LO, hi=2.5):
    return int(np.ceil((hi - lo) / h_bin)) + 1


def tight_cube(A, whiten, h_bin, margin=3):
    """``(lo, bins)``: the smallest cube on the lattice ``LO + n h`` holding ``W A`` with
    ``margin`` bins to spare.  Any cube that holds the data gives the same energy
    (the histogram is zero outside it), so the O(N^2)-sized references run fast."""
    u = np.asarray(A, np.float64).reshape(-1, 3) @ np.asarray(whiten, np.float64).T
    lo = LO + np.floor((u.min() - LO) / h_bin - margin) * h_bin
    return float(lo), int(np.ceil((u.max() - lo) / h_bin + margin)) + 1


def run_term(be, A, prior, lo=LO, h_bin=H_BIN, bins=None, lam=0.7, gA0=None, e0=None):
    t, h, w, _ = A.shape
    bins = bins or bins_for(h_bin, lo)
    m = be.energy_albedo_entropy
    scratch = m.allocate_entropy_scratch(t, bins, device=be.device)
    gA = be.asarray(np.zeros(A.shape, np.float32) if gA0 is None else gA0.copy())
    er = be.asarray(np.zeros(t * h) if e0 is None else e0.copy())
    taps = entropy_blur_weights(prior.sigma_p, h_bin)
    m.entropy_term(be.asarray(A), be.asarray(prior.whiten.astype(np.float32)), lo, h_bin,
                   be.asarray(taps), prior.sigma_p, scratch, gA, er, lam=lam)
    out = {k: be.numpy(v).copy() for k, v in scratch._asdict().items()}
    return be.numpy(er).copy(), be.numpy(gA).copy(), out


def test_reference_blur_is_the_3d_convolution(rng):
    hist = np.zeros((1, 9, 9, 9))
    hist[0, rng.integers(0, 9, 6), rng.integers(0, 9, 6), rng.integers(0, 9, 6)] = 1.0
    taps = np.array([0.2, 0.5, 1.0, 0.5, 0.2])
    out = ref.entropy_blur(hist, taps)
    direct = np.zeros_like(hist)
    for i, j, k in zip(*np.nonzero(hist[0])):
        for a in range(-2, 3):
            for b in range(-2, 3):
                for c in range(-2, 3):
                    if 0 <= i + a < 9 and 0 <= j + b < 9 and 0 <= k + c < 9:
                        direct[0, i + a, j + b, k + c] += taps[a + 2] * taps[b + 2] * taps[c + 2]
    np.testing.assert_allclose(out, direct)


@pytest.mark.parametrize("spread", [0.02, 0.1])
def test_histogram_energy_converges_to_the_direct_sum(rng, prior, spread):
    """|E_hist - E_direct| shrinks with the bin width h; the compensated blur makes it O(h^4)-small."""
    A = make_albedo(rng, 1, 20, 20, spread=spread).astype(np.float64)
    e_direct, _ = ref.entropy_direct(A, prior.whiten, prior.sigma_p, 1.0)
    errors = {}
    for h in (0.12, 0.06, 0.03):
        lo, bins = tight_cube(A, prior.whiten, h)
        for comp in (False, True):
            taps = entropy_blur_weights(prior.sigma_p, h, compensate=comp)
            e_hist, _ = ref.entropy_term(A, prior.whiten, lo, h, taps, prior.sigma_p, 1.0, bins)
            errors[h, comp] = abs(e_hist[0] - e_direct[0])
    for h in (0.12, 0.06, 0.03):
        assert errors[h, False] < 0.5 * (h / prior.sigma_p) ** 2
        assert errors[h, True] < 0.05 * (h / prior.sigma_p) ** 2
    assert errors[0.03, False] < errors[0.06, False] < errors[0.12, False]


def test_kernel_energy_matches_the_direct_sum(kernel_backend, rng, prior):
    A = make_albedo(rng, 2, 13, 17)
    er, _, _ = run_term(kernel_backend, A, prior, h_bin=0.04, lam=1.0)
    e_direct, _ = ref.entropy_direct(A, prior.whiten, prior.sigma_p, 1.0)
    np.testing.assert_allclose(er, e_direct, atol=0.05 * (0.04 / prior.sigma_p) ** 2)


def test_gradient_is_exact_for_the_discrete_energy(rng, prior):
    """float64 reference: central differences of the histogram energy."""
    A = make_albedo(rng, 1, 4, 5, spread=0.1, n_colours=2).astype(np.float64)
    taps = entropy_blur_weights(prior.sigma_p, H_BIN)
    lo, bins = tight_cube(A, prior.whiten, H_BIN)
    args = (prior.whiten, lo, H_BIN, taps, prior.sigma_p, 1.0, bins)
    _, gA = ref.entropy_term(A, *args)
    fd = finite_differences(lambda a: ref.entropy_term(a, *args)[0].sum(), A, h=1e-7)
    np.testing.assert_allclose(gA, fd, rtol=1e-4, atol=1e-5 * np.abs(fd).max())


def test_descent_slope_matches_the_direct_sum(rng, prior):
    """Along the true descent direction, the histogram gradient's slope approaches Eq. 12's."""
    A = make_albedo(rng, 1, 20, 20, spread=0.05).astype(np.float64)
    _, g_direct = ref.entropy_direct(A, prior.whiten, prior.sigma_p, 1.0)
    d = -g_direct / np.linalg.norm(g_direct)
    for h, tol in ((0.06, 0.02), (0.03, 0.01)):
        taps = entropy_blur_weights(prior.sigma_p, h)
        lo, bins = tight_cube(A, prior.whiten, h)
        _, g_hist = ref.entropy_term(A, prior.whiten, lo, h, taps, prior.sigma_p, 1.0, bins)
        assert abs(np.sum(g_hist * d) - np.sum(g_direct * d)) < tol * np.linalg.norm(g_direct)


def test_lattice_shift_leaves_the_energy_unchanged(kernel_backend, rng, prior):
    """Translating the whitened cloud by whole bins (inside the cube) changes nothing."""
    A = make_albedo(rng, 1, 11, 13)
    shift = np.linalg.solve(prior.whiten, H_BIN * np.array([3.0, -2.0, 5.0]))
    er0, gA0, _ = run_term(kernel_backend, A, prior, lam=1.0)
    er1, gA1, _ = run_term(kernel_backend, (A.astype(np.float64) + shift).astype(np.float32), prior, lam=1.0)
    np.testing.assert_allclose(er1, er0, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(gA1, gA0, rtol=1e-2, atol=1e-3 * np.abs(gA0).max())


def test_outside_the_cube_is_clamped(kernel_backend, rng, prior):
    A = make_albedo(rng, 1, 6, 7)
    A[0, 0, 0] = np.linalg.solve(prior.whiten, [20.0, -20.0, 20.0])   # outside on every axis
    A[0, 0, 1] = np.linalg.solve(prior.whiten, [-20.0, 20.0, -20.0])
    A[0, 0, 2] = np.linalg.solve(prior.whiten, [30.0, 25.0, -30.0])
    er, gA, s = run_term(kernel_backend, A, prior, lam=1.0)
    assert np.isfinite(er).all() and np.isfinite(gA).all()
    np.testing.assert_array_equal(gA[0, 0, :3], 0.0)
    taps = entropy_blur_weights(prior.sigma_p, H_BIN)
    r_er, r_gA = ref.entropy_term(A, prior.whiten.astype(np.float32), LO, H_BIN, taps, prior.sigma_p,
                                  1.0, bins_for(H_BIN))
    np.testing.assert_allclose(er, r_er, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(gA, r_gA, rtol=1e-3, atol=1e-4 * np.abs(r_gA).max())


def test_bad_input_raises(kernel_backend, prior):
    m = kernel_backend.energy_albedo_entropy
    T, H, W, B = 1, 4, 5, 8
    A = kernel_backend.asarray(np.zeros((T, H, W, 3), np.float32))
    Wm = kernel_backend.asarray(prior.whiten.astype(np.float32))
    taps = kernel_backend.asarray(entropy_blur_weights(prior.sigma_p, H_BIN))
    s = m.allocate_entropy_scratch(T, B, device=kernel_backend.device)
    gA = kernel_backend.zeros((T, H, W, 3))
    er = kernel_backend.zeros((T * H,), np.float64)
    with pytest.raises(ValueError, match="bins"):
        m.allocate_entropy_scratch(T, 1, device=kernel_backend.device)
    with pytest.raises(ValueError, match="n_frames"):
        m.allocate_entropy_scratch(0, B, device=kernel_backend.device)
    with pytest.raises(TypeError, match="scratch must be an EntropyScratch"):
        m.entropy_term(A, Wm, LO, H_BIN, taps, prior.sigma_p, tuple(s), gA, er, lam=1.0)
    with pytest.raises(ValueError, match=r"A must have shape \(T, H, W, 3\)"):
        m.entropy_histogram(kernel_backend.asarray(np.zeros((T, H, W, 4), np.float32)), Wm, LO, H_BIN,
                            s.hist, s.row_flags)
    with pytest.raises(TypeError, match="whiten must have dtype float32"):
        m.entropy_histogram(A, kernel_backend.asarray(prior.whiten), LO, H_BIN, s.hist, s.row_flags)
    with pytest.raises(ValueError, match=r"\(T, B, B, B\)"):
        m.entropy_histogram(A, Wm, LO, H_BIN, kernel_backend.zeros((T, B, B, B + 1)), s.row_flags)
    with pytest.raises(TypeError, match="row_flags must have dtype int32"):
        m.entropy_histogram(A, Wm, LO, H_BIN, s.hist, kernel_backend.zeros((2, T, B, B)))
    for bad in (0.0, -0.1, float("nan")):
        with pytest.raises(ValueError, match="h must be"):
            m.entropy_histogram(A, Wm, LO, bad, s.hist, s.row_flags)
    with pytest.raises(ValueError, match="lo must be"):
        m.entropy_histogram(A, Wm, float("inf"), H_BIN, s.hist, s.row_flags)
    with pytest.raises(ValueError, match="odd length"):
        m.entropy_blur(s.hist, kernel_backend.asarray(np.ones(4, np.float32)), s.row_flags, s.tmp, s.blurred)
    with pytest.raises(TypeError, match="dots must have dtype float64"):
        m.entropy_dot(s.hist, s.blurred, kernel_backend.zeros((T,)))
    with pytest.raises(ValueError, match="gA must have shape"):
        m.entropy_slice_gradient(A, Wm, LO, H_BIN, s.blurred, s.dots, kernel_backend.zeros((T, H, W + 1, 3)), 1.0)
    with pytest.raises(ValueError, match="not a multiple"):
        m.entropy_energy(kernel_backend.zeros((2,), np.float64), prior.sigma_p, 20, er[:3], 1.0)
    with pytest.raises(ValueError, match="n_pixels"):
        m.entropy_energy(s.dots, prior.sigma_p, 0, er, 1.0)
    with pytest.raises(ValueError, match="sigma_p"):
        m.entropy_energy(s.dots, 0.0, 20, er, 1.0)
    with pytest.raises(ValueError, match="energy_rows must have shape"):
        m.entropy_term(A, Wm, LO, H_BIN, taps, prior.sigma_p, s, gA, kernel_backend.zeros((T * H + 1,), np.float64),
                       lam=1.0)
    with pytest.raises(ValueError, match="lam"):
        m.entropy_term(A, Wm, LO, H_BIN, taps, prior.sigma_p, s, gA, er, lam=float("nan"))
