"""Edge-preserving smoothing at the noise level (kernels/*/denoise.py): the generic contract from
the case table, plus what the filter is for: noise averaged out, a step far above the range kept,
a constant layer and a zero range left as they are, and the conversion of the noise's step."""
import numpy as np
import pytest

from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

from ivkernels.kernels.reference import denoise as ref

TestContract = contract("denoise")

T, H, W = 2, 29, 37


def bilateral(be, src, rs, radius=3, sigma_space=2.0):
    out = be.zeros(src.shape)
    be.denoise.bilateral(be.asarray(src), be.asarray(rs), out, radius, sigma_space)
    return be.numpy(out).copy()


def test_noise_averages_out_and_a_large_step_stays(kernel_backend, rng):
    clean = np.zeros((T, H, W, 1), np.float32)
    clean[:, :, W // 2:] = -1.5                       # a step of 1.5 log units down the middle
    noisy = clean + rng.normal(0.0, 0.1, clean.shape).astype(np.float32)
    out = bilateral(kernel_backend, noisy, np.full((T, H, W), 0.2, np.float32))
    left, right = out[:, 3:-3, 3:W // 2 - 4], out[:, 3:-3, W // 2 + 4:-3]
    # 7x7 window at sigma_space 2: the noise's deviation falls to under a third
    assert (left - 0.0).std() < 0.1 / 3 and (right + 1.5).std() < 0.1 / 3
    # the step keeps its size: the sides do not mix
    assert abs(out[:, :, W // 2 - 1].mean() - 0.0) < 0.05
    assert abs(out[:, :, W // 2].mean() + 1.5) < 0.05


def test_constant_layer_and_zero_range_are_kept(kernel_backend, rng):
    const = np.full((T, H, W, 3), -0.7, np.float32)
    np.testing.assert_allclose(bilateral(kernel_backend, const, np.full((T, H, W), 0.5, np.float32)), const,
                               atol=1e-6)
    src = rng.normal(0.0, 1.0, (T, H, W, 3)).astype(np.float32)
    rs = np.zeros((T, H, W), np.float32)
    rs[0, 5, 7] = np.nan
    rs[1, 2, 3] = -1.0
    assert np.array_equal(bilateral(kernel_backend, src, rs), src)


def test_range_sigma_converts_a_step_of_the_offset_log(kernel_backend):
    offset = 0.02
    brightness = np.array([0.5, 0.1, 0.02, 0.001], np.float32)       # the last is held at offset / 10
    img = np.log(brightness + offset)[None, None, :, None].repeat(3, axis=-1).astype(np.float32)
    level = np.zeros((1, 1, 4, 2), np.float32)
    level[..., 0] = 0.01
    out = kernel_backend.zeros((1, 1, 4))
    kernel_backend.denoise.range_sigma(kernel_backend.asarray(img), kernel_backend.asarray(level), out, 2.0, offset)
    got = kernel_backend.numpy(out)[0, 0]
    want = 2.0 * 0.01 * (brightness + offset) / np.maximum(brightness, offset / 10)
    np.testing.assert_allclose(got, want, rtol=1e-5)
    np.testing.assert_allclose(got[-1], 2.0 * 0.01 * 0.021 / 0.002, rtol=1e-5)
    np.testing.assert_allclose(ref.range_sigma(img, level, 2.0, offset)[0, 0], want, rtol=1e-6)


def test_more_than_three_channels_are_refused(kernel_backend):
    src = kernel_backend.zeros((1, 4, 5, 4))
    with pytest.raises(ValueError, match="1 to 3 channels"):
        kernel_backend.denoise.bilateral(src, kernel_backend.zeros((1, 4, 5)), kernel_backend.zeros((1, 4, 5, 4)), 1, 1.0)
