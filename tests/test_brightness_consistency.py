"""The brightness test of a window whose light holds still (``Params.luminance_change_max``).

A dark grey square slides over a light grey wall under a still light: the
wall pixels it covers in the next frame keep their flow (zero) but not their
brightness.  The chromaticity test cannot see them (both surfaces are grey);
the brightness test clears them, near the flow jump only, and only in a
window of one independent shading.
"""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.params import Params
from ivkernels.solver.motion_maps import brightness_consistency, motion_maps, window_occlusion

STEP = 3        # pixels the square moves per frame


def sliding_square(T=3, H=30, W=40, exposure=0.1):
    """Frames (T, H, W, 3) and the true forward flow (T-1, H, W, 2); the exposure rises
    by ``exposure`` log units per frame (a global change the test must ignore)."""
    frames = np.full((T, H, W, 3), 0.6, np.float32)
    flow = np.zeros((T - 1, H, W, 2), np.float32)
    for t in range(T):
        x0 = 8 + STEP * t
        frames[t, 10:20, x0:x0 + 10] = 0.06
        frames[t] *= np.float32(np.exp(exposure * t))
        if t < T - 1:
            flow[t, 10:20, x0:x0 + 10, 0] = STEP
    return np.clip(frames, 0.0, 1.0), flow


@pytest.fixture(params=["warp", "numpy"])
def be(request):
    return get_backend(request.param)


def test_covered_wall_is_cleared_near_the_jump_only(be):
    frames, flow = sliding_square()
    params = Params(luminance_change_max=0.2)
    frames_be, flow_be = be.asarray(frames), be.asarray(flow)
    occ, _ = motion_maps(be, frames_be, flow_be, params)
    before = be.numpy(occ).copy()
    after = be.numpy(brightness_consistency(be, frames_be, flow_be, occ, params)).copy()
    np.testing.assert_array_equal(be.numpy(occ), before)             # the input map is not changed
    for t in range(flow.shape[0]):
        x0 = 8 + STEP * t
        covered = (slice(10, 20), slice(x0 + 10, x0 + 10 + STEP))     # wall hidden by the square at t + 1
        assert before[t][covered].mean() > 0.5                       # divergence and colour miss most of them
        assert not after[t][covered].any()
    assert np.all(after <= before)                                   # it only clears
    far = np.zeros(before.shape[1:], bool)
    far[:, :2] = far[:2, :] = True                                   # wall far from any flow jump
    np.testing.assert_array_equal(after[:, far], before[:, far])


def test_backends_agree():
    frames, flow = sliding_square(H=23, W=37)
    params = Params(luminance_change_max=0.2, luminance_change_radius=2)
    maps = []
    for name in ("warp", "taichi", "numpy"):
        b = get_backend(name)
        occ, _ = motion_maps(b, b.asarray(frames), b.asarray(flow), params)
        maps.append(b.numpy(brightness_consistency(b, b.asarray(frames), b.asarray(flow), occ, params)).copy())
    np.testing.assert_array_equal(maps[0], maps[2])
    np.testing.assert_array_equal(maps[1], maps[2])


def test_only_where_the_light_holds_still(be):
    frames, flow = sliding_square()
    frames_be, flow_be = be.asarray(frames), be.asarray(flow)
    on, off = Params(luminance_change_max=0.2), Params(luminance_change_max=0.0)
    occ, _ = motion_maps(be, frames_be, flow_be, on)
    assert window_occlusion(be, frames_be, flow_be, occ, on, 2.5) is occ       # the light changes
    assert window_occlusion(be, frames_be, flow_be, occ, off, 1.0) is occ      # switched off
    assert window_occlusion(be, frames_be, None, None, on, 1.0) is None        # no flow
    gated = be.numpy(window_occlusion(be, frames_be, flow_be, occ, on, 1.0))
    assert gated.sum() < be.numpy(occ).sum()
