"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic` (same names, same
signatures, NumPy arrays passed as ``ti.types.ndarray()``).

See the Warp module for the equations.  Each kernel's outermost loop runs
over the ``T * H`` image rows in parallel and loops over ``x`` inside, like
the Warp kernels.
"""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import GREY_WEIGHTS  # noqa: F401  (rgb2gray weights, re-exported)
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)


nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)
nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@ti.func
def srgb_encode(c):
    c = ti.math.clamp(c, 0.0, 1.0)
    result = 12.92 * c
    if c > 0.0031308:
        result = 1.055 * ti.pow(c, 1.0 / 2.4) - 0.055
    return result


@ti.func
def robust_weight(z, a, eps, quad_frac, quad_weight):
    robust = 0.0
    if quad_frac < 1.0:
        robust = 2.0 * a * ti.pow(z * z + eps * eps, a - 1.0)
    return quad_frac * quad_weight + (1.0 - quad_frac) * robust


@ti.func
def rof_divergence(p: ti.template(), t, y, x):
    d = p[t, y, x, 0] + p[t, y, x, 1]
    if x > 0:
        d -= p[t, y, x - 1, 0]
    if y > 0:
        d -= p[t, y - 1, x, 1]
    return d


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@ti.kernel
def _srgb_grey(rgb: nd4, out: nd3, wr: ti.f32, wg: ti.f32, wb: ti.f32):
    for t, y in ti.ndrange(out.shape[0], out.shape[1]):
        for x in range(out.shape[2]):
            g = wr * srgb_encode(rgb[t, y, x, 0]) + wg * srgb_encode(rgb[t, y, x, 1]) \
                + wb * srgb_encode(rgb[t, y, x, 2])
            out[t, y, x] = 255.0 * g


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
def _log_grey(rgb: nd4, out: nd3, wr: ti.f32, wg: ti.f32, wb: ti.f32, floor: ti.f32):
    for t, y in ti.ndrange(out.shape[0], out.shape[1]):
        for x in range(out.shape[2]):
            g = wr * rgb[t, y, x, 0] + wg * rgb[t, y, x, 1] + wb * rgb[t, y, x, 2]
            out[t, y, x] = ti.log(ti.max(g, floor))


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


@ti.kernel
def _assemble_system(flow: nd4, data: nd4, smooth: nd4, out: nd4, lam: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for t, y in ti.ndrange(flow.shape[0], height):
        for x in range(width):
            u = flow[t, y, x, 0]
            v = flow[t, y, x, 1]
            diag_u = 0.0
            diag_v = 0.0
            rhs_u = -data[t, y, x, 3]
            rhs_v = -data[t, y, x, 4]
            if x < width - 1:
                wu = lam * smooth[t, y, x, 0]
                wv = lam * smooth[t, y, x, 2]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y, x + 1, 0] - u)
                rhs_v += wv * (flow[t, y, x + 1, 1] - v)
            if x > 0:
                wu = lam * smooth[t, y, x - 1, 0]
                wv = lam * smooth[t, y, x - 1, 2]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y, x - 1, 0] - u)
                rhs_v += wv * (flow[t, y, x - 1, 1] - v)
            if y < height - 1:
                wu = lam * smooth[t, y, x, 1]
                wv = lam * smooth[t, y, x, 3]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y + 1, x, 0] - u)
                rhs_v += wv * (flow[t, y + 1, x, 1] - v)
            if y > 0:
                wu = lam * smooth[t, y - 1, x, 1]
                wv = lam * smooth[t, y - 1, x, 3]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y - 1, x, 0] - u)
                rhs_v += wv * (flow[t, y - 1, x, 1] - v)
            out[t, y, x, 0] = data[t, y, x, 0] + diag_u
            out[t, y, x, 1] = data[t, y, x, 1]
            out[t, y, x, 2] = data[t, y, x, 2] + diag_v
            out[t, y, x, 3] = rhs_u
            out[t, y, x, 4] = rhs_v


@ti.kernel
def _sor_sweep(du: nd4, system: nd4, smooth: nd4, lam: ti.f32, omega: ti.f32, parity: ti.i32):
    height = du.shape[1]
    width = du.shape[2]
    for t, y in ti.ndrange(du.shape[0], height):
        x0 = (parity + y) % 2
        for k in range((width - x0 + 1) // 2):
            x = x0 + 2 * k
            rhs_u = system[t, y, x, 3]
            rhs_v = system[t, y, x, 4]
            if x < width - 1:
                rhs_u += lam * smooth[t, y, x, 0] * du[t, y, x + 1, 0]
                rhs_v += lam * smooth[t, y, x, 2] * du[t, y, x + 1, 1]
            if x > 0:
                rhs_u += lam * smooth[t, y, x - 1, 0] * du[t, y, x - 1, 0]
                rhs_v += lam * smooth[t, y, x - 1, 2] * du[t, y, x - 1, 1]
            if y < height - 1:
                rhs_u += lam * smooth[t, y, x, 1] * du[t, y + 1, x, 0]
                rhs_v += lam * smooth[t, y, x, 3] * du[t, y + 1, x, 1]
            if y > 0:
                rhs_u += lam * smooth[t, y - 1, x, 1] * du[t, y - 1, x, 0]
                rhs_v += lam * smooth[t, y - 1, x, 3] * du[t, y - 1, x, 1]
            a11 = system[t, y, x, 0]
            a12 = system[t, y, x, 1]
            a22 = system[t, y, x, 2]
            det = a11 * a22 - a12 * a12
            if det > 1.0e-20 * (a11 * a22 + 1.0e-30):
                new_u = (a22 * rhs_u - a12 * rhs_v) / det
                new_v = (a11 * rhs_v - a12 * rhs_u) / det
                du[t, y, x, 0] = (1.0 - omega) * du[t, y, x, 0] + omega * new_u
                du[t, y, x, 1] = (1.0 - omega) * du[t, y, x, 1] + omega * new_v


@ti.kernel
def _apply_update(flow: nd4, du: nd4, out: nd4, limit: ti.f32):
    for t, y in ti.ndrange(flow.shape[0], flow.shape[1]):
        for x in range(flow.shape[2]):
            for c in ti.static(range(2)):
                d = du[t, y, x, c]
                if limit > 0.0:
                    d = ti.math.clamp(d, -limit, limit)
                out[t, y, x, c] = flow[t, y, x, c] + d


@ti.kernel
def _select_masked(mask: nd3, inside_mask: nd4, outside_mask: nd4, out: nd4):
    for t, y in ti.ndrange(mask.shape[0], mask.shape[1]):
        for x in range(mask.shape[2]):
            for c in range(out.shape[3]):
                if mask[t, y, x] >= 0.5:
                    out[t, y, x, c] = inside_mask[t, y, x, c]
                else:
                    out[t, y, x, c] = outside_mask[t, y, x, c]


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


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("srgb_grey")
def srgb_grey(rgb, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.srgb_grey`."""
    _srgb_grey(rgb, out, *GREY_WEIGHTS)


