"""Taichi mirror of :mod:`ivkernels.kernels.warp.derivatives`: the 5-point image
gradient, the flow's Sobel magnitude and its one-sided divergence, same host
functions and signatures, NumPy arrays passed as ``ti.types.ndarray()``.

Parallel over the ``T * H`` rows; neighbour indices clamped (replicate border).
"""
import taichi as ti
from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.derivatives import FAMILY

host = implements(FAMILY, FRONT)


nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.kernel
def five_point_gradient_rows(src: nd4, gx: nd4, gy: nd4):
    height = src.shape[1]
    width = src.shape[2]
    for r in range(src.shape[0] * height):
        t = r // height
        y = r - t * height
        ym2 = ti.max(y - 2, 0)
        ym1 = ti.max(y - 1, 0)
        yp1 = ti.min(y + 1, height - 1)
        yp2 = ti.min(y + 2, height - 1)
        for x in range(width):
            xm2 = ti.max(x - 2, 0)
            xm1 = ti.max(x - 1, 0)
            xp1 = ti.min(x + 1, width - 1)
            xp2 = ti.min(x + 2, width - 1)
            for c in range(src.shape[3]):
                gx[t, y, x, c] = (src[t, y, xm2, c] - 8.0 * src[t, y, xm1, c]
                                  + 8.0 * src[t, y, xp1, c] - src[t, y, xp2, c]) / 12.0
                gy[t, y, x, c] = (src[t, ym2, x, c] - 8.0 * src[t, ym1, x, c]
                                  + 8.0 * src[t, yp1, x, c] - src[t, yp2, x, c]) / 12.0


@ti.kernel
def flow_sobel_magnitude_rows(flow: nd4, out: nd3):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        ym = ti.max(y - 1, 0)
        yp = ti.min(y + 1, height - 1)
        for x in range(width):
            xm = ti.max(x - 1, 0)
            xp = ti.min(x + 1, width - 1)
            total = 0.0
            for c in ti.static(range(2)):
                sx = ((flow[t, ym, xp, c] - flow[t, ym, xm, c])
                      + 2.0 * (flow[t, y, xp, c] - flow[t, y, xm, c])
                      + (flow[t, yp, xp, c] - flow[t, yp, xm, c])) / 8.0
                sy = ((flow[t, yp, xm, c] - flow[t, ym, xm, c])
                      + 2.0 * (flow[t, yp, x, c] - flow[t, ym, x, c])
                      + (flow[t, yp, xp, c] - flow[t, ym, xp, c])) / 8.0
                total += sx * sx + sy * sy
            out[t, y, x] = ti.sqrt(total)


@ti.kernel
def divergence_negative_rows(flow: nd4, out: nd3):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        ym = ti.max(y - 1, 0)
        yp = ti.min(y + 1, height - 1)
        for x in range(width):
            xm = ti.max(x - 1, 0)
            xp = ti.min(x + 1, width - 1)
            div = 0.5 * (flow[t, y, xp, 0] - flow[t, y, xm, 0]) + 0.5 * (flow[t, yp, x, 1] - flow[t, ym, x, 1])
            out[t, y, x] = ti.min(div, 0.0)


@host("image_gradient")
def image_gradient(src, gx, gy) -> None:
    """x and y derivatives with ``[1 -8 0 8 -1] / 12``, replicate border; see
    :func:`ivkernels.kernels.warp.derivatives.image_gradient` (NumPy arrays here)."""
    if src.size:
        five_point_gradient_rows(src, gx, gy)


@host("flow_sobel_magnitude")
def flow_sobel_magnitude(flow, out) -> None:
    """``sqrt(sum_c Sx(u_c)^2 + Sy(u_c)^2)`` with 1/8-normalised Sobel kernels; see
    :func:`ivkernels.kernels.warp.derivatives.flow_sobel_magnitude`."""
    if flow.size:
        flow_sobel_magnitude_rows(flow, out)


@host("divergence_negative")
def divergence_negative(flow, out) -> None:
    """One-sided divergence ``min(du/dx + dv/dy, 0)`` of Eq. 7, central differences; see
    :func:`ivkernels.kernels.warp.derivatives.divergence_negative`."""
    if flow.size:
        divergence_negative_rows(flow, out)
