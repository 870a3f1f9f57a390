"""Colour conversions (kernels/*/colour.py): the generic contract from the case table, plus
flat buffers of any shape, invertibility and continuity of the curves, known Lab values,
the log floor, bad input."""
import cv2
import numpy as np
import pytest

from ivkernels.kernels.reference import colour as ref
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("colour")

SHAPE = (2, 37, 53, 3)


def apply(be, fn, src, out_shape=None, *args):
    out = be.zeros(src.shape if out_shape is None else out_shape)
    getattr(be.colour, fn)(be.asarray(src), out, *args)
    return be.numpy(out).copy()


@pytest.mark.parametrize("shape", [(1,), (5, 7), (4099 * 3,)])
def test_transfer_curves_on_flat_buffers_of_any_shape(kernel_backend, rng, shape):
    x = rng.random(shape, dtype=np.float32)
    x.flat[:4] = [0.0, 0.04045, 0.0031308, 1.0][:x.size]
    np.testing.assert_allclose(apply(kernel_backend, "srgb_to_linear", x), ref.srgb_to_linear(x), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(apply(kernel_backend, "linear_to_srgb", x), ref.linear_to_srgb(x), rtol=1e-5, atol=1e-7)


def test_transfer_curves_invert_and_are_continuous(kernel_backend):
    x = np.linspace(0, 1, 2001, dtype=np.float32)
    lin = apply(kernel_backend, "srgb_to_linear", x)
    np.testing.assert_allclose(apply(kernel_backend, "linear_to_srgb", lin), x, atol=2e-6)
    assert np.all(np.diff(lin) > 0)
    # the two pieces meet at the threshold to within the standard's rounding
    for thr, fn in ((0.04045, "srgb_to_linear"), (0.0031308, "linear_to_srgb")):
        lo_hi = apply(kernel_backend, fn, np.array([thr, np.nextafter(np.float32(thr), 1)], np.float32))
        assert abs(lo_hi[1] - lo_hi[0]) < 1e-6


def test_lab_known_values(kernel_backend, rng):
    rgb = rng.random(SHAPE, dtype=np.float32)
    rgb[0, 0, :4] = [[1, 1, 1], [0, 0, 0], [1, 0, 0], [0.18, 0.18, 0.18]]
    lab = apply(kernel_backend, "linear_rgb_to_lab", rgb)
    np.testing.assert_allclose(lab[0, 0, 0], [100, 0, 0], atol=1e-3)
    np.testing.assert_allclose(lab[0, 0, 1], [0, 0, 0], atol=1e-6)
    np.testing.assert_allclose(lab[0, 0, 2], [53.2408, 80.0925, 67.2032], atol=1e-2)   # sRGB red
    np.testing.assert_allclose(lab[0, 0, 3], [49.4961, 0, 0], atol=1e-2)               # 18% grey
    # independent implementation: OpenCV's linear-RGB -> Lab
    np.testing.assert_allclose(lab[0], cv2.cvtColor(rgb[0], cv2.COLOR_LRGB2Lab), atol=0.05)


def test_log_floor_is_exact_at_the_floor(kernel_backend, rng):
    x = rng.normal(size=(3, 37, 53)).astype(np.float32)
    assert apply(kernel_backend, "log_floor", x, None, 1e-4).min() == np.float32(np.log(np.float32(1e-4)))


def test_bad_input_raises(kernel_backend):
    be = kernel_backend
    c = be.colour
    with pytest.raises(ValueError, match="rgb"):
        c.linear_rgb_to_lab(be.zeros((2, 4, 5, 4)), be.zeros((2, 4, 5, 4)))
    with pytest.raises(ValueError, match="out"):
        c.luminance(be.zeros((2, 4, 5, 3)), be.zeros((2, 4, 5, 1)))
    with pytest.raises(ValueError, match="out"):
        c.srgb_to_linear(be.zeros((4, 5)), be.zeros((5, 4)))
    with pytest.raises(ValueError, match="floor"):
        c.log_floor(be.zeros((4,)), be.zeros((4,)), 0.0)
    with pytest.raises(TypeError, match="float32"):
        c.linear_to_srgb(be.zeros((4,), np.float64), be.zeros((4,)))
    with pytest.raises(ValueError, match="contiguous"):
        c.srgb_to_linear(be.zeros((4, 6)), be.zeros((4, 12))[:, ::2])
