"""The host solver: windows, pyramid shapes, L-BFGS, and the assembled energy."""
import numpy as np
import pytest

from ivkernels import Params
from ivkernels.decompose import window_ranges
from ivkernels.priors import load_albedo_prior
from ivkernels.solver.energy import WindowEnergy
from ivkernels.solver.lbfgs import LBFGS
from ivkernels.solver.pyramid import coarse_to_fine, level_shapes


@pytest.mark.parametrize("n, window, overlap", [(1, 8, 2), (8, 8, 2), (9, 8, 2), (30, 8, 2),
                                                (300, 8, 2), (17, 5, 0), (10, 3, 2)])
def test_windows_cover_every_frame_and_link_every_pair(n, window, overlap):
    ranges = window_ranges(n, window, overlap)
    assert ranges[0][0] == 0 and ranges[0][2] == 0
    assert ranges[-1][1] == n
    covered = set()
    for i, (start, stop, carried) in enumerate(ranges):
        assert stop - start == min(window, n)
        if i:
            prev_stop = ranges[i - 1][1]
            assert carried == prev_stop - start >= 1          # the pair across windows is linked
            assert start + carried == prev_stop
        covered.update(range(start, stop))
    assert covered == set(range(n))


def test_coarse_to_fine_gives_every_callback_its_level_index():
    # two levels of one shape (a pyramid scale close to 1): the index, not the shape, tells them apart
    shapes = [(9, 12), (9, 12), (5, 6)]
    calls = []

    def init(level, shape):
        calls.append(("init", level, shape))
        return [level]

    def upsample(level, shape, state):
        calls.append(("upsample", level, shape, state[-1]))
        return state + [level]

    def solve_level(level, shape, state):
        calls.append(("solve", level, shape))
        return state

    assert coarse_to_fine(shapes, solve_level, init, upsample) == [2, 1, 0]
    assert calls == [("init", 2, (5, 6)), ("solve", 2, (5, 6)),
                     ("upsample", 1, (9, 12), 2), ("solve", 1, (9, 12)),
                     ("upsample", 0, (9, 12), 1), ("solve", 0, (9, 12))]
    assert coarse_to_fine([(4, 4)], solve_level, init, upsample) == [0]
    with pytest.raises(ValueError, match="at least one level"):
        coarse_to_fine([], solve_level, init, upsample)


def test_coarse_to_fine_can_start_at_a_finer_level():
    shapes = [(9, 12), (5, 6), (3, 3)]
    calls = []

    def init(level, shape):
        calls.append(("init", level))
        return [level]

    def upsample(level, shape, state):
        calls.append(("upsample", level))
        return state + [level]

    def solve_level(level, shape, state):
        calls.append(("solve", level))
        return state

    assert coarse_to_fine(shapes, solve_level, init, upsample, start_level=1) == [1, 0]
    assert calls == [("init", 1), ("solve", 1), ("upsample", 0), ("solve", 0)]
    calls.clear()
    assert coarse_to_fine(shapes, solve_level, init, upsample, start_level=0) == [0]
    assert calls == [("init", 0), ("solve", 0)]
    for bad in (-1, 3):
        with pytest.raises(ValueError, match="start_level"):
            coarse_to_fine(shapes, solve_level, init, upsample, start_level=bad)


def test_start_level_is_the_coarsest_level_that_holds_the_start():
    from ivkernels.solver.window_solver import start_level_for

    shapes = [(240, 320), (120, 160), (60, 80), (30, 40)]
    assert start_level_for(shapes, (120, 160)) == 1          # its own level
    assert start_level_for(shapes, (30, 40)) == 3
    assert start_level_for(shapes, (100, 150)) == 1          # between levels: the next larger one
    assert start_level_for(shapes, (61, 70)) == 1
    assert start_level_for(shapes, (240, 320)) == 0
    assert start_level_for(shapes, (10, 10)) == 3


def test_level_shapes():
    assert level_shapes(240, 320, 0.5, 24) == [(240, 320), (120, 160), (60, 80), (30, 40)]
    assert level_shapes(10, 10, 0.5, 24) == [(10, 10)]
    with pytest.raises(ValueError):
        level_shapes(0, 5, 0.5, 24)


def test_params_validation():
    with pytest.raises(ValueError, match="overlap"):
        Params(window=4, overlap=4)
    with pytest.raises(ValueError, match="eps_data"):
        Params(eps_data=-1.0)
    with pytest.raises(TypeError, match="unknown"):
        Params().replace(not_a_weight=1.0)
    assert Params().replace(eps_data=3.0).eps_data == 3.0


