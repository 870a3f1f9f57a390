"""Median filters: the generic contract from the case table (5x5 median, Classic+NL's weighted
flow median and the shading S~ update of Eq. 9, 10, 13 against brute-force NumPy), plus the
sorting network, Li & Osher's formula vs a grid search, continuous values with every pixel
masked (each selection starts from the previous pixel's answer), 2-means around the size at
which it is skipped, surf at a motion boundary, untouched pixels, a workspace reused across
shapes, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import median as ref
from ivkernels.kernels.workspace import Workspace
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("median")


def median5x5(be, src):
    out = be.empty(src.shape)
    be.median.median5x5(be.asarray(src), out)
    return be.numpy(out).copy()


def wmedian_shading(be, S, flow, w_bnd, **kw):
    out = be.empty(S.shape)
    be.median.weighted_median_shading(*(be.asarray(a) for a in (S, flow, w_bnd)), out, **kw)
    return be.numpy(out).copy()


def wmedian_flow(be, flow, lab, occ, mask, **kw):
    out = be.empty(flow.shape)
    be.median.weighted_median_flow(*(be.asarray(a) for a in (flow, lab, occ, mask)), out, **kw)
    return be.numpy(out).copy()


def two_region_flow(rng, t, h, w, noise=0.05, radius=None):
    """Flow (t, h, w, 2): a static background and a disc moving by (3, 1), plus noise."""
    yy, xx = np.mgrid[0:h, 0:w]
    radius = min(h, w) / 3 if radius is None else radius
    disc = (yy - h / 2) ** 2 + (xx - w / 3) ** 2 < radius**2
    flow = np.zeros((t, h, w, 2), np.float32)
    flow[:, disc] = (3.0, 1.0)
    flow += rng.normal(0.0, noise, flow.shape).astype(np.float32)
    return flow, disc


def shading_inputs(rng, t, h, w, t_flow):
    S = (rng.integers(0, 6, (t, h, w)) / 5.0).astype(np.float32)  # ties
    S += rng.normal(0, 0.02, S.shape).astype(np.float32) * (rng.random(S.shape) < 0.5)
    flow, _ = two_region_flow(rng, t_flow, h, w)
    w_bnd = (rng.random((t_flow, h, w)) < 0.4).astype(np.float32)
    return S, flow, w_bnd


def flow_inputs(rng, t, h, w):
    flow = (rng.integers(-4, 5, (t, h, w, 2)) / 2.0).astype(np.float32)  # ties
    lab = rng.uniform(0, 30, (t, h, w, 3)).astype(np.float32)
    occ = np.where(rng.random((t, h, w)) < 0.8, 1.0, rng.random((t, h, w))).astype(np.float32)
    mask = (rng.random((t, h, w)) < 0.5).astype(np.float32)
    return flow, lab, occ, mask


@pytest.mark.parametrize("n", [1, 3, 9, 25, 49])
def test_median_network_selects_the_median(rng, n):
    from ivkernels.kernels.warp.median import median_network

    pairs = median_network(n)
    assert all(0 <= i < j < n for i, j in pairs)
    for trial in range(500):
        v = rng.integers(0, 3, n).astype(float) if trial % 2 else rng.random(n)
        w = v.copy()
        for i, j in pairs:
            w[i], w[j] = min(w[i], w[j]), max(w[i], w[j])
        assert w[n // 2] == np.median(v)


def test_median5x5_tiny_images(kernel_backend, rng):
    for h, w in ((1, 1), (2, 3), (4, 1)):
        src = rng.normal(size=(1, h, w, 1)).astype(np.float32)
        np.testing.assert_array_equal(median5x5(kernel_backend, src), ref.median5x5(src).astype(np.float32))


# ----------------------------------------------------------------------------- selection / Li & Osher

def grid_minimiser(values, weights, s, lam):
    """Brute-force 1-D minimisation of the (convex) objective: a grid of step 1e-3,
    then a grid of step 1e-6 around its best point."""
    lo, hi = min(values.min(), s) - 0.1, max(values.max(), s) + 0.1
    for step in (1e-3, 1e-6):
        u = np.arange(lo, hi, step)
        f = np.abs(u[:, None] - values[None]) @ weights + lam * (u - s) ** 2
        best = u[np.argmin(f)]
        lo, hi = best - 2e-3, best + 2e-3
    return best, f.min()


@pytest.mark.parametrize("lam", [0.5, 5.0, 50.0])
def test_li_osher_reference_matches_grid_search(rng, lam):
    for _ in range(20):
        n = int(rng.integers(1, 30))
        v = np.round(rng.normal(size=n), 1)
        wts = rng.random(n)
        s = float(rng.normal())
        u = ref.l1_quadratic_minimiser(v, wts, s, lam)
        ug, fg = grid_minimiser(v, wts, s, lam)
        assert abs(u - ug) < 2e-5
        assert np.abs(u - v) @ wts + lam * (u - s) ** 2 <= fg + 1e-9


@pytest.mark.parametrize("lam", [0.05, 5.0, 50.0])
def test_shading_li_osher_kernel_matches_grid_search(kernel_backend, rng, lam):
    """Constant flow (surf = 1 everywhere): every masked pixel is the exact minimiser."""
    S = rng.uniform(0, 1, (1, 9, 11)).astype(np.float32)
    flow = np.zeros((1, 9, 11, 2), np.float32)
    w_bnd = np.zeros((1, 9, 11), np.float32)
    pix = [(0, 0), (4, 5), (8, 3), (2, 10)]
    for y, x in pix:
        w_bnd[0, y, x] = 1
    out = wmedian_shading(kernel_backend, S, flow, w_bnd, radius=3, sigma_s=2.0, lam=lam)
    for y, x in pix:
        wts = ref.shading_weights(flow[0], y, x, 3, 2.0).ravel()
        vals = ref._window(S[0], y, x, 3).ravel()
        ug, fg = grid_minimiser(vals[wts > 0], wts[wts > 0], float(S[0, y, x]), lam)
        u = float(out[0, y, x])
        assert abs(u - ug) < 1e-4
        assert np.abs(u - vals) @ wts + lam * (u - S[0, y, x]) ** 2 <= fg + 1e-5
    untouched = w_bnd == 0
    np.testing.assert_array_equal(out[untouched], S[untouched])


@pytest.mark.parametrize("lam", [0.0, 0.001, 3.0])
def test_shading_only_centre_weight_keeps_value(kernel_backend, rng, lam):
    S, flow, _ = shading_inputs(rng, 2, 9, 11, 2)
    out = wmedian_shading(kernel_backend, S, flow, np.ones((2, 9, 11), np.float32), radius=4, sigma_s=1e-3, lam=lam)
    np.testing.assert_array_equal(out, S)


@pytest.mark.parametrize("radius", [1, 3, 7])
def test_weighted_medians_continuous_values_every_pixel(kernel_backend, rng, radius):
    """No ties and every pixel masked: each selection starts from the previous pixel's answer,
    rarely an answer again; the results are the reference's."""
    h, w = 13, 17
    flow, _ = two_region_flow(rng, 2, h, w, noise=0.3, radius=4.5)
    lab = rng.uniform(0, 30, (2, h, w, 3)).astype(np.float32)
    occ = rng.uniform(0.2, 1.0, (2, h, w)).astype(np.float32)
    ones = np.ones((2, h, w), np.float32)
    got = wmedian_flow(kernel_backend, flow, lab, occ, ones, radius=radius, sigma_i=10.0)
    np.testing.assert_array_equal(got, ref.weighted_median_flow(flow, lab, occ, ones, radius=radius,
                                                                sigma_i=10.0).astype(np.float32))
    S = rng.normal(0.0, 1.0, (3, h, w)).astype(np.float32)
    for lam in (0.0, 0.001, 2.0):
        got = wmedian_shading(kernel_backend, S, flow, ones, radius=radius, lam=lam)
        want = ref.weighted_median_shading(S, flow, ones, radius=radius, lam=lam)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)


