"""Occlusion and motion-boundary maps (kernels/*/maps.py)."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import derivatives as ref_derivatives
from ivkernels.kernels.reference import maps as ref
from ivkernels.kernels.workspace import Workspace

T, H, W = 2, 37, 53


def random_inputs(rng, t=T):
    """Lab frames 0..t (L in [0, 100], a, b in [-40, 40]), a flow partly leaving the image,
    and its one-sided divergence."""
    lab = np.concatenate([rng.uniform(0, 100, (t + 1, H, W, 1)), rng.uniform(-40, 40, (t + 1, H, W, 2))], -1)
    lab = lab.astype(np.float32)
    lab[1:] = 0.9 * lab[:-1] + 0.1 * lab[1:]           # neighbouring frames look alike
    flow = rng.normal(scale=2.0, size=(t, H, W, 2)).astype(np.float32)
    flow[:, :, :3, 0] = -4.0                             # leaves through the left border
    div_neg = ref_derivatives.divergence_negative(flow).astype(np.float32)
    return lab, flow, div_neg


def occlusion(be, fn, lab, flow, div_neg, *args):
    out = be.zeros(flow.shape[:3])
    getattr(be.maps, fn)(be.asarray(lab), be.asarray(flow), be.asarray(div_neg), out, *args)
    return be.numpy(out).copy()


def boundary(be, mag, threshold, radius, **kw):
    out = be.zeros(mag.shape)
    be.maps.motion_boundary(be.asarray(mag), out, threshold, radius, **kw)
    return be.numpy(out).copy()


@pytest.mark.parametrize("sigmas", [(20.0, 0.3), (40.0, 1.0)])
def test_occlusion_matches_reference(backend, rng, sigmas):
    lab, flow, div_neg = random_inputs(rng)
    soft = occlusion(backend, "occlusion_soft", lab, flow, div_neg, *sigmas)
    want = ref.occlusion_soft(lab, flow, div_neg, *sigmas)
    np.testing.assert_allclose(soft, want, atol=2e-5)
    binary = occlusion(backend, "occlusion_binary", lab, flow, div_neg, *sigmas, 0.5)
    want_binary = ref.occlusion_binary(lab, flow, div_neg, *sigmas, 0.5)
    undecided = np.abs(want - 0.5) < 1e-4           # float32 rounding may fall either side
    np.testing.assert_array_equal(binary[~undecided], want_binary[~undecided])
    assert 0.05 < binary.mean() < 0.95
    assert np.all(binary[:, :, :3] == 0)             # left the image


def test_occlusion_hand_cases(backend):
    lab = np.zeros((2, H, W, 3), np.float32)
    lab[1, ..., 0] = 20.0                            # L differs by sigma_e: o = exp(-1/2)
    flow = np.zeros((1, H, W, 2), np.float32)
    div = np.zeros((1, H, W), np.float32)
    soft = occlusion(backend, "occlusion_soft", lab, flow, div)
    np.testing.assert_allclose(soft, np.exp(-0.5), rtol=1e-6)
    np.testing.assert_array_equal(occlusion(backend, "occlusion_binary", lab, flow, div), 1)
    np.testing.assert_array_equal(occlusion(backend, "occlusion_binary", lab, flow, div, 20.0, 0.3, 0.7), 0)
    div[0, 5, 5] = -0.3                              # compression of sigma_d: another factor exp(-1/2)
    np.testing.assert_allclose(occlusion(backend, "occlusion_soft", lab, flow, div)[0, 5, 5], np.exp(-1), rtol=1e-6)
    flow[0, 10, 10] = (0.0, -11.0)                   # lands above the image
    assert occlusion(backend, "occlusion_binary", lab, flow, div)[0, 10, 10] == 0
    assert occlusion(backend, "occlusion_soft", lab, flow, div)[0, 10, 10] == 0


@pytest.mark.parametrize("radius", [0, 1, 3])
def test_motion_boundary_matches_reference(backend, rng, radius):
    mag = rng.random((T, H, W), dtype=np.float32) ** 8
    np.testing.assert_array_equal(boundary(backend, mag, 0.8, radius), ref.motion_boundary(mag, 0.8, radius))


def test_motion_boundary_hand_case(backend):
    mag = np.zeros((1, H, W), np.float32)
    mag[0, 1, 20] = 2.0
    mag[0, 30, 40] = 1.0                             # equal to the threshold: not an edge
    out = boundary(backend, mag, 1.0, 2)
    want = np.zeros_like(out)
    want[0, 0:4, 18:23] = 1                          # clipped at the top border
    np.testing.assert_array_equal(out, want)


def test_motion_boundary_workspace_reused_across_shapes(backend, rng):
    mags = [rng.random(shape, dtype=np.float32) ** 8 for shape in ((T, H, W), (1, 9, 11))]
    ws = Workspace()
    for _ in range(2):          # the second round finds the buffers left by the first
        for mag in mags:
            np.testing.assert_array_equal(boundary(backend, mag, 0.8, 2, workspace=ws),
                                          ref.motion_boundary(mag, 0.8, 2))
    assert len(ws) == 2


def test_bad_input_raises(backend):
    m = backend.maps
    lab, flow, div, out = (backend.zeros(s) for s in ((T + 1, H, W, 3), (T, H, W, 2), (T, H, W), (T, H, W)))
    with pytest.raises(ValueError, match="flow"):
        m.occlusion_soft(backend.zeros((T, H, W, 3)), flow, div, out)
    with pytest.raises(ValueError, match="lab"):
        m.occlusion_binary(backend.zeros((T + 1, H, W, 1)), flow, div, out)
    with pytest.raises(ValueError, match="div_neg"):
        m.occlusion_soft(lab, flow, backend.zeros((T, H, W - 1)), out)
    with pytest.raises(ValueError, match="sigma"):
        m.occlusion_soft(lab, flow, div, out, sigma_e=0.0)
    with pytest.raises(ValueError, match="radius"):
        m.motion_boundary(div, out, 0.5, -1)
    with pytest.raises(ValueError, match="out"):
        m.motion_boundary(div, backend.zeros((T, H, W, 1)), 0.5, 1)
    with pytest.raises(TypeError, match="float32"):
        m.motion_boundary(backend.zeros((T, H, W), np.float64), out, 0.5, 1)
    with pytest.raises(TypeError, match="workspace must be"):
        m.motion_boundary(div, out, 0.5, 1, workspace=[])


def test_warp_and_taichi_agree(rng):
    lab, flow, div_neg = random_inputs(rng)
    mag = rng.random((T, H, W), dtype=np.float32) ** 8
    wb, tb = get_backend("warp"), get_backend("taichi")
    np.testing.assert_allclose(occlusion(wb, "occlusion_soft", lab, flow, div_neg),
                               occlusion(tb, "occlusion_soft", lab, flow, div_neg), atol=2e-5)
    a = occlusion(wb, "occlusion_binary", lab, flow, div_neg)
    b = occlusion(tb, "occlusion_binary", lab, flow, div_neg)
    assert np.mean(a != b) < 1e-3
    np.testing.assert_array_equal(boundary(wb, mag, 0.7, 2), boundary(tb, mag, 0.7, 2))


def test_one_and_two_threads_agree(rng):
    be = get_backend("warp")
    lab, flow, div_neg = random_inputs(rng, t=3)
    mag = rng.random((3, H, W), dtype=np.float32) ** 8
    res = []
    for n in (1, 2):
        with threads(n):
            res.append([occlusion(be, "occlusion_soft", lab, flow, div_neg),
                        occlusion(be, "occlusion_binary", lab, flow, div_neg), boundary(be, mag, 0.7, 2)])
    for a, b in zip(*res):
        np.testing.assert_array_equal(a, b)


# ------------------------------------------------ warp reliability (temporal terms' weight)
def reliability(be, log_image, flow, occ, max_spread):
    out = be.asarray(occ.copy())
    be.maps.warp_reliability(be.asarray(log_image), be.asarray(flow), out, max_spread)
    return be.numpy(out).copy()


@pytest.mark.parametrize("max_spread", [0.05, 0.3])
def test_warp_reliability_matches_reference(backend, rng, max_spread):
    log_image = rng.normal(0.0, 0.5, (T + 1, H, W, 3)).astype(np.float32)
    log_image[:, 10:20, 10:30] = -1.0                     # a flat patch
    flow = rng.normal(scale=2.0, size=(T, H, W, 2)).astype(np.float32)
    flow[:, :, :3, 0] = -4.0                              # leaves through the left border
    occ = (rng.uniform(size=(T, H, W)) > 0.2).astype(np.float32)
    got = reliability(backend, log_image, flow, occ, max_spread)
    spread = ref.corner_spread(log_image, flow)
    clear = np.abs(spread - max_spread) > 1e-4            # away from float ties
    np.testing.assert_array_equal(got[clear], ref.warp_reliability(log_image, flow, occ, max_spread)[clear])
    assert 0 < (got < occ).mean() < 1


def test_warp_reliability_hand_cases(backend):
    """Whole-pixel flow and flat images keep w_occ; a half-pixel sample across a step clears it."""
    t, h, w = 2, 9, 11
    step = np.zeros((t, h, w, 3), np.float32)
    step[:, :, 5:] = 1.0
    occ = np.ones((t - 1, h, w), np.float32)
    whole = np.zeros((t - 1, h, w, 2), np.float32)
    whole[..., 0] = 2.0
    assert reliability(backend, step, whole, occ, 0.01).all()
    half = np.zeros((t - 1, h, w, 2), np.float32)
    half[..., 0] = 0.5
    flat = np.full((t, h, w, 3), 0.3, np.float32)
    assert reliability(backend, flat, half, occ, 0.01).all()
    got = reliability(backend, step, half, occ, 0.01)
    assert not got[:, :, 4].any()                         # sample at x = 4.5 straddles the step
    assert got[:, :, :4].all() and got[:, :, 5:].all()


def test_warp_reliability_bad_input(backend):
    img = backend.asarray(np.zeros((2, 4, 4, 3), np.float32))
    flow = backend.asarray(np.zeros((1, 4, 4, 2), np.float32))
    with pytest.raises(ValueError, match="occ must have shape"):
        backend.maps.warp_reliability(img, flow, backend.asarray(np.zeros((2, 4, 4), np.float32)), 0.1)
    with pytest.raises(ValueError, match="max_spread"):
        backend.maps.warp_reliability(img, flow, backend.asarray(np.zeros((1, 4, 4), np.float32)), 0.0)
