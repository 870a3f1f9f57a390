"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.irls`:
the weights of one IRLS step (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["data_coefficients", "data_coefficients_channels", "smoothness_weights"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)


@ti.func
def robust_weight(z, a, eps, quad_frac, quad_weight):
    robust = 0.0
    if quad_frac < 1.0:
        robust = 2.0 * a * ti.pow(z * z + eps * eps, a - 1.0)
    return quad_frac * quad_weight + (1.0 - quad_frac) * robust


@ti.kernel
def _data_coefficients(i1: nd3, i1x: nd3, i1y: nd3, warped: nd4, inside: nd3, du: nd4, out: nd4,
                       blend: ti.f32, a: ti.f32, eps: ti.f32, quad_frac: ti.f32, quad_weight: ti.f32):
    for t, y in ti.ndrange(i1.shape[0], i1.shape[1]):
        for x in range(i1.shape[2]):
            ix = 0.0
            iy = 0.0
            it = 0.0
            if inside[t, y, x] > 0.5:
                ix = blend * warped[t, y, x, 1] + (1.0 - blend) * i1x[t, y, x]
                iy = blend * warped[t, y, x, 2] + (1.0 - blend) * i1y[t, y, x]
                it = warped[t, y, x, 0] - i1[t, y, x]
            residual = it + ix * du[t, y, x, 0] + iy * du[t, y, x, 1]
            psi = robust_weight(residual, a, eps, quad_frac, quad_weight)
            out[t, y, x, 0] = psi * ix * ix
            out[t, y, x, 1] = psi * ix * iy
            out[t, y, x, 2] = psi * iy * iy
            out[t, y, x, 3] = psi * ix * it
            out[t, y, x, 4] = psi * iy * it


@ti.kernel
def _data_coefficients_channels(first: nd4, warped: nd4, inside: nd3, du: nd4, weights: nd1, out: nd4,
                                blend: ti.f32, a: ti.f32, eps: ti.f32, quad_frac: ti.f32,
                                quad_weight: ti.f32):
    for t, y in ti.ndrange(first.shape[0], first.shape[1]):
        for x in range(first.shape[2]):
            sxx = 0.0
            sxy = 0.0
            syy = 0.0
            sxt = 0.0
            syt = 0.0
            if inside[t, y, x] > 0.5:
                du0 = du[t, y, x, 0]
                du1 = du[t, y, x, 1]
                for c in range(weights.shape[0]):
                    ix = blend * warped[t, y, x, 3 * c + 1] + (1.0 - blend) * first[t, y, x, 3 * c + 1]
                    iy = blend * warped[t, y, x, 3 * c + 2] + (1.0 - blend) * first[t, y, x, 3 * c + 2]
                    it = warped[t, y, x, 3 * c] - first[t, y, x, 3 * c]
                    psi = weights[c] * robust_weight(it + ix * du0 + iy * du1, a, eps, quad_frac, quad_weight)
                    sxx += psi * ix * ix
                    sxy += psi * ix * iy
                    syy += psi * iy * iy
                    sxt += psi * ix * it
                    syt += psi * iy * it
            out[t, y, x, 0] = sxx
            out[t, y, x, 1] = sxy
            out[t, y, x, 2] = syy
            out[t, y, x, 3] = sxt
            out[t, y, x, 4] = syt


@ti.kernel
def _smoothness_weights(flow: nd4, du: nd4, out: nd4, a: ti.f32, eps: ti.f32,
                        quad_frac: ti.f32, quad_weight: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for t, y in ti.ndrange(flow.shape[0], height):
        for x in range(width):
            for c in ti.static(range(2)):
                here = flow[t, y, x, c] + du[t, y, x, c]
                w_right = 0.0
                w_down = 0.0
                if x < width - 1:
                    w_right = robust_weight(flow[t, y, x + 1, c] + du[t, y, x + 1, c] - here,
                                            a, eps, quad_frac, quad_weight)
                if y < height - 1:
                    w_down = robust_weight(flow[t, y + 1, x, c] + du[t, y + 1, x, c] - here,
                                           a, eps, quad_frac, quad_weight)
                out[t, y, x, 2 * c] = w_right
                out[t, y, x, 2 * c + 1] = w_down


@host("data_coefficients")
def data_coefficients(i1, i1x, i1y, warped, inside, du, out, blend: float = 0.5, a: float = 0.45,
                      eps: float = 1e-3, quad_frac: float = 0.0, quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.data_coefficients`."""
    _data_coefficients(i1, i1x, i1y, warped, inside, du, out, float(blend), float(a), float(eps),
                       float(quad_frac), float(quad_weight))


@host("data_coefficients_channels")
def data_coefficients_channels(first, warped, inside, du, weights, out, blend: float = 0.5, a: float = 0.45,
                               eps: float = 1e-3, quad_frac: float = 0.0, quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.data_coefficients_channels`."""
    _data_coefficients_channels(first, warped, inside, du, weights, out, float(blend), float(a), float(eps),
                                float(quad_frac), float(quad_weight))


@host("smoothness_weights")
def smoothness_weights(flow, du, out, a: float = 0.45, eps: float = 1e-3, quad_frac: float = 0.0,
                       quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.smoothness_weights`."""
    _smoothness_weights(flow, du, out, float(a), float(eps), float(quad_frac), float(quad_weight))
