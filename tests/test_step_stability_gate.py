"""Weiss's cue read only where the light changes (``Params.shading_step_stability_changing_light``).

With the switch on (the default), a window whose count of independent shadings is 1 (no
shading change along the flow above the floor) is solved exactly as with
``shading_step_stability = 0``; a window whose light changes is solved exactly
as with the switch off.
"""
import numpy as np

import ivkernels as iv
from ivkernels.backends import get_backend
from ivkernels.solver.independent_shadings import independent_shadings, window_params

#: Small and fast: one window of four frames at 36x44, two pyramid levels.
FAST = dict(pyramid_min_size=18, lbfgs_iterations=10, lbfgs_iterations_coarse=20)


def still_scene(T=4, H=36, W=44, light_change=0.0, seed=0):
    """A grey checkerboard with dark squares under a smooth light, camera and scene still,
    with 3% sensor noise (which moves the steps' contrast a little from frame to frame);
    the light's direction swings by ``light_change`` (log units across the frame) each frame."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:H, 0:W] / np.array([H, W])[:, None, None]
    levels = rng.uniform(0.05, 0.8, (H // 6 + 1, W // 6 + 1))
    albedo = np.repeat(np.repeat(levels, 6, 0), 6, 1)[:H, :W]
    frames = np.empty((T, H, W, 3), np.float32)
    for t in range(T):
        angle = 2.0 * t
        log_shading = -0.3 + 0.2 * yy + light_change * (np.cos(angle) * xx + np.sin(angle) * yy)
        noise = 1.0 + 0.03 * rng.standard_normal((H, W))
        frames[t] = np.clip(albedo * np.exp(log_shading) * noise, 0.0, 1.0)[..., None]
    return frames, np.zeros((T - 1, H, W, 2), np.float32)


def count(frames, flow):
    be = get_backend("warp")
    return independent_shadings(be, be.asarray(frames), be.asarray(flow), iv.Params().independent_shading_gain,
                                iv.Params().log_floor)


def solve(frames, flow, **fields):
    return iv.decompose(frames, flow=flow, params=iv.Params(**FAST, **fields))


def test_a_still_light_is_solved_without_weiss_cue():
    frames, flow = still_scene()
    assert count(frames, flow) == 1.0
    gated = solve(frames, flow, shading_step_stability_changing_light=True)
    no_cue = solve(frames, flow, shading_step_stability=0.0)
    cue = solve(frames, flow, shading_step_stability_changing_light=False)
    np.testing.assert_array_equal(gated.albedo, no_cue.albedo)
    np.testing.assert_array_equal(gated.shading, no_cue.shading)
    assert gated.diagnostics["independent_shadings"] == [1.0]
    assert np.max(np.abs(cue.albedo - no_cue.albedo)) > 0        # the cue acts on this scene


def test_a_changing_light_keeps_weiss_cue():
    frames, flow = still_scene(light_change=0.5)
    assert count(frames, flow) > 1.0
    gated = solve(frames, flow, shading_step_stability_changing_light=True)
    plain = solve(frames, flow, shading_step_stability_changing_light=False)
    np.testing.assert_array_equal(gated.albedo, plain.albedo)
    np.testing.assert_array_equal(gated.shading, plain.shading)


def test_window_params_divide_the_priors_and_drop_the_cue_only_at_one_shading():
    p = iv.Params()
    one = window_params(p, 1.0)
    assert one.shading_step_stability == 0.0 and one.lam_albedo_smooth == p.lam_albedo_smooth
    two = window_params(p, 2.0)
    assert two.shading_step_stability == p.shading_step_stability
    assert two.lam_albedo_smooth == p.lam_albedo_smooth / 2 and two.lam_albedo_sparsity == p.lam_albedo_sparsity / 2
    off = iv.Params(shading_step_stability_changing_light=False, shading_stable_gain=0.0, shading_light_edge_tau=0.0,
                    shading_light_edge_spread=0.0)
    assert window_params(off, 1.0) is off
    assert window_params(off, 4.0).shading_step_stability == off.shading_step_stability
