"""Colour Retinex baseline (Grosse et al. 2009) and its Poisson integration."""
import numpy as np
import pytest

from ivkernels.baselines import _poisson_neumann, color_retinex
from ivkernels.metrics import lmse


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
    (np.zeros((4, 5, 3), np.uint8), {}, TypeError, "to_linear_float"),
    (np.zeros((4, 5)), {}, ValueError, r"\(T, H, W, 3\)"),
    (np.zeros((2, 4, 5, 4)), {}, ValueError, r"\(T, H, W, 3\)"),
    (np.zeros((0, 4, 5, 3)), {}, ValueError, "empty"),
    (np.full((4, 5, 3), np.nan), {}, ValueError, "NaN"),
    (np.full((4, 5, 3), -0.5), {}, ValueError, ">= 0"),
    (np.ones((4, 5, 3)), {"threshold_gray": 0.0}, ValueError, "threshold_gray"),
    (np.ones((4, 5, 3)), {"threshold_color": np.nan}, ValueError, "threshold_color"),
    (np.ones((4, 5, 3)), {"eps": -1.0}, ValueError, "eps"),
])
def test_color_retinex_rejects(frames, kw, exc, msg):
    with pytest.raises(exc, match=msg):
        color_retinex(frames, **kw)


def test_color_retinex_beats_image_on_synthetic_sequences():
    """Averaged over the synthetic kinds, as the paper's baseline comparison needs."""
    from ivkernels import synthetic

    ours, base = [], []
    for kind in synthetic.KINDS:
        seq = synthetic.render_sequence(kind, n_frames=3, size=(60, 80), seed=0)
        a, _ = color_retinex(seq.frames)
        ours.append(lmse(a, seq.albedo))
        base.append(lmse(seq.frames, seq.albedo))
    assert np.mean(ours) < np.mean(base)
