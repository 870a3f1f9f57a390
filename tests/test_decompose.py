"""decompose(): the public API end to end on small synthetic sequences."""
import dataclasses
import importlib

import numpy as np
import pytest

import ivkernels as iv
from ivkernels import Params
from ivkernels.evaluation import metrics, synthetic

# Small and fast: a few levels, few iterations; behaviour, not accuracy.
FAST = Params(outer_iterations=2, lbfgs_iterations=15)


@pytest.fixture(scope="module")
def seq():
    return synthetic.render_sequence("objects_camera", n_frames=3, size=(40, 56), seed=3)


def test_outputs_have_the_documented_shapes_and_reconstruct_the_input(seq):
    video = iv.decompose(seq.frames, flow=seq.flow, params=FAST)
    T, H, W, _ = seq.frames.shape
    assert video.albedo.shape == (T, H, W, 3) and video.albedo.dtype == np.float32
    assert video.shading.shape == (T, H, W) and video.shading.dtype == np.float32
    assert video.flow.shape == (T - 1, H, W, 2)
    assert video.occlusion.shape == video.boundary.shape == (T - 1, H, W)
    assert set(np.unique(video.occlusion)) <= {0.0, 1.0}
    assert np.isfinite(video.albedo).all() and (video.shading > 0).all()
    assert np.percentile(video.albedo, 99) == pytest.approx(1.0, rel=1e-3)
    # Eq. 3 is enforced as the constraint A + S = I: the product is the input
    # (below the log floor, the floor)
    floored = np.maximum(seq.frames, FAST.log_floor)
    np.testing.assert_allclose(video.reconstruct(), floored, rtol=1e-3, atol=1e-6)
    d = video.diagnostics
    assert [(r["window"], r["level"]) for r in d["levels"]][-1] == (0, 0)
    assert all(isinstance(r["converged"], bool) and len(r["stop_reasons"]) == FAST.outer_iterations
               for r in d["levels"])
    assert d["energy"] and d["seconds"]["solve"] > 0
    energies = [row[-1] for row in d["energy"] if row[1] == 0]    # finest level
    assert energies[-1] <= energies[0]


def test_uint8_input_and_single_frame(seq):
    frames8 = seq.frames_srgb8()
    video = iv.decompose(frames8[:1], params=FAST)
    assert video.albedo.shape == (1, *frames8.shape[1:])
    assert video.flow is None


def test_without_temporal_terms_no_flow_is_estimated(seq):
    video = iv.decompose(seq.frames, temporal=False, params=FAST)
    assert video.flow is None and video.occlusion is None and video.boundary is None


@pytest.mark.parametrize("bad, match", [
    (np.zeros((3, 20, 20)), "3"),
    (np.full((2, 20, 20, 3), np.nan, np.float32), "finite|NaN"),
    (np.full((2, 20, 20, 3), 2.0, np.float32), r"\[0, 1\]|range"),
])
def test_bad_frames_raise(bad, match):
    with pytest.raises((ValueError, TypeError), match=match):
        iv.decompose(bad, params=FAST)


def test_bad_arguments_raise(seq):
    with pytest.raises(ValueError, match="flow must have shape"):
        iv.decompose(seq.frames, flow=np.zeros((1, 4, 4, 2), np.float32), params=FAST)
    with pytest.raises(ValueError, match="unknown flow method"):
        iv.decompose(seq.frames, flow="nope", params=FAST)
    with pytest.raises(ValueError, match="backend"):
        iv.decompose(seq.frames, backend="torch", params=FAST)
    with pytest.raises(TypeError, match="Params"):
        iv.decompose(seq.frames, params={"lam_data": 1})


@pytest.mark.slow
def test_long_video_in_windows_stays_coherent():
    seq = synthetic.render_sequence("static_moving_light", n_frames=14, size=(36, 48), seed=5)
    params = FAST.replace(window=5, overlap=2)
    video = iv.decompose(seq.frames, flow=seq.flow, params=params)
    assert len(video.diagnostics["windows"]) > 2
    # a static scene: the albedo should hardly change over the whole video, across windows
    log_a = np.log(video.albedo)
    spread = np.abs(log_a - np.median(log_a, axis=0)).mean()
    input_spread = np.abs(np.log(seq.frames) - np.median(np.log(seq.frames), axis=0)).mean()
    assert spread < 0.65 * input_spread


@pytest.mark.slow
def test_taichi_backend_gives_the_same_decomposition(seq):
    a = iv.decompose(seq.frames, flow=seq.flow, params=FAST, backend="warp")
    b = iv.decompose(seq.frames, flow=seq.flow, params=FAST, backend="taichi")
    la = metrics.intrinsic_lmse(b.albedo, b.shading, a.albedo, a.shading)
    assert la["mean"] < 0.02


