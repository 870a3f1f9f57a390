"""Illumination-robust data terms of Classic+NL (log grey, soft census, multi-channel
constancy) in kernels/*/flow_classic.py; their generic contract (against the NumPy
reference) runs with the family's in test_kernels_flow_classic.py.  Here: the log floor, a
gain becoming an offset, a hand-computed census with its border, offsets ignored, one
channel equal to the brightness term, the gradient feature of a ramp, bad input."""
import numpy as np
import pytest

from kernel_harness import call_host, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

T, H, W = 2, 23, 37          # odd sizes: the red-black and border paths both run


def run(be, name, inputs, outputs, *params):
    """``be.flow_classic.<name>(*inputs, *outputs, *params)`` on copies; the outputs as NumPy."""
    return call_host(be, "flow_classic", name, inputs, outputs, *params)


def channel_system(rng, c, t=T, h=H, w=W):
    first = rng.normal(scale=20, size=(t, h, w, 3 * c)).astype(np.float32)
    warped = (first + rng.normal(scale=4, size=first.shape)).astype(np.float32)
    inside = (rng.random((t, h, w)) > 0.1).astype(np.float32)
    du = rng.normal(scale=0.3, size=(t, h, w, 2)).astype(np.float32)
    weights = rng.uniform(0.2, 2.0, c).astype(np.float32)
    return first, warped, inside, du, weights


def test_log_grey_floor(kernel_backend, rng):
    rgb = rng.uniform(0, 1, (T, H, W, 3)).astype(np.float32)
    rgb[0, 0, :3] = 0.0                                  # below the floor
    out = run(kernel_backend, "log_grey", [rgb], [np.zeros((T, H, W))], 1e-3)
    np.testing.assert_allclose(out[0, 0, :3], np.log(1e-3), rtol=1e-6)


def test_log_grey_turns_a_gain_into_an_offset(kernel_backend, rng):
    rgb = rng.uniform(0.05, 0.5, (1, H, W, 3)).astype(np.float32)
    a = run(kernel_backend, "log_grey", [rgb], [np.zeros((1, H, W))])
    b = run(kernel_backend, "log_grey", [1.7 * rgb], [np.zeros((1, H, W))])
    np.testing.assert_allclose(b - a, np.log(1.7), atol=1e-5)


def test_soft_census_tiny_case_and_border(kernel_backend):
    img = np.array([[[0.0, 3.0], [4.0, 0.0]]], np.float32)       # (1, 2, 2)
    out = run(kernel_backend, "soft_census", [img], [np.zeros((1, 2, 2, 8))], 1, 4.0, 1.0)
    # pixel (0, 0): offsets (-1,-1) (-1,0) (-1,1) (0,-1) (0,1) (1,-1) (1,0) (1,1), replicate border
    d = np.array([0, 0, 3, 0, 3, 4, 4, 0], np.float64)
    np.testing.assert_allclose(out[0, 0, 0], d / np.sqrt(d * d + 16.0), atol=1e-6)


def test_soft_census_ignores_gain_on_flat_and_offset(kernel_backend, rng):
    img = rng.uniform(50, 200, (1, H, W)).astype(np.float32)
    a = run(kernel_backend, "soft_census", [img], [np.zeros((1, H, W, 8))], 1, 1e-3, 1.0)
    b = run(kernel_backend, "soft_census", [img + 30.0], [np.zeros((1, H, W, 8))], 1, 1e-3, 1.0)
    np.testing.assert_allclose(a, b, atol=1e-3)


def test_one_channel_equals_brightness_term(kernel_backend, rng):
    """One channel of weight 1 is Classic+NL's brightness-constancy term."""
    first, warped, inside, du, _ = channel_system(rng, 1)
    weights = np.ones(1, np.float32)
    out = run(kernel_backend, "data_coefficients_channels", [first, warped, inside, du, weights],
              [np.zeros((T, H, W, 5))])
    single = run(kernel_backend, "data_coefficients", [first[..., 0], first[..., 1], first[..., 2], warped, inside, du],
                 [np.zeros((T, H, W, 5))])
    np.testing.assert_allclose(out, single, rtol=1e-6, atol=1e-6 * np.abs(single).max())


def test_bad_input_raises(kernel_backend):
    be = kernel_backend
    with pytest.raises(ValueError, match="shape"):
        be.flow_classic.soft_census(be.zeros((T, H, W)), be.zeros((T, H, W, 9)), 1, 4.0, 1.0)
    with pytest.raises(ValueError, match="radius"):
        be.flow_classic.soft_census(be.zeros((T, H, W)), be.zeros((T, H, W, 8)), 0, 4.0, 1.0)
    with pytest.raises(ValueError, match="eps"):
        be.flow_classic.soft_census(be.zeros((T, H, W)), be.zeros((T, H, W, 8)), 1, 0.0, 1.0)
    with pytest.raises(ValueError, match="shape"):
        be.flow_classic.data_coefficients_channels(be.zeros((T, H, W, 6)), be.zeros((T, H, W, 6)),
                                                   be.zeros((T, H, W)), be.zeros((T, H, W, 2)),
                                                   be.zeros((3,)), be.zeros((T, H, W, 5)))
    with pytest.raises(ValueError, match="floor"):
        be.flow_classic.log_grey(be.zeros((T, H, W, 3)), be.zeros((T, H, W)), 0.0)


def test_gradient_feature_of_a_ramp(kernel_backend):
    """The gradient-constancy feature as the flow builds it: image_gradient, then pack_gradient."""
    ramp = np.broadcast_to(2.5 * np.arange(W, dtype=np.float32)[:, None], (1, H, W, 1)).copy()
    zeros = np.zeros((1, H, W, 1))
    gx, gy = call_host(kernel_backend, "derivatives", "image_gradient", [ramp], [zeros, zeros])
    g = run(kernel_backend, "pack_gradient", [gx[..., 0], gy[..., 0]], [np.zeros((1, H, W, 2))])
    np.testing.assert_array_equal(g, np.concatenate([gx, gy], axis=-1))
    np.testing.assert_allclose(g[0, :, 2:-2, 0], 2.5, rtol=1e-5)
    np.testing.assert_allclose(g[..., 1], 0.0, atol=1e-6)
