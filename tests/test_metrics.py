"""LMSE, flow errors, temporal incoherence, albedo consistency and flicker."""
import numpy as np
import pytest

from ivkernels.evaluation.metrics import (_dis_flow, albedo_consistency, albedo_drift, albedo_flicker, angular_error,
                                          dark_ratio, endpoint_error, flow_errors, intrinsic_lmse, lmse, luminance,
                                          temporal_incoherence, tracked_albedo_change)


def _lmse_loops(est, truth, mask, window, step):
    """Grosse et al.'s definition, written as explicit loops over windows (grey, one frame)."""
    h, w = truth.shape
    ssq = total = 0.0
    for i in range(0, h - window + 1, step):
        for j in range(0, w - window + 1, step):
            e = est[i:i + window, j:j + window]
            t = truth[i:i + window, j:j + window]
            m = mask[i:i + window, j:j + window]
            ee = np.sum(e * e * m)
            alpha = np.sum(t * e * m) / ee if ee > 0 else 0.0
            ssq += np.sum(m * (t - alpha * e) ** 2)
            total += np.sum(m * t * t)
    return ssq / total


# ----------------------------------------------------------------------------- LMSE
def test_lmse_perfect_scaled_and_zero(rng):
    truth = rng.uniform(0.1, 1, (37, 53, 3))
    assert lmse(truth, truth) == pytest.approx(0.0, abs=1e-14)
    assert lmse(3.7 * truth, truth) == pytest.approx(0.0, abs=1e-14)
    assert lmse(np.zeros_like(truth), truth) == pytest.approx(1.0, abs=1e-14)


def test_lmse_per_window_scale_is_free(rng):
    truth = rng.uniform(0.1, 1, (40, 60))
    scales = np.kron(rng.uniform(0.2, 5.0, (4, 6)), np.ones((10, 10)))   # one scale per 10x10 tile
    est = truth * scales
    assert lmse(est, truth, window=10, step=10) == pytest.approx(0.0, abs=1e-14)
    # with overlapping 20-pixel windows the tiles no longer align: the error is positive
    assert lmse(est, truth) > 0.01


def test_lmse_hand_computed():
    truth = np.ones((2, 2))
    est = np.array([[1.0, 0.0], [1.0, 0.0]])
    # one window (the image is smaller than 20): alpha = 2/2 = 1, ssq = 2, total = 4
    assert lmse(est, truth) == pytest.approx(0.5)
    # window=1: four single-pixel windows; where est = 0, alpha = 0 and the error is
    # t^2 = 1, elsewhere 0 -> 2/4
    assert lmse(est, truth, window=1, step=1) == pytest.approx(0.5)
    # step larger than the image: only the window at (0, 0)
    t = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    e = np.array([[1.0, 1.0, 9.0], [1.0, 1.0, 9.0]])
    # window 2x2 at (0,0): t=(1,2,4,5), e=1 -> alpha=3, ssq=4+1+1+4=10, total=46
    assert lmse(e, t, window=2, step=5) == pytest.approx(10.0 / 46.0)


def test_lmse_matches_loop_reference(rng):
    truth = rng.uniform(0, 1, (37, 53))
    est = truth + rng.normal(scale=0.2, size=truth.shape)
    mask = rng.uniform(size=truth.shape) > 0.2
    for window, step in [(20, 10), (7, 3), (10, 10)]:
        ref = _lmse_loops(est, truth, mask.astype(float), window, step)
        assert lmse(est, truth, window=window, step=step, mask=mask) == pytest.approx(ref, rel=1e-12)


def test_lmse_colour_is_mean_of_channels_and_stack_mean_of_frames(rng):
    truth = rng.uniform(0.1, 1, (3, 30, 41, 3))
    est = truth * rng.uniform(0.5, 1.5, truth.shape)
    per_frame = [np.mean([lmse(est[f, ..., c], truth[f, ..., c]) for c in range(3)]) for f in range(3)]
    assert lmse(est[0], truth[0]) == pytest.approx(per_frame[0], rel=1e-12)
    assert lmse(est, truth) == pytest.approx(np.mean(per_frame), rel=1e-12)
    grey_stack = lmse(est[..., 0], truth[..., 0])           # (T, H, W)
    assert grey_stack == pytest.approx(np.mean([lmse(est[f, ..., 0], truth[f, ..., 0]) for f in range(3)]))