@host("row_min_max")
def row_min_max(src, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.row_min_max`."""
    _min_max(src, out)


@host("scale_shift")
def scale_shift(src, out, scale, shift) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.scale_shift`."""
    _scale_shift(src, out, scale, shift)


@host("rof_dual_step")
def rof_dual_step(img, p_in, p_out, theta: float, delta: float) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.rof_dual_step`."""
    _rof_dual_step(img, p_in, p_out, float(theta), float(delta))


@host("rof_texture")
def rof_texture(img, p, out, theta: float, alpha: float) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.rof_texture`."""
    _rof_texture(img, p, out, float(theta), float(alpha))


@host("pack_image_gradient")
def pack_image_gradient(img, gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_image_gradient`."""
    _pack_image_gradient(img, gx, gy, out)


@host("pack_gradient")
def pack_gradient(gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_gradient`."""
    _pack_gradient(gx, gy, out)


@host("data_coefficients")
def data_coefficients(i1, i1x, i1y, warped, inside, du, out, blend: float = 0.5, a: float = 0.45,
                      eps: float = 1e-3, quad_frac: float = 0.0, quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.data_coefficients`."""
    _data_coefficients(i1, i1x, i1y, warped, inside, du, out, float(blend), float(a), float(eps),
                       float(quad_frac), float(quad_weight))


@host("smoothness_weights")
def smoothness_weights(flow, du, out, a: float = 0.45, eps: float = 1e-3, quad_frac: float = 0.0,
                       quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.smoothness_weights`."""
    _smoothness_weights(flow, du, out, float(a), float(eps), float(quad_frac), float(quad_weight))


@host("assemble_system")
def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.assemble_system`."""
    _assemble_system(flow, data, smooth, out, float(lam))


@host("sor_sweep")
def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.sor_sweep`."""
    _sor_sweep(du, system, smooth, float(lam), float(omega), int(parity))


@host("apply_update")
def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.apply_update`."""
    _apply_update(flow, du, out, float(limit))


@host("select_masked")
def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.select_masked`."""
    _select_masked(mask, inside_mask, outside_mask, out)


@host("flow_sobel_components")
def flow_sobel_components(flow, out, row_energy) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.flow_sobel_components`."""
    _flow_sobel_components(flow, out, row_energy)


@host("thin_edges")
def thin_edges(sobel, cutoff, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.thin_edges`."""
    _thin_edges(sobel, cutoff, out)


@host("log_grey")
def log_grey(rgb, out, floor: float = 1e-3) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.log_grey`."""
    _log_grey(rgb, out, *GREY_WEIGHTS, float(floor))


@host("soft_census")
def soft_census(img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.soft_census`."""
    _soft_census(img, out, radius, float(eps), float(scale))


@host("pack_channels_gradient")
def pack_channels_gradient(feat, gx, gy, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.pack_channels_gradient`."""
    _pack_channels_gradient(feat, gx, gy, out)


@host("data_coefficients_channels")
def data_coefficients_channels(first, warped, inside, du, weights, out, blend: float = 0.5, a: float = 0.45,
                               eps: float = 1e-3, quad_frac: float = 0.0, quad_weight: float = 2e6) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.data_coefficients_channels`."""
    _data_coefficients_channels(first, warped, inside, du, weights, out, float(blend), float(a), float(eps),
                                float(quad_frac), float(quad_weight))
