"""Taichi mirror of :mod:`ivkernels.kernels.warp.pyramid`: separable Gaussian
blur and bilinear resizing (pixel-centre mapping, clamped corners), same host
functions and signatures, NumPy arrays passed as ``ti.types.ndarray()``.

Parallel over output rows; the bilinear helpers come from
:mod:`ivkernels.kernels.taichi.sampling`.
"""

import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import gaussian_kernel
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.pyramid import FAMILY
from ivkernels.kernels.taichi.sampling import bilinear_at, clamped_corners

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.kernel
def blur_x_rows(src: nd4, dst: nd4, weights: nd1, radius: ti.i32):
    height = src.shape[1]
    width = src.shape[2]
    for r in range(src.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            for c in range(src.shape[3]):
                acc = 0.0
                for k in range(-radius, radius + 1):
                    acc += weights[k + radius] * src[t, y, ti.math.clamp(x + k, 0, width - 1), c]
                dst[t, y, x, c] = acc


@ti.kernel
def blur_y_rows(src: nd4, dst: nd4, weights: nd1, radius: ti.i32):
    height = src.shape[1]
    for r in range(src.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(src.shape[2]):
            for c in range(src.shape[3]):
                acc = 0.0
                for k in range(-radius, radius + 1):
                    acc += weights[k + radius] * src[t, ti.math.clamp(y + k, 0, height - 1), x, c]
                dst[t, y, x, c] = acc


@ti.kernel
def resize_bilinear_rows(src: nd4, out: nd4, scale_x: ti.f32, scale_y: ti.f32):
    height = out.shape[1]
    for r in range(out.shape[0] * height):
        t = r // height
        y = r - t * height
        y0, y1, fy = clamped_corners((ti.cast(y, ti.f32) + 0.5) * scale_y - 0.5, src.shape[1])
        for x in range(out.shape[2]):
            x0, x1, fx = clamped_corners((ti.cast(x, ti.f32) + 0.5) * scale_x - 0.5, src.shape[2])
            for c in range(out.shape[3]):
                out[t, y, x, c] = bilinear_at(src, t, c, x0, x1, fx, y0, y1, fy)


@ti.kernel
def resize_flow_rows(src: nd4, out: nd4, scale_x: ti.f32, scale_y: ti.f32, gain_x: ti.f32, gain_y: ti.f32):
    height = out.shape[1]
    for r in range(out.shape[0] * height):
        t = r // height
        y = r - t * height
        y0, y1, fy = clamped_corners((ti.cast(y, ti.f32) + 0.5) * scale_y - 0.5, src.shape[1])
        for x in range(out.shape[2]):
            x0, x1, fx = clamped_corners((ti.cast(x, ti.f32) + 0.5) * scale_x - 0.5, src.shape[2])
            out[t, y, x, 0] = bilinear_at(src, t, 0, x0, x1, fx, y0, y1, fy) * gain_x
            out[t, y, x, 1] = bilinear_at(src, t, 1, x0, x1, fx, y0, y1, fy) * gain_y


@host("gaussian_blur")
def gaussian_blur(src, out, scratch, sigma: float) -> None:
    """Separable Gaussian blur truncated at 3 sigma, replicate border; ``sigma <= 0``
    copies.  Pyramid choice: ``sigma = 1 / sqrt(2 * scale)`` before resampling by
    ``scale < 1``.  See :func:`ivkernels.kernels.warp.pyramid.gaussian_blur`."""
    if sigma <= 0.0:
        if out is not src:
            np.copyto(out, src)
        return
    if src.size == 0:
        return
    taps = gaussian_kernel(sigma)
    radius = (len(taps) - 1) // 2
    blur_x_rows(src, scratch, taps, radius)
    blur_y_rows(scratch, out, taps, radius)


def _scales(src, out):
    """Source pixels per target pixel along x and y."""
    return src.shape[2] / out.shape[2], src.shape[1] / out.shape[1]


@host("resize_bilinear")
def resize_bilinear(src, out) -> None:
    """Bilinear resize (T, h, w, C) -> (T, H, W, C), pixel-centre mapping, clamped; see
    :func:`ivkernels.kernels.warp.pyramid.resize_bilinear` (NumPy arrays here)."""
    scale_x, scale_y = _scales(src, out)
    if out.size:
        resize_bilinear_rows(src, out, scale_x, scale_y)


@host("resize_flow")
def resize_flow(src, out) -> None:
    """Resize a flow (T, h, w, 2) -> (T, H, W, 2) and scale dx by W / w, dy by H / h; see
    :func:`ivkernels.kernels.warp.pyramid.resize_flow`."""
    scale_x, scale_y = _scales(src, out)
    if out.size:
        resize_flow_rows(src, out, scale_x, scale_y, out.shape[2] / src.shape[2], out.shape[1] / src.shape[1])
