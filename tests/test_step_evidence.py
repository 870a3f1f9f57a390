"""Retinex's per-frame cue on Eq. 9's local term (ivkernels.solver.step_evidence)."""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.evaluation import synthetic
from ivkernels.solver.step_evidence import DARK_OFFSET, chromatic_share, grey_step_gate, step_evidence, step_gate


def _reference(log_image, tau, tau_chroma):
    """Pixel by pixel, pair by pair: the docstring's formula."""
    I = np.log(np.exp(np.asarray(log_image, np.float64)) + DARK_OFFSET)
    T, h, w, _ = I.shape
    out = np.zeros((T, h, w))
    for t in range(T):
        for y in range(h):
            for x in range(w):
                best = 0.0
                for dy in (-1, 0, 1):
                    for dx in (-1, 0, 1):
                        yy, xx = y + dy, x + dx
                        if (dy, dx) == (0, 0) or not (0 <= yy < h and 0 <= xx < w):
                            continue
                        a, b = I[t, y, x], I[t, yy, xx]
                        dL = abs(a.mean() - b.mean())
                        dC = np.abs((a - a.mean()) - (b - b.mean())).max()
                        ev = (1 - np.exp(-(dL / tau) ** 2)) * (np.exp(-(dC / tau_chroma) ** 2)
                                                               if np.isfinite(tau_chroma) else 1.0)
                        best = max(best, ev)
                out[t, y, x] = best
    return out


@pytest.mark.parametrize("shape", [(1, 5, 7), (2, 6, 3), (1, 1, 4)])
@pytest.mark.parametrize("tau_chroma", [0.05, np.inf])
def test_matches_the_formula_pair_by_pair(shape, tau_chroma):
    rng = np.random.default_rng(3)
    log_image = rng.normal(0, 0.2, shape + (3,)).astype(np.float32)
    got = step_evidence(log_image, 0.1, tau_chroma)
    np.testing.assert_allclose(got, _reference(log_image, 0.1, tau_chroma), atol=1e-5)


def test_chromatic_share_counts_the_sharp_steps_that_change_colour():
    grey = np.zeros((1, 4, 6, 3), np.float32)
    grey[:, :, 3:] = -1.0                                    # one grey step per row
    assert chromatic_share(grey, 0.1, 0.05) == 0.0
    coloured = grey.copy()
    coloured[:, 2:, :] += np.log(np.array([1.0, 0.5, 0.5], np.float32))    # a colour step between rows
    share = chromatic_share(coloured, 0.1, 0.05)
    # sharp pairs: 4 horizontal grey steps, 6 vertical colour steps (the grey step's pair counts once)
    assert share == pytest.approx(6 / 10)
    assert chromatic_share(np.zeros((1, 3, 3, 3), np.float32), 0.1, 0.05) == 0.0


def test_a_sharp_grey_step_counts_a_ramp_and_a_coloured_step_do_not():
    h, w = 8, 40
    x = np.arange(w, dtype=np.float32)
    grey_step = np.where(x < 20, 0.0, -1.0)[None, None, :, None] * np.ones((1, h, 1, 3), np.float32)
    ramp = (-x / w)[None, None, :, None] * np.ones((1, h, 1, 3), np.float32)      # same change, 40 px
    colour_step = grey_step * np.array([1.0, 0.2, 0.6], np.float32)             # chromaticity changes
    assert step_evidence(grey_step, 0.1, 0.05)[0, 4, 19] > 0.99
    assert step_evidence(ramp, 0.1, 0.05).max() < 0.07                     # 1 - exp(-(0.025 / 0.1)^2)
    assert step_evidence(colour_step, 0.1, 0.05).max() < 1e-6
    assert step_evidence(colour_step, 0.1, np.inf)[0, 4, 19] > 0.9         # without the chroma test it counts


def test_gate_is_one_plus_gain_times_evidence_and_checks_its_arguments():
    rng = np.random.default_rng(0)
    log_image = rng.normal(0, 0.3, (2, 5, 6, 3)).astype(np.float32)
    np.testing.assert_allclose(step_gate(log_image, 4.0, 0.1, 0.05),
                               1 + 4.0 * step_evidence(log_image, 0.1, 0.05), rtol=1e-6)
    assert np.all(step_gate(log_image, 0.0, 0.1) == 1.0)
    for bad in (dict(gain=-1.0, tau=0.1), dict(gain=1.0, tau=0.0), dict(gain=np.nan, tau=0.1),
                dict(gain=1.0, tau=0.1, tau_chroma=0.0)):
        with pytest.raises(ValueError):
            step_gate(log_image, **bad)


def test_grey_step_gate_scales_the_gain_by_the_grey_share():
    rng = np.random.default_rng(5)
    log_image = rng.normal(-1.0, 0.3, (2, 6, 9, 3)).astype(np.float32)
    share = chromatic_share(log_image, 0.1, 0.05)
    assert 0 < share < 1
    np.testing.assert_allclose(grey_step_gate(log_image, 8.0, 0.1, 0.05),
                               1 + 8.0 * (1 - share) ** 2 * step_evidence(log_image, 0.1, 0.05), rtol=1e-6)
    np.testing.assert_allclose(grey_step_gate(log_image, 8.0, 0.1), step_gate(log_image, 8.0, 0.1), rtol=1e-6)


