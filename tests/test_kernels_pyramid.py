"""Gaussian blur and bilinear resizing (kernels/*/pyramid.py)."""
import cv2
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import pyramid as ref

T, H, W = 2, 37, 53


def blur(be, src, sigma):
    out, scratch = be.zeros(src.shape), be.zeros(src.shape)
    be.pyramid.gaussian_blur(be.asarray(src), out, scratch, sigma)
    return be.numpy(out).copy()


def resize(be, fn, src, size):
    out = be.zeros((src.shape[0], *size, src.shape[3]))
    getattr(be.pyramid, fn)(be.asarray(src), out)
    return be.numpy(out).copy()


@pytest.mark.parametrize("sigma", [0.3, 1.0, 2.3])
def test_gaussian_blur_matches_reference(backend, rng, sigma):
    src = rng.random((T, H, W, 3), dtype=np.float32)
    np.testing.assert_allclose(blur(backend, src, sigma), ref.gaussian_blur(src, sigma), atol=2e-6)


def test_gaussian_blur_hand_cases(backend, rng):
    src = np.zeros((1, H, W, 1), np.float32)
    src[0, 18, 26] = 1.0
    out = blur(backend, src, 1.5)
    k = np.arange(-5, 6)
    g = np.exp(-k**2 / (2 * 1.5**2))
    g /= g.sum()
    np.testing.assert_allclose(out[0, 13:24, 21:32, 0], np.outer(g, g), atol=1e-7)   # impulse response
    assert out[0, :13].max() == 0 and out[0, :, 32:].max() == 0                      # truncated at 3 sigma
    const = np.full((1, H, W, 2), 0.25, np.float32)
    np.testing.assert_allclose(blur(backend, const, 2.0), 0.25, rtol=1e-6)           # borders replicate
    x = rng.random((T, H, W, 1), dtype=np.float32)
    np.testing.assert_array_equal(blur(backend, x, 0.0), x)                          # sigma <= 0 copies
    arr, scratch = backend.asarray(x.copy()), backend.zeros(x.shape)                 # out may be src
    backend.pyramid.gaussian_blur(arr, arr, scratch, 1.0)
    np.testing.assert_allclose(backend.numpy(arr), ref.gaussian_blur(x, 1.0), atol=2e-6)


@pytest.mark.parametrize("size", [(19, 27), (74, 106), (37, 53), (5, 90), (1, 1)])
def test_resize_bilinear_matches_reference(backend, rng, size):
    src = rng.random((T, H, W, 3), dtype=np.float32)
    out = resize(backend, "resize_bilinear", src, size)
    np.testing.assert_allclose(out, ref.resize_bilinear(src, size), atol=1e-5)
    if size == (H, W):
        np.testing.assert_array_equal(out, src)


@pytest.mark.parametrize("size", [(74, 106), (19, 27)])
def test_resize_bilinear_matches_opencv(backend, rng, size):
    src = rng.random((1, H, W, 3), dtype=np.float32)
    want = cv2.resize(src[0], (size[1], size[0]), interpolation=cv2.INTER_LINEAR)
    np.testing.assert_allclose(resize(backend, "resize_bilinear", src, size)[0], want, atol=1e-5)


def test_resize_flow(backend, rng):
    flow = rng.normal(size=(T, H, W, 2)).astype(np.float32)
    for size in ((74, 106), (19, 27)):
        np.testing.assert_allclose(resize(backend, "resize_flow", flow, size), ref.resize_flow(flow, size),
                                   rtol=1e-5, atol=1e-5)
    const = np.broadcast_to(np.float32([1.0, -2.0]), (1, 10, 20, 2)).copy()
    np.testing.assert_allclose(resize(backend, "resize_flow", const, (5, 40)), np.broadcast_to([2.0, -1.0], (1, 5, 40, 2)),
                               rtol=1e-6)


def test_bad_input_raises(backend):
    p = backend.pyramid
    src = backend.zeros((T, H, W, 3))
    with pytest.raises(ValueError, match="scratch"):
        p.gaussian_blur(src, backend.zeros((T, H, W, 3)), backend.zeros((T, H, W, 1)), 1.0)
    with pytest.raises(ValueError, match="scratch"):
        p.gaussian_blur(src, backend.zeros((T, H, W, 3)), src, 1.0)
    with pytest.raises(ValueError, match="out"):
        p.resize_bilinear(src, backend.zeros((T, 10, 10, 2)))
    with pytest.raises(ValueError, match="out"):
        p.resize_bilinear(src, backend.zeros((T + 1, 10, 10, 3)))
    with pytest.raises(ValueError, match="src"):
        p.resize_flow(src, backend.zeros((T, 10, 10, 2)))
    with pytest.raises(TypeError, match="float32"):
        p.resize_flow(backend.zeros((T, H, W, 2), np.float64), backend.zeros((T, 10, 10, 2)))


def test_warp_and_taichi_agree(rng):
    src = rng.random((T, H, W, 2), dtype=np.float32)
    wb, tb = get_backend("warp"), get_backend("taichi")
    np.testing.assert_allclose(blur(wb, src, 1.2), blur(tb, src, 1.2), atol=2e-6)
    for fn in ("resize_bilinear", "resize_flow"):
        np.testing.assert_allclose(resize(wb, fn, src, (19, 27)), resize(tb, fn, src, (19, 27)), atol=2e-6)


def test_one_and_two_threads_agree(rng):
    be = get_backend("warp")
    src = rng.random((3, H, W, 2), dtype=np.float32)
    res = []
    for n in (1, 2):
        with threads(n):
            res.append([blur(be, src, 1.2), resize(be, "resize_bilinear", src, (19, 27)),
                        resize(be, "resize_flow", src, (74, 106))])
    for a, b in zip(*res):
        np.testing.assert_array_equal(a, b)
