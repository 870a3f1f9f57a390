"""Albedo GSM smoothness (Eq. 11): the generic contract from the case table (value and gradient
vs the NumPy reference, finite differences), plus window radii at tiny borders, each pair
counted twice, table look-up and extrapolation, the shipped table's consistency, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import energy_albedo_gsm as ref
from ivkernels.kernels.workspace import Workspace
from ivkernels.priors import load_albedo_prior, tabulate_gsm
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("energy_albedo_gsm")


@pytest.fixture(scope="module")
def prior():
    return load_albedo_prior()


def tables(prior, n=None):
    """float32 (sigma_inv, table_g, table_dg) and r2_max; ``n`` re-tabulates the mixture densely."""
    if n is None:
        tg, tdg = prior.table_g, prior.table_dg
    else:
        tg, tdg, _ = tabulate_gsm(prior.alphas, prior.sigmas, prior.r2_max, n)
    return (prior.sigma_inv.astype(np.float32), tg.astype(np.float32), tdg.astype(np.float32)), prior.r2_max


def make_albedo(rng, t, h, w, patch=6, outliers=True):
    """Log albedo: flat patches (large differences at patch edges), mild noise, a few outliers
    whose differences lie beyond the table (r2 > r2_max)."""
    base = rng.normal(-1.0, 0.5, (t, h // patch + 1, w // patch + 1, 3))
    A = np.repeat(np.repeat(base, patch, 1), patch, 2)[:, :h, :w]
    A = A + rng.normal(0.0, 0.02, (t, h, w, 3))
    if outliers:
        idx = rng.integers(0, t * h * w, max(1, t * h * w // 50))
        A.reshape(-1, 3)[idx] += 4.0
    return A.astype(np.float32)


def run(be, A, arrays, r2_max, gA0=None, e0=None, **kw):
    t, h, w, _ = A.shape
    gA = be.asarray(np.zeros(A.shape, np.float32) if gA0 is None else gA0.copy())
    er = be.asarray(np.zeros(t * h, np.float64) if e0 is None else e0.copy())
    be.energy_albedo_gsm.gsm_smoothness(be.asarray(A), *(be.asarray(a) for a in arrays),
                                             r2_max, gA, er, **kw)
    return be.numpy(er).copy(), be.numpy(gA).copy()


@pytest.mark.parametrize("radius, shape", [(1, (1, 3, 4)), (2, (2, 1, 7)), (3, (1, 5, 2)), (2, (1, 1, 1))])
def test_window_radius_and_borders(kernel_backend, rng, prior, radius, shape):
    A = make_albedo(rng, *shape, patch=1, outliers=False)
    arrays, r2_max = tables(prior)
    er, gA = run(kernel_backend, A, arrays, r2_max, lam=1.3, radius=radius)
    r_er, r_gA = ref.gsm_smoothness(A, *arrays, r2_max, lam=1.3, radius=radius)
    np.testing.assert_allclose(er, r_er, rtol=2e-5)
    np.testing.assert_allclose(gA, r_gA, rtol=1e-4, atol=1e-5 * max(1.0, np.abs(r_gA).max()))


@pytest.mark.parametrize("radius, shape", [(2, (3, 25, 9)), (3, (2, 45, 13)), (1, (1, 70, 6))])
def test_bands_split_inside_frames(kernel_backend, rng, prior, radius, shape):
    """Frames of 25 to 70 rows: the rows are walked in several bands (at least 32 rows
    each), whose boundaries fall inside frames and frames' inside bands."""
    A = make_albedo(rng, *shape, patch=3)
    arrays, r2_max = tables(prior)
    er, gA = run(kernel_backend, A, arrays, r2_max, lam=0.9, radius=radius)
    r_er, r_gA = ref.gsm_smoothness(A, *arrays, r2_max, lam=0.9, radius=radius)
    np.testing.assert_allclose(er, r_er, rtol=2e-5, atol=1e-6 * np.abs(r_er).max())
    np.testing.assert_allclose(gA, r_gA, rtol=1e-4, atol=1e-5 * max(1.0, np.abs(r_gA).max()))


def test_reference_counts_each_pair_twice(prior):
    """Hand case: two pixels, one unordered pair, visited from both sides."""
    A = np.zeros((1, 1, 2, 3))
    A[0, 0, 1] = [0.1, -0.2, 0.05]
    arrays, r2_max = tables(prior)
    d = A[0, 0, 0] - A[0, 0, 1]
    r2 = d @ prior.sigma_inv @ d
    g, dg = ref.gsm_lookup(r2, arrays[1], arrays[2], r2_max)
    er, gA = ref.gsm_smoothness(A, *arrays, r2_max, lam=2.0)
    np.testing.assert_allclose(er.sum(), 2.0 * 2 * g)
    np.testing.assert_allclose(gA[0, 0, 0], 2.0 * 4 * dg * (prior.sigma_inv @ d))
    np.testing.assert_allclose(gA[0, 0, 1], -gA[0, 0, 0])
    np.testing.assert_allclose(g, prior.gsm_cost(r2)[0], rtol=1e-3)


def test_constant_albedo_costs_nothing(kernel_backend, prior):
    A = np.full((2, 5, 7, 3), -0.7, np.float32)
    arrays, r2_max = tables(prior)
    er, gA = run(kernel_backend, A, arrays, r2_max, lam=3.0)
    assert not er.any() and not gA.any()


