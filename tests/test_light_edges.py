"""Weiss's cue for the light's own edges (``Params.shading_light_edge_tau``).

The factor comes from the ``step_evidence.moving_steps`` kernel (checked
against its NumPy reference in the kernel battery); here: what it says on a
scene built so the answer is known (a shadow whose outline sweeps a grey
checkerboard under a changing light), that it stays out of the way where the
scene moves or the light holds still, and what it does to a solve.
"""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.evaluation import metrics
from ivkernels.solver.independent_shadings import window_params
from ivkernels.solver.step_evidence import light_edge_factor
from test_stable_pairs import FAST, checkerboard_scene

TAU = 0.25


def factor_of(be, frames, flow, tau=TAU):
    return be.numpy(light_edge_factor(be, be.asarray(np.log(np.maximum(frames, 1e-4))), be.asarray(flow), tau))


def test_the_factor_marks_the_shadow_outline_in_its_frame_only(any_backend):
    frames, flow, albedo, shadows = checkerboard_scene()
    factor = factor_of(any_backend, frames, flow)
    T, H, W = factor.shape
    assert (T, H, W) == frames.shape[:3]
    for t, c in enumerate(shadows):
        # both pixels of the pair the outline crosses in frame t, in that frame only
        assert factor[t, :, c - 1].max() < 0.05 and factor[t, :, c].max() < 0.05
        # in the other frames only a little lower (the dark offset of the steps' log, DARK_OFFSET,
        # shrinks a square's edge in the frames the shadow covers it)
        others = [u for u in range(T) if abs(shadows[u] - c) > 1]
        assert factor[others][:, :, c].min() > 0.75
    # away from every outline (the left half: the checkerboard's steps hold in every frame) the
    # shading keeps Eq. 9's full weight
    assert factor[:, :, : min(shadows) - 2].min() > 0.9


def test_moving_pixels_and_short_windows_keep_the_full_weight(any_backend):
    frames, flow, _, _ = checkerboard_scene()
    moving = np.full_like(flow, 0.0)
    moving[..., 0] = 2.0                                 # every pixel moves 2 px: nothing is still
    assert (factor_of(any_backend, frames, moving) == 1.0).all()
    # a still pixel beside a moving one: its pair with it is left out, its other pairs are read
    one = flow.copy()
    one[:, :, : 10, 0] = 2.0
    factor = factor_of(any_backend, frames, one)
    assert (factor[:, :, :10] == 1.0).all() and factor[:, :, 11:].min() < 0.05


def test_the_switch_keeps_the_factor_to_windows_whose_light_changes():
    # by default the factor is read under a still light too (n = 1): a shadow swept by a moving object
    assert window_params(iv.Params(shading_light_edge_tau=TAU), 1.0).shading_light_edge_tau == TAU
    still_only = iv.Params(shading_light_edge_tau=TAU, shading_light_edge_changing_light=True)
    assert window_params(still_only, 1.0).shading_light_edge_tau == 0.0
    assert window_params(still_only, 1.5).shading_light_edge_tau == TAU
    assert window_params(iv.Params(), 2.0).shading_light_edge_tau == iv.Params().shading_light_edge_tau


def relief_and_outline(T=7, H=36, W=44, seed=3):
    """``checkerboard_scene``'s passing shadow outline, and a fine relief (a random height field)
    over its left 12 columns, lit from a direction that turns by 2 radians each frame, so its
    steps change in every frame.  Returns ``(frames, flow, shadow_columns)``."""
    frames, flow, _, shadows = checkerboard_scene(T=T, H=H, W=W)
    rng = np.random.default_rng(seed)
    height = rng.normal(0.0, 0.6, (H, 12))
    gy, gx = np.gradient(height)
    for t in range(T):
        shade = np.exp(0.8 * (np.cos(2.0 * t) * gx + np.sin(2.0 * t) * gy))
        frames[t, :, :12] = np.clip(frames[t, :, :12] * shade[..., None], 0.0, 1.0)
    return frames, flow, shadows


