"""Built-in optical flow (ivkernels.flow): Classic+NL on the kernels, and OpenCV's DIS / Farneback."""
import importlib.util

import numpy as np
import pytest

from ivkernels.flow import FLOW_METHODS, estimate_flow
from ivkernels.flow.classic_nl import (PRESETS, ClassicNLSettings, auto_levels, gnc_schedule,
                                       pyramid_sizes, settings_for)
from ivkernels.kernels.launch import threads

H, W = 48, 64
MARGIN = 6


def texture(rng, h=H, w=W, waves=24):
    """A smooth random colour texture as a function of continuous (x, y)."""
    freq = rng.uniform(0.08, 0.6, waves)
    angle = rng.uniform(0, np.pi, waves)
    phase = rng.uniform(0, 2 * np.pi, waves)
    amp = rng.uniform(0.5, 1.0, (waves, 3))

    def f(x, y):
        arg = freq * (np.cos(angle) * x[..., None] + np.sin(angle) * y[..., None]) + phase
        val = np.sin(arg) @ amp / np.sqrt(waves)
        return np.clip(0.5 + 0.25 * val, 0.02, 0.98).astype(np.float32)

    return f


def pair(rng, motion):
    """Frames ``f(x)`` and ``f(x - u(x))`` for a smooth motion ``u`` (a callable of the grid)."""
    f = texture(rng)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    u = motion(x, y)
    frames = np.stack([f(x, y), f(x - u[..., 0], y - u[..., 1])])
    return frames, u


def interior_epe(flow, u):
    d = flow[MARGIN:-MARGIN, MARGIN:-MARGIN] - u[MARGIN:-MARGIN, MARGIN:-MARGIN]
    return float(np.sqrt((d ** 2).sum(-1)).mean())


def test_settings_and_schedule():
    assert gnc_schedule(3) == [1.0, 0.5, 0.0]
    assert gnc_schedule(2) == [1.0, 0.0]
    assert gnc_schedule(1) == [1.0]
    assert auto_levels(480, 640, 2.0) == 6
    assert auto_levels(388, 584, 2.0) == 6
    assert pyramid_sizes(480, 640, 2.0, 3) == [(480, 640), (240, 320), (120, 160)]
    assert pyramid_sizes(388, 584, 1.25, 2) == [(388, 584), (311, 468)]
    assert PRESETS["classic_nl_fast"].gnc_stages == 2 and PRESETS["classic_nl_fast"].warps == 3
    assert PRESETS["classic_nl"].gnc_stages == 3 and PRESETS["classic_nl"].warps == 10
    assert PRESETS["classic_nl"].quadratic_wm_finest and not PRESETS["classic_nl_fast"].quadratic_wm_finest
    assert settings_for("classic_nl_fast", sor_sweeps=7).sor_sweeps == 7
    with pytest.raises(TypeError, match="unknown option"):
        settings_for("classic_nl", no_such_thing=1)
    with pytest.raises(ValueError, match="sor_omega"):
        ClassicNLSettings(sor_omega=2.5)


def test_translation_recovered(rng):
    frames, u = pair(rng, lambda x, y: np.broadcast_to([1.6, -0.7], x.shape + (2,)))
    flow = estimate_flow(frames)
    assert flow.shape == (1, H, W, 2) and flow.dtype == np.float32
    assert interior_epe(flow[0], u) < 0.1


def test_smooth_field_recovered(rng):
    def motion(x, y):
        return np.stack([1.2 * np.sin(2 * np.pi * y / H) + 0.5,
                         0.8 * np.cos(2 * np.pi * x / W) - 0.3], -1)

    frames, u = pair(rng, motion)
    flow = estimate_flow(frames)
    assert interior_epe(flow[0], u) < 0.2


def test_zero_motion_gives_zero_flow(rng):
    frames, _ = pair(rng, lambda x, y: np.zeros(x.shape + (2,)))
    flow = estimate_flow(frames)
    np.testing.assert_allclose(flow, 0.0, atol=1e-5)


def test_several_frames_and_uint8(rng):
    f = texture(rng)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    frames = np.stack([f(x - 0.8 * k, y) for k in range(3)])
    flow = estimate_flow(frames, sor_sweeps=15)
    assert flow.shape == (2, H, W, 2)
    for k in range(2):
        assert interior_epe(flow[k], np.broadcast_to([0.8, 0.0], (H, W, 2))) < 0.12
    srgb = np.where(frames > 0.0031308, 1.055 * frames ** (1 / 2.4) - 0.055, 12.92 * frames)
    flow8 = estimate_flow(np.rint(srgb * 255).astype(np.uint8), sor_sweeps=15)
    assert np.abs(flow8 - flow).mean() < 0.05