@pytest.mark.parametrize("step", [0.3, 0.44, 0.47, 0.5, 0.53, 0.7])
def test_shading_two_means_near_the_skipped_size(kernel_backend, rng, step):
    """A stripe two pixels wide moving by (step, step / 2) over a static background, every
    pixel masked: the 2-means is skipped where the window's flow vectors span less than
    sqrt(0.8) * 0.5 px, run above, and splits from min_separation = 0.5 px on.  Every pixel
    is the reference's; the stripe keeps its value exactly when the windows split."""
    h, w = 15, 19
    stripe = (np.arange(w) >= 8) & (np.arange(w) < 10)
    flow = np.zeros((1, h, w, 2), np.float32)
    flow[0, :, stripe] = (step, step / 2)
    flow += rng.normal(0.0, 0.002, flow.shape).astype(np.float32)
    S = np.broadcast_to(stripe.astype(np.float32), (1, h, w)) + rng.normal(0.0, 0.01, (1, h, w)).astype(np.float32)
    ones = np.ones((1, h, w), np.float32)
    got = wmedian_shading(kernel_backend, S, flow, ones, radius=3, lam=0.0)
    np.testing.assert_allclose(got, ref.weighted_median_shading(S, flow, ones, radius=3, lam=0.0), rtol=0, atol=1e-6)
    splits = np.hypot(step, step / 2) > 0.51
    assert ((got[0][:, stripe] > 0.5) == splits).all()


