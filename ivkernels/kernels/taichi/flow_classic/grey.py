"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.grey`:
the input's grey level and its normalisation (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import GREY_WEIGHTS
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["srgb_grey", "log_grey", "row_min_max", "scale_shift"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)


@ti.func
def srgb_encode(c):
    c = ti.math.clamp(c, 0.0, 1.0)
    result = 12.92 * c
    if c > 0.0031308:
        result = 1.055 * ti.pow(c, 1.0 / 2.4) - 0.055
    return result


@ti.kernel
def _srgb_grey(rgb: nd4, out: nd3, wr: ti.f32, wg: ti.f32, wb: ti.f32):
    for t, y in ti.ndrange(out.shape[0], out.shape[1]):
        for x in range(out.shape[2]):
            g = wr * srgb_encode(rgb[t, y, x, 0]) + wg * srgb_encode(rgb[t, y, x, 1]) \
                + wb * srgb_encode(rgb[t, y, x, 2])
            out[t, y, x] = 255.0 * g


@ti.kernel
def _log_grey(rgb: nd4, out: nd3, wr: ti.f32, wg: ti.f32, wb: ti.f32, floor: ti.f32):
    for t, y in ti.ndrange(out.shape[0], out.shape[1]):
        for x in range(out.shape[2]):
            g = wr * rgb[t, y, x, 0] + wg * rgb[t, y, x, 1] + wb * rgb[t, y, x, 2]
            out[t, y, x] = ti.log(ti.max(g, floor))


@ti.kernel
def _min_max(src: nd4, out: nd3):
    for t, y in ti.ndrange(src.shape[0], src.shape[1]):
        r = t * src.shape[1] + y
        for c in range(src.shape[3]):
            lo = src[t, y, 0, c]
            hi = lo
            for x in range(1, src.shape[2]):
                v = src[t, y, x, c]
                lo = ti.min(lo, v)
                hi = ti.max(hi, v)
            out[r, c, 0] = lo
            out[r, c, 1] = hi


@ti.kernel
def _scale_shift(src: nd4, out: nd4, scale: nd1, shift: nd1):
    for t, y in ti.ndrange(src.shape[0], src.shape[1]):
        for x in range(src.shape[2]):
            for c in range(src.shape[3]):
                out[t, y, x, c] = src[t, y, x, c] * scale[c] + shift[c]


@host("srgb_grey")
def srgb_grey(rgb, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.srgb_grey`."""
    _srgb_grey(rgb, out, *GREY_WEIGHTS)


@host("log_grey")
def log_grey(rgb, out, floor: float = 1e-3) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.log_grey`."""
    _log_grey(rgb, out, *GREY_WEIGHTS, float(floor))


@host("row_min_max")
def row_min_max(src, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.row_min_max`."""
    _min_max(src, out)


@host("scale_shift")
def scale_shift(src, out, scale, shift) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.scale_shift`."""
    _scale_shift(src, out, scale, shift)