def test_lmse_zero_channel_left_out(rng):
    truth = rng.uniform(0.1, 1, (25, 25, 3))
    truth[..., 2] = 0.0
    est = truth.copy()
    est[..., 2] = rng.uniform(size=(25, 25))                 # error only in the empty channel
    assert lmse(est, truth) == pytest.approx(0.0, abs=1e-14)


def test_lmse_mask_ignores_outside(rng):
    truth = rng.uniform(0.1, 1, (30, 30))
    est = truth * 1.3 + rng.normal(scale=0.05, size=truth.shape)
    mask = np.ones((30, 30), bool)
    mask[:, 15:] = False
    garbage = est.copy()
    garbage[:, 15:] = 100.0
    assert lmse(garbage, truth, mask=mask) == pytest.approx(lmse(est, truth, mask=mask), rel=1e-12)
    stack_mask = np.stack([mask, mask])
    two = np.stack([est, est])
    assert lmse(two, np.stack([truth, truth]), mask=stack_mask) == pytest.approx(lmse(est, truth, mask=mask))


def test_intrinsic_lmse(rng):
    a = rng.uniform(0.1, 1, (2, 20, 20, 3))
    s = rng.uniform(0.1, 1, (2, 20, 20))
    out = intrinsic_lmse(a * 2, np.zeros_like(s), a, s)
    assert out["albedo"] == pytest.approx(0.0, abs=1e-14)
    assert out["shading"] == pytest.approx(1.0)
    assert out["mean"] == pytest.approx(0.5)


@pytest.mark.parametrize("est, truth, kwargs, exc, msg", [
    (np.zeros((5, 5)), np.ones((5, 6)), {}, ValueError, "shape"),
    (np.zeros((5,)), np.ones((5,)), {}, ValueError, "expected"),
    (np.full((5, 5), np.nan), np.ones((5, 5)), {}, ValueError, "NaN"),
    (np.zeros((5, 5)), np.ones((5, 5)), {"window": 0}, ValueError, "window"),
    (np.zeros((5, 5)), np.ones((5, 5)), {"step": 2.5}, ValueError, "step"),
    (np.zeros((5, 5)), np.zeros((5, 5)), {}, ValueError, "zero inside every window"),
    (np.zeros((5, 5)), np.ones((5, 5)), {"mask": np.ones((4, 5))}, ValueError, "mask"),
    (np.zeros((5, 5)), np.ones((5, 5)), {"mask": np.array(["a"] * 25).reshape(5, 5)}, TypeError, "mask"),
    (np.array([["a"]]), np.ones((1, 1)), {}, TypeError, "numeric"),
])
def test_lmse_rejects(est, truth, kwargs, exc, msg):
    with pytest.raises(exc, match=msg):
        lmse(est, truth, **kwargs)


# ----------------------------------------------------------------------------- flow errors
def test_constant_flows():
    gt = np.zeros((2, 7, 9, 2))
    f = np.zeros_like(gt)
    f[..., 0] = 3.0
    f[..., 1] = 4.0
    assert endpoint_error(f, gt) == pytest.approx(5.0)
    f1 = np.zeros_like(gt)
    f1[..., 0] = 1.0
    assert angular_error(f1, gt) == pytest.approx(45.0)       # (1,0,1) vs (0,0,1)
    assert angular_error(f1, -f1) == pytest.approx(90.0)      # (1,0,1) vs (-1,0,1): cos = 0
    assert angular_error(f, f) == pytest.approx(0.0, abs=1e-5)
    assert flow_errors(f1, gt) == pytest.approx({"epe": 1.0, "aae": 45.0})