def test_lbfgs_minimises_an_ill_conditioned_quadratic(backend, rng):
    n = 501
    diag = np.logspace(0, 3, n).astype(np.float32)
    target = rng.standard_normal(n).astype(np.float32)
    d_be, t_be = backend.asarray(diag), backend.asarray(target)

    def fun(x, g):
        xn = backend.numpy(x)
        r = xn - backend.numpy(t_be)
        backend.vecops.copy(backend.asarray((backend.numpy(d_be) * r).astype(np.float32)), g)
        return float(0.5 * np.sum(diag.astype(np.float64) * r.astype(np.float64) ** 2))

    x, g = backend.zeros((n,)), backend.zeros((n,))
    e0 = fun(x, g)
    e = LBFGS(backend, n, memory=8).minimize(fun, x, g, 300, rel_tol=0.0)
    assert e < 1e-6 * e0
    np.testing.assert_allclose(backend.numpy(x), target, atol=1e-2)


def test_lbfgs_does_not_stop_on_its_first_short_step(backend):
    """``E = C + |x - 1|^2 / 2`` from 0 with a large constant C: the first step, along the
    steepest descent and scaled to a change of at most ``first_step`` = 0.1, lowers E by
    less than ``rel_tol`` of it.  That is no sign of convergence: the run goes on, and
    its first quasi-Newton step (exact curvature 1) lands on the minimum."""
    n, offset = 10, 1e8

    def fun(x, g):
        r = backend.numpy(x).astype(np.float64) - 1.0
        backend.vecops.copy(backend.asarray(r.astype(np.float32)), g)
        return offset + 0.5 * float(r @ r)

    x, g = backend.zeros((n,)), backend.zeros((n,))
    opt = LBFGS(backend, n, memory=4, first_step=0.1)
    steps = []
    opt.minimize(fun, x, g, 20, rel_tol=1e-6, on_iteration=lambda k, e: steps.append(e))
    # the first step's decrease, 0.5 * 10 * (1 - 0.9^2) = 0.95, is below 1e-6 * 1e8
    assert offset + 5.0 - steps[0] == pytest.approx(0.95, rel=1e-3)
    np.testing.assert_allclose(backend.numpy(x), 1.0, atol=1e-5)
    assert opt.stop_reason == "tolerance" and len(steps) >= 2


def _two_loop(g, pairs):
    """Textbook L-BFGS direction -H g (Nocedal & Wright Alg. 7.4) in float64."""
    q, alphas = g.copy(), []
    for s, y in reversed(pairs):
        a = (s @ q) / (s @ y)
        q -= a * y
        alphas.append(a)
    s, y = pairs[-1]
    q *= (s @ y) / (y @ y)
    for (s, y), a in zip(pairs, reversed(alphas)):
        q += (a - (y @ q) / (s @ y)) * s
    return -q


@pytest.mark.parametrize("memory", [2, 3])
def test_lbfgs_bookkeeping_matches_the_vectors(backend, rng, memory):
    """After many steps (slots recycled), the host Gram matrix equals the basis
    rows' dot products, and the coefficient two-loop gives the textbook direction."""
    n = 4096 + 37
    A = rng.standard_normal((n, 6)) / np.sqrt(n)

    def fun(x, g):
        xn = backend.numpy(x).astype(np.float64)
        grad = xn * np.linspace(1.0, 50.0, n) + A @ (A.T @ xn) + np.tanh(xn)
        backend.vecops.copy(backend.asarray(grad.astype(np.float32)), g)
        return float(0.5 * xn @ (xn * np.linspace(1.0, 50.0, n)) + 0.5 * np.sum((A.T @ xn) ** 2)
                     + np.sum(np.log(np.cosh(xn))))

    x = backend.asarray(rng.standard_normal(n).astype(np.float32))
    g = backend.zeros((n,))
    opt = LBFGS(backend, n, memory=memory)
    opt.minimize(fun, x, g, 7, rel_tol=0.0)
    assert len(opt._pairs) == memory - 1        # the last step's pair needs one more gradient
    basis = backend.numpy(opt._basis).astype(np.float64)
    m = memory
    live = [r for slot, _ in opt._pairs for r in (slot, m + slot)]
    gram = basis[live] @ basis[live].T
    np.testing.assert_allclose(opt._gram[np.ix_(live, live)], gram, rtol=1e-4, atol=1e-6 * np.abs(gram).max())
    for slot, rho in opt._pairs:
        np.testing.assert_allclose(rho, 1.0 / (basis[slot] @ basis[m + slot]), rtol=1e-4)
    # the direction from the current gradient, both ways
    cur = opt._g_rows[0]
    backend.vecops.copy(g, opt._basis[cur])
    rows = live + [cur]
    gd = backend.vecops.dots(opt._basis, opt._basis[cur], rows)
    opt._gram[cur, rows] = gd
    opt._gram[rows, cur] = gd
    c = opt._direction(cur)
    d = c @ backend.numpy(opt._basis).astype(np.float64)
    pairs = [(basis[slot], basis[m + slot]) for slot, _ in opt._pairs]
    expected = _two_loop(backend.numpy(g).astype(np.float64), pairs)
    np.testing.assert_allclose(d, expected, rtol=1e-4, atol=1e-5 * np.abs(expected).max())