def test_refining_an_initial_flow_skips_the_quadratic_stage(rng, monkeypatch):
    from ivkernels.flow.classic_nl import ClassicNL

    def motion(x, y):
        return np.stack([1.2 * np.sin(2 * np.pi * y / H) + 0.5, 0.8 * np.cos(2 * np.pi * x / W) - 0.3], -1)

    frames, u = pair(rng, motion)
    init = estimate_flow(frames)
    kept = init.copy()
    shapes, warp_step = [], ClassicNL._warp_step

    def counted(self, lv, *args, **kwargs):
        shapes.append(lv.shape)
        return warp_step(self, lv, *args, **kwargs)

    monkeypatch.setattr(ClassicNL, "_warp_step", counted)
    refined = estimate_flow(frames, init=init, gnc_start=1)
    np.testing.assert_array_equal(init, kept)                       # the caller's flow is not written
    later = pyramid_sizes(H, W, PRESETS["classic_nl_fast"].gnc_spacing, PRESETS["classic_nl_fast"].gnc_levels)
    assert shapes == [later[1]] * 3 + [later[0]] * 3                # only the robust stage, its two levels
    assert interior_epe(refined[0], u) < 0.2
    shapes.clear()
    assert np.array_equal(estimate_flow(frames, gnc_start=1), init)  # no initial flow: every stage runs
    assert len(shapes) > 6
    with pytest.raises(ValueError, match="gnc_start"):
        settings_for("classic_nl_fast", gnc_start=2)


def test_weighted_median_after_the_last_warp_only(rng, monkeypatch):
    from ivkernels.flow.classic_nl import ClassicNL

    def motion(x, y):
        return np.stack([1.2 * np.sin(2 * np.pi * y / H) + 0.5, 0.8 * np.cos(2 * np.pi * x / W) - 0.3], -1)

    frames, u = pair(rng, motion)
    # one warp per level: the only warp is the last, nothing changes
    np.testing.assert_array_equal(estimate_flow(frames, warps=1, wm_last_warp=True), estimate_flow(frames, warps=1))
    steps, warp_step = [], ClassicNL._warp_step

    def counted(self, lv, flow, quad_frac, weighted_median, *args, **kwargs):
        steps.append((lv.shape, quad_frac, weighted_median))
        return warp_step(self, lv, flow, quad_frac, weighted_median, *args, **kwargs)

    monkeypatch.setattr(ClassicNL, "_warp_step", counted)
    every = estimate_flow(frames)
    every_steps = list(steps)
    steps.clear()
    last = estimate_flow(frames, wm_last_warp=True)
    warps = PRESETS["classic_nl_fast"].warps
    assert [s[:2] for s in steps] == [s[:2] for s in every_steps]           # the same warping steps
    for k in range(0, len(steps), warps):                                    # per level: only the last
        level_every, level_last = every_steps[k:k + warps], steps[k:k + warps]
        assert [w for *_, w in level_last] == [False] * (warps - 1) + [level_every[-1][2]]
    assert sum(w for *_, w in steps) < sum(w for *_, w in every_steps)
    assert interior_epe(last[0], u) < 0.2 and interior_epe(every[0], u) < 0.2


def test_one_thread_equals_two_threads(rng):
    frames, _ = pair(rng, lambda x, y: np.broadcast_to([0.9, 0.4], x.shape + (2,)))
    with threads(1):
        one = estimate_flow(frames, sor_sweeps=10, rof_iters=20)
    with threads(2):
        two = estimate_flow(frames, sor_sweeps=10, rof_iters=20)
    np.testing.assert_array_equal(one, two)


_TAICHI_FAMILIES = ("colour", "sampling", "derivatives", "maps", "pyramid", "median", "flow_classic")


@pytest.mark.slow
@pytest.mark.skipif(any(importlib.util.find_spec(f"ivkernels.kernels.taichi.{f}") is None
                        for f in _TAICHI_FAMILIES), reason="a Taichi kernel family is missing")
def test_warp_and_taichi_agree_end_to_end(rng):
    frames, u = pair(rng, lambda x, y: np.broadcast_to([1.1, 0.6], x.shape + (2,)))
    opts = dict(sor_sweeps=15, rof_iters=30)
    a = estimate_flow(frames, backend="warp", **opts)
    b = estimate_flow(frames, backend="taichi", **opts)
    assert np.abs(a - b).mean() < 0.02
    assert interior_epe(b[0], u) < 0.1


