"""The gate of the local shading smoothness (Eq. 9, ``Params.shading_gate_tau``) end to end:
off reproduces the ungated energy exactly, and on a static scene under a moving light it
keeps a moving shadow edge in the shading that a strong ungated smoothness pushes into the albedo."""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels import Params
from ivkernels.evaluation import synthetic

FAST = Params(outer_iterations=2, lbfgs_iterations=15)


@pytest.fixture(scope="module")
def seq():
    return synthetic.render_sequence("static_moving_light", n_frames=3, size=(40, 56), seed=3)


def test_gate_off_is_the_ungated_term(seq):
    """tau = 0 (off) and a tau so large that the gate is exactly 1 give the same decomposition,
    bit for bit: the gated kernel with gate 1 is the plain one."""
    off = iv.decompose(seq.frames, flow=seq.flow, params=FAST.replace(shading_gate_tau=0.0))
    wide = iv.decompose(seq.frames, flow=seq.flow, params=FAST.replace(shading_gate_tau=1e30))
    np.testing.assert_array_equal(off.shading, wide.shading)
    np.testing.assert_array_equal(off.albedo, wide.albedo)


def test_gate_needs_the_flow(seq):
    """Without temporal terms (no flow) the gate is not computed: tau changes nothing."""
    a = iv.decompose(seq.frames, temporal=False, params=FAST.replace(shading_gate_tau=0.0))
    b = iv.decompose(seq.frames, temporal=False, params=FAST.replace(shading_gate_tau=0.1))
    np.testing.assert_array_equal(a.shading, b.shading)


def moving_shadow_scene(T=4, H=32, W=40):
    """Block-textured colour albedo (4x4 blocks), a smooth light and an achromatic shadow edge
    (factor 0.4) 6 rows lower each frame: ``(albedo (H, W, 3), frames (T, H, W, 3), edge rows)``."""
    rng = np.random.default_rng(1)
    albedo = np.repeat(np.repeat(rng.uniform(0.15, 0.9, (H // 4, W // 4, 3)), 4, 0), 4, 1).astype(np.float32)
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    rows = [6 + 6 * t for t in range(T)]
    shading = np.stack([(0.8 + 0.15 * np.cos(xx / W + 0.3 * t)) * np.where(yy < r, 0.4, 1.0)
                        for t, r in enumerate(rows)]).astype(np.float32)
    return albedo, albedo[None] * shading[..., None], rows


def test_moving_shadow_stays_in_the_shading_albedo_edges_in_the_albedo():
    albedo, frames, rows = moving_shadow_scene()
    T, H, W, _ = frames.shape
    truth = np.log(albedo).mean(-1)

    def errors(tau, occlusion_colour=True):
        # With Eq. 7's colour term the moving shadow's edge is marked occluded and the
        # temporal terms leave it to the local smoothness: the case the gate is for.  The
        # light-edge factor, which frees the same edge by another cue, is off: the gate alone.
        video = iv.decompose(frames, flow=np.zeros((T - 1, H, W, 2), np.float32),
                             params=Params(lam_shading_local=100.0, shading_gate_tau=tau,
                                           occlusion_colour=occlusion_colour, shading_light_edge_tau=0.0))
        A = np.log(video.albedo).mean(-1)
        across_shadow = np.mean([np.abs((A[t, r] - A[t, r - 1]) - (truth[r] - truth[r - 1])).mean()
                                 for t, r in enumerate(rows)])
        block_columns = np.arange(4, W, 4)       # the albedo's vertical edges
        across_albedo = np.abs((A[:, :, block_columns] - A[:, :, block_columns - 1])
                               - (truth[:, block_columns] - truth[:, block_columns - 1])).mean()
        return across_shadow, across_albedo

    shadow_gated, albedo_gated = errors(0.1)
    shadow_plain, _ = errors(0.0)
    # the shadow's log step is 0.92: without the gate over a tenth of it reaches the albedo,
    # and the gate keeps out at least four fifths of that
    assert shadow_plain > 0.1 and shadow_gated < 0.2 * shadow_plain
    assert albedo_gated < 0.05
    # Without the colour term (the default) the temporal albedo term holds at the
    # shadow's edge, and the ungated smoothness keeps the shadow out of the albedo too.
    shadow_default, _ = errors(0.0, occlusion_colour=False)
    assert shadow_default < 0.04