def _small_problem(backend, rng, T=3, h=11, w=13):
    i = rng.uniform(0.05, 1.0, (T, h, w, 3)).astype(np.float32)
    flow = rng.uniform(-1.5, 1.5, (T - 1, h, w, 2)).astype(np.float32)
    occ = (rng.uniform(size=(T - 1, h, w)) > 0.2).astype(np.float32)
    bnd = (rng.uniform(size=(T - 1, h, w)) > 0.7).astype(np.float32)
    lum = (i @ np.array([0.2126, 0.7152, 0.0722], np.float32)) + 0.001
    be = backend
    params = Params(eps_data=0.2, eps_shading=0.2, lam_albedo_smooth=1.0, lam_albedo_sparsity=1.0)
    energy = WindowEnergy(be, be.asarray(np.log(i)), be.asarray(lum.astype(np.float32)),
                          be.asarray(flow), be.asarray(occ), be.asarray(bnd), params,
                          load_albedo_prior())
    x0 = rng.normal(0, 0.3, energy.X.shape).astype(np.float32)
    be.vecops.copy(be.asarray(x0), energy.X)
    be.vecops.copy(be.asarray(rng.normal(0, 0.3, (T, h, w)).astype(np.float32)).reshape((T * h * w,)),
                   energy.S_tilde.reshape((T * h * w,)))
    return energy, x0


def _assert_directional_derivatives(be, fun, x0, g, rng, n_directions=3, h=1e-2):
    """``g . d`` against the central difference of ``fun`` (evaluating its own
    ``X``, ``G``) along random unit directions ``d`` around ``x0``."""
    for _ in range(n_directions):
        d = rng.standard_normal(x0.shape)
        d /= np.linalg.norm(d)
        vals = []
        for sgn in (1, -1):
            be.vecops.copy(be.asarray((x0 + sgn * h * d).astype(np.float32)), fun.X)
            vals.append(fun(fun.X, fun.G))
        fd = (vals[0] - vals[1]) / (2 * h)
        assert fd == pytest.approx(g @ d, rel=2e-2, abs=1e-2 * np.abs(g).max())


def test_assembled_gradient_matches_directional_difference(backend, rng):
    energy, x0 = _small_problem(backend, rng)
    be = backend
    energy(energy.X, energy.G)
    g = be.numpy(energy.G).astype(np.float64).copy()
    _assert_directional_derivatives(be, energy, x0, g, rng)


def test_gradient_with_the_stable_pairs_matches_directional_difference(backend, rng):
    """Eq. 9's local term with the stable steps' pairs added (``shading_stable_gain``)."""
    T, h, w = 4, 11, 13
    base = rng.uniform(0.05, 1.0, (1, h, w, 3))
    light = rng.uniform(0.5, 1.0, (T, 1, 1, 1))                 # a changing light over a still scene
    i = (base * light * rng.uniform(0.98, 1.02, (T, h, w, 3))).astype(np.float32)
    flow = rng.uniform(-0.3, 0.3, (T - 1, h, w, 2)).astype(np.float32)
    occ = np.ones((T - 1, h, w), np.float32)
    lum = (i @ np.array([0.2126, 0.7152, 0.0722], np.float32)) + 0.001
    be = backend
    params = Params(eps_data=0.2, eps_shading=0.2, shading_stable_gain=8.0, shading_stable_floor=0.0)
    energy = WindowEnergy(be, be.asarray(np.log(i)), be.asarray(lum.astype(np.float32)), be.asarray(flow),
                          be.asarray(occ), be.asarray(np.zeros_like(occ)), params, load_albedo_prior())
    assert (be.numpy(energy.stable_pairs) > 0.5).sum() > 20
    x0 = rng.normal(0, 0.3, energy.X.shape).astype(np.float32)
    be.vecops.copy(be.asarray(x0), energy.X)
    be.vecops.fill(energy.S_tilde.reshape((T * h * w,)), 0.0)
    energy(energy.X, energy.G)
    g = be.numpy(energy.G).astype(np.float64).copy()
    _assert_directional_derivatives(be, energy, x0, g, rng)


