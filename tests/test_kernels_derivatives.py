"""Image and flow derivatives (kernels/*/derivatives.py)."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import derivatives as ref

T, H, W = 2, 37, 53


def gradient(be, src):
    gx, gy = be.zeros(src.shape), be.zeros(src.shape)
    be.derivatives.image_gradient(be.asarray(src), gx, gy)
    return be.numpy(gx).copy(), be.numpy(gy).copy()


def flow_map(be, fn, flow):
    out = be.zeros(flow.shape[:3])
    getattr(be.derivatives, fn)(be.asarray(flow), out)
    return be.numpy(out).copy()


@pytest.mark.parametrize("channels", [1, 3])
def test_image_gradient_matches_reference(backend, rng, channels):
    src = rng.random((T, H, W, channels), dtype=np.float32)
    gx, gy = gradient(backend, src)
    want_x, want_y = ref.image_gradient(src)
    np.testing.assert_allclose(gx, want_x, atol=1e-6)
    np.testing.assert_allclose(gy, want_y, atol=1e-6)


def test_image_gradient_of_ramp_and_borders(backend):
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    src = np.stack([2 * xx - 3 * yy, xx * 0 + 5], -1)[None]
    gx, gy = gradient(backend, src)
    np.testing.assert_allclose(gx[0, :, 2:-2, 0], 2, rtol=1e-6)     # interior: exact slope
    np.testing.assert_allclose(gy[0, 2:-2, :, 0], -3, rtol=1e-6)
    np.testing.assert_allclose(gx[0, :, 0, 0], (8 * 2 - 4) / 12, rtol=1e-6)   # replicate border
    np.testing.assert_array_equal(gx[..., 1], 0)                     # constant: exactly zero


def test_flow_maps_match_reference(backend, rng):
    flow = rng.normal(scale=2.0, size=(T, H, W, 2)).astype(np.float32)
    np.testing.assert_allclose(flow_map(backend, "flow_sobel_magnitude", flow),
                               ref.flow_sobel_magnitude(flow), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(flow_map(backend, "divergence_negative", flow),
                               ref.divergence_negative(flow), atol=1e-6)


def test_flow_maps_hand_cases(backend):
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    expanding = np.stack([0.1 * xx, 0.2 * yy], -1)[None]
    np.testing.assert_array_equal(flow_map(backend, "divergence_negative", expanding), 0)
    contracting = -expanding
    d = flow_map(backend, "divergence_negative", contracting)
    np.testing.assert_allclose(d[0, 1:-1, 1:-1], -0.3, rtol=1e-5)
    np.testing.assert_allclose(d[0, 0, 0], -0.15, rtol=1e-5)   # one-sided differences halve at a corner
    mag = flow_map(backend, "flow_sobel_magnitude", expanding)
    np.testing.assert_allclose(mag[0, 1:-1, 1:-1], np.hypot(0.1, 0.2), rtol=1e-5)
    step = np.zeros((1, H, W, 2), np.float32)
    step[0, :, W // 2:, 0] = 4.0
    mag = flow_map(backend, "flow_sobel_magnitude", step)
    np.testing.assert_allclose(mag[0, 5, W // 2 - 1:W // 2 + 1], 2.0, rtol=1e-6)
    assert mag[0, 5, : W // 2 - 1].max() == 0 and mag[0, 5, W // 2 + 1:].max() == 0


def test_non_contiguous_input(backend, rng):
    big = rng.random((T, H, W, 4), dtype=np.float32)
    gx, gy = backend.zeros((T, H, W, 2)), backend.zeros((T, H, W, 2))
    backend.derivatives.image_gradient(backend.asarray(big)[:, :, :, 1:3], gx, gy)
    want_x, want_y = ref.image_gradient(big[..., 1:3])
    np.testing.assert_allclose(backend.numpy(gx), want_x, atol=1e-6)
    np.testing.assert_allclose(backend.numpy(gy), want_y, atol=1e-6)


def test_bad_input_raises(backend):
    d = backend.derivatives
    with pytest.raises(ValueError, match="gy"):
        d.image_gradient(backend.zeros((T, H, W, 3)), backend.zeros((T, H, W, 3)), backend.zeros((T, H, W, 2)))
    with pytest.raises(ValueError, match="flow"):
        d.flow_sobel_magnitude(backend.zeros((T, H, W, 3)), backend.zeros((T, H, W)))
    with pytest.raises(ValueError, match="out"):
        d.divergence_negative(backend.zeros((T, H, W, 2)), backend.zeros((T, H, W, 1)))
    with pytest.raises(TypeError, match="float32"):
        d.divergence_negative(backend.zeros((T, H, W, 2), np.float64), backend.zeros((T, H, W)))


def test_warp_and_taichi_agree(rng):
    src = rng.random((T, H, W, 3), dtype=np.float32)
    flow = rng.normal(size=(T, H, W, 2)).astype(np.float32)
    wb, tb = get_backend("warp"), get_backend("taichi")
    for a, b in zip(gradient(wb, src), gradient(tb, src)):
        np.testing.assert_allclose(a, b, atol=1e-6)
    for fn in ("flow_sobel_magnitude", "divergence_negative"):
        np.testing.assert_allclose(flow_map(wb, fn, flow), flow_map(tb, fn, flow), rtol=1e-5, atol=1e-6)


def test_one_and_two_threads_agree(rng):
    be = get_backend("warp")
    src = rng.random((3, H, W, 2), dtype=np.float32)
    res = []
    for n in (1, 2):
        with threads(n):
            res.append([*gradient(be, src), flow_map(be, "flow_sobel_magnitude", src),
                        flow_map(be, "divergence_negative", src)])
    for a, b in zip(*res):
        np.testing.assert_array_equal(a, b)