def test_shading_surf_stops_at_motion_boundary(kernel_backend, rng):
    """A bright disc moving over a static dark background, w_bnd = 1 everywhere.

    With surf the window of every pixel keeps only its own surface, so the
    median returns the picture unchanged; with a flow that has no boundary
    (surf = 1 everywhere) the same median erodes the disc into the background.
    """
    from ivkernels.kernels.warp import median as warp_median

    assert (ref.KMEANS_ITERATIONS, ref.MIN_SEPARATION) == (warp_median.KMEANS_ITERATIONS, warp_median.MIN_SEPARATION)
    h, w = 31, 37
    flow, disc = two_region_flow(rng, 1, h, w, noise=0.1, radius=5.5)
    S = np.where(disc, 1.0, 0.0)[None].astype(np.float32)
    w_bnd = np.ones((1, h, w), np.float32)
    kept = wmedian_shading(kernel_backend, S, flow, w_bnd, lam=0.0)
    np.testing.assert_array_equal(kept, S)
    eroded = wmedian_shading(kernel_backend, S, np.zeros_like(flow), w_bnd, lam=0.0)
    assert (eroded[0][disc] == 0).all()
    # the weights of a background pixel next to the disc vanish on the disc side
    ys, xs = np.nonzero(disc)
    y, x = ys[0] - 1, xs[0]
    wts = ref.shading_weights(flow[0], y, x)
    win_disc = ref._window(disc.astype(float), y, x, 7) > 0
    assert wts[win_disc].max() == 0 and wts[~win_disc].min() > 0


def test_workspace_reused_across_shapes_gives_the_same_result(kernel_backend, rng):
    shading = [shading_inputs(rng, 2, 9, 11, 1), shading_inputs(rng, 1, 7, 13, 1)]
    flows = [flow_inputs(rng, 2, 9, 11), flow_inputs(rng, 1, 7, 13)]
    fresh = [(wmedian_shading(kernel_backend, *s, radius=2, lam=0.1), wmedian_flow(kernel_backend, *f, radius=3))
             for s, f in zip(shading, flows)]
    ws = Workspace()
    for _ in range(2):          # the second round finds the window rows left by the first
        for s, f, (want_s, want_f) in zip(shading, flows, fresh):
            np.testing.assert_array_equal(wmedian_shading(kernel_backend, *s, radius=2, lam=0.1, workspace=ws),
                                          want_s)
            np.testing.assert_array_equal(wmedian_flow(kernel_backend, *f, radius=3, workspace=ws), want_f)
    m = kernel_backend.median
    shapes = [m.shading_scratch_shape((2, 9, 11), 2), m.shading_scratch_shape((1, 7, 13), 2),
              m.flow_scratch_shape((2, 9, 11, 2), 3), m.flow_scratch_shape((1, 7, 13, 2), 3),
              (1, 9, 11, 4), (1, 7, 13, 4)]          # the surface centres found without the caller's
    assert len(ws) == 6 and ws.nbytes == 4 * sum(int(np.prod(shape)) for shape in shapes)