def test_lookup_extrapolates_beyond_table(prior):
    arrays, r2_max = tables(prior)
    tg, tdg = arrays[1], arrays[2]
    r2 = np.array([0.0, r2_max, 2 * r2_max, 1e4])
    g, dg = ref.gsm_lookup(r2, tg, tdg, r2_max)
    np.testing.assert_allclose(g[:2], [0.0, tg[-1]], atol=1e-6)
    np.testing.assert_allclose(g[2:], tg[-1] + tdg[-1] * (r2[2:] - r2_max), rtol=1e-12)
    np.testing.assert_allclose(dg[1:], tdg[-1])
    exact, exact_dg = prior.gsm_cost(r2)
    np.testing.assert_allclose(g, exact, rtol=1e-4, atol=1e-6)


def test_lookup_interpolates_linearly_in_r2(prior):
    """Inside a cell the table is read linearly in r2 (exact for a linear g)."""
    r2_max, n = 4.0, 9
    s = np.linspace(0, 2.0, n)
    g_lin, dg_lin = 3.0 * s ** 2, np.full(n, 3.0)
    r2 = np.linspace(0, r2_max, 101)
    g, dg = ref.gsm_lookup(r2, g_lin, dg_lin, r2_max)
    np.testing.assert_allclose(g, 3.0 * r2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(dg, 3.0)


def test_shipped_table_gradient_is_consistent(rng, prior):
    """With the shipped 8192-point table, the directional derivative of the
    interpolated energy matches the interpolated g' within 1%."""
    A = make_albedo(rng, 1, 9, 11, patch=4).astype(np.float64)
    arrays, r2_max = tables(prior)
    _, gA = ref.gsm_smoothness(A, *arrays, r2_max, 1.0)
    for _ in range(3):
        d = rng.standard_normal(A.shape)
        eps = 1e-5
        fd = (ref.gsm_smoothness(A + eps * d, *arrays, r2_max, 1.0)[0].sum()
              - ref.gsm_smoothness(A - eps * d, *arrays, r2_max, 1.0)[0].sum()) / (2 * eps)
        assert abs(fd - np.sum(gA * d)) <= 1e-2 * np.linalg.norm(gA) * np.linalg.norm(d)


def test_bad_input_raises(kernel_backend, prior):
    arrays, r2_max = tables(prior)
    P, tg, tdg = (kernel_backend.asarray(a) for a in arrays)
    A = kernel_backend.asarray(np.zeros((1, 4, 5, 3), np.float32))
    gA = kernel_backend.zeros((1, 4, 5, 3))
    er = kernel_backend.zeros((4,), np.float64)
    f = kernel_backend.energy_albedo_gsm.gsm_smoothness
    with pytest.raises(TypeError, match="A must have dtype float32"):
        f(kernel_backend.asarray(np.zeros((1, 4, 5, 3))), P, tg, tdg, r2_max, gA, er, lam=1.0)
    with pytest.raises(TypeError, match="A must be"):
        f(np.zeros((1, 4, 5, 3)).tolist(), P, tg, tdg, r2_max, gA, er, lam=1.0)
    with pytest.raises(ValueError, match=r"A must have shape \(T, H, W, 3\)"):
        f(kernel_backend.asarray(np.zeros((1, 4, 5, 2), np.float32)), P, tg, tdg, r2_max, gA, er, lam=1.0)
    with pytest.raises(ValueError, match="sigma_inv must have shape"):
        f(A, kernel_backend.asarray(np.eye(2, dtype=np.float32)), tg, tdg, r2_max, gA, er, lam=1.0)
    with pytest.raises(ValueError, match="table_dg must have shape"):
        f(A, P, tg, kernel_backend.asarray(arrays[2][:-1].copy()), r2_max, gA, er, lam=1.0)
    with pytest.raises(ValueError, match="at least 2 entries"):
        one = kernel_backend.asarray(np.zeros(1, np.float32))
        f(A, P, one, one, r2_max, gA, er, lam=1.0)
    with pytest.raises(ValueError, match="gA must have shape"):
        f(A, P, tg, tdg, r2_max, kernel_backend.zeros((1, 4, 6, 3)), er, lam=1.0)
    with pytest.raises(TypeError, match="energy_rows must have dtype float64"):
        f(A, P, tg, tdg, r2_max, gA, kernel_backend.zeros((4,)), lam=1.0)
    with pytest.raises(ValueError, match="energy_rows must have shape"):
        f(A, P, tg, tdg, r2_max, gA, kernel_backend.zeros((5,), np.float64), lam=1.0)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="r2_max"):
            f(A, P, tg, tdg, bad, gA, er, lam=1.0)
    with pytest.raises(ValueError, match="lam"):
        f(A, P, tg, tdg, r2_max, gA, er, lam=float("nan"))
    for bad in (0, -2, 2.0, True):
        with pytest.raises(ValueError, match="radius"):
            f(A, P, tg, tdg, r2_max, gA, er, lam=1.0, radius=bad)


def test_workspace_reused_across_shapes_gives_the_same_result(kernel_backend, rng, prior):
    arrays, r2_max = tables(prior)
    a, b = make_albedo(rng, 2, 13, 17), make_albedo(rng, 1, 9, 20)
    fresh = [run(kernel_backend, x, arrays, r2_max, lam=0.7) for x in (a, b)]
    ws = Workspace()
    held = []
    for _ in range(2):          # the second round finds the buffers left by the first
        for x, want in zip((a, b), fresh):
            for got, w in zip(run(kernel_backend, x, arrays, r2_max, lam=0.7, workspace=ws), want):
                np.testing.assert_array_equal(got, w)
        held.append(len(ws))
    # the row-slot buffers per image shape and the cell coefficients once, none added by the second round
    assert held[0] == held[1] >= 3
    ws.clear()
    assert ws.nbytes == 0
