"""The weights of one IRLS step: data coefficients and smoothness weights.

Each robust penalty ``rho(z) = (z^2 + eps^2)^a`` (blended with a quadratic
during graduated non-convexity) is replaced by its weight
``psi(z) = rho'(z) / z`` (:func:`robust_weight`) at the current estimate:
:func:`data_coefficients` and :func:`data_coefficients_channels` give
``psi_D`` times the products of the linearised constancy term,
:func:`smoothness_weights` the weights of the four first-order differences.
Part of :mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

__all__ = ["data_coefficients", "data_coefficients_channels", "smoothness_weights"]

wp.set_module_options({"enable_backward": False})


@wp.func
def robust_weight(z: float, a: float, eps: float, quad_frac: float, quad_weight: float):
    """IRLS weight ``psi(z) = rho'(z) / z`` of the GNC-blended penalty.

    ``rho = quad_frac * rho_Q + (1 - quad_frac) * rho_GC`` with the
    generalised Charbonnier ``rho_GC(z) = (z^2 + eps^2)^a`` (its
    ``psi = 2 a (z^2 + eps^2)^(a-1)``) and a quadratic whose ``psi`` is the
    constant ``quad_weight`` (``2 / sigma^2`` for ``rho_Q = z^2 / sigma^2``).
    """
    robust = 0.0
    if quad_frac < 1.0:
        robust = 2.0 * a * wp.pow(z * z + eps * eps, a - 1.0)
    return quad_frac * quad_weight + (1.0 - quad_frac) * robust


@wp.kernel
def data_coefficients_rows(row_begin: int, tiles: int, i1: wp.array3d(dtype=float),
                           i1x: wp.array3d(dtype=float), i1y: wp.array3d(dtype=float),
                           warped: wp.array4d(dtype=float), inside: wp.array3d(dtype=float),
                           du: wp.array4d(dtype=float), out: wp.array4d(dtype=float), blend: float, a: float,
                           eps: float, quad_frac: float, quad_weight: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, i1.shape[2])
    height = i1.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
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


@wp.kernel
def data_coefficients_channels_rows(row_begin: int, tiles: int, first: wp.array4d(dtype=float),
                                    warped: wp.array4d(dtype=float), inside: wp.array3d(dtype=float),
                                    du: wp.array4d(dtype=float), weights: wp.array(dtype=float),
                                    out: wp.array4d(dtype=float), blend: float, a: float, eps: float,
                                    quad_frac: float, quad_weight: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, first.shape[2])
    height = first.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        sxx = float(0.0)
        sxy = float(0.0)
        syy = float(0.0)
        sxt = float(0.0)
        syt = float(0.0)
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


@wp.kernel
def smoothness_weights_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                            du: wp.array4d(dtype=float), out: wp.array4d(dtype=float), a: float, eps: float,
                            quad_frac: float, quad_weight: float):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        for c in range(2):
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
    """IRLS coefficients of the linearised brightness-constancy term.

    Derivatives as in Classic+NL: ``It = I2(x + u) - I1``, ``Ix = blend *
    I2x(x + u) + (1 - blend) * I1x`` (the same for y), all three set to 0 where
    ``x + u`` leaves the image.  The weight ``psi`` (see :func:`robust_weight`)
    is taken at the linearised residual ``It + Ix du + Iy dv``.

    i1, i1x, i1y : (T, H, W) float32, first frames and their derivatives.
    warped : (T, H, W, 3) float32, second frames and their x/y derivatives
        warped by the current flow (channels ``I2, I2x, I2y``).
    inside : (T, H, W) float32, 1 where ``x + u`` lies in the image.
    du : (T, H, W, 2) float32, current flow increment.
    out : (T, H, W, 5) float32 ``psi * (Ix Ix, Ix Iy, Iy Iy, Ix It, Iy It)``.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w = i1.shape
    dev = i1.device
    tiles = row_tiles(w, dev)
    launch_rows(data_coefficients_rows, t * h * tiles,
                [tiles, i1, i1x, i1y, warped, inside, du, out, float(blend), float(a), float(eps),
                 float(quad_frac), float(quad_weight)], dev)


@host("data_coefficients_channels")
def data_coefficients_channels(first, warped, inside, du, weights, out, blend: float = 0.5, a: float = 0.45,
                               eps: float = 1e-3, quad_frac: float = 0.0, quad_weight: float = 2e6) -> None:
    """IRLS coefficients of a constancy term on C feature channels, summed.

    ``E_D = sum_c w_c rho(It_c + Ix_c du + Iy_c dv)``, each channel linearised
    as in :func:`data_coefficients` (``Ix_c = blend * I2x_c(x + u) + (1 - blend)
    * I1x_c``, ``It_c = I2_c(x + u) - I1_c``) and penalised by its own robust
    weight; all terms 0 where ``x + u`` leaves the image.  One channel with
    weight 1 is :func:`data_coefficients`; the channels (I, Ix, Iy) with
    weights (1, gamma, gamma) are brightness plus gradient constancy (Brox et
    al., ECCV 2004); the :func:`soft_census` channels a census data term.

    first : (T, H, W, 3C) float32, channels ``(I1_c, I1x_c, I1y_c)`` of the first frames.
    warped : (T, H, W, 3C) float32, the same of the second frames warped by the flow.
    inside : (T, H, W) float32, 1 where ``x + u`` lies in the image.
    du : (T, H, W, 2) float32, current increment.
    weights : (C,) float32 channel weights ``w_c``.
    out : (T, H, W, 5) float32 ``sum_c psi_c (Ix Ix, Ix Iy, Iy Iy, Ix It, Iy It)_c``.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = first.shape
    dev = first.device
    tiles = row_tiles(w, dev)
    launch_rows(data_coefficients_channels_rows, t * h * tiles,
                [tiles, first, warped, inside, du, weights, out, float(blend), float(a), float(eps),
                 float(quad_frac), float(quad_weight)], dev)


@host("smoothness_weights")
def smoothness_weights(flow, du, out, a: float = 0.45, eps: float = 1e-3, quad_frac: float = 0.0,
                       quad_weight: float = 2e6) -> None:
    """IRLS weights of the first-order smoothness term on ``u + du``.

    flow, du : (T, H, W, 2) float32.
    out : (T, H, W, 4) float32: ``psi`` of the difference to the right
        neighbour and to the neighbour below, for u (channels 0, 1) and
        v (channels 2, 3); 0 where that neighbour does not exist.
    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = flow.shape
    tiles = row_tiles(w, flow.device)
    launch_rows(smoothness_weights_rows, t * h * tiles,
                [tiles, flow, du, out, float(a), float(eps), float(quad_frac), float(quad_weight)], flow.device)
