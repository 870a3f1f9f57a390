"""The flow across windows in decompose(): the last pass's flow of the shared frames is kept by the
next window, and the next window's first-pass flow estimated on a second thread changes nothing."""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.evaluation import synthetic

decompose_module = __import__("ivkernels.decompose", fromlist=["FLOW_AHEAD"])

FAST = dict(lbfgs_iterations=2, guide_lbfgs_iterations=2, window=4, overlap=2)


@pytest.fixture(scope="module")
def seq():
    return synthetic.render_sequence("objects_camera", n_frames=6, size=(40, 48), seed=3)


def test_window_ranges_share_frames():
    # 6 frames, windows of 4 sharing 2: frames 0-3, then 2-5; pair 2 (frames 2-3) lies in both
    assert decompose_module.window_ranges(6, 4, 2) == [(0, 4, 0), (2, 6, 2)]


def test_the_next_window_keeps_the_last_pass_flow_of_the_shared_pairs(seq, monkeypatch):
    calls = []
    real = decompose_module.estimate_flow

    def spy(frames, *args, **options):
        calls.append((len(frames), options.get("init") is not None))
        return real(frames, *args, **options)

    monkeypatch.setattr(decompose_module, "estimate_flow", spy)
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", False)
    windows = list(iv.iter_decompose(seq.frames, params=iv.Params(**FAST), threads=2))
    assert [(w.start, w.stop) for w in windows] == [(0, 4), (2, 6)]
    # pair 2 (frames 2-3) is in both windows: the second keeps the first's last-pass flow, bit for bit
    np.testing.assert_array_equal(windows[1].flow[0], windows[0].flow[2])
    # warm-started calls: the first window's 3 pairs (4 frames), then only the second's 2 new pairs
    assert [n for n, warm in calls if warm] == [4, 3]
    # the second window's new pairs are still estimated (not copies of anything)
    assert not np.array_equal(windows[1].flow[1], windows[0].flow[2])


def test_flow_ahead_on_a_second_thread_gives_the_same_video(seq, monkeypatch):
    params = iv.Params(**FAST)
    frames = synthetic.render_sequence("objects_camera", n_frames=8, size=(40, 48), seed=3).frames
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", False)
    serial = iv.decompose(frames, params=params, threads=2)
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", True)
    ahead = iv.decompose(frames, params=params, threads=2)
    assert len(ahead.diagnostics["windows"]) == 3
    assert "flow ahead" in ahead.diagnostics["seconds"] and "flow ahead" not in serial.diagnostics["seconds"]
    # the forward-backward check's backward flow: on the second thread, or on the caller's
    assert "back flow, overlapped" in ahead.diagnostics["seconds"] and "back flow" in serial.diagnostics["seconds"]
    for name in ("albedo", "shading", "flow", "occlusion", "boundary"):
        np.testing.assert_array_equal(getattr(ahead, name), getattr(serial, name), err_msg=name)


@pytest.mark.parametrize("ahead", [False, True])
def test_the_backward_flow_is_estimated_once_per_pair_from_the_reversed_frames(seq, monkeypatch, ahead):
    """The check's backward flow runs at ``flow_round_trip_scale`` of the frames' size (40x48 ->
    16x19, the floor of 16 px), on the frames in reverse order; pairs a later window shares
    are not estimated again."""
    shape = decompose_module.scaled_shape(40, 48, iv.Params().flow_round_trip_scale)
    assert shape == (16, 19)
    backward = []
    real = decompose_module.estimate_flow

    def spy(frames, *args, **options):
        flow = real(frames, *args, **options)
        if tuple(frames.shape[1:3]) == shape:
            backward.append((np.array(frames), flow))
        return flow

    monkeypatch.setattr(decompose_module, "estimate_flow", spy)
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", ahead)
    iv.decompose(seq.frames, params=iv.Params(**FAST), threads=2)
    assert sum(len(frames) - 1 for frames, _ in backward) == len(seq.frames) - 1    # 5 pairs, once each
    small = decompose_module.downsample
    be = iv.backends.get_backend("warp")
    first = np.array(be.numpy(small(be, be.asarray(seq.frames[:4]), shape)))
    np.testing.assert_array_equal(backward[0][0], first[::-1])       # frames 3, 2, 1, 0


def test_an_error_on_the_flow_thread_reaches_the_caller(seq, monkeypatch):
    real = decompose_module._Decomposer._first_pass_flow
    seen = []

    def failing(self, frames):
        seen.append(len(frames))
        if len(seen) > 1:
            raise RuntimeError("flow failed on the second window")
        return real(self, frames)

    monkeypatch.setattr(decompose_module._Decomposer, "_first_pass_flow", failing)
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", True)
    with pytest.raises(RuntimeError, match="second window"):
        iv.decompose(seq.frames, params=iv.Params(**FAST), threads=2)


def test_no_flow_ahead_thread_outside_warp_on_the_cpu(monkeypatch):
    frames = synthetic.render_sequence("static_moving_light", n_frames=6, size=(40, 48), seed=3).frames
    monkeypatch.setattr(decompose_module, "FLOW_AHEAD", True)
    video = iv.decompose(frames, backend="numpy", params=iv.Params(**FAST), threads=2)
    assert len(video.diagnostics["windows"]) == 2
    assert "flow ahead" not in video.diagnostics["seconds"]