def test_flow_passes_reestimate_the_flow_on_the_guide_albedo(seq, monkeypatch):
    flow_module = importlib.import_module("ivkernels.decompose")    # where decompose() looks estimate_flow up

    calls = []
    original = flow_module.estimate_flow

    def spy(frames, method="classic_nl_fast", **options):
        calls.append((method, "init" in options, np.asarray(frames).dtype, np.shape(frames)[1:3]))
        return original(frames, method=method, **options)

    monkeypatch.setattr(flow_module, "estimate_flow", spy)
    checked = iv.decompose(seq.frames, flow="dis", params=FAST, flow_passes=1)
    # the forward-backward check's backward flow: the same method, at a quarter of the size (16 px floor)
    assert len(calls) == 2 and calls[1][:2] == ("dis", False) and calls[1][3] == (16, 22)
    FAST_NO_CHECK = dataclasses.replace(FAST, flow_round_trip_max=0.0)
    calls.clear()
    one = iv.decompose(seq.frames, flow="dis", params=FAST_NO_CHECK, flow_passes=1)
    assert len(calls) == 1 and one.diagnostics["flow_method"] == "dis"
    assert calls[0][3] == seq.frames.shape[1:3]                 # a single pass runs at full size
    assert np.all(checked.occlusion <= one.occlusion)          # the check only clears w_occ
    calls.clear()
    two = iv.decompose(seq.frames, flow="dis", params=FAST_NO_CHECK, flow_passes=3)
    # pass 1 on the input at the guide's size (it only feeds the guide), passes 2 and 3 at full
    # size on guide albedos (float32 in [0, 1]); DIS takes no init
    assert [c[0] for c in calls] == ["dis"] * 3 and not any(c[1] for c in calls)
    assert [c[3] for c in calls] == [(20, 28), seq.frames.shape[1:3], seq.frames.shape[1:3]]
    calls.clear()
    full = iv.decompose(seq.frames, flow="dis", params=dataclasses.replace(FAST_NO_CHECK, first_flow_at_guide_size=False),
                        flow_passes=2)
    assert [c[3] for c in calls] == [seq.frames.shape[1:3]] * 2 and full.flow.shape == seq.flow.shape
    # the later passes at the guide's size once its shorter side (20) reaches flow_refine_guide_min_side
    for least, later in ((20, (20, 28)), (21, seq.frames.shape[1:3]), (0, seq.frames.shape[1:3])):
        calls.clear()
        small = iv.decompose(seq.frames, flow="dis", params=dataclasses.replace(FAST_NO_CHECK, flow_refine_guide_min_side=least),
                             flow_passes=3)
        assert [c[3] for c in calls] == [(20, 28), later, later] and small.flow.shape == seq.flow.shape
    assert two.diagnostics["flow_method"] == "dis, 3 passes with the intrinsic video"
    assert "guide" in two.diagnostics["seconds"] and "guide" not in one.diagnostics["seconds"]
    assert two.flow.shape == seq.flow.shape and not np.array_equal(two.flow, one.flow)
    # a given flow, or no temporal terms: nothing to re-estimate
    calls.clear()
    given = iv.decompose(seq.frames, flow=seq.flow, params=FAST, flow_passes=2)
    assert not calls and given.diagnostics["flow_method"] == "given"
    for bad in (0, 1.5, True, "2"):
        with pytest.raises(ValueError, match="flow_passes must be"):
            iv.decompose(seq.frames, flow=seq.flow, params=FAST, flow_passes=bad)


def test_classic_flow_passes_refine_from_the_previous_flow_with_fewer_warps(seq, monkeypatch):
    flow_module = importlib.import_module("ivkernels.decompose")    # where decompose() looks estimate_flow up

    calls = []
    original = flow_module.estimate_flow

    def spy(frames, method="classic_nl_fast", **options):
        calls.append({k: v for k, v in options.items() if k in ("init", "warps")})
        return original(frames, method=method, **options)

    monkeypatch.setattr(flow_module, "estimate_flow", spy)
    params = dataclasses.replace(FAST, flow_refine_warps=1, flow_round_trip_max=0.0)     # no backward flow
    iv.decompose(seq.frames, params=params, flow_passes=2)
    assert len(calls) == 2 and calls[0] == {}                  # pass 1: the method's own schedule
    assert calls[1]["warps"] == 1 and calls[1]["init"].shape == seq.flow.shape
    calls.clear()
    video = iv.decompose(seq.frames, params=dataclasses.replace(params, flow_refine_guide_min_side=1), flow_passes=2)
    # at the guide's size: the starting flow resized with the albedo, the result back at full size
    assert calls[1]["init"].shape == (seq.flow.shape[0], 20, 28, 2) and video.flow.shape == seq.flow.shape
    with pytest.raises(ValueError, match="flow_refine_warps"):
        Params(flow_refine_warps=0)
    with pytest.raises(ValueError, match="flow_refine_guide_min_side"):
        Params(flow_refine_guide_min_side=-1)


def test_iteration_budget_per_level():
    """lbfgs_iterations bounds the finest level, lbfgs_iterations_coarse the others."""
    seq = synthetic.render_sequence("objects_camera", n_frames=2, size=(64, 80), seed=3)
    params = Params(outer_iterations=2, lbfgs_iterations=4, lbfgs_iterations_coarse=2)
    video = iv.decompose(seq.frames, flow=seq.flow, params=params)
    rows = video.diagnostics["energy"]               # (window, level, outer, iteration, E)
    levels = {row[1] for row in rows}
    assert 0 in levels and len(levels) > 1
    for level in levels:
        budget = 4 if level == 0 else 2
        its = [row[3] for row in rows if row[1] == level]
        assert max(its) < budget
        assert {row[2] for row in rows if row[1] == level} <= {0, 1}
