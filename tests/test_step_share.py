"""The chromatic share of the step evidence read around each pixel
(ivkernels.solver.step_evidence.local_chromatic_share, Params.shading_step_share_radius)."""
import numpy as np
import pytest

from ivkernels.solver.step_evidence import (DARK_OFFSET, SHARE_PRIOR_STEPS, chromatic_share, grey_step_gate,
                                            local_chromatic_share, step_evidence)


def _reference(log_image, tau, tau_chroma, radius):
    """Pixel by pixel: count the sharp and the chromatic steps to the right and below
    of every pixel in the window, add the prior, divide."""
    I = np.log(np.exp(np.asarray(log_image, np.float64)) + DARK_OFFSET)
    T, h, w, _ = I.shape
    sharp = np.zeros((T, h, w))
    chrom = np.zeros((T, h, w))
    for t in range(T):
        for y in range(h):
            for x in range(w):
                for yy, xx in ((y, x + 1), (y + 1, x)):
                    if yy >= h or xx >= w:
                        continue
                    a, b = I[t, y, x], I[t, yy, xx]
                    dC = np.abs((a - a.mean()) - (b - b.mean())).max()
                    is_chrom = dC > tau_chroma
                    sharp[t, y, x] += is_chrom or abs(a.mean() - b.mean()) > tau
                    chrom[t, y, x] += is_chrom
    whole = chrom.sum() / sharp.sum() if sharp.sum() else 0.0
    r = max(1, int(round(radius * min(h, w))))
    out = np.zeros((T, h, w))
    for t in range(T):
        for y in range(h):
            for x in range(w):
                win = (t, slice(max(0, y - r), y + r + 1), slice(max(0, x - r), x + r + 1))
                out[t, y, x] = (chrom[win].sum() + SHARE_PRIOR_STEPS * whole) / (sharp[win].sum() + SHARE_PRIOR_STEPS)
    return out


@pytest.mark.parametrize("shape, radius", [((1, 7, 9), 0.3), ((2, 5, 3), 0.5), ((1, 1, 6), 0.1), ((1, 9, 4), 1.0)])
def test_matches_the_count_pixel_by_pixel(shape, radius):
    rng = np.random.default_rng(5)
    log_image = rng.normal(0, 0.15, shape + (3,)).astype(np.float32)
    got = local_chromatic_share(log_image, 0.1, 0.05, radius)
    assert got.shape == shape and got.dtype == np.float32
    np.testing.assert_allclose(got, _reference(log_image, 0.1, 0.05, radius), atol=1e-6)


def _grey_floor_beside_coloured_stripes(h=40, w=80):
    """Left half: grey checkerboard; right half: coloured stripes; (1, h, w, 3) log image."""
    y, x = np.mgrid[:h, :w]
    img = np.where(((y // 5) + (x // 5)) % 2 == 0, 0.8, 0.3)[..., None] * np.ones(3)
    colours = np.array([[0.8, 0.2, 0.2], [0.2, 0.7, 0.3], [0.3, 0.3, 0.9]])
    right = x >= w // 2
    img[right] = colours[(x[right] // 4) % 3]
    return np.log(img[None]).astype(np.float32)


def test_a_grey_floor_keeps_its_own_low_share_beside_coloured_stripes():
    log_image = _grey_floor_beside_coloured_stripes()
    whole = chromatic_share(log_image, 0.1, 0.05)
    local = local_chromatic_share(log_image, 0.1, 0.05, 0.2)
    assert 0.3 < whole < 0.8
    assert local[0, 20, 5] < 0.1            # deep in the grey half
    assert local[0, 20, 75] > 0.9           # deep in the coloured half
    # the gate: the floor's grey steps get (nearly) the whole gain only when read locally
    gate_local = grey_step_gate(log_image, 8.0, 0.1, 0.05, share_radius=0.2)
    gate_whole = grey_step_gate(log_image, 8.0, 0.1, 0.05)
    ev = step_evidence(log_image, 0.1, 0.05)
    edge = (0, 20, 4)                       # on a checker edge of the grey half
    assert ev[edge] > 0.9
    assert gate_local[edge] > 1 + 8.0 * 0.8 * ev[edge]
    assert gate_whole[edge] < 1 + 8.0 * (1 - whole) ** 2 * ev[edge] + 1e-5


def test_a_grey_video_has_no_chromatic_share_anywhere():
    rng = np.random.default_rng(1)
    grey = np.repeat(rng.normal(0, 0.3, (2, 11, 13, 1)), 3, axis=-1).astype(np.float32)
    assert np.all(local_chromatic_share(grey, 0.1, 0.05, 0.2) == 0.0)
    assert np.all(local_chromatic_share(np.zeros((1, 4, 4, 3), np.float32), 0.1, 0.05, 0.2) == 0.0)


def test_radius_zero_is_the_whole_videos_share_bit_for_bit():
    rng = np.random.default_rng(2)
    log_image = rng.normal(0, 0.3, (2, 6, 9, 3)).astype(np.float32)
    share = chromatic_share(log_image, 0.1, 0.05)
    expected = (1.0 + 8.0 * (1.0 - share) ** 2 * step_evidence(log_image, 0.1, 0.05)).astype(np.float32)
    assert np.array_equal(grey_step_gate(log_image, 8.0, 0.1, 0.05, share_radius=0.0), expected)


@pytest.mark.parametrize("bad", [-0.1, np.nan, np.inf])
def test_a_bad_radius_is_refused(bad):
    with pytest.raises(ValueError, match="share_radius"):
        grey_step_gate(np.zeros((1, 3, 3, 3), np.float32), 8.0, 0.1, 0.05, share_radius=bad)
