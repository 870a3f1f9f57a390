"""Taichi mirror of :mod:`ivkernels.kernels.warp.denoise`: the noise's step in ``log i`` and the
bilateral filter of a log layer, same host functions and signatures, NumPy arrays passed as
``ti.types.ndarray()``; a parallel loop over the ``T * H`` rows."""
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.denoise import DARK_FRACTION, FAMILY

host = implements(FAMILY, FRONT)

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.kernel
def range_sigma_rows(offset_image: nd4, level: nd4, out: nd3, scale: ti.f32, offset: ti.f32, dark: ti.f32):
    height = out.shape[1]
    for r in range(out.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(out.shape[2]):
            e = ti.exp((offset_image[t, y, x, 0] + offset_image[t, y, x, 1] + offset_image[t, y, x, 2]) / 3.0)
            brightness = ti.max(e - offset, dark * offset)
            out[t, y, x] = scale * level[t, y, x, 0] * e / brightness


@ti.kernel
def bilateral_rows(src: nd4, rs: nd3, out: nd4, radius: ti.i32, inv_space: ti.f32):
    height = src.shape[1]
    width = src.shape[2]
    channels = src.shape[3]
    inv_channels = 1.0 / ti.cast(channels, ti.f32)
    for r in range(src.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            sigma = rs[t, y, x]
            if not (sigma > 0.0):          # 0, negative or NaN: the pixel keeps its value
                for c in range(channels):
                    out[t, y, x, c] = src[t, y, x, c]
            else:
                inv_range = 1.0 / (2.0 * sigma * sigma)
                for c in range(channels):
                    out[t, y, x, c] = 0.0
                den = 0.0
                for dy in range(-radius, radius + 1):
                    yy = y + dy
                    if 0 <= yy < height:
                        for dx in range(-radius, radius + 1):
                            xx = x + dx
                            if 0 <= xx < width:
                                d2 = 0.0
                                for c in range(channels):
                                    d = src[t, yy, xx, c] - src[t, y, x, c]
                                    d2 += d * d
                                w = ti.exp(-ti.cast(dy * dy + dx * dx, ti.f32) * inv_space
                                           - d2 * inv_channels * inv_range)
                                den += w
                                for c in range(channels):
                                    out[t, y, x, c] += w * src[t, yy, xx, c]
                for c in range(channels):
                    out[t, y, x, c] /= den


@host("range_sigma")
def range_sigma(offset_image, level, out, scale: float, offset: float) -> None:
    """The noise's log-luminance step in ``log i``, times ``scale``; see
    :func:`ivkernels.kernels.warp.denoise.range_sigma`."""
    if out.size:
        range_sigma_rows(offset_image, level, out, scale, offset, DARK_FRACTION)


@host("bilateral")
def bilateral(src, range_sigma, out, radius: int, sigma_space: float) -> None:
    """Bilateral filter of a log layer with a per-pixel range; see
    :func:`ivkernels.kernels.warp.denoise.bilateral`."""
    if src.size:
        bilateral_rows(src, range_sigma, out, radius, 1.0 / (2.0 * sigma_space ** 2))
