"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.edges`:
the Sobel edges of a flow field, thinned (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["flow_sobel_components", "thin_edges"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.func
def sobel_at(flow: ti.template(), t, y, x, c):
    height = flow.shape[1]
    width = flow.shape[2]
    ym = ti.max(y - 1, 0)
    yp = ti.min(y + 1, height - 1)
    xm = ti.max(x - 1, 0)
    xp = ti.min(x + 1, width - 1)
    gx = (flow[t, ym, xp, c] + 2.0 * flow[t, y, xp, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, y, xm, c] - flow[t, yp, xm, c]) / 8.0
    gy = (flow[t, yp, xm, c] + 2.0 * flow[t, yp, x, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, ym, x, c] - flow[t, ym, xp, c]) / 8.0
    return gx, gy


@ti.kernel
def _flow_sobel_components(flow: nd4, out: nd4, row_energy: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for t, y in ti.ndrange(flow.shape[0], flow.shape[1]):
        sum_u = 0.0
        sum_v = 0.0
        for x in range(flow.shape[2]):
            gxu, gyu = sobel_at(flow, t, y, x, 0)
            gxv, gyv = sobel_at(flow, t, y, x, 1)
            out[t, y, x, 0] = gxu
            out[t, y, x, 1] = gyu
            out[t, y, x, 2] = gxv
            out[t, y, x, 3] = gyv
            sum_u += gxu * gxu + gyu * gyu
            sum_v += gxv * gxv + gyv * gyv
        row_energy[t * flow.shape[1] + y, 0] = sum_u
        row_energy[t * flow.shape[1] + y, 1] = sum_v


@ti.func
def sobel_energy(sobel: ti.template(), t, y, x, c):
    gx = sobel[t, y, x, 2 * c]
    gy = sobel[t, y, x, 2 * c + 1]
    return gx * gx + gy * gy


@ti.kernel
def _thin_edges(sobel: nd4, cutoff: ti.types.ndarray(dtype=ti.f32, ndim=2), out: nd3):
    height = sobel.shape[1]
    width = sobel.shape[2]
    for t, y in ti.ndrange(sobel.shape[0], height):
        ym = ti.max(y - 1, 0)
        yp = ti.min(y + 1, height - 1)
        for x in range(width):
            xm = ti.max(x - 1, 0)
            xp = ti.min(x + 1, width - 1)
            edge = 0.0
            for c in ti.static(range(2)):
                b = sobel_energy(sobel, t, y, x, c)
                if b > cutoff[t, c]:
                    ax = ti.abs(sobel[t, y, x, 2 * c])
                    ay = ti.abs(sobel[t, y, x, 2 * c + 1])
                    if ax >= ay and b > sobel_energy(sobel, t, y, xm, c) and b >= sobel_energy(sobel, t, y, xp, c):
                        edge = 1.0
                    if ay >= ax and b > sobel_energy(sobel, t, ym, x, c) and b >= sobel_energy(sobel, t, yp, x, c):
                        edge = 1.0
            out[t, y, x] = edge


@host("flow_sobel_components")
def flow_sobel_components(flow, out, row_energy) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.flow_sobel_components`."""
    _flow_sobel_components(flow, out, row_energy)


@host("thin_edges")
def thin_edges(sobel, cutoff, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.thin_edges`."""
    _thin_edges(sobel, cutoff, out)