def test_flow_errors_mask_and_unknown_gt():
    gt = np.zeros((6, 8, 2))
    f = np.zeros_like(gt)
    f[:3, ..., 0] = 2.0                      # error 2 on the top half
    mask = np.zeros((6, 8), bool)
    mask[:3] = True
    assert endpoint_error(f, gt) == pytest.approx(1.0)
    assert endpoint_error(f, gt, mask=mask) == pytest.approx(2.0)
    assert endpoint_error(f, gt, mask=~mask) == pytest.approx(0.0)
    gt_unknown = gt.copy()
    gt_unknown[:3] = 1e10                    # unknown ground truth is ignored
    assert endpoint_error(f, gt_unknown) == pytest.approx(0.0)
    assert angular_error(f, gt_unknown) == pytest.approx(0.0, abs=1e-5)
    gt_nan = gt.copy()
    gt_nan[:3, :, 1] = np.nan
    assert endpoint_error(f, gt_nan) == pytest.approx(0.0)
    f_nan = f.copy()
    f_nan[:3] = np.nan                       # non-finite estimate where gt is unknown: fine
    assert endpoint_error(f_nan, gt_unknown) == pytest.approx(0.0)


@pytest.mark.parametrize("f, g, mask, exc, msg", [
    (np.zeros((4, 5, 2)), np.zeros((4, 6, 2)), None, ValueError, "shape"),
    (np.zeros((4, 5, 3)), np.zeros((4, 5, 3)), None, ValueError, r"\(\.\.\., H, W, 2\)"),
    (np.zeros((4, 5, 2)), np.full((4, 5, 2), 1e10), None, ValueError, "no pixel"),
    (np.zeros((4, 5, 2)), np.zeros((4, 5, 2)), np.zeros((4, 5), bool), ValueError, "no pixel"),
    (np.full((4, 5, 2), np.inf), np.zeros((4, 5, 2)), None, ValueError, "NaN or infinite"),
    (np.zeros((4, 5, 2)), np.zeros((4, 5, 2)), np.ones((5, 4)), ValueError, "mask"),
    (np.zeros((4, 5, 2), bool), np.zeros((4, 5, 2)), None, TypeError, "numeric"),
])
def test_flow_errors_reject(f, g, mask, exc, msg):
    for fn in (endpoint_error, angular_error):
        with pytest.raises(exc, match=msg):
            fn(f, g, mask=mask)


# ----------------------------------------------------------------------------- temporal measures
def _translating_texture(rng, t=3, h=48, w=64, shift=(2, 1)):
    """Smooth random texture moved by an integer shift per frame (np.roll), and its flow."""
    import cv2

    base = rng.uniform(0.05, 1.0, (h, w, 3)).astype(np.float32)
    base = cv2.GaussianBlur(base, (0, 0), 1.5)
    frames = np.stack([np.roll(base, (shift[1] * k, shift[0] * k), axis=(0, 1)) for k in range(t)])
    flow = np.zeros((t - 1, h, w, 2), np.float32)
    flow[..., 0], flow[..., 1] = shift
    vis = np.ones((t - 1, h, w), np.float32)
    vis[:, h - shift[1]:] = 0
    vis[:, :, w - shift[0]:] = 0
    return frames, flow, vis


def test_temporal_incoherence_with_given_method(rng):
    albedo, flow, vis = _translating_texture(rng)
    exact = temporal_incoherence(albedo, flow, vis, flow_method=lambda a: flow)
    assert exact == {"epe": 0.0, "epe_visible": 0.0}
    off = temporal_incoherence(albedo, flow, None, flow_method=lambda a: flow + np.array([0.0, 1.0]))
    assert off["epe"] == pytest.approx(1.0) and np.isnan(off["epe_visible"])


def test_temporal_incoherence_dis_tracks_translation(rng):
    albedo, flow, vis = _translating_texture(rng)
    f = _dis_flow(albedo)
    assert f.shape == flow.shape and f.dtype == np.float32
    coherent = temporal_incoherence(albedo, flow, vis)
    assert coherent["epe_visible"] < 0.5
    # the same albedo with an illumination change that moves with the frame: less coherent
    ramp = np.linspace(0.3, 1.0, albedo.shape[2], dtype=np.float32)
    flicker = albedo * np.stack([ramp, ramp[::-1], ramp])[:, None, :, None]
    assert temporal_incoherence(flicker, flow, vis)["epe_visible"] > coherent["epe_visible"]
    # a broadcast (static) albedo, which is not contiguous, is accepted
    static = np.broadcast_to(albedo[0], albedo.shape)
    assert temporal_incoherence(static, np.zeros_like(flow))["epe"] < 0.1
    # the global scale of the albedo does not matter (normalised per sequence)
    scaled = temporal_incoherence(0.5 * albedo, flow, vis)
    assert scaled["epe"] == pytest.approx(coherent["epe"], abs=1e-6)