def test_fixed_frames_get_no_gradient(backend, rng):
    energy, _ = _small_problem(backend, rng)
    energy.n_fixed = 1
    energy(energy.X, energy.G)
    T, h, w = energy.shape
    gA, gS = backend.numpy(energy.gA), backend.numpy(energy.gS)
    assert not gA[0].any() and not gS[0].any()
    assert gA[1:].any() and gS[1:].any()


def test_term_energies_sum_to_total(backend, rng):
    energy, _ = _small_problem(backend, rng)
    total = energy(energy.X, energy.G)
    terms = energy.term_energies()
    assert set(terms) >= {"data", "temporal_albedo", "temporal_shading", "coupling",
                          "shading_local", "albedo_smooth"}
    assert sum(terms.values()) == pytest.approx(total, rel=1e-5)


# ------------------------------------------- Eq. 2 on the data-consistent set A = I - S
def test_constrained_gradient_matches_directional_difference(backend, rng):
    """dE/dS of E(I - S, S) against a central difference of the constrained energy."""
    from ivkernels.solver.energy import ConstrainedEnergy

    energy, x0 = _small_problem(backend, rng)
    problem = ConstrainedEnergy(energy)
    be = backend
    S0 = x0[3 * energy.n:].copy()
    be.vecops.copy(be.asarray(S0), problem.X)
    problem(problem.X, problem.G)
    g = be.numpy(problem.G).astype(np.float64).copy()
    A = be.numpy(energy.A).reshape(-1, 3)
    I = be.numpy(energy.I).reshape(-1, 3)
    np.testing.assert_allclose(A, I - S0[:, None], atol=1e-6)     # A follows S
    _assert_directional_derivatives(be, problem, S0, g, rng)


def test_constrained_energy_has_no_data_term_and_fixed_frames_stay(backend, rng):
    from ivkernels.solver.energy import ConstrainedEnergy

    energy, _ = _small_problem(backend, rng)
    energy.n_fixed = 1
    problem = ConstrainedEnergy(energy)
    total = problem(problem.X, problem.G)
    T, h, w = energy.shape
    g = backend.numpy(problem.G).reshape(T, h, w).copy()
    assert not g[0].any() and g[1:].any()
    terms = energy.term_energies()
    assert total == pytest.approx(sum(v for k, v in terms.items() if k != "data"), rel=1e-5)


def test_non_finite_energy_names_the_term(backend, rng):
    energy, x0 = _small_problem(backend, rng)
    I = backend.numpy(energy.I).copy()          # a copy on CUDA: write it back through the backend
    I[0, 1, 2, 0] = np.nan
    backend.vecops.copy(backend.asarray(I).reshape((I.size,)), energy.I.reshape((I.size,)))
    with pytest.raises(FloatingPointError, match="not finite.*(temporal|albedo_smooth|data)"):
        energy(energy.X, energy.G)


def test_level_iterations_grow_coarser_up_to_the_cap():
    from ivkernels.solver.window_solver import level_iterations

    p = Params(lbfgs_iterations=40, lbfgs_iterations_coarse=200, lbfgs_level_growth=2.0)
    assert [level_iterations(p, level) for level in range(5)] == [40, 80, 160, 200, 200]
    flat = p.replace(lbfgs_level_growth=1.0, lbfgs_iterations_coarse=10)
    assert [level_iterations(flat, level) for level in range(3)] == [40, 10, 10]
    with pytest.raises(ValueError, match="lbfgs_level_growth"):
        Params(lbfgs_level_growth=0.5)


# ------------------ the edge-aware coarse basis, S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...)) (coarse_basis.py)
def _coarse_problem(backend, rng, spacings=(3,)):
    from ivkernels.solver.coarse_basis import CoarseBasisProblem
    from ivkernels.solver.energy import ConstrainedEnergy

    energy, x0 = _small_problem(backend, rng, T=3, h=13, w=14)
    problem = ConstrainedEnergy(energy)
    backend.vecops.copy(backend.asarray(x0[3 * energy.n:].copy()), problem.X)
    coarse = CoarseBasisProblem(problem, list(spacings), 0.5)
    coarse.start()
    return energy, problem, coarse


