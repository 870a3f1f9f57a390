"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.rof`:
the ROF structure-texture decomposition (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["rof_dual_step", "rof_texture"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.func
def rof_divergence(p: ti.template(), t, y, x):
    d = p[t, y, x, 0] + p[t, y, x, 1]
    if x > 0:
        d -= p[t, y, x - 1, 0]
    if y > 0:
        d -= p[t, y - 1, x, 1]
    return d


@ti.kernel
def _rof_dual_step(img: nd3, p_in: nd4, p_out: nd4, theta: ti.f32, delta: ti.f32):
    height = img.shape[1]
    width = img.shape[2]
    for t, y in ti.ndrange(img.shape[0], height):
        for x in range(width):
            v = img[t, y, x] + theta * rof_divergence(p_in, t, y, x)
            gx = 0.0
            gy = 0.0
            if x < width - 1:
                gx = img[t, y, x + 1] + theta * rof_divergence(p_in, t, y, x + 1) - v
            if y < height - 1:
                gy = img[t, y + 1, x] + theta * rof_divergence(p_in, t, y + 1, x) - v
            px = p_in[t, y, x, 0] + delta * gx
            py = p_in[t, y, x, 1] + delta * gy
            norm = ti.max(1.0, ti.sqrt(px * px + py * py))
            p_out[t, y, x, 0] = px / norm
            p_out[t, y, x, 1] = py / norm


@ti.kernel
def _rof_texture(img: nd3, p: nd4, out: nd3, theta: ti.f32, alpha: ti.f32):
    for t, y in ti.ndrange(img.shape[0], img.shape[1]):
        for x in range(img.shape[2]):
            structure = img[t, y, x] + theta * rof_divergence(p, t, y, x)
            out[t, y, x] = img[t, y, x] - alpha * structure


@host("rof_dual_step")
def rof_dual_step(img, p_in, p_out, theta: float, delta: float) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.rof_dual_step`."""
    _rof_dual_step(img, p_in, p_out, float(theta), float(delta))


@host("rof_texture")
def rof_texture(img, p, out, theta: float, alpha: float) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.rof_texture`."""
    _rof_texture(img, p, out, float(theta), float(alpha))