def test_temporal_incoherence_rejects(rng):
    albedo, flow, vis = _translating_texture(rng)
    with pytest.raises(ValueError, match=r"\(T, H, W, 3\)"):
        temporal_incoherence(albedo[..., 0], flow, vis)
    with pytest.raises(ValueError, match="at least 2 frames"):
        temporal_incoherence(albedo[:1], flow[:0], vis[:0])
    with pytest.raises(ValueError, match="flow_gt"):
        temporal_incoherence(albedo, flow[:1], vis)
    with pytest.raises(ValueError, match="visibility"):
        temporal_incoherence(albedo, flow, vis[..., :-1])
    with pytest.raises(ValueError, match=">= 0"):
        temporal_incoherence(albedo - 2.0, flow, vis)
    with pytest.raises(TypeError, match="callable"):
        temporal_incoherence(albedo, flow, vis, flow_method="dis")
    with pytest.raises(ValueError, match="flow_method returned"):
        temporal_incoherence(albedo, flow, vis, flow_method=lambda a: flow[:, :-1])


def test_albedo_consistency(rng):
    albedo, flow, vis = _translating_texture(rng)
    assert albedo_consistency(albedo, flow, vis) == pytest.approx(0.0, abs=1e-5)
    # a per-frame global scale is removed by the median normalisation
    scaled = albedo * np.array([1.0, 0.5, 2.0], np.float32)[:, None, None, None]
    assert albedo_consistency(scaled, flow, vis) == pytest.approx(0.0, abs=1e-5)
    assert albedo_consistency(albedo, flow, None) == pytest.approx(0.0, abs=1e-5)
    # a local change of the second frame shows up; marked occluded, only the shift of
    # frame 1's median (the per-frame normalisation) remains
    changed = albedo.copy()
    changed[1, 10:30, 10:30] *= 0.5
    seen = albedo_consistency(changed, flow, vis)
    assert seen > 0.05
    hidden = vis.copy()
    hidden[0, 9:29, 8:28] = 0           # pixels of frame 0 that land in the square (shift (2, 1))
    hidden[1, 10:30, 10:30] = 0         # pixels of the square itself, compared with frame 2
    assert albedo_consistency(changed, flow, hidden) < 0.4 * seen
    # flow pointing out of the image everywhere leaves nothing to compare
    with pytest.raises(ValueError, match="no visible pixel"):
        albedo_consistency(albedo, flow + 1000.0, vis)
    with pytest.raises(ValueError, match="eps"):
        albedo_consistency(albedo, flow, vis, eps=0.0)
    with pytest.raises(ValueError, match="flow_gt"):
        albedo_consistency(albedo, flow[..., :1], vis)