#: one level, and three (node grids 14 x 15, 8 x 8 and 4 x 4 on the 13 x 14 frames)
SPACINGS = [(3,), (1, 3, 9)]


@pytest.mark.parametrize("spacings", SPACINGS)
def test_coarse_basis_starts_at_the_current_shading(backend, rng, spacings):
    energy, problem, coarse = _coarse_problem(backend, rng, spacings)
    S = backend.numpy(problem.X).copy()
    np.testing.assert_array_equal(backend.numpy(coarse.s), S)
    assert not backend.numpy(coarse.X)[energy.n:].any()
    assert [f.spacing for f in coarse.fields] == list(spacings)
    assert coarse(coarse.X, coarse.G) == pytest.approx(problem(problem.X, problem.G), rel=1e-6)


@pytest.mark.parametrize("spacings", SPACINGS)
def test_coarse_basis_gradient_matches_directional_difference(backend, rng, spacings):
    """dE/d[s, z_k] (z_k through c_k Q_k^T ... P_0^T) against central differences of
    E(s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...))), along all of X and along each level's z_k alone."""
    energy, problem, coarse = _coarse_problem(backend, rng, spacings)
    be = backend
    x0 = be.numpy(coarse.X).astype(np.float64).copy()
    x0[energy.n:] = rng.normal(0, 0.2, x0.size - energy.n)          # non-zero coarse fields
    be.vecops.copy(be.asarray(x0.astype(np.float32)), coarse.X)
    coarse(coarse.X, coarse.G)
    g = be.numpy(coarse.G).astype(np.float64).copy()
    _assert_directional_derivatives(be, coarse, x0.astype(np.float32), g, rng)
    offset = energy.n
    for field in coarse.fields:
        part = slice(offset, offset + field.size)
        offset += field.size
        assert np.abs(g[part]).max() > 0
        d = np.zeros_like(x0)
        d[part] = rng.standard_normal(field.size)
        d /= np.linalg.norm(d)
        vals = []
        for sgn in (1, -1):
            be.vecops.copy(be.asarray((x0 + sgn * 1e-2 * d).astype(np.float32)), coarse.X)
            vals.append(coarse(coarse.X, coarse.G))
        assert (vals[0] - vals[1]) / 2e-2 == pytest.approx(g @ d, rel=2e-2, abs=1e-2 * np.abs(g).max())


