"""Flow and intrinsic video estimated together (ivkernels.flow.joint)."""
import numpy as np
import pytest

from ivkernels import synthetic
from ivkernels.flow.joint import FLOW_SOURCES, joint_decompose, occlusion_iou


def test_occlusion_iou_hand_computed():
    occ = np.ones((1, 2, 3), np.float32)
    vis = np.ones((1, 2, 3), np.float32)
    assert occlusion_iou(occ, vis) == 1.0                 # nothing occluded, nothing found
    occ[0, 0, :2] = 0.0                                   # found: (0,0), (0,1)
    vis[0, 0, 1:] = 0.0                                   # truth: (0,1), (0,2)
    assert occlusion_iou(occ, vis) == pytest.approx(1 / 3)
    with pytest.raises(ValueError, match="shape"):
        occlusion_iou(occ, vis[:, :1])


def test_bad_arguments_raise():
    frames = np.zeros((2, 16, 16, 3), np.float32)
    with pytest.raises(ValueError, match="passes"):
        joint_decompose(frames, passes=0)
    with pytest.raises(ValueError, match="source"):
        joint_decompose(frames, source="shading")
    with pytest.raises(ValueError, match="flow method"):
        joint_decompose(frames, method="raft")
    assert FLOW_SOURCES == ("albedo", "relit", "input")


@pytest.mark.slow
@pytest.mark.parametrize("source", ["albedo", "relit"])
def test_passes_recorded(source):
    seq = synthetic.render_sequence("static_moving_light", n_frames=3, size=(32, 48), seed=1)
    result = joint_decompose(seq.frames, passes=2, source=source, truth=seq)
    video = result.video
    assert [p.index for p in result.history] == [1, 2]
    assert np.isnan(result.history[0].flow_change) and result.history[1].flow_change >= 0
    assert video.flow.shape == seq.flow.shape and video.occlusion.shape == seq.visibility.shape
    for p in result.history:
        assert p.epe >= 0 and 0 <= p.occlusion_iou <= 1 and p.lmse["mean"] >= 0
    assert "2 joint passes" in video.diagnostics["flow_method"]
    assert len(video.diagnostics["joint_passes"]) == 2


@pytest.mark.slow
def test_input_source_stops_when_flow_settles():
    seq = synthetic.render_sequence("static_moving_light", n_frames=2, size=(32, 48), seed=1)
    result = joint_decompose(seq.frames, passes=4, source="input", warm_start=False, tol=1e-6)
    assert len(result.history) == 2 and result.history[1].flow_change == 0.0
