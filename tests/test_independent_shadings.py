"""The window's number of independent shadings (ivkernels.solver.independent_shadings).

Frames are built from a known albedo and known shadings, so the answer is
known: the same shading twice is one draw, unrelated shadings are ``T``,
a global change of the light's strength is no new shading, and a moving
camera under one light is one draw once the flow is followed.  Every
backend must give the NumPy backend's number, and ``decompose`` must divide
both albedo priors by it.
"""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.backends import get_backend
from ivkernels.solver.independent_shadings import (CHANGE_BLUR_PX, LIT_LUMINANCE, MAD_TO_STD,
                                                   SHADING_CHANGE_FLOOR, independent_shadings,
                                                   shading_change_ratios)

H, W = 45, 61          # odd sizes


def smooth_field(rng, scale=1.0, cells=4):
    """A smooth random log field (H, W): bilinear up-sampling of a coarse random grid."""
    coarse = rng.normal(0.0, scale, (cells + 1, cells + 1))
    y = np.linspace(0, cells, H)[:, None]
    x = np.linspace(0, cells, W)[None, :]
    y0, x0 = np.minimum(y.astype(int), cells - 1), np.minimum(x.astype(int), cells - 1)
    fy, fx = y - y0, x - x0
    return ((1 - fy) * (1 - fx) * coarse[y0, x0] + (1 - fy) * fx * coarse[y0, x0 + 1]
            + fy * (1 - fx) * coarse[y0 + 1, x0] + fy * fx * coarse[y0 + 1, x0 + 1])


def frames_from(log_albedo, log_shadings):
    """Linear frames (T, H, W, 3) float32 = exp(A + S_t), A (H, W, 3), S_t (T, H, W)."""
    return np.exp(log_albedo[None] + log_shadings[..., None]).astype(np.float32)


@pytest.fixture
def scene(rng):
    """A fine random albedo (pixel noise, so the blur removes it) around 0.3, as log."""
    return np.log(0.3) + rng.uniform(-0.3, 0.3, (H, W, 3))


def count(be_name, frames, flow=None, gain=1.0):
    be = get_backend(be_name)
    if flow is None:
        flow = np.zeros((frames.shape[0] - 1, H, W, 2), np.float32)
    return independent_shadings(be, be.asarray(frames), be.asarray(flow), gain, 1e-4)


def test_one_light_is_one_shading(any_backend, rng, scene):
    S = np.repeat(smooth_field(rng)[None], 5, axis=0)
    assert count(any_backend.name, frames_from(scene, S)) == pytest.approx(1.0, abs=1e-6)


def test_unrelated_shadings_count_nearly_each_frame(any_backend, rng, scene):
    T = 6
    S = np.stack([smooth_field(rng) for _ in range(T)])
    n = count(any_backend.name, frames_from(scene, S))
    assert 0.7 * T < n <= T


def test_a_stronger_light_is_no_new_shading(any_backend, rng, scene):
    S = smooth_field(rng)[None] + np.array([0.0, 0.4, -0.3, 0.8])[:, None, None]
    assert count(any_backend.name, frames_from(scene, S)) == pytest.approx(1.0, abs=1e-6)


def test_a_moving_camera_under_one_light_is_one_shading_once_the_flow_is_followed(rng):
    """The scene (albedo and shading) moves 3 px right per frame; the true flow undoes it."""
    T, shift = 4, 3
    big_A = np.log(0.3) + rng.uniform(-0.3, 0.3, (H, W + T * shift, 3))
    big_S = np.concatenate([smooth_field(rng), smooth_field(rng)], axis=1)[:, :W + T * shift]
    frames = np.stack([np.exp(big_A + big_S[..., None])[:, (T - t) * shift:(T - t) * shift + W]
                       for t in range(T)]).astype(np.float32)
    flow = np.zeros((T - 1, H, W, 2), np.float32)
    flow[..., 0] = shift                     # frame t at x is frame t+1 at x + shift
    assert count("numpy", frames, flow) == pytest.approx(1.0, abs=1e-6)
    assert count("numpy", frames) > 1.2      # without the flow the motion looks like new light


def test_ratios_match_a_direct_computation(any_backend, rng, scene):
    """r_t against the formula on NumPy arrays (zero flow, a dark corner left out)."""
    from ivkernels.kernels.reference.pyramid import gaussian_blur

    T = 4
    S = np.stack([smooth_field(rng, scale=s) for s in (0.5, 0.2, 0.05, 0.3)])
    frames = frames_from(scene, S)
    frames[:, :10, :12] = 0.001                              # below LIT_LUMINANCE
    be = get_backend(any_backend.name)
    got = shading_change_ratios(be, be.asarray(frames), be.zeros((T - 1, H, W, 2)), 1e-4)
    L = np.log(np.maximum(frames.astype(np.float64) @ [0.2126, 0.7152, 0.0722], 1e-4))
    B = gaussian_blur(L[..., None], CHANGE_BLUR_PX)[..., 0]

    def robust_var(v):
        return (MAD_TO_STD * np.median(np.abs(v - np.median(v)))) ** 2

    for t in range(T - 1):
        use = (B[t] >= np.log(LIT_LUMINANCE)) & (B[t + 1] >= np.log(LIT_LUMINANCE))
        want = max(0.0, 1.0 - SHADING_CHANGE_FLOOR / robust_var((B[t + 1] - B[t])[use]))
        assert got[t] == pytest.approx(want, rel=0.05, abs=1e-3)
    assert got.max() > 0.5                                   # the case holds a large change