@pytest.mark.parametrize("spacings", SPACINGS)
def test_coarse_basis_finish_leaves_s_plus_the_nested_fields_in_the_shading(backend, rng, spacings):
    """S = s + P_0 (z_0 + Q_1 (z_1 / 3 + Q_2 (z_2 / 9))), each P_0, Q_k the NumPy reference's
    prolongation, with weights from the albedo I - s at the pixels (P_0, spacing
    spacings[0]) and at the level below's nodes (Q_k, spacing 3), the nodes found here
    from their definition (node j on row min(j * spacing, size - 1) of the level below)."""
    from ivkernels.kernels.reference import coarse_basis as ref
    from ivkernels.solver.coarse_basis import LEVEL_RATIO

    energy, problem, coarse = _coarse_problem(backend, rng, spacings)
    be = backend
    s = be.numpy(coarse.s).astype(np.float64).reshape(energy.shape)
    albedo = be.numpy(energy.I).astype(np.float64) - s[..., None]
    guides, ratios = [albedo], [spacings[0]]
    zs = []
    for k, field in enumerate(coarse.fields):
        if k > 0:
            below = guides[-1]
            rows = [min(j * ratios[-1], below.shape[1] - 1) for j in range((below.shape[1] - 1) // ratios[-1] + 2)]
            cols = [min(i * ratios[-1], below.shape[2] - 1) for i in range((below.shape[2] - 1) // ratios[-1] + 2)]
            guides.append(below[:, rows][:, :, cols])
            ratios.append(LEVEL_RATIO)
        weights = ref.coarse_weights(guides[k], ratios[k], 0.5)
        np.testing.assert_allclose(be.numpy(field.weights), weights, atol=1e-5)
        z = rng.normal(0, 0.3, field.z.shape).astype(np.float32)
        be.vecops.copy(be.asarray(z.reshape(-1)), field.z_flat)
        assert field.scale == LEVEL_RATIO ** -k and field.spacing == spacings[k]
        zs.append((field.scale * z, weights))
    field_sum = zs[-1][0]
    for k in range(len(zs) - 1, 0, -1):                       # down to level 0's nodes
        field_sum = zs[k - 1][0] + ref.prolong(field_sum, zs[k][1], ratios[k])
    want = s + ref.prolong(field_sum, zs[0][1], ratios[0])
    coarse.finish()
    np.testing.assert_allclose(be.numpy(energy.S), want, atol=1e-5)
    I = be.numpy(energy.I)
    np.testing.assert_allclose(be.numpy(energy.A), I - be.numpy(energy.S)[..., None], atol=1e-5)


def test_coarse_basis_start_stays_on_the_device(backend, rng, monkeypatch):
    """Each alternation's start gathers the nested levels' albedo with backend kernels: no
    copy to the host (on a GPU that was the window's whole albedo, every alternation)."""
    energy, problem, coarse = _coarse_problem(backend, rng, (1, 3, 9))
    weights = [backend.numpy(f.weights).copy() for f in coarse.fields]

    def refuse(*args, **kwargs):
        raise AssertionError("CoarseBasisProblem.start read an array back to the host")

    monkeypatch.setattr(backend, "numpy", refuse)
    coarse.start()
    monkeypatch.undo()
    for f, before in zip(coarse.fields, weights):
        np.testing.assert_array_equal(backend.numpy(f.weights), before)     # the same albedo, the same weights


def test_coarse_basis_spacings_must_grow_by_the_level_ratio(backend, rng):
    from ivkernels.solver.coarse_basis import CoarseBasisProblem
    from ivkernels.solver.energy import ConstrainedEnergy

    energy, _ = _small_problem(backend, rng, T=2, h=13, w=14)
    with pytest.raises(ValueError, match="grow by 3"):
        CoarseBasisProblem(ConstrainedEnergy(energy), [2, 4], 0.5)


def test_coarse_basis_levels_that_fit():
    from ivkernels.solver.coarse_basis import coarse_spacings, uses_coarse_basis

    assert uses_coarse_basis((16, 20), 4) and not uses_coarse_basis((15, 40), 4)
    assert not uses_coarse_basis((480, 640), 0)
    assert coarse_spacings((480, 640), 4, 2) == [4, 12]
    assert coarse_spacings((480, 640), 4, 8) == [4, 12, 36, 108]
    assert coarse_spacings((47, 640), 4, 2) == [4]           # 12 needs a side of 48
    assert coarse_spacings((48, 64), 4, 2) == [4, 12]
    assert coarse_spacings((15, 40), 4, 2) == []
    assert coarse_spacings((480, 640), 0, 2) == []


def test_coarse_basis_needs_a_level(backend, rng):
    from ivkernels.solver.coarse_basis import CoarseBasisProblem
    from ivkernels.solver.energy import ConstrainedEnergy

    energy, _ = _small_problem(backend, rng, T=2, h=9, w=10)
    with pytest.raises(ValueError, match="at least one coarse level"):
        CoarseBasisProblem(ConstrainedEnergy(energy), [], 0.5)


def _finest_energy_at_ten_iterations(kind: str, size: tuple[int, int], seed: int, **fields) -> float:
    """The finest level's last energy of decompose() with the true flow, 4 frames,
    10 L-BFGS iterations per alternation and the given Params fields."""
    import ivkernels as iv
    from ivkernels.evaluation import synthetic

    seq = synthetic.render_sequence(kind, n_frames=4, size=size, seed=seed)
    video = iv.decompose(seq.frames, flow=seq.flow, params=Params(lbfgs_iterations=10, **fields))
    return [e for (w, level, o, k, e) in video.diagnostics["energy"] if level == 0][-1]


def test_the_coarse_basis_descends_faster_at_the_same_budget():
    """A static scene under a moving light: with the coarse basis the finest level ends
    lower in energy than without it."""
    final = {spacing: _finest_energy_at_ten_iterations("static_moving_light", (64, 80), 3,
                                                       coarse_basis_spacing=spacing)
             for spacing in (0, 4)}
    assert final[4] < 0.995 * final[0]


def test_a_second_scaled_coarse_level_descends_further_at_the_same_budget():
    """Objects moving in front of a camera: with a second coarse field (spacing 12, scaled
    by 1/3) the finest level ends lower in energy than with the first alone."""
    final = {levels: _finest_energy_at_ten_iterations("objects_camera", (120, 160), 4,
                                                      coarse_basis_levels=levels)
             for levels in (1, 2)}
    assert final[2] < 0.999 * final[1]