def test_shading_median_given_its_centres_is_bit_for_bit_the_same(kernel_backend, rng):
    """The solver finds the centres once per flow and passes them in: same bits as finding them inside."""
    be = kernel_backend
    kinds = set()
    for t, h, w, radius, lam in [(3, 17, 23, 3, 0.001), (2, 12, 9, 7, 0.0), (1, 5, 6, 2, 2.0)]:
        S, flow, w_bnd = shading_inputs(rng, t, h, w, max(t - 1, 1))
        want = wmedian_shading(be, S, flow, w_bnd, radius=radius, lam=lam)
        centres = be.empty((*flow.shape[:3], 4))
        be.median.surface_centres(be.asarray(flow), be.asarray(w_bnd), centres, radius=radius)
        c = be.numpy(centres)
        assert (c[w_bnd < 0.5] == 0).all()                           # not a boundary pixel: no split
        split = (c[..., :2] != c[..., 2:]).any(-1)
        kinds |= {"split"} if split.any() else set()
        kinds |= {"one surface"} if (~split & (w_bnd >= 0.5)).any() else set()
        got = wmedian_shading(be, S, flow, w_bnd, radius=radius, lam=lam, centres=centres)
        np.testing.assert_array_equal(got, want)
        # wrong centres change the answer: they are read, not found again
        got_wrong = wmedian_shading(be, S, flow, w_bnd, radius=radius, lam=lam, centres=be.zeros(c.shape))
        assert not np.array_equal(got_wrong, want)
    assert kinds == {"split", "one surface"}                        # both kinds of window occur


def test_flow_only_centre_weight_keeps_flow(kernel_backend, rng):
    flow, lab, occ, _ = flow_inputs(rng, 1, 9, 11)
    ones = np.ones((1, 9, 11), np.float32)
    # colour weights underflow to 0 except at the centre (lab distance 0)
    np.testing.assert_array_equal(wmedian_flow(kernel_backend, flow, lab, ones, ones, radius=3, sigma_i=1e-3), flow)
    # no weight at all (occ = 0 everywhere, centre included): the flow is kept
    np.testing.assert_array_equal(wmedian_flow(kernel_backend, flow, lab, 0 * ones, ones, radius=3), flow)


def test_bad_input_raises(kernel_backend, rng):
    S, flow, w_bnd = (kernel_backend.asarray(a) for a in shading_inputs(rng, 2, 5, 6, 1))
    out = kernel_backend.empty((2, 5, 6))
    m = kernel_backend.median
    with pytest.raises(ValueError, match="out must have shape"):
        m.median5x5(kernel_backend.asarray(np.zeros((1, 5, 6, 2), np.float32)), kernel_backend.empty((1, 5, 6, 1)))
    with pytest.raises(ValueError, match="expected T' <= T"):
        m.weighted_median_shading(S, kernel_backend.zeros((3, 5, 6, 2)), kernel_backend.zeros((3, 5, 6)), out)
    with pytest.raises(ValueError, match="w_bnd must have shape"):
        m.weighted_median_shading(S, flow, kernel_backend.zeros((2, 5, 6)), out)
    with pytest.raises(ValueError, match="radius"):
        m.weighted_median_shading(S, flow, w_bnd, out, radius=-1)
    with pytest.raises(ValueError, match="sigma_s"):
        m.weighted_median_shading(S, flow, w_bnd, out, sigma_s=0.0)
    with pytest.raises(ValueError, match="lam"):
        m.weighted_median_shading(S, flow, w_bnd, out, lam=-1.0)
    with pytest.raises(TypeError, match="workspace must be"):
        m.weighted_median_shading(S, flow, w_bnd, out, workspace=kernel_backend.empty((10, 3)))
    with pytest.raises(TypeError, match="S must have dtype float32"):
        m.weighted_median_shading(kernel_backend.zeros((2, 5, 6), np.float64), flow, w_bnd, out)
    fl = kernel_backend.zeros((1, 5, 6, 2))
    with pytest.raises(ValueError, match="lab must have shape"):
        m.weighted_median_flow(fl, kernel_backend.zeros((1, 5, 6, 1)), w_bnd, w_bnd, kernel_backend.empty((1, 5, 6, 2)))
    with pytest.raises(ValueError, match="sigma_i"):
        m.weighted_median_flow(fl, kernel_backend.zeros((1, 5, 6, 3)), w_bnd, w_bnd, kernel_backend.empty((1, 5, 6, 2)),
                               sigma_i=-1.0)
