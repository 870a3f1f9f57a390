"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.features`:
the feature channels of the data term (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["pack_image_gradient", "pack_gradient", "soft_census", "pack_channels_gradient"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.kernel
def _pack_image_gradient(img: nd3, gx: nd3, gy: nd3, out: nd4):
    for t, y in ti.ndrange(img.shape[0], img.shape[1]):
        for x in range(img.shape[2]):
            out[t, y, x, 0] = img[t, y, x]
            out[t, y, x, 1] = gx[t, y, x]
            out[t, y, x, 2] = gy[t, y, x]


@ti.kernel
def _pack_gradient(gx: nd3, gy: nd3, out: nd4):
    for t, y in ti.ndrange(gx.shape[0], gx.shape[1]):
        for x in range(gx.shape[2]):
            out[t, y, x, 0] = gx[t, y, x]
            out[t, y, x, 1] = gy[t, y, x]


@ti.kernel
def _soft_census(img: nd3, out: nd4, radius: ti.i32, eps: ti.f32, scale: ti.f32):
    height = img.shape[1]
    width = img.shape[2]
    for t, y in ti.ndrange(img.shape[0], height):
        for x in range(width):
            centre = img[t, y, x]
            k = 0
            for dy in range(-radius, radius + 1):
                yy = ti.math.clamp(y + dy, 0, height - 1)
                for dx in range(-radius, radius + 1):
                    if dy != 0 or dx != 0:
                        d = img[t, yy, ti.math.clamp(x + dx, 0, width - 1)] - centre
                        out[t, y, x, k] = scale * d / ti.sqrt(d * d + eps * eps)
                        k += 1


@ti.kernel
def _pack_channels_gradient(feat: nd4, gx: nd4, gy: nd4, out: nd4):
    for t, y in ti.ndrange(feat.shape[0], feat.shape[1]):
        for x in range(feat.shape[2]):
            for c in range(feat.shape[3]):
                out[t, y, x, 3 * c] = feat[t, y, x, c]
                out[t, y, x, 3 * c + 1] = gx[t, y, x, c]
                out[t, y, x, 3 * c + 2] = gy[t, y, x, c]


@host("pack_image_gradient")
def pack_image_gradient(img, gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_image_gradient`."""
    _pack_image_gradient(img, gx, gy, out)


@host("pack_gradient")
def pack_gradient(gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_gradient`."""
    _pack_gradient(gx, gy, out)


@host("soft_census")
def soft_census(img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.soft_census`."""
    _soft_census(img, out, radius, float(eps), float(scale))


@host("pack_channels_gradient")
def pack_channels_gradient(feat, gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_channels_gradient`."""
    _pack_channels_gradient(feat, gx, gy, out)
