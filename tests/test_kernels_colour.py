"""Colour conversions (kernels/*/colour.py)."""
import cv2
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import colour as ref

SHAPE = (2, 37, 53, 3)


def apply(be, fn, src, out_shape=None, *args):
    out = be.zeros(src.shape if out_shape is None else out_shape)
    getattr(be.colour, fn)(be.asarray(src), out, *args)
    return be.numpy(out).copy()


@pytest.mark.parametrize("shape", [(1,), (5, 7), SHAPE, (4099 * 3,)])
def test_transfer_curves_match_reference(backend, rng, shape):
    x = rng.random(shape, dtype=np.float32)
    x.flat[:4] = [0.0, 0.04045, 0.0031308, 1.0]
    np.testing.assert_allclose(apply(backend, "srgb_to_linear", x), ref.srgb_to_linear(x), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(apply(backend, "linear_to_srgb", x), ref.linear_to_srgb(x), rtol=1e-5, atol=1e-7)


def test_transfer_curves_invert_and_are_continuous(backend, rng):
    x = np.linspace(0, 1, 2001, dtype=np.float32)
    lin = apply(backend, "srgb_to_linear", x)
    np.testing.assert_allclose(apply(backend, "linear_to_srgb", lin), x, atol=2e-6)
    assert np.all(np.diff(lin) > 0)
    # the two pieces meet at the threshold to within the standard's rounding
    for thr, fn in ((0.04045, "srgb_to_linear"), (0.0031308, "linear_to_srgb")):
        lo_hi = apply(backend, fn, np.array([thr, np.nextafter(np.float32(thr), 1)], np.float32))
        assert abs(lo_hi[1] - lo_hi[0]) < 1e-6


def test_in_place(backend, rng):
    x = rng.random((3, 5), dtype=np.float32)
    arr = backend.asarray(x.copy())
    backend.colour.srgb_to_linear(arr, arr)
    np.testing.assert_allclose(backend.numpy(arr), ref.srgb_to_linear(x), rtol=1e-5)


def test_lab_matches_reference_and_known_values(backend, rng):
    rgb = rng.random(SHAPE, dtype=np.float32)
    rgb[0, 0, :4] = [[1, 1, 1], [0, 0, 0], [1, 0, 0], [0.18, 0.18, 0.18]]
    lab = apply(backend, "linear_rgb_to_lab", rgb)
    np.testing.assert_allclose(lab, ref.linear_rgb_to_lab(rgb), atol=2e-4)
    np.testing.assert_allclose(lab[0, 0, 0], [100, 0, 0], atol=1e-3)
    np.testing.assert_allclose(lab[0, 0, 1], [0, 0, 0], atol=1e-6)
    np.testing.assert_allclose(lab[0, 0, 2], [53.2408, 80.0925, 67.2032], atol=1e-2)   # sRGB red
    np.testing.assert_allclose(lab[0, 0, 3], [49.4961, 0, 0], atol=1e-2)               # 18% grey
    # independent implementation: OpenCV's linear-RGB -> Lab
    np.testing.assert_allclose(lab[0], cv2.cvtColor(rgb[0], cv2.COLOR_LRGB2Lab), atol=0.05)


def test_luminance_and_log_floor(backend, rng):
    rgb = rng.random(SHAPE, dtype=np.float32)
    np.testing.assert_allclose(apply(backend, "luminance", rgb, SHAPE[:3]), ref.luminance(rgb), rtol=1e-6)
    x = rng.normal(size=(3, 37, 53)).astype(np.float32)
    got = apply(backend, "log_floor", x, None, 1e-4)
    np.testing.assert_allclose(got, ref.log_floor(x, 1e-4), rtol=1e-6)
    assert got.min() == np.float32(np.log(np.float32(1e-4)))


def test_bad_input_raises(backend):
    c = backend.colour
    with pytest.raises(ValueError, match="rgb"):
        c.linear_rgb_to_lab(backend.zeros((2, 4, 5, 4)), backend.zeros((2, 4, 5, 4)))
    with pytest.raises(ValueError, match="out"):
        c.luminance(backend.zeros((2, 4, 5, 3)), backend.zeros((2, 4, 5, 1)))
    with pytest.raises(ValueError, match="out"):
        c.srgb_to_linear(backend.zeros((4, 5)), backend.zeros((5, 4)))
    with pytest.raises(ValueError, match="floor"):
        c.log_floor(backend.zeros((4,)), backend.zeros((4,)), 0.0)
    with pytest.raises(TypeError, match="float32"):
        c.linear_to_srgb(backend.zeros((4,), np.float64), backend.zeros((4,)))
    with pytest.raises(ValueError, match="contiguous"):
        c.srgb_to_linear(backend.zeros((4, 6)), backend.zeros((4, 12))[:, ::2])


def test_warp_and_taichi_agree(rng):
    rgb = rng.random(SHAPE, dtype=np.float32)
    wb, tb = get_backend("warp"), get_backend("taichi")
    for fn, shape, args in (("srgb_to_linear", None, ()), ("linear_to_srgb", None, ()),
                            ("linear_rgb_to_lab", None, ()), ("luminance", SHAPE[:3], ()),
                            ("log_floor", None, (0.01,))):
        np.testing.assert_allclose(apply(wb, fn, rgb, shape, *args), apply(tb, fn, rgb, shape, *args),
                                   rtol=1e-5, atol=1e-4)


def test_one_and_two_threads_agree(rng):
    be = get_backend("warp")
    rgb = rng.random((3, 37, 53, 3), dtype=np.float32)
    res = []
    for n in (1, 2):
        with threads(n):
            res.append([apply(be, "srgb_to_linear", rgb), apply(be, "linear_rgb_to_lab", rgb),
                        apply(be, "luminance", rgb, rgb.shape[:3]), apply(be, "log_floor", rgb, None, 0.1)])
    for a, b in zip(*res):
        np.testing.assert_array_equal(a, b)
