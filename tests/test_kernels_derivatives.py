"""Image and flow derivatives (kernels/*/derivatives.py): the generic contract from the case
table, plus exact slopes of a ramp, replicate borders, hand-computed flow maps, bad input."""
import numpy as np
import pytest

from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("derivatives")

T, H, W = 2, 37, 53


def gradient(be, src):
    gx, gy = be.zeros(src.shape), be.zeros(src.shape)
    be.derivatives.image_gradient(be.asarray(src), gx, gy)
    return be.numpy(gx).copy(), be.numpy(gy).copy()


def flow_map(be, fn, flow):
    out = be.zeros(flow.shape[:3])
    getattr(be.derivatives, fn)(be.asarray(flow), out)
    return be.numpy(out).copy()


def test_image_gradient_of_ramp_and_borders(kernel_backend):
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    src = np.stack([2 * xx - 3 * yy, xx * 0 + 5], -1)[None]
    gx, gy = gradient(kernel_backend, src)
    np.testing.assert_allclose(gx[0, :, 2:-2, 0], 2, rtol=1e-6)     # interior: exact slope
    np.testing.assert_allclose(gy[0, 2:-2, :, 0], -3, rtol=1e-6)
    np.testing.assert_allclose(gx[0, :, 0, 0], (8 * 2 - 4) / 12, rtol=1e-6)   # replicate border
    np.testing.assert_array_equal(gx[..., 1], 0)                     # constant: exactly zero


def test_flow_maps_hand_cases(kernel_backend):
    be = kernel_backend
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    expanding = np.stack([0.1 * xx, 0.2 * yy], -1)[None]
    np.testing.assert_array_equal(flow_map(be, "divergence_negative", expanding), 0)
    contracting = -expanding
    d = flow_map(be, "divergence_negative", contracting)
    np.testing.assert_allclose(d[0, 1:-1, 1:-1], -0.3, rtol=1e-5)
    np.testing.assert_allclose(d[0, 0, 0], -0.15, rtol=1e-5)   # one-sided differences halve at a corner
    mag = flow_map(be, "flow_sobel_magnitude", expanding)
    np.testing.assert_allclose(mag[0, 1:-1, 1:-1], np.hypot(0.1, 0.2), rtol=1e-5)
    step = np.zeros((1, H, W, 2), np.float32)
    step[0, :, W // 2:, 0] = 4.0
    mag = flow_map(be, "flow_sobel_magnitude", step)
    np.testing.assert_allclose(mag[0, 5, W // 2 - 1:W // 2 + 1], 2.0, rtol=1e-6)
    assert mag[0, 5, : W // 2 - 1].max() == 0 and mag[0, 5, W // 2 + 1:].max() == 0


def test_bad_input_raises(kernel_backend):
    be = kernel_backend
    d = be.derivatives
    with pytest.raises(ValueError, match="gy"):
        d.image_gradient(be.zeros((T, H, W, 3)), be.zeros((T, H, W, 3)), be.zeros((T, H, W, 2)))
    with pytest.raises(ValueError, match="flow"):
        d.flow_sobel_magnitude(be.zeros((T, H, W, 3)), be.zeros((T, H, W)))
    with pytest.raises(ValueError, match="out"):
        d.divergence_negative(be.zeros((T, H, W, 2)), be.zeros((T, H, W, 1)))
    with pytest.raises(TypeError, match="float32"):
        d.divergence_negative(be.zeros((T, H, W, 2), np.float64), be.zeros((T, H, W)))
