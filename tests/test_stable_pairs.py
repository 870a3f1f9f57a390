"""Weiss's cue on the pairs across a stable step (``Params.shading_stable_gain``).

The pair weights come from the ``step_evidence.stable_pairs`` kernel (checked
against its NumPy reference in the kernel battery); here: what they say on a
scene built so the answer is known, that a window under one light is solved
exactly as without them, and that under a changing light they move a grey
albedo step out of the shading.
"""
import numpy as np
import ivkernels as iv
from ivkernels.backends import get_backend
from ivkernels.solver.independent_shadings import window_params
from ivkernels.solver.step_evidence import stable_pair_weights

#: Small and fast: one window of six frames at 36x44, two pyramid levels.
FAST = dict(pyramid_min_size=18, lbfgs_iterations=20, lbfgs_iterations_coarse=40)


def checkerboard_scene(T=6, H=36, W=44, light_change=0.6, noise=0.0, seed=0, shadow_depth=0.7):
    """A grey checkerboard of 6-pixel squares (albedo 0.25 / 0.55, a step under
    ``MAX_STABLE_STEP``) under a smooth light whose
    direction swings by ``light_change`` log units across the frame each frame, plus a
    shadow over the right half (``shadow_depth`` log units deep) whose edge (a column) moves
    with the light, camera and scene still.  Returns ``(frames, flow, albedo, shadow_columns)``."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:H, 0:W]
    albedo = np.where(((yy // 6) + (xx // 6)) % 2 == 0, 0.55, 0.25)
    frames = np.empty((T, H, W, 3), np.float32)
    shadow_columns = []
    for t in range(T):
        angle = 2.0 * t
        log_shading = -0.3 + light_change * (np.cos(angle) * xx / W + np.sin(angle) * yy / H)
        column = W // 2 + 3 * t + 1                 # over the right half, never on a square's edge
        log_shading = log_shading - shadow_depth * (xx >= column)
        shadow_columns.append(column)
        frames[t] = np.clip(albedo * np.exp(log_shading) * (1 + noise * rng.standard_normal((H, W))),
                            0.0, 1.0)[..., None]
    return frames, np.zeros((T - 1, H, W, 2), np.float32), albedo, shadow_columns


def test_the_weights_find_the_albedo_steps_and_not_the_moving_shadow(any_backend):
    frames, flow, albedo, shadows = checkerboard_scene()
    be = any_backend
    p = iv.Params()
    pairs = be.numpy(stable_pair_weights(be, be.asarray(np.log(np.maximum(frames, 1e-4))), be.asarray(flow),
                                         p.shading_step_tau, p.shading_stable_spread, p.shading_stable_floor,
                                         p.shading_step_static_flow))
    assert pairs.shape == (36, 44, 2)
    across_x = albedo[:, 1:] != albedo[:, :-1]          # right pairs across a square's edge
    across_y = albedo[1:] != albedo[:-1]                # lower pairs across one
    # every pair across a square's edge that no shadow reaches in any frame is stable (the
    # shadow, moving over the right half, darkens a pair in some frames, and the dark offset
    # of the steps' log, DARK_OFFSET, then changes its contrast there)
    lit = np.arange(44) + 1 < min(shadows)
    for stable in (pairs[:, :-1, 0][across_x & lit[None, :-1]], pairs[:-1, :, 1][across_y & lit[None, :]]):
        assert stable.size > 20 and stable.min() > 0.5 and np.median(stable) > 0.85
    for c in shadows:                                   # the shadow's edge: a step in one frame only
        assert (pairs[:, c - 1, 0] == 0).all()
    # pairs inside a square (no step) and the last column and row (no neighbour) carry no weight
    assert (pairs[:, :-1, 0][~across_x] == 0).all()
    assert (pairs[:-1, :, 1][~across_y] == 0).all()
    assert (pairs[:, -1, 0] == 0).all() and (pairs[-1, :, 1] == 0).all()


def test_moving_pixels_get_no_weight():
    frames, flow, _, _ = checkerboard_scene()
    flow[2, 10:20, 5:15, 0] = 1.5                        # one frame pair moves a patch
    be = get_backend("warp")
    pairs = be.numpy(stable_pair_weights(be, be.asarray(np.log(np.maximum(frames, 1e-4))), be.asarray(flow),
                                         0.1, 0.05, 0.3, 1.0))
    assert (pairs[10:20, 5:15] == 0).all()
    assert (pairs[9, 5:15, 1] == 0).all() and (pairs[10:20, 4, 0] == 0).all()   # pairs into the patch
    assert pairs[20:, :, 1].max() > 0.85


def test_one_light_is_solved_exactly_as_without_the_pairs():
    frames, flow, _, _ = checkerboard_scene(light_change=0.0)
    frames[:] = frames[:1]                               # not even the shadow moves: one shading
    on = iv.decompose(frames, flow=flow, params=iv.Params(**FAST, shading_stable_gain=8.0))
    off = iv.decompose(frames, flow=flow, params=iv.Params(**FAST, shading_stable_gain=0.0))
    assert on.diagnostics["independent_shadings"] == [1.0]
    np.testing.assert_array_equal(on.albedo, off.albedo)
    np.testing.assert_array_equal(on.shading, off.shading)
    assert window_params(iv.Params(shading_stable_gain=8.0), 1.0).shading_stable_gain == 0.0
    assert window_params(iv.Params(shading_stable_gain=8.0), 2.0).shading_stable_gain == 8.0


def _step_contrast(video, albedo):
    """Median over the frames and the squares' edges of the estimated log-albedo step, as a
    fraction of the true one."""
    L = np.log(np.maximum(video.albedo, 1e-6)).mean(axis=-1)           # (T, H, W)
    across = albedo[:, 1:] != albedo[:, :-1]
    sign = np.sign(np.log(albedo[:, 1:]) - np.log(albedo[:, :-1]))
    steps = (L[:, :, 1:] - L[:, :, :-1]) * sign
    return float(np.median(steps[:, across]) / np.log(0.55 / 0.25))


def test_a_changing_light_moves_the_grey_steps_into_the_albedo():
    frames, flow, albedo, _ = checkerboard_scene()
    params = dict(FAST, shading_step_gain=0.0)           # the Retinex cue off: Weiss's pairs alone
    off = iv.decompose(frames, flow=flow, params=iv.Params(**params, shading_stable_gain=0.0))
    on = iv.decompose(frames, flow=flow, params=iv.Params(**params, shading_stable_gain=8.0))
    assert on.diagnostics["independent_shadings"][0] > 1.0
    c_off, c_on = _step_contrast(off, albedo), _step_contrast(on, albedo)
    assert c_on > c_off + 0.05, (c_off, c_on)
    assert c_on <= 1.1