def test_pixel_noise_is_no_new_shading(any_backend, rng, scene):
    """One lamp seen through a noisy camera (2% of white on a dim scene, about 0.1) counts once."""
    S = np.repeat(smooth_field(rng, scale=0.3)[None], 5, axis=0)
    frames = 0.3 * frames_from(scene, S)
    noisy = np.clip(frames + rng.normal(0.0, 0.02, frames.shape), 0.0, 1.0).astype(np.float32)
    assert count(any_backend.name, noisy) == pytest.approx(1.0, abs=0.05)


def test_a_change_below_the_floor_is_no_new_shading(any_backend, rng, scene):
    """Shadings that differ by less than flow error and a slow lamp give count once."""
    base = smooth_field(rng)
    floor_std = np.sqrt(SHADING_CHANGE_FLOOR)
    S = np.stack([base + 0.3 * floor_std * smooth_field(rng) for _ in range(5)])
    assert count(any_backend.name, frames_from(scene, S)) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("case", ["no flow", "gain 0", "one frame", "all dark"])
def test_the_count_is_one_where_nothing_can_be_read(rng, scene, case):
    be = get_backend("numpy")
    S = np.stack([smooth_field(rng) for _ in range(3)])
    frames = frames_from(scene, S)
    flow, gain = be.zeros((2, H, W, 2)), 1.0
    if case == "no flow":
        flow = None
    elif case == "gain 0":
        gain = 0.0
    elif case == "one frame":
        frames, flow = frames[:1], be.zeros((0, H, W, 2))
    else:
        frames = np.full_like(frames, 0.005)
    assert independent_shadings(be, be.asarray(frames), flow, gain, 1e-4) == 1.0


def test_the_gain_scales_the_count_and_t_caps_it(rng, scene):
    S = np.stack([smooth_field(rng, scale=0.3) for _ in range(5)])
    frames = frames_from(scene, S)
    n1 = count("numpy", frames, gain=1.0)
    assert 1.0 < n1 < 5.0
    assert count("numpy", frames, gain=0.5) == pytest.approx(1.0 + 0.5 * (n1 - 1.0))
    assert count("numpy", frames, gain=100.0) == 5.0


def test_decompose_divides_both_albedo_priors_by_the_count(rng, scene, monkeypatch):
    """The solve sees lam_As / n and lam_Ap / n; the ablation and gain 0 see the caller's weights."""
    from ivkernels.solver import energy

    T = 3
    S = np.stack([smooth_field(rng) for _ in range(T)])
    frames = np.clip(frames_from(scene, S), 0.0, 1.0)
    params = iv.Params(lam_albedo_smooth=0.9, lam_albedo_sparsity=0.5, lbfgs_iterations=2,
                       outer_iterations=1, coarse_basis_spacing=0)
    seen = []
    real_init = energy.WindowEnergy.__init__

    def spy(self, be, log_image, w_lum, flow, occlusion, boundary, p, *args, **kwargs):
        seen.append((p.lam_albedo_smooth, p.lam_albedo_sparsity))
        real_init(self, be, log_image, w_lum, flow, occlusion, boundary, p, *args, **kwargs)

    monkeypatch.setattr(energy.WindowEnergy, "__init__", spy)
    zero = np.zeros((T - 1, H, W, 2), np.float32)
    video = iv.decompose(frames, flow=zero, params=params)
    (n,) = video.diagnostics["independent_shadings"]
    assert n > 1.5
    # The guide solve counts on its own, half-size frames: the same count to a fraction of a percent.
    assert seen and all(s == pytest.approx((0.9 / n, 0.5 / n), rel=0.01) for s in seen)

    for kwargs in ({"temporal": False}, {"flow": zero, "params": params.replace(independent_shading_gain=0.0)}):
        seen.clear()
        video = iv.decompose(frames, **{"params": params, **kwargs})
        assert video.diagnostics["independent_shadings"] == [1.0]
        assert seen and all(s == (0.9, 0.5) for s in seen)


def test_a_window_that_carries_frames_counts_as_a_full_window(rng, scene):
    """``n_frames`` sets the T of the count; the ratios are still the window's own."""
    S = np.stack([smooth_field(rng, scale=0.3) for _ in range(3)])
    be = get_backend("numpy")
    args = (be, be.asarray(frames_from(scene, S)), be.zeros((2, H, W, 2)), 1.0, 1e-4)
    own = independent_shadings(*args)
    assert 1.0 < own < 3.0
    assert independent_shadings(*args, n_frames=8) == pytest.approx(min(8.0, 1.0 + (own - 1.0) * 7 / 2))
