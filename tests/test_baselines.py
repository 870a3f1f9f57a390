"""Baselines: colour Retinex (Grosse et al. 2009), its Poisson integration, and the
Weiss (2001) temporal median, plain and along the flow."""
import numpy as np
import pytest

from ivkernels.evaluation.baselines import (GROSSE_THRESHOLDS, LUMINANCE_TUNED_THRESHOLD, TUNED_THRESHOLDS,
                                            _invert_flow, _poisson_neumann, color_retinex, luminance_retinex, weiss,
                                            weiss_flow)
from ivkernels.evaluation.metrics import albedo_flicker, lmse


def _blocks_times_smooth(rng, h=60, w=80, block=10):
    """Piecewise-constant colour albedo times a smooth grey shading (linear RGB)."""
    cells = rng.uniform(0.1, 1.0, (h // block + 1, w // block + 1, 3))
    albedo = np.repeat(np.repeat(cells, block, 0), block, 1)[:h, :w]
    y, x = np.mgrid[0:h, 0:w]
    shading = 0.2 + 0.8 * np.exp(-((x - 0.4 * w) ** 2 + (y - 0.4 * h) ** 2) / (2 * (0.45 * w) ** 2))
    return albedo, shading, albedo * shading[..., None]


@pytest.mark.parametrize("shape", [(2, 37, 53), (1, 1, 6), (1, 5, 1), (1, 2, 2)])
def test_poisson_neumann_integrates_exact_gradients(rng, shape):
    s = rng.normal(size=shape)
    s -= s.mean(axis=(1, 2), keepdims=True)
    out = _poisson_neumann(s[:, :, 1:] - s[:, :, :-1], s[:, 1:] - s[:, :-1])
    np.testing.assert_allclose(out, s, atol=1e-10)


def test_poisson_neumann_is_least_squares(rng):
    # an inconsistent (curl-carrying) field: the result zeroes the energy's gradient
    gx = rng.normal(size=(1, 9, 10))
    gy = rng.normal(size=(1, 8, 11))
    s = _poisson_neumann(gx, gy)[0]
    rx = (s[:, 1:] - s[:, :-1]) - gx[0]
    ry = (s[1:] - s[:-1]) - gy[0]
    grad = np.zeros_like(s)                 # d/ds of 0.5 * (|rx|^2 + |ry|^2)
    grad[:, 1:] += rx
    grad[:, :-1] -= rx
    grad[1:] += ry
    grad[:-1] -= ry
    np.testing.assert_allclose(grad, 0.0, atol=1e-10)


def test_color_retinex_recovers_blocks_times_smooth_shading(rng):
    albedo, shading, image = _blocks_times_smooth(rng)
    a, s = color_retinex(image.astype(np.float32))
    assert a.shape == image.shape and s.shape == shading.shape
    assert a.dtype == np.float32 and s.dtype == np.float32
    np.testing.assert_allclose(a * s[..., None], image, rtol=1e-5, atol=1e-7)
    assert np.percentile(a, 99) == pytest.approx(1.0, rel=1e-5)
    base = lmse(image, albedo)
    assert lmse(a, albedo) < 0.1 * base
    assert lmse(s, shading) < 0.1 * lmse(np.ones_like(shading), shading)


def test_color_retinex_frames_are_independent(rng):
    frames = np.stack([_blocks_times_smooth(rng)[2] for _ in range(3)])
    a, s = color_retinex(frames)
    assert a.shape == frames.shape and s.shape == frames.shape[:3]
    a1, s1 = color_retinex(frames[1])
    np.testing.assert_allclose(a[1], a1, rtol=1e-6)
    np.testing.assert_allclose(s[1], s1, rtol=1e-6)
    # each frame has its own scale: albedo's 99th percentile is 1 per frame
    np.testing.assert_allclose(np.percentile(a.reshape(3, -1), 99, axis=1), 1.0, rtol=1e-5)


def test_color_retinex_thresholds():
    # one step of log-size 0.1 in grey: reflectance at threshold 0.075, shading at 0.2
    image = np.full((8, 12, 3), 0.5)
    image[:, 6:] *= np.exp(0.1)
    a, s = color_retinex(image, threshold_gray=0.075)
    assert np.ptp(s) < 1e-6 and np.ptp(a[..., 0]) > 0.05
    a, s = color_retinex(image, threshold_gray=0.2)
    assert np.ptp(a) < 1e-6
    # a pure chromaticity change (same grey mean of log) counts only via threshold_color
    image = np.full((8, 12, 3), 0.5)
    image[:, 6:] *= np.exp(np.array([0.3, -0.3, 0.0]))
    a, s = color_retinex(image, threshold_gray=0.075, threshold_color=0.2)
    assert np.ptp(s) < 1e-6
    a, s = color_retinex(image, threshold_gray=0.075, threshold_color=1.0)
    assert np.ptp(s) > 1e-3


@pytest.mark.parametrize("frames, kw, exc, msg", [
    (np.zeros((4, 5, 3), np.int32), {}, TypeError, "unsupported dtype"),
    (np.zeros((4, 5)), {}, ValueError, r"\(T, H, W, 3\)"),
    (np.zeros((2, 4, 5, 4)), {}, ValueError, r"\(T, H, W, 3\)"),
    (np.zeros((0, 4, 5, 3)), {}, ValueError, "empty"),
    (np.full((4, 5, 3), np.nan), {}, ValueError, "NaN"),
    (np.full((4, 5, 3), -0.5), {}, ValueError, r"linear RGB in \[0, 1\]"),
    (np.full((4, 5, 3), 2.0), {}, ValueError, r"linear RGB in \[0, 1\]"),
    (np.ones((4, 5, 3)), {"threshold_gray": 0.0}, ValueError, "threshold_gray"),
    (np.ones((4, 5, 3)), {"threshold_color": np.nan}, ValueError, "threshold_color"),
    (np.ones((4, 5, 3)), {"eps": -1.0}, ValueError, "eps"),
])
def test_color_retinex_rejects(frames, kw, exc, msg):
    with pytest.raises(exc, match=msg):
        color_retinex(frames, **kw)


def test_baselines_take_frames_as_decompose_does(rng):
    """One rule for frames (ivkernels.validation): uint8 is sRGB, decoded as decompose decodes it."""
    from ivkernels.io import to_linear_float

    srgb = rng.integers(1, 256, (3, 6, 7, 3), dtype=np.uint8)
    linear = to_linear_float(srgb)
    np.testing.assert_array_equal(color_retinex(srgb)[0], color_retinex(linear)[0])
    np.testing.assert_array_equal(weiss(list(srgb))[0], weiss(linear)[0])


def test_color_retinex_beats_image_on_synthetic_sequences():
    """Averaged over the synthetic kinds, as the paper's baseline comparison needs."""
    from ivkernels.evaluation import synthetic

    ours, base = [], []
    for kind in synthetic.KINDS:
        seq = synthetic.render_sequence(kind, n_frames=3, size=(60, 80), seed=0)
        a, _ = color_retinex(seq.frames)
        ours.append(lmse(a, seq.albedo))
        base.append(lmse(seq.frames, seq.albedo))
    assert np.mean(ours) < np.mean(base)


def test_color_retinex_threshold_presets(rng):
    image = _blocks_times_smooth(rng, 30, 40)[2]
    a, s = color_retinex(image, thresholds="grosse")
    a0, s0 = color_retinex(image, *GROSSE_THRESHOLDS)
    np.testing.assert_array_equal(a, a0)
    a, s = color_retinex(image)
    a1, s1 = color_retinex(image, *TUNED_THRESHOLDS)
    np.testing.assert_array_equal(a, a1)
    # an explicit value overrides the preset's
    a, _ = color_retinex(image, threshold_gray=0.3, thresholds="grosse")
    a2, _ = color_retinex(image, 0.3, GROSSE_THRESHOLDS[1])
    np.testing.assert_array_equal(a, a2)
    with pytest.raises(ValueError, match="thresholds must be one of"):
        color_retinex(image, thresholds="mit")


# ----------------------------------------------------------------------------- Weiss
def _moving_shadow_scene(rng, t=5, h=24, w=30, block=6, shift=(0, 0)):
    """Blocks of colour albedo; a static camera (or a camera panning by integer ``shift``
    px per frame) and a hard shadow band moving across: every pixel is shadowed in at
    most 2 of the 5 frames.  Each frame also has its own light intensity."""
    cells = rng.uniform(0.2, 1.0, (h // block + 2, w // block + 2, 3))
    big = np.repeat(np.repeat(cells, block, 0), block, 1)
    albedo = np.stack([np.roll(big, (k * shift[1], k * shift[0]), axis=(0, 1))[:h, :w] for k in range(t)])
    shading = np.empty((t, h, w))
    xs = np.arange(w)
    for k in range(t):
        band = (xs >= 3 + 5 * k) & (xs < 3 + 5 * k + 7)          # 7 px wide, moves 5 px per frame
        shading[k] = np.where(band[None, :], 0.3, 1.0) * (0.6 + 0.1 * k)
    return albedo, shading, albedo * shading[..., None]


def _log_ratio_spread(estimate, truth):
    """ptp over pixels and channels of log(estimate / truth), per frame (0: equal up to a scale)."""
    r = np.log(estimate.astype(np.float64)) - np.log(truth)
    return np.ptp(r.reshape(r.shape[0], -1), axis=1)


@pytest.mark.parametrize("colour", ["chromaticity", "channels"])
def test_weiss_removes_a_moving_shadow(rng, colour):
    albedo, shading, frames = _moving_shadow_scene(rng)
    a, s = weiss(frames.astype(np.float32), colour=colour)
    assert a.shape == frames.shape and s.shape == frames.shape[:3]
    assert a.dtype == np.float32 and s.dtype == np.float32
    # the same albedo in every frame, equal to the truth up to one scale: the shadow is gone
    np.testing.assert_array_equal(a, np.broadcast_to(a[0], a.shape))
    assert np.all(_log_ratio_spread(a, albedo) < 1e-5)
    assert np.percentile(a, 99) == pytest.approx(1.0, rel=1e-5)
    # the shadow went to the shading, which reproduces the image (grey shading, exact here)
    assert lmse(s, shading) < 1e-10
    np.testing.assert_allclose(a * s[..., None], frames, rtol=1e-5)
    # every frame taken alone, colour Retinex with Grosse's thresholds takes the hard
    # grey shadow edge for a reflectance edge and keeps it in its albedo
    cret, _ = color_retinex(frames, thresholds="grosse")
    assert np.all(_log_ratio_spread(cret, albedo) > 0.5)


def test_weiss_flow_equals_weiss_at_zero_flow(rng):
    frames = rng.uniform(0.0, 1.0, (4, 9, 11, 3)).astype(np.float32)
    frames[1, 2, 3] = 0.0                                        # a pixel at the eps floor
    zero = np.zeros((3, 9, 11, 2), np.float32)
    for colour in ("chromaticity", "channels"):
        a, s = weiss(frames, colour=colour)
        for vis in (None, np.ones((3, 9, 11), np.float32)):
            af, sf = weiss_flow(frames, zero, vis, colour=colour)
            np.testing.assert_allclose(af, a, rtol=1e-6, atol=1e-7)
            np.testing.assert_allclose(sf, s, rtol=1e-6, atol=1e-7)


def test_weiss_flow_follows_a_panning_camera(rng):
    # the camera pans 2 px right and 1 px down per frame over the blocks while the shadow
    # band moves across the image: along the flow the shadow is gone from the albedo
    albedo, shading, frames = _moving_shadow_scene(rng, shift=(2, 1))
    t, h, w, _ = frames.shape
    flow = np.zeros((t - 1, h, w, 2), np.float32)
    flow[..., 0], flow[..., 1] = 2.0, 1.0
    vis = np.ones((t - 1, h, w), np.float32)
    vis[:, h - 1:] = 0
    vis[:, :, w - 2:] = 0
    a, s = weiss_flow(frames, flow, vis)
    assert a.shape == frames.shape and s.shape == frames.shape[:3]
    plain, _ = weiss(frames)
    assert lmse(a, albedo) < 1e-3
    assert lmse(a, albedo) < 0.05 * lmse(plain, albedo)
    assert lmse(a, albedo) < 0.05 * lmse(color_retinex(frames)[0], albedo)
    # and it does not flicker along the flow (one scale chained through the frames)
    assert albedo_flicker(a, flow, vis) < 0.02
    # radius=0: each frame alone, the shadow stays
    alone, _ = weiss_flow(frames, flow, vis, radius=0)
    assert lmse(alone, albedo) > 10 * lmse(a, albedo)


def test_invert_flow_of_a_translation():
    u = np.zeros((6, 7, 2))
    u[..., 0] = 1.5
    v, ok = _invert_flow(u, np.ones((6, 7)))
    np.testing.assert_allclose(v, -u, atol=1e-12)
    # pixels of frame t+1 left of x = 1.5 come from outside frame t
    np.testing.assert_array_equal(ok, np.broadcast_to(np.arange(7) >= 2, (6, 7)))


@pytest.mark.parametrize("shape", [(3, 1, 5), (3, 5, 1), (2, 2, 2), (3, 7, 4)])
def test_weiss_odd_sizes(rng, shape):
    frames = rng.uniform(0.05, 1.0, shape + (3,))
    a, s = weiss(frames)
    assert a.shape == frames.shape and s.shape == shape
    flow = rng.uniform(-0.7, 0.7, (shape[0] - 1,) + shape[1:] + (2,))
    a, s = weiss_flow(frames, flow)
    assert a.shape == frames.shape and s.shape == shape
    assert np.all(np.isfinite(a)) and np.all(a >= 0) and np.all(np.isfinite(s))


def test_weiss_non_contiguous_input(rng):
    frames = rng.uniform(0.05, 1.0, (4, 10, 12, 3))
    view = frames[:, ::-1, ::2]
    a, s = weiss(view)
    a0, s0 = weiss(np.ascontiguousarray(view))
    np.testing.assert_array_equal(a, a0)
    flow = np.zeros((3, 10, 6, 2))
    np.testing.assert_array_equal(weiss_flow(view, flow)[0], weiss_flow(np.ascontiguousarray(view), flow)[0])


_OK = np.full((3, 4, 5, 3), 0.5)
_FLOW = np.zeros((2, 4, 5, 2))


@pytest.mark.parametrize("call, exc, msg", [
    (lambda: weiss(np.zeros((3, 4, 5, 3), np.int32)), TypeError, "unsupported dtype"),
    (lambda: weiss(_OK[:1]), ValueError, "at least 2 frames"),
    (lambda: weiss(_OK[0]), ValueError, "at least 2 frames"),
    (lambda: weiss(_OK[..., :2]), ValueError, r"\(T, H, W, 3\)"),
    (lambda: weiss(-_OK), ValueError, r"linear RGB in \[0, 1\]"),
    (lambda: weiss(_OK * np.nan), ValueError, "NaN"),
    (lambda: weiss(_OK, eps=0.0), ValueError, "eps"),
    (lambda: weiss(_OK, colour="rgb"), ValueError, "colour"),
    (lambda: weiss_flow(_OK, _FLOW[:1]), ValueError, r"\(T-1, H, W, 2\)"),
    (lambda: weiss_flow(_OK, _FLOW[..., :1]), ValueError, r"\(T-1, H, W, 2\)"),
    (lambda: weiss_flow(_OK, _FLOW * np.nan), ValueError, "NaN"),
    (lambda: weiss_flow(_OK, _FLOW.astype(bool)), TypeError, "flow"),
    (lambda: weiss_flow(_OK, _FLOW, np.ones((2, 4, 4))), ValueError, "visibility"),
    (lambda: weiss_flow(_OK, _FLOW, radius=-1), ValueError, "radius"),
    (lambda: weiss_flow(_OK, _FLOW, radius=1.5), ValueError, "radius"),
    (lambda: weiss_flow(_OK, _FLOW, colour="grey"), ValueError, "colour"),
])
def test_weiss_rejects(call, exc, msg):
    with pytest.raises(exc, match=msg):
        call()


def test_weiss_beats_the_input_and_grosse_retinex_on_the_static_moving_light_kind():
    from ivkernels.evaluation import synthetic

    seq = synthetic.render_sequence("static_moving_light", n_frames=5, size=(48, 64), seed=3)
    a, s = weiss(seq.frames)
    c, _ = color_retinex(seq.frames, thresholds="grosse")
    assert lmse(a, seq.albedo) < lmse(c, seq.albedo) < lmse(seq.frames, seq.albedo)



# ----------------------------------------------------------------------------
# luminance Retinex
# ----------------------------------------------------------------------------

def _grey_blocks_times_smooth(rng, h=61, w=79, block=10):
    """Grey blocks (steps of at least a factor 1.5) times the smooth shading of
    :func:`_blocks_times_smooth`, as (T=2, H, W, 3) with equal channels."""
    levels = np.array([0.08, 0.15, 0.3, 0.6, 0.9])
    cells = levels[rng.integers(0, 5, (2, h // block + 1, w // block + 1))]
    # neighbouring cells differ: re-draw equal neighbours by stepping one level
    for axis in (1, 2):
        same = np.diff(cells, axis=axis) == 0
        idx = np.searchsorted(levels, np.take(cells, range(1, cells.shape[axis]), axis=axis))
        bumped = levels[np.where(idx + 1 < 5, idx + 1, idx - 1)]
        part = np.take(cells, range(1, cells.shape[axis]), axis=axis)
        part = np.where(same, bumped, part)
        cells = np.concatenate([np.take(cells, [0], axis=axis), part], axis=axis)
    albedo = np.repeat(np.repeat(cells, block, 1), block, 2)[:, :h, :w]
    _, shading, _ = _blocks_times_smooth(rng, h, w, block)
    frames = albedo * shading
    return np.repeat(albedo[..., None], 3, -1), shading, np.repeat(frames[..., None], 3, -1)


def test_luminance_retinex_recovers_grey_blocks_where_colour_retinex_cannot(rng):
    albedo, shading, frames = _grey_blocks_times_smooth(rng)
    a, s = luminance_retinex(frames.astype(np.float32), threshold=0.2)
    assert a.shape == frames.shape and s.shape == frames.shape[:3] and a.dtype == s.dtype == np.float32
    np.testing.assert_allclose(a * s[..., None], frames, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(np.percentile(a.reshape(2, -1), 99, axis=1), 1.0, rtol=1e-5)
    base = lmse(frames, albedo)
    assert lmse(a, albedo) < 0.05 * base
    # colour Retinex with the tuned grey threshold (2.0) leaves grey steps in the shading
    a_c, _ = color_retinex(frames.astype(np.float32))
    assert lmse(a_c, albedo) > 0.5 * base


def test_luminance_retinex_against_a_hand_computed_split():
    """One row: a ramp of small steps (shading) and one large step (reflectance)."""
    x = np.arange(12)
    shading = np.exp(0.02 * x)                      # log steps 0.02 < threshold
    albedo = np.where(x < 6, 0.2, 0.6)              # one log step 1.1 > threshold
    image = np.repeat((albedo * shading)[None, :, None], 3, axis=-1)      # (1, 12, 3)
    a, s = luminance_retinex(image, threshold=0.5)
    # the shading keeps every small step and drops the large one, with the shading's
    # own 0.02 that the large step carries: exp(0.02 x - 0.02 [x >= 6]) up to a scale
    expected = np.exp(0.02 * x - 0.02 * (x >= 6))
    ratio = s[0] / expected
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-5)
    np.testing.assert_allclose(a[0, :, 0] / a[0, 0, 0], albedo * shading / expected / (albedo[0] * shading[0]),
                               rtol=1e-5)


def test_luminance_retinex_keeps_the_input_chromaticity_in_the_albedo(rng):
    _, _, image = _blocks_times_smooth(rng, 31, 45, 7)
    a, s = luminance_retinex(image)
    chroma = lambda v: v / v.sum(-1, keepdims=True)           # noqa: E731
    np.testing.assert_allclose(chroma(a.astype(np.float64)), chroma(image), rtol=1e-5, atol=1e-7)
    a_default, _ = luminance_retinex(image, threshold=LUMINANCE_TUNED_THRESHOLD)
    np.testing.assert_array_equal(a, a_default)
    a1, s1 = luminance_retinex(image[None])
    np.testing.assert_array_equal(a1[0], a)


@pytest.mark.parametrize("kw, msg", [(dict(threshold=0.0), "threshold"), (dict(threshold=True), "threshold"),
                                     (dict(eps=-1.0), "eps")])
def test_luminance_retinex_rejects(kw, msg):
    with pytest.raises(ValueError, match=msg):
        luminance_retinex(np.full((4, 5, 3), 0.5), **kw)