@pytest.mark.parametrize("method", ["dis", "farneback"])
def test_opencv_methods(rng, method):
    frames, u = pair(rng, lambda x, y: np.broadcast_to([1.5, 0.5], x.shape + (2,)))
    flow = estimate_flow(frames, method=method)
    assert flow.shape == (1, H, W, 2) and flow.dtype == np.float32
    assert interior_epe(flow[0], u) < 0.5


def test_bad_input_raises(rng):
    good = rng.random((2, 16, 16, 3)).astype(np.float32)
    with pytest.raises(ValueError, match="at least 2 frames"):
        estimate_flow(good[:1])
    with pytest.raises(ValueError, match=r"\(T, H, W, 3\)"):
        estimate_flow(good[..., :2])
    with pytest.raises(ValueError, match=r"\(T, H, W, 3\)"):
        estimate_flow(good[0])
    with pytest.raises(ValueError, match="at least 4x4"):
        estimate_flow(good[:, :3])
    bad = good.copy()
    bad[0, 3, 3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        estimate_flow(bad)
    with pytest.raises(TypeError, match="dtype"):
        estimate_flow((good * 1000).astype(np.int16))
    with pytest.raises(TypeError, match="numpy array"):
        estimate_flow("frames.mp4")
    with pytest.raises(ValueError, match="unknown flow method"):
        estimate_flow(good, method="raft")
    with pytest.raises(TypeError, match="unknown option"):
        estimate_flow(good, warp_count=3)
    with pytest.raises(ValueError, match="init"):
        estimate_flow(good, init=np.zeros((1, 8, 8, 2), np.float32))
    with pytest.raises(ValueError, match="preset"):
        estimate_flow(good, method="dis", preset="slow")
    with pytest.raises(ValueError, match="at least 16x16"):
        estimate_flow(np.zeros((2, 15, 40, 3), np.float32), method="dis")
    with pytest.raises(ValueError, match="backend"):
        estimate_flow(good, backend="torch")
    assert FLOW_METHODS == ("classic_nl_fast", "classic_nl", "dis", "farneback")


@pytest.mark.parametrize("options", [dict(data_term="brightness"),
                                     dict(data_term="gradient", brightness_weight=0.0),
                                     dict(data_term="gradient", brightness_weight=1.0, gradient_weight=0.5),
                                     dict(data_term="census", census_eps=8.0),
                                     dict(data_term="gradient", log_input=True, brightness_weight=0.0),
                                     dict(data_term="gradient", data_outside=True)])
def test_data_terms_recover_translation_and_zero(rng, options):
    frames, u = pair(rng, lambda x, y: np.broadcast_to([1.3, -0.6], x.shape + (2,)))
    flow = estimate_flow(frames, sor_sweeps=30, **options)
    assert interior_epe(flow[0], u) < 0.15
    still = np.stack([frames[0], frames[0]])
    np.testing.assert_allclose(estimate_flow(still, sor_sweeps=30, **options), 0.0, atol=1e-5)


def test_gradient_term_holds_under_changing_light(rng):
    """A static scene whose light brightens unevenly between the frames: the
    default (gradient) data term reports less than half the false motion of
    brightness constancy."""
    f = texture(rng)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    img = f(x, y)
    gain = (0.75 + 0.5 * x / W + 0.2 * np.sin(y / 9.0)).astype(np.float32)[..., None]
    frames = np.stack([img, np.clip(img * gain, 0, 1)])
    zero = np.zeros((H, W, 2))
    robust = interior_epe(estimate_flow(frames)[0], zero)
    brightness = interior_epe(estimate_flow(frames, data_term="brightness", lam=3.0, lam_coarse_factor=1.0)[0], zero)
    assert robust < 0.25 and robust < 0.5 * brightness


def test_data_term_settings_checked():
    assert PRESETS["classic_nl_fast"].data_term in ("brightness", "gradient", "census")
    with pytest.raises(ValueError, match="data_term"):
        ClassicNLSettings(data_term="ncc")
    with pytest.raises(ValueError, match="census_radius"):
        ClassicNLSettings(census_radius=0)
    with pytest.raises(ValueError, match="brightness_weight"):
        ClassicNLSettings(brightness_weight=-1.0)
    with pytest.raises(ValueError, match="lam_coarse_factor"):
        ClassicNLSettings(lam_coarse_factor=0.5)
