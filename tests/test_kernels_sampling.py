"""Bilinear / bicubic warping and the bilinear splat (kernels/*/sampling.py): the generic
contract from the case table, plus the adjoint pair <Wx, y> = <x, W^T y>, hand cases, exact
quadratics of the bicubic kernel, a shading map as a one-channel view, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import sampling as ref
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("sampling")

T, H, W = 2, 37, 53


def random_flow(rng, t=T, h=H, w=W, scale=4.0):
    """Flow with fractional vectors, some pointing far outside the image."""
    flow = rng.normal(scale=scale, size=(t, h, w, 2)).astype(np.float32)
    far = rng.random((t, h, w)) < 0.05
    flow[far] = rng.uniform(-3 * w, 3 * w, size=(int(far.sum()), 2)).astype(np.float32)
    flow[:, 0, :, 1] = -0.5                # top row samples above the image
    flow[:, :, -1, 0] = 0.75               # right column samples beyond the border
    return flow


def run_warp(be, fn, src, flow):
    t, h, w, c = src.shape
    out, inside = be.zeros((t, h, w, c)), be.zeros((t, h, w))
    getattr(be.sampling, fn)(be.asarray(src), be.asarray(flow), out, inside)
    return be.numpy(out).copy(), be.numpy(inside).copy()


def run_splat(be, values, flow, initial=None):
    out = be.asarray(np.zeros(values.shape, np.float32) if initial is None else initial.copy())
    be.sampling.splat_bilinear(be.asarray(values), be.asarray(flow), out)
    return be.numpy(out).copy()


def test_warp_bilinear_hand_cases(kernel_backend):
    src = np.arange(12, dtype=np.float32).reshape(1, 3, 4, 1)   # value = 4 y + x
    flow = np.zeros((1, 3, 4, 2), np.float32)
    out, inside = run_warp(kernel_backend, "warp_bilinear", src, flow)
    np.testing.assert_array_equal(out, src)                       # no motion: exact copy
    np.testing.assert_array_equal(inside, 1.0)
    flow[..., 0], flow[..., 1] = 0.25, 0.5
    out, inside = run_warp(kernel_backend, "warp_bilinear", src, flow)
    # interior: a linear image is sampled exactly; last column / row replicate the border
    np.testing.assert_allclose(out[0, 1, 1, 0], 4 * 1.5 + 1.25, rtol=1e-6)
    np.testing.assert_allclose(out[0, 0, 3, 0], 0.5 * 3 + 0.5 * 7, rtol=1e-6)
    assert inside[0, 1, 1] == 1 and inside[0, 2, 1] == 0 and inside[0, 1, 3] == 0


@pytest.mark.parametrize("scale", [0.7, 5.0, 200.0])
def test_warp_splat_adjoint(kernel_backend, rng, scale):
    x = rng.normal(size=(T, H, W, 3)).astype(np.float32)
    y = rng.normal(size=(T, H, W, 3)).astype(np.float32)
    flow = random_flow(rng, scale=scale)
    # float64 reference: the identity holds to rounding
    wx, _ = ref.warp_bilinear(x, flow)
    lhs64, rhs64 = np.vdot(wx, y), np.vdot(x.astype(np.float64), ref.splat_bilinear(y, flow))
    assert abs(lhs64 - rhs64) <= 1e-9 * np.abs(wx * y).sum()
    # the kernels reach the float64 value to float32 precision
    wx32, _ = run_warp(kernel_backend, "warp_bilinear", x, flow)
    sy32 = run_splat(kernel_backend, y, flow)
    scale_ref = np.abs(wx * y).sum()
    assert abs(np.vdot(wx32.astype(np.float64), y) - lhs64) <= 1e-6 * scale_ref
    assert abs(np.vdot(x.astype(np.float64), sy32) - rhs64) <= 1e-6 * scale_ref


def test_warp_bicubic_reproduces_quadratic_and_identity(kernel_backend, rng):
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float64)
    quad = (0.3 * xx**2 + 0.2 * yy**2 - 0.1 * xx * yy + xx)[None, ..., None]
    flow = np.zeros((1, H, W, 2), np.float32)
    flow[..., 0], flow[..., 1] = 0.375, -0.625
    out, _ = run_warp(kernel_backend, "warp_bicubic", quad.astype(np.float32), flow)
    px, py = xx + 0.375, yy - 0.625
    exact = 0.3 * px**2 + 0.2 * py**2 - 0.1 * px * py + px
    interior = (slice(None), slice(3, -3), slice(3, -3), 0)
    # Keys' a = -0.5 kernel interpolates quadratics exactly (third-order accurate)
    np.testing.assert_allclose(out[interior], exact[None, 3:-3, 3:-3], rtol=1e-5, atol=1e-3)
    zero = np.zeros((1, H, W, 2), np.float32)
    out, _ = run_warp(kernel_backend, "warp_bicubic", quad.astype(np.float32), zero)
    np.testing.assert_array_equal(out, quad.astype(np.float32))


def test_shading_as_single_channel_view(kernel_backend, rng):
    shading = rng.random((T, H, W), dtype=np.float32)
    flow = random_flow(rng)
    src = kernel_backend.asarray(shading).reshape((T, H, W, 1))
    out, inside = kernel_backend.zeros((T, H, W, 1)), kernel_backend.zeros((T, H, W))
    kernel_backend.sampling.warp_bilinear(src, kernel_backend.asarray(flow), out, inside)
    want, _ = ref.warp_bilinear(shading[..., None], flow)
    np.testing.assert_allclose(kernel_backend.numpy(out), want, atol=2e-5)


def test_bad_input_raises(kernel_backend):
    s = kernel_backend.sampling
    src, flow = kernel_backend.zeros((T, H, W, 3)), kernel_backend.zeros((T, H, W, 2))
    out, inside = kernel_backend.zeros((T, H, W, 3)), kernel_backend.zeros((T, H, W))
    with pytest.raises(ValueError, match="flow"):
        s.warp_bilinear(src, kernel_backend.zeros((T, H, W, 3)), out, inside)
    with pytest.raises(ValueError, match="out"):
        s.warp_bicubic(src, flow, kernel_backend.zeros((T, H, W, 1)), inside)
    with pytest.raises(ValueError, match="inside"):
        s.warp_bilinear(src, flow, out, kernel_backend.zeros((T, H, W - 1)))
    with pytest.raises(TypeError, match="float32"):
        s.splat_bilinear(kernel_backend.zeros((T, H, W, 3), np.float64), flow, out)
    with pytest.raises(ValueError, match="src"):
        s.warp_bilinear(kernel_backend.zeros((T, H, W)), flow, out, inside)
    with pytest.raises(TypeError, match="values"):
        s.splat_bilinear(np.zeros((T, H, W, 3), np.float32).tolist(), flow, out)
