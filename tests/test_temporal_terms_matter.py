"""The temporal terms (Eq. 4-8) change the answer where time carries information.

A static scene under a moving lamp: the cast shadows sweep over the floor and
the objects while the albedo stays put.  With the temporal terms (flow = 0,
exact for a static camera) the recovered albedo is the same in every frame
where the shadows pass and closer to the truth; the "IV w/o flow" ablation,
which sees each frame alone, lets part of every shadow into that frame's
albedo, so its albedo flickers where the shadows move.
"""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.evaluation import metrics, synthetic


def _flicker(log_albedo: np.ndarray, mask: np.ndarray) -> float:
    """Mean |A_{t+1} - A_t| (log, over channels) inside ``mask`` (static scene: no flow)."""
    return float(np.abs(np.diff(log_albedo, axis=0)).mean(-1)[:, mask].mean())


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 5])
def test_moving_shadows_leave_the_albedo_only_with_temporal_terms(seed):
    seq = synthetic.render_sequence("static_moving_light", n_frames=5, size=(48, 64), seed=seed)
    log_shading = np.log(seq.shading)
    swept = (log_shading.max(0) - log_shading.min(0)) > 0.7       # a shadow passes here
    assert 0.05 < swept.mean() < 0.6
    iv_video = iv.decompose(seq.frames, flow=seq.flow)
    ablation = iv.decompose(seq.frames, temporal=False)
    lmse_iv = metrics.lmse(iv_video.albedo, seq.albedo)
    lmse_ablation = metrics.lmse(ablation.albedo, seq.albedo)
    assert lmse_iv < 0.85 * lmse_ablation
    flicker_iv = _flicker(np.log(iv_video.albedo), swept)
    flicker_ablation = _flicker(np.log(ablation.albedo), swept)
    assert flicker_iv < 0.25 * flicker_ablation
