"""A still camera's flow held at zero on the surfaces that stay (ivkernels/solver/still_flow.py)
and its place in decompose(): only an estimated flow, only under a still camera, forward and
backward flow alike."""
import numpy as np

import ivkernels as iv
from ivkernels.kernels.reference import maps as ref
from ivkernels.kernels.reference.step_evidence import DARK_OFFSET
from ivkernels.solver import still_flow

decompose_module = __import__("ivkernels.decompose", fromlist=["FLOW_AHEAD"])

FAST = dict(lbfgs_iterations=2, guide_lbfgs_iterations=2)
T, H, W = 5, 48, 64


def shadow_scene(camera_step: float = 0.0) -> np.ndarray:
    """(T, H, W, 3) linear RGB: a still grey checkerboard (period 6) under a hard shadow band 6 px
    wide that moves 6 px a frame, and a printed square that moves 2 px a frame; with
    ``camera_step`` > 0 everything shifts by that many whole pixels a frame (a panning camera)."""
    y, x = np.mgrid[:H, :W]
    board = np.where((y // 6 + x // 6) % 2 == 0, 0.7, 0.25)
    print_ = np.random.default_rng(5).uniform(0.1, 0.9, (12, 12))
    frames = []
    for k in range(T):
        img = board.copy()
        img[:, 8 + 6 * k: 14 + 6 * k] *= 0.4                     # the shadow's band
        img[30:42, 10 + 2 * k: 22 + 2 * k] = print_               # the moving square
        img = np.roll(img, int(camera_step * k), axis=1)
        frames.append(np.repeat(img[..., None], 3, 2))
    return np.asarray(frames, np.float32)


def expected_mask(frames, params) -> np.ndarray:
    """The reference's still pixels, and where float32 rounding may decide them."""
    log_image = np.log(np.maximum(frames.astype(np.float64), params.log_floor) + DARK_OFFSET)
    means = ref.still_window_means(log_image, still_flow.STILL_SURFACE_RADIUS)
    want = ref.still_surface(log_image, params.flow_still_surface_tau, still_flow.STILL_SURFACE_RADIUS,
                             params.flow_still_surface_share) > 0.5
    return want, (np.abs(means - params.flow_still_surface_tau) <= 1e-4).any(0)


def test_camera_holds_still_reads_the_median_flow():
    flow = np.zeros((2, 6, 8, 2), np.float32)
    assert still_flow.camera_holds_still(flow)
    flow[:, :2] = (3.0, 4.0)                   # a third moves: the median is still 0
    assert still_flow.camera_holds_still(flow)
    flow[:, 2:, :5] = 5.0                      # most pixels move
    assert not still_flow.camera_holds_still(flow)
    assert not still_flow.camera_holds_still(np.zeros((0, 6, 8, 2), np.float32))


def test_a_light_pulling_the_flow_every_way_is_a_still_camera_a_pan_is_not():
    """Between the two bounds the vector median over the still pixels decides: flow of random
    directions (a moving light's pull) cancels out, a pan's sub-pixel drift does not."""
    rng = np.random.default_rng(1)
    angle = rng.uniform(0, 2 * np.pi, (5, 40, 50))
    pulled = (0.3 * np.stack([np.cos(angle), np.sin(angle)], -1)).astype(np.float32)
    still = np.ones((40, 50), bool)
    assert still_flow.STILL_CAMERA_FLOW < still_flow.median_flow_length(pulled) < still_flow.MOVING_CAMERA_FLOW
    assert still_flow.still_surface_drift(pulled, still) < still_flow.STILL_SURFACE_DRIFT
    assert still_flow.camera_holds_still(pulled, still)
    assert not still_flow.camera_holds_still(pulled)                # no mask: the median alone decides
    assert not still_flow.camera_holds_still(pulled, np.zeros_like(still))     # no still pixel
    panned = pulled.copy()
    panned[..., 0] += 0.15                                            # a pan of 0.15 px a frame
    assert still_flow.camera_holds_still(panned, still) is False
    np.testing.assert_allclose(still_flow.still_surface_drift(panned, still), 0.15, atol=0.03)
    # the drift reads the still pixels only: a moving object elsewhere does not count
    object_ = np.zeros((40, 50), bool)
    object_[:, :20] = True
    moved = pulled.copy()
    moved[:, object_] = (2.0, 0.0)
    assert still_flow.still_surface_drift(moved, ~object_) < still_flow.STILL_SURFACE_DRIFT
    assert still_flow.still_surface_drift(moved, still) > still_flow.STILL_SURFACE_DRIFT
    # a light that pulls the still pixels one way in one pair and another way in the next:
    # a common drift no larger than twice the pairs' scatter is not the camera's
    erratic = pulled.copy()
    erratic[0] += (0.3, 0.0)
    erratic[1] += (0.0, 0.3)
    erratic[2] += (-0.1, 0.1)
    np.testing.assert_allclose(still_flow.pair_drifts(erratic, still)[:3, :2], [[0.3, 0], [0, 0.3], [-0.1, 0.1]],
                               atol=0.05)
    assert still_flow.still_surface_drift(erratic, still) == 0.0
    assert still_flow.camera_holds_still(erratic, still)
    # the same drift in a window of one pair has no scatter to be told from: the camera's
    assert still_flow.still_surface_drift(erratic[:1], still) > 0.25
    assert not still_flow.camera_holds_still(erratic[:1], still)
    # nor do three pairs, too few to tell a common drift from their scatter
    assert still_flow.still_surface_drift(erratic[:3], still) == 0.0
    assert not still_flow.camera_holds_still(erratic[:3], still)
    # a slow zoom or roll about the centre: the vector median is 0, but the radial or the
    # rotational rate is the same pair after pair
    y, x = np.mgrid[:40, :50]
    x, y = x - 24.5, y - 19.5
    for zoom, roll in ((0.01, 0.0), (0.0, 0.01)):
        turned = pulled + np.stack([zoom * x - roll * y, zoom * y + roll * x], -1).astype(np.float32)
        assert still_flow.median_flow_length(turned) < still_flow.MOVING_CAMERA_FLOW
        drifts = still_flow.pair_drifts(turned, still)
        assert np.abs(drifts[:, :2]).max() < 0.05
        half_diagonal = np.hypot(40, 50) / 2
        np.testing.assert_allclose(drifts[:, 2 if zoom else 3], (zoom or roll) * half_diagonal, rtol=0.2)
        assert not still_flow.camera_holds_still(turned, still)
    # past the moving camera's bound nothing is still, whatever the drift
    assert not still_flow.camera_holds_still(pulled * 2.0, still)


def test_hold_still_surfaces_zeroes_every_pair_at_the_mask_only():
    rng = np.random.default_rng(0)
    flow = rng.normal(size=(3, 5, 7, 2)).astype(np.float32)
    still = rng.uniform(size=(5, 7)) < 0.4
    held = still_flow.hold_still_surfaces(flow, still)
    assert held is not flow and held.dtype == flow.dtype
    np.testing.assert_array_equal(held[:, still], 0.0)
    np.testing.assert_array_equal(held[:, ~still], flow[:, ~still])
    # with ``small`` the short vectors go too, pair by pair
    short = np.hypot(flow[..., 0], flow[..., 1]) < 0.8
    held = still_flow.hold_still_surfaces(flow, still, small=0.8)
    gone = still[None] | short
    np.testing.assert_array_equal(held[gone], 0.0)
    np.testing.assert_array_equal(held[~gone], flow[~gone])
    assert 0 < short[:, ~still].mean() < 1
    assert still_flow.hold_still_surfaces(flow, None) is flow
    assert still_flow.hold_still_surfaces(None, still) is None


def test_still_surface_mask_against_the_reference(any_backend):
    frames = shadow_scene()
    params = iv.Params()
    be = any_backend
    got = still_flow.still_surface_mask(be, be.asarray(frames), params)
    want, undecided = expected_mask(frames, params)
    np.testing.assert_array_equal(got[~undecided], want[~undecided])
    # the shadowed board is still, the moving print is not
    assert want[:24].mean() > 0.95
    assert not want[33:39, 20:24].any()


def test_decompose_holds_the_estimated_flow_at_still_surfaces():
    frames = shadow_scene()
    params = iv.Params(flow_still_small=0.0, **FAST)
    video = iv.decompose(frames, params=params, threads=2)
    want, undecided = expected_mask(frames, params)
    held = want & ~undecided
    assert held.mean() > 0.5
    np.testing.assert_array_equal(video.flow[:, held], 0.0)
    # the square, which moves, keeps a flow
    assert np.abs(video.flow[:, 33:39, 16:20, 0]).mean() > 0.5


def test_decompose_holds_short_vectors_under_a_still_camera():
    """With ``flow_still_small`` every vector of the returned flow is 0 or at least that long;
    the still pixels are 0 and the moving square keeps long vectors."""
    frames = shadow_scene()
    params = iv.Params(**FAST)
    assert params.flow_still_small > 0
    video = iv.decompose(frames, params=params, threads=2)
    length = np.hypot(video.flow[..., 0], video.flow[..., 1])
    assert np.all((length == 0) | (length >= params.flow_still_small))
    want, undecided = expected_mask(frames, params)
    np.testing.assert_array_equal(length[:, want & ~undecided], 0.0)
    off = iv.decompose(frames, params=params.replace(flow_still_small=0.0), threads=2)
    length_off = np.hypot(off.flow[..., 0], off.flow[..., 1])
    assert ((length_off > 0) & (length_off < params.flow_still_small)).mean() > 0.05
    # where the square's flow was long without the hold, it mostly stays long
    long_off = length_off[:, 30:42, 10:26] >= 1.0
    assert long_off.sum() > 20
    assert (length[:, 30:42, 10:26][long_off] >= params.flow_still_small).mean() > 0.6


def test_the_backward_flow_is_held_too(monkeypatch):
    """The forward-backward check then keeps w_occ at the held pixels: both flows are zero there."""
    frames = shadow_scene()
    seen = {}
    real = decompose_module.motion_maps

    def spy(be, frames_be, flow_be, params, back_flow=None, **kw):
        seen["flow"], seen["back"] = np.array(be.numpy(flow_be)), np.array(be.numpy(back_flow))
        return real(be, frames_be, flow_be, params, back_flow=back_flow, **kw)

    monkeypatch.setattr(decompose_module, "motion_maps", spy)
    params = iv.Params(**FAST)
    iv.decompose(frames, params=params, threads=2)
    want, undecided = expected_mask(frames, params)
    held = want & ~undecided
    np.testing.assert_array_equal(seen["flow"][:, held], 0.0)
    np.testing.assert_array_equal(seen["back"][:, held], 0.0)


def test_a_given_flow_and_a_moving_camera_are_left_alone():
    frames = shadow_scene()
    given = np.random.default_rng(1).normal(0.0, 0.05, (T - 1, H, W, 2)).astype(np.float32)
    video = iv.decompose(frames, flow=given, params=iv.Params(**FAST), threads=2)
    np.testing.assert_array_equal(video.flow, given)
    panning = shadow_scene(camera_step=2.0)
    on = iv.decompose(panning, params=iv.Params(**FAST), threads=2)
    off = iv.decompose(panning, params=iv.Params(flow_still_surface_tau=0.0, **FAST), threads=2)
    assert np.median(np.hypot(*np.moveaxis(on.flow, -1, 0))) > still_flow.STILL_CAMERA_FLOW
    np.testing.assert_array_equal(on.flow, off.flow)
    np.testing.assert_array_equal(on.albedo, off.albedo)


def test_a_sub_pixel_pan_is_not_held(monkeypatch):
    """A camera panning a quarter pixel a frame: the median flow lies between the two bounds and
    some pixels look still, but they drift with the pan, so nothing is held."""
    frames = shadow_scene()
    step = 0.25
    panned = []
    for k, frame in enumerate(frames):
        whole, part = divmod(step * k, 1.0)
        panned.append((1 - part) * np.roll(frame, int(whole), axis=1) + part * np.roll(frame, int(whole) + 1, axis=1))
    panned = np.asarray(panned, np.float32)
    seen = {}
    real = decompose_module.camera_holds_still

    def spy(flow, still=None):
        seen["length"] = still_flow.median_flow_length(flow)
        seen["drift"] = still_flow.still_surface_drift(flow, still)
        return real(flow, still)

    monkeypatch.setattr(decompose_module, "camera_holds_still", spy)
    on = iv.decompose(panned, params=iv.Params(**FAST), threads=2)
    assert still_flow.STILL_CAMERA_FLOW < seen["length"] < still_flow.MOVING_CAMERA_FLOW
    assert still_flow.STILL_SURFACE_DRIFT * 3 < seen["drift"] < 1.0
    off = iv.decompose(panned, params=iv.Params(flow_still_surface_tau=0.0, **FAST), threads=2)
    np.testing.assert_array_equal(on.flow, off.flow)
    np.testing.assert_array_equal(on.albedo, off.albedo)