# ----------------------------------------------------------------------------- albedo flicker
def test_albedo_flicker_hand_computed_static():
    # 3 frames of 2x2 RGB: frame 1 has one pixel doubled (all channels), frame 2 equals frame 0
    a = np.full((3, 2, 2, 3), 0.25)
    a[1, 0, 1] = 0.5
    # p99 is taken over all 36 values, 3 of them 0.5: a global scale, which cancels
    # pairs (0,1) and (1,2): one pixel of 4 changes by |log 2| each time -> mean log(2)/4
    assert albedo_flicker(a) == pytest.approx(np.log(2.0) / 4.0, rel=1e-12)
    # a global scale changes nothing; a per-frame scale is flicker (unlike albedo_consistency)
    assert albedo_flicker(7.0 * a) == pytest.approx(np.log(2.0) / 4.0, rel=1e-12)
    b = np.full((2, 2, 2, 3), 0.25)
    b[1] *= 1.5
    assert albedo_flicker(b) == pytest.approx(np.log(1.5), rel=1e-12)
    # the mask keeps pixels of frame t: without (0, 1) nothing changes
    mask = np.ones((2, 2), bool)
    mask[0, 1] = False
    assert albedo_flicker(a, mask=mask) == pytest.approx(0.0, abs=1e-15)
    # the eps floor acts on the normalised albedo: 0 and 1e-6 of a 0.25 albedo are the same
    c = np.full((2, 2, 2, 3), 0.25)
    c[1, 0, 0] = 0.0
    d = c.copy()
    d[1, 0, 0] = 1e-6
    assert albedo_flicker(c) == pytest.approx(albedo_flicker(d), rel=1e-12)
    assert albedo_flicker(c) == pytest.approx(np.log(1.0 / 1e-3) / 4.0, rel=1e-12)


def test_albedo_flicker_along_flow(rng):
    albedo, flow, vis = _translating_texture(rng)
    assert albedo_flicker(albedo, flow, vis) == pytest.approx(0.0, abs=1e-5)
    # zero flow on a moving texture: flicker, which the flow explains away
    assert albedo_flicker(albedo) > 0.05
    # a frame brightened as a whole: |log 2| on both of its pairs, at every counted pixel
    scaled = albedo * np.array([1.0, 2.0, 1.0], np.float32)[:, None, None, None]
    assert albedo_flicker(scaled, flow, vis) == pytest.approx(np.log(2.0), rel=1e-4)
    assert albedo_consistency(scaled, flow, vis) == pytest.approx(0.0, abs=1e-5)
    # pixels marked occluded are not compared
    changed = albedo.copy()
    changed[1, 10:30, 10:30] *= 0.5
    hidden = vis.copy()
    hidden[0, 9:29, 8:28] = 0
    hidden[1, 10:30, 10:30] = 0
    assert albedo_flicker(changed, flow, vis) > 0.05
    assert albedo_flicker(changed, flow, hidden) == pytest.approx(0.0, abs=1e-5)


def test_albedo_flicker_rejects(rng):
    albedo, flow, vis = _translating_texture(rng)
    with pytest.raises(ValueError, match="at least 2 frames"):
        albedo_flicker(albedo[:1])
    with pytest.raises(ValueError, match=r"\(T, H, W, 3\)"):
        albedo_flicker(albedo[..., 0])
    with pytest.raises(ValueError, match="flow_gt"):
        albedo_flicker(albedo, flow[:1], vis)
    with pytest.raises(ValueError, match="needs a flow"):
        albedo_flicker(albedo, None, vis)
    with pytest.raises(ValueError, match="mask"):
        albedo_flicker(albedo, mask=np.ones((3, 3), bool))
    with pytest.raises(ValueError, match="empty"):
        albedo_flicker(albedo, mask=np.zeros(albedo.shape[1:3], bool))
    with pytest.raises(ValueError, match="no visible pixel"):
        albedo_flicker(albedo, flow + 1000.0, vis)
    with pytest.raises(ValueError, match="eps"):
        albedo_flicker(albedo, eps=0.0)
    with pytest.raises(ValueError, match="99th percentile"):
        albedo_flicker(np.zeros_like(albedo))



# ----------------------------------------------------------------------------
# dark_ratio and albedo_drift (footage without ground truth)
# ----------------------------------------------------------------------------

