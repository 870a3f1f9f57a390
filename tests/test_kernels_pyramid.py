"""Gaussian blur and bilinear resizing (kernels/*/pyramid.py): the generic contract from the
case table, plus the impulse response, OpenCV's resize, same-size and constant-flow resizes,
bad input."""
import cv2
import numpy as np
import pytest

from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("pyramid")

T, H, W = 2, 37, 53


def blur(be, src, sigma):
    out, scratch = be.zeros(src.shape), be.zeros(src.shape)
    be.pyramid.gaussian_blur(be.asarray(src), out, scratch, sigma)
    return be.numpy(out).copy()


def resize(be, fn, src, size):
    out = be.zeros((src.shape[0], *size, src.shape[3]))
    getattr(be.pyramid, fn)(be.asarray(src), out)
    return be.numpy(out).copy()


def test_gaussian_blur_hand_cases(kernel_backend, rng):
    src = np.zeros((1, H, W, 1), np.float32)
    src[0, 18, 26] = 1.0
    out = blur(kernel_backend, src, 1.5)
    k = np.arange(-5, 6)
    g = np.exp(-k**2 / (2 * 1.5**2))
    g /= g.sum()
    np.testing.assert_allclose(out[0, 13:24, 21:32, 0], np.outer(g, g), atol=1e-7)   # impulse response
    assert out[0, :13].max() == 0 and out[0, :, 32:].max() == 0                      # truncated at 3 sigma
    const = np.full((1, H, W, 2), 0.25, np.float32)
    np.testing.assert_allclose(blur(kernel_backend, const, 2.0), 0.25, rtol=1e-6)           # borders replicate
    x = rng.random((T, H, W, 1), dtype=np.float32)
    np.testing.assert_array_equal(blur(kernel_backend, x, 0.0), x)                   # sigma <= 0 copies


def test_resize_to_the_same_size_copies(kernel_backend, rng):
    src = rng.random((T, H, W, 3), dtype=np.float32)
    np.testing.assert_array_equal(resize(kernel_backend, "resize_bilinear", src, (H, W)), src)


@pytest.mark.parametrize("size", [(74, 106), (19, 27)])
def test_resize_bilinear_matches_opencv(kernel_backend, rng, size):
    src = rng.random((1, H, W, 3), dtype=np.float32)
    want = cv2.resize(src[0], (size[1], size[0]), interpolation=cv2.INTER_LINEAR)
    np.testing.assert_allclose(resize(kernel_backend, "resize_bilinear", src, size)[0], want, atol=1e-5)


def test_resize_flow_scales_the_vectors(kernel_backend):
    const = np.broadcast_to(np.float32([1.0, -2.0]), (1, 10, 20, 2)).copy()
    np.testing.assert_allclose(resize(kernel_backend, "resize_flow", const, (5, 40)),
                               np.broadcast_to([2.0, -1.0], (1, 5, 40, 2)), rtol=1e-6)


def test_bad_input_raises(kernel_backend):
    p = kernel_backend.pyramid
    src = kernel_backend.zeros((T, H, W, 3))
    with pytest.raises(ValueError, match="scratch"):
        p.gaussian_blur(src, kernel_backend.zeros((T, H, W, 3)), kernel_backend.zeros((T, H, W, 1)), 1.0)
    with pytest.raises(ValueError, match="scratch"):
        p.gaussian_blur(src, kernel_backend.zeros((T, H, W, 3)), src, 1.0)
    with pytest.raises(ValueError, match="out"):
        p.resize_bilinear(src, kernel_backend.zeros((T, 10, 10, 2)))
    with pytest.raises(ValueError, match="out"):
        p.resize_bilinear(src, kernel_backend.zeros((T + 1, 10, 10, 3)))
    with pytest.raises(ValueError, match="src"):
        p.resize_flow(src, kernel_backend.zeros((T, 10, 10, 2)))
    with pytest.raises(TypeError, match="float32"):
        p.resize_flow(kernel_backend.zeros((T, H, W, 2), np.float64), kernel_backend.zeros((T, 10, 10, 2)))