def test_params_refuse_bad_step_settings():
    for field, value in (("shading_step_gain", -1.0), ("shading_step_tau", 0.0), ("shading_step_chroma", -0.1)):
        with pytest.raises(ValueError):
            iv.Params(**{field: value})


def test_a_grey_checkerboard_stays_in_the_albedo_with_the_cue():
    """Static grey checkerboard under smooth static light, no flow: without the
    cue the squares go into the shading; with it the albedo keeps them."""
    h, w, T = 48, 64, 2
    yy, xx = np.mgrid[0:h, 0:w]
    board = np.where(((yy // 8) + (xx // 8)) % 2 == 0, 0.7, 0.25).astype(np.float32)
    light = (0.4 + 0.6 * (xx / w)).astype(np.float32)
    frames = np.repeat((board * light)[None, :, :, None], 3, -1).repeat(T, 0)
    flow = np.zeros((T - 1, h, w, 2), np.float32)

    def board_contrast(params):
        albedo = iv.decompose(frames, flow=flow, params=params, flow_passes=1).albedo[0, ..., 1]
        dark, bright = board < 0.5, board > 0.5
        return float(np.median(albedo[dark]) / np.median(albedo[bright]))

    truth = 0.25 / 0.7
    with_cue = board_contrast(iv.Params(shading_step_gain=16.0))
    without = board_contrast(iv.Params(shading_step_gain=0.0))
    assert abs(with_cue - truth) < abs(without - truth)
    assert with_cue < 0.6


def _dark_disc(noise_channels: int):
    """Eight 48x64 still frames of a dark grey disc (albedo 0.08, radius 12) on a grey floor
    (0.5) with noise of std 0.003 drawn per colour channel (3) or shared by them (1); the
    disc's inside and the floor, 2 px from its edge; no flow (:func:`synthetic.dark_disc`)."""
    frames, inside, outside = synthetic.dark_disc((48, 64), 8, 12, 0.08, 0.003, per_channel=noise_channels == 3)
    return frames, np.zeros((7, 48, 64, 2), np.float32), inside, outside


def _disc_ratio(frames, flow, inside, outside, params):
    """Median albedo luminance inside the disc over that of the floor."""
    albedo = iv.decompose(frames, flow=flow, params=params, flow_passes=1).albedo.mean(-1)
    return float(np.median(albedo[:, inside]) / np.median(albedo[:, outside]))


def test_a_dark_grey_disc_under_colour_noise_stays_in_the_albedo():
    """A colour camera's noise in a dark grey material changes every pair's chromaticity
    and makes it step; read as it is, the disc's edge looks coloured and the step evidence
    lets the disc go into the shading.  Read net of the local noise floor
    (``Params.shading_step_noise``), the edge stays a grey step and the disc dark."""
    frames, flow, inside, outside = _dark_disc(noise_channels=3)
    truth = 0.08 / 0.5
    kept = _disc_ratio(frames, flow, inside, outside, iv.Params(shading_step_noise=2.5))
    lost = _disc_ratio(frames, flow, inside, outside, iv.Params(shading_step_noise=0.0))   # the steps as they are
    assert abs(kept - truth) < 0.1, kept
    assert lost > 0.6, lost          # what the floor is there for: without it the disc goes to the shading


def test_a_dark_grey_disc_in_greyscale_noise_stays_in_the_albedo():
    """Noise shared by the channels (greyscale footage) leaves the chromaticity alone."""
    frames, flow, inside, outside = _dark_disc(noise_channels=1)
    assert abs(_disc_ratio(frames, flow, inside, outside, iv.Params()) - 0.08 / 0.5) < 0.1


def reference_floor(offset, flow=None, cap=0.0):
    """The noise floor by the references: the twice-taken 5x5 median of the temporal steps
    (with a flow) or of the frame's own steps, capped at ``cap`` times the noise level
    function of the same steps (0: not capped).  Also the oracle of test_step_evidence_kernels."""
    from ivkernels.kernels.reference import median as ref_median
    from ivkernels.kernels.reference import step_evidence as ref
    from ivkernels.solver.step_evidence import NOISE_FLOOR_PASSES

    steps = ref.temporal_steps(offset, flow) if flow is not None and offset.shape[0] > 1 else ref.typical_steps(offset)
    table = ref.level_medians(ref.step_histogram(offset, steps.astype(np.float32))).astype(np.float32)
    for _ in range(NOISE_FLOOR_PASSES):
        steps = ref_median.median5x5(steps)
    return ref.cap_at_level(offset, table, cap, steps) if cap > 0 else steps


@pytest.mark.parametrize("cap", [0.0, 0.8, 3.0])
@pytest.mark.parametrize("backend_name", ["warp", "taichi", "numpy"])
def test_the_noise_floor_is_the_twice_taken_5x5_median_of_the_steps(backend_name, cap):
    """With a flow: of the changes between frames along it; one frame or none: of the frame's own
    steps; with a cap, capped at that many times the noise level function of the same steps."""
    from ivkernels.backends.registry import get_backend
    from ivkernels.solver.step_evidence import noise_floor

    be = get_backend(backend_name)
    rng = np.random.default_rng(4)
    offset = np.log(rng.uniform(0.02, 1.0, (3, 31, 33, 3))).astype(np.float32)
    flow = (rng.integers(-2, 3, (2, 31, 33, 2)) + rng.uniform(-0.4, 0.4, (2, 31, 33, 2))).astype(np.float32)
    got = be.numpy(noise_floor(be, be.asarray(offset), be.asarray(flow), cap))
    want = reference_floor(offset, flow, cap)
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6)
    if cap == 0.8:
        assert np.mean(got < reference_floor(offset, flow) - 1e-6) > 0.2          # the cap binds
    single = be.numpy(noise_floor(be, be.asarray(offset[:1]), be.asarray(flow[:0]), cap))
    np.testing.assert_allclose(single, reference_floor(offset[:1], None, cap), rtol=1e-4, atol=1e-6)
    without = be.numpy(noise_floor(be, be.asarray(offset), None, cap))
    np.testing.assert_allclose(without, reference_floor(offset, None, cap), rtol=1e-4, atol=1e-6)


def test_the_noise_floor_over_a_flow_sees_the_noise_and_not_the_print():
    """Fine print (a random grey pattern of one-pixel cells) moving one pixel a frame under
    noise new in every frame: the floor read from the change along the flow is the noise's
    (that of the noise alone on a flat grey), while the frame's own steps take the print for noise."""
    from ivkernels.backends.registry import get_backend
    from ivkernels.kernels.reference import step_evidence as ref
    from ivkernels.solver.step_evidence import noise_floor

    be = get_backend("warp")
    rng = np.random.default_rng(5)
    T, h, w, sigma = 4, 40, 56, 0.02
    print_ = np.log(np.where(rng.random((h, w + T)) < 0.5, 0.2, 0.6))
    frames = np.stack([print_[:, t: t + w] for t in range(T)])[..., None].repeat(3, -1)     # moves 1 px left a frame
    noise = rng.normal(0.0, sigma, (T, h, w, 3))
    flow = np.zeros((T - 1, h, w, 2), np.float32)
    flow[..., 0] = -1.0
    inner = (slice(None), slice(3, -3), slice(3, -4))                                    # clear of the frame's edge

    def floor_of(img, f=None):
        out = noise_floor(be, be.asarray(img.astype(np.float32)), None if f is None else be.asarray(f))
        return be.numpy(out)[inner]

    noise_only = floor_of(np.log(0.4) + noise)
    temporal = floor_of(frames + noise, flow)
    spatial = floor_of(frames + noise)
    for c in range(2):
        assert abs(np.median(temporal[..., c]) / np.median(noise_only[..., c]) - 1.0) < 0.15
        assert np.median(spatial[..., 0]) > 5 * np.median(temporal[..., 0])
    assert ref.temporal_steps(frames, flow)[inner].max() < 1e-12            # print alone: no change along the flow


def test_the_cap_keeps_a_region_where_the_flow_misses_from_reading_the_print_as_noise():
    """The same fine print under noise, its flow right on three quarters of the frame and zero
    (a miss) on the right quarter: there the local floor reads the print's change, many times
    the noise, while the cap at 3 times the noise level function holds it near the noise;
    where the flow is right the cap does not bind."""
    from ivkernels.backends.registry import get_backend
    from ivkernels.solver.step_evidence import noise_floor

    be = get_backend("warp")
    rng = np.random.default_rng(7)
    T, h, w, sigma = 4, 48, 64, 0.02
    print_ = np.log(np.where(rng.random((h, w + T)) < 0.5, 0.2, 0.6))
    frames = np.stack([print_[:, t: t + w] for t in range(T)])[..., None].repeat(3, -1)     # moves 1 px left a frame
    img = (frames + rng.normal(0.0, sigma, (T, h, w, 3))).astype(np.float32)
    flow = np.zeros((T - 1, h, w, 2), np.float32)
    flow[:, :, : 3 * w // 4, 0] = -1.0
    right = (slice(None), slice(3, -3), slice(3, 3 * w // 4 - 3))
    missed = (slice(None), slice(3, -3), slice(3 * w // 4 + 3, -3))
    noise_only = be.numpy(noise_floor(be, be.asarray((np.log(0.4) + rng.normal(0.0, sigma, img.shape))
                                                     .astype(np.float32))))
    local = be.numpy(noise_floor(be, be.asarray(img), be.asarray(flow)))
    capped = be.numpy(noise_floor(be, be.asarray(img), be.asarray(flow), 3.0))
    noise = np.median(noise_only[..., 0])
    assert np.median(local[missed][..., 0]) > 6 * noise                       # the print read as noise
    assert np.median(capped[missed][..., 0]) < 0.5 * np.median(local[missed][..., 0])
    assert np.median(capped[missed][..., 0]) < 3.0 * 1.5 * noise
    np.testing.assert_array_equal(np.median(capped[right], axis=(0, 1, 2)), np.median(local[right], axis=(0, 1, 2)))