def _footage(seed=0, t=4, h=30, w=40):
    """Albedo and shading (T, H, W) where exactly 10% of the input pixels are darker
    than all others: dark coats (albedo 0.05-0.08) in full light, on a pale floor
    (0.5-0.9) under a shading in [0.5, 1]."""
    rng = np.random.default_rng(seed)
    n = t * h * w
    albedo = rng.uniform(0.5, 0.9, n)
    shading = rng.uniform(0.5, 1.0, n)
    dark = rng.permutation(n)[: n // 10]
    albedo[dark] = rng.uniform(0.05, 0.08, len(dark))
    shading[dark] = 1.0                     # input <= 0.08 < 0.25 <= every other pixel
    return albedo.reshape(t, h, w), shading.reshape(t, h, w), np.isin(np.arange(n), dark).reshape(t, h, w)


def test_dark_ratio_on_a_constructed_case():
    albedo, shading, dark = _footage()
    frames = albedo * shading
    expected = np.median(albedo[dark]) / np.median(albedo)
    assert dark_ratio(albedo, frames) == pytest.approx(expected, rel=1e-12)
    assert dark_ratio(albedo, frames) <= 0.4                              # the truth keeps the coats dark
    assert dark_ratio(np.ones_like(frames), frames) == pytest.approx(1.0)  # everything in the shading
    # scale-invariant, and RGB with equal channels reads as its grey
    rgb = np.repeat(albedo[..., None], 3, axis=-1)
    assert dark_ratio(3.0 * rgb, np.repeat(frames[..., None], 3, axis=-1)) == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(luminance(rgb), albedo, rtol=1e-12)


def test_dark_ratio_with_a_mask_counts_only_the_mask():
    albedo, shading, _ = _footage(1)
    frames = albedo * shading
    mask = np.zeros(albedo.shape[1:], bool)
    mask[:, :17] = True
    assert dark_ratio(albedo, frames, mask=mask) == pytest.approx(dark_ratio(albedo[:, :, :17], frames[:, :, :17]))


@pytest.mark.parametrize("call, match", [
    (lambda f: dark_ratio(f, f[:, :5]), "differ in size"),
    (lambda f: dark_ratio(f, f, fraction=1.0), "fraction"),
    (lambda f: dark_ratio(f[0, 0], f[0, 0]), "expected"),
    (lambda f: dark_ratio(f, f, mask=np.zeros(f.shape[1:], bool)), "mask is empty"),
    (lambda f: albedo_drift(f[:1]), "at least 2"),
    (lambda f: luminance(f), "last axis of 3"),
])
def test_dark_ratio_and_drift_refuse_bad_input(call, match):
    albedo, shading, _ = _footage()
    with pytest.raises(ValueError, match=match):
        call(albedo * shading)


def test_albedo_drift_on_a_known_ramp():
    rng = np.random.default_rng(3)
    base = rng.uniform(0.05, 0.9, (1, 17, 23, 3))
    t = np.arange(24)
    ramp = base * np.exp(-0.0004 * t)[:, None, None, None]        # -0.04% a frame
    assert albedo_drift(ramp) == pytest.approx(-4.0, rel=1e-9)     # -4% per 100 frames
    assert albedo_drift(np.broadcast_to(base, ramp.shape)) == pytest.approx(0.0, abs=1e-9)
    # a linear (not exponential) ramp: the log-line fit, by hand with least squares
    lin = base * (1 + 0.01 * t)[:, None, None, None]
    levels = np.log(np.median(lin @ np.array([0.2126, 0.7152, 0.0722]), axis=(1, 2)))
    design = np.stack([t, np.ones_like(t)], axis=1).astype(float)
    slope = np.linalg.lstsq(design, levels, rcond=None)[0][0]
    assert albedo_drift(lin) == pytest.approx(1e4 * slope, rel=1e-9)
    # only the mask counts: a drifting region outside it is ignored
    mixed = np.broadcast_to(base, ramp.shape).copy()
    mixed[:, :, 12:] = ramp[:, :, 12:]
    mask = np.zeros((17, 23), bool)
    mask[:, :12] = True
    assert albedo_drift(mixed, mask=mask) == pytest.approx(0.0, abs=1e-9)


def test_albedo_drift_against_a_reference_ignores_content_that_enters_the_view():
    rng = np.random.default_rng(4)
    t = 30
    # a pan over a bright-to-dark gradient: the true albedo's level falls frame by frame
    truth = np.stack([rng.uniform(0.2, 0.9, (9, 11, 3)) * np.exp(-0.01 * k) for k in range(t)])
    assert albedo_drift(truth) < -80                 # about -100, the content's own change
    # a method that gets the albedo right up to a fixed scale does not drift
    assert albedo_drift(0.7 * truth, reference=truth) == pytest.approx(0.0, abs=1e-9)
    # one whose scale falls 0.02% a frame drifts -2% per 100 frames
    drifting = truth * np.exp(-0.0002 * np.arange(t))[:, None, None, None]
    assert albedo_drift(drifting, reference=truth) == pytest.approx(-2.0, rel=1e-6)
    # grey stacks work the same
    assert albedo_drift(drifting[:, :, :, 0], reference=truth[:, :, :, 0]) == pytest.approx(-2.0, rel=1e-6)
    with pytest.raises(ValueError, match="positive"):
        albedo_drift(truth, reference=truth * 0)


# ----------------------------------------------------------------------------
# tracked_albedo_change (points followed along the ground-truth flow)
# ----------------------------------------------------------------------------

def _panning(t=5, h=19, w=27, shift=(2, 1), seed=4):
    """A textured albedo seen through a window that moves ``shift`` (x, y) pixels a frame,
    its true flow (every pixel moves by ``-shift``) and visibility (what stays in view)."""
    rng = np.random.default_rng(seed)
    sx, sy = shift
    world = rng.uniform(0.1, 0.9, (h + sy * t, w + sx * t, 3))
    albedo = np.stack([world[k * sy:k * sy + h, k * sx:k * sx + w] for k in range(t)])
    flow = np.zeros((t - 1, h, w, 2))
    flow[..., 0], flow[..., 1] = -sx, -sy
    yy, xx = np.mgrid[:h, :w]
    vis = np.broadcast_to((xx >= sx) & (yy >= sy), (t - 1, h, w)).astype(float)
    return albedo, flow, vis


def test_tracked_change_is_zero_for_an_albedo_that_holds_along_the_flow():
    albedo, flow, vis = _panning()
    out = tracked_albedo_change(albedo, flow, vis)
    assert out["median"] == pytest.approx(0.0, abs=1e-6)
    assert out["mean_abs"] == pytest.approx(0.0, abs=1e-6)
    # what survives 4 frames of a (2, 1) pan in 19x27: columns >= 8, rows >= 4
    assert out["tracked"] == pytest.approx((27 - 8) * (19 - 4) / (27 * 19))


def test_tracked_change_follows_the_points_not_the_pixels():
    albedo, flow, vis = _panning()
    brighter = albedo.copy()
    brighter[-1] *= 1.03                          # the last frame's albedo 3% brighter everywhere
    out = tracked_albedo_change(brighter, flow, vis)
    assert out["median"] == pytest.approx(0.03, rel=1e-5)
    assert out["mean_abs"] == pytest.approx(0.03, rel=1e-5)
    # compared in place (flow=None) the pan reads as a large change, which is not the albedo's
    assert tracked_albedo_change(albedo)["mean_abs"] > 0.2


def test_tracked_change_of_one_region_shows_in_the_mean_not_the_median():
    a = np.full((3, 10, 12), 0.5)
    a[-1, :, :4] *= 0.9                            # a third of the scene 10% darker at the end
    out = tracked_albedo_change(a)
    assert out["median"] == pytest.approx(0.0, abs=1e-12)
    assert out["mean_abs"] == pytest.approx(np.exp(-np.log(0.9) / 3) - 1, rel=1e-6)   # logs in float32
    assert out["tracked"] == 1.0


@pytest.mark.parametrize("call, match", [
    (lambda a, f, v: tracked_albedo_change(a[:1]), "at least 2"),
    (lambda a, f, v: tracked_albedo_change(-a), "positive"),
    (lambda a, f, v: tracked_albedo_change(a, f[:, :-1], v), "expected shape"),
    (lambda a, f, v: tracked_albedo_change(a, None, v), "visibility needs a flow"),
    (lambda a, f, v: tracked_albedo_change(a, f, np.zeros_like(v)), "no point"),
    (lambda a, f, v: tracked_albedo_change(a, f * 100, v), "no point"),     # everything leaves the view
])
def test_tracked_change_refuses_bad_input(call, match):
    albedo, flow, vis = _panning()
    with pytest.raises(ValueError, match=match):
        call(albedo, flow, vis)