def test_the_spread_keeps_a_relief_smooth_and_still_frees_the_passing_outline(any_backend):
    frames, flow, shadows = relief_and_outline()
    log_image = any_backend.asarray(np.log(np.maximum(frames, 1e-4)))
    flow = any_backend.asarray(flow)
    plain = any_backend.numpy(light_edge_factor(any_backend, log_image, flow, TAU))
    spread = any_backend.numpy(light_edge_factor(any_backend, log_image, flow, TAU, spread=2.0))
    # the relief's steps change in every frame: without the spread its smoothing is cut almost
    # everywhere; with it only where a step departs from its usual spread (the factor is the
    # smallest over four pairs, so a typical departure still lowers it to about a half)
    relief_plain, relief_spread = np.median(plain[:, :, 1:11]), np.median(spread[:, :, 1:11])
    assert relief_plain < 0.05 and relief_spread > 0.35, (relief_plain, relief_spread)
    assert (spread[:, :, 1:11] > 0.5).mean() > 0.35 and (plain[:, :, 1:11] > 0.5).mean() < 0.15
    # an outline crosses each of its pairs in one frame only (the MAD stays near 0): freed as before
    for t, c in enumerate(shadows):
        assert spread[t, :, c - 1].max() < 0.05 and spread[t, :, c].max() < 0.05
    # spread 0 is the plain factor, bit for bit
    zero = any_backend.numpy(light_edge_factor(any_backend, log_image, flow, TAU, spread=0.0))
    np.testing.assert_array_equal(zero, plain)


def test_the_spread_is_read_only_where_the_light_changes():
    p = iv.Params(shading_light_edge_spread=2.0)
    assert window_params(p, 1.0).shading_light_edge_spread == 0.0
    assert window_params(p, 1.5).shading_light_edge_spread == 2.0
    everywhere = iv.Params(shading_light_edge_spread=2.0, shading_light_edge_spread_changing_light=False)
    assert window_params(everywhere, 1.0).shading_light_edge_spread == 2.0


@pytest.mark.slow
def test_a_shadow_swept_under_a_still_light_leaves_the_albedo():
    # the light holds still and only a hard shadow's outline moves (3 log units: a bulb with little
    # ambient light, beyond the reach of Tukey's temporal albedo term): the window counts one
    # shading, and the factor, read there by default, frees the shading's step where the outline passes
    frames, flow, albedo, shadows = checkerboard_scene(light_change=0.0, shadow_depth=3.0)
    truth = np.repeat(albedo[None, ..., None], len(frames), axis=0).repeat(3, axis=-1)
    err, leak = {}, {}
    for name, switch in (("changing light only", True), ("default", False)):
        out = iv.decompose(frames, flow=flow, params=iv.Params(**FAST, shading_light_edge_changing_light=switch))
        assert out.diagnostics["independent_shadings"] == [1.0]
        err[name] = metrics.lmse(out.albedo, truth)
        A = np.log(out.albedo.mean(axis=-1))
        leak[name] = max(abs(float(np.median(A[t, :, c - 1] - A[t, :, c]))) for t, c in enumerate(shadows))
    assert err["default"] < 0.8 * err["changing light only"], err
    assert leak["default"] < 0.5 * leak["changing light only"], leak


@pytest.mark.slow
def test_the_solve_keeps_the_moving_outline_out_of_the_albedo():
    # a light that swings by 1.2 log units across the frame: the outline's first frame is where
    # the solve without the factor leaves part of the shadow's step in the albedo
    frames, flow, albedo, shadows = checkerboard_scene(light_change=1.2)
    truth = np.repeat(albedo[None, ..., None], len(frames), axis=0).repeat(3, axis=-1)
    err, leak = {}, {}
    for name, tau in (("off", 0.0), ("on", TAU)):
        out = iv.decompose(frames, flow=flow, params=iv.Params(**FAST, shading_light_edge_tau=tau))
        err[name] = metrics.lmse(out.albedo, truth)
        A = np.log(out.albedo.mean(axis=-1))
        leak[name] = max(abs(float(np.median(A[t, :, c - 1] - A[t, :, c]))) for t, c in enumerate(shadows))
    assert err["on"] < 0.8 * err["off"] and leak["on"] < 0.5 * leak["off"], (err, leak)
