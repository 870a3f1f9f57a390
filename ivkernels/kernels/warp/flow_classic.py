"""Per-pixel kernels of the Classic+NL optical flow (Sun, Roth & Black, IJCV 2014).

The flow of the intrinsic video (paper Sec. 3, "pre-computed ... using
Classic+NL") minimises, per pyramid level and per warping step, the
linearised energy

    E(du) = sum_x rho_D(It + Ix du + Iy dv)
          + lam * sum_{x ~ y} rho_S((u + du)(y) - (u + du)(x)) + (same for v),

with rho the generalised Charbonnier ``rho(z) = (z^2 + eps^2)^a`` (a = 0.45,
eps = 1e-3), blended with a quadratic during graduated non-convexity (GNC).
One iteratively-reweighted least-squares (IRLS) step replaces each rho by
its weight ``psi(z) = rho'(z) / z`` at the current estimate and solves the
resulting 2x2-per-pixel sparse linear system for ``(du, dv)``:

    (psi_D Ix^2 + lam sum_n w^u_n) du + psi_D Ix Iy dv - lam sum_n w^u_n du_n
        = -psi_D Ix It - lam sum_n w^u_n (u - u_n)          (and the same for v)

(the normal equations of the Classic+NL "flow operator"; ``n`` runs over the
4-neighbours joined by an existing first-order difference).  The system is
solved data-parallel by red-black successive over-relaxation: pixels with
``(x + y) % 2 == parity`` read only neighbours of the other colour, so a
sweep of one colour is race-free and can be split into row bands anywhere.

Also here: the ROF structure-texture decomposition the flow is computed on
(Chambolle's dual projection), the sRGB grey conversion of the input, and
two small helpers (per-row min/max, per-channel affine rescale) that the
host uses to normalise images the way the public Classic+NL code does.

Array layout: see :mod:`ivkernels.kernels`.  Every kernel runs one thread per
image row (``row = t * H + y``) and loops over ``x``; all are gathers except
:func:`sor_sweep`, which updates ``du`` in place one colour at a time.

The sweep reads only ``du``: :func:`assemble_system` first folds the data
coefficients, the smoothness weights and the current flow into each pixel's
2x2 block and right-hand side, which keeps a sweep's memory traffic low.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import GREY_WEIGHTS  # noqa: F401  (rgb2gray weights, re-exported)
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def srgb_encode(c: float):
    """sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1]."""
    c = wp.clamp(c, 0.0, 1.0)
    result = 12.92 * c
    if c > 0.0031308:
        result = 1.055 * wp.pow(c, 1.0 / 2.4) - 0.055
    return result


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


@wp.func
def rof_divergence(p: wp.array4d(dtype=float), t: int, y: int, x: int):
    """Backward-difference divergence of the dual field ``p`` at ``(y, x)``;
    ``p`` is taken as zero outside the image (Chambolle 2004, Eq. 8)."""
    d = p[t, y, x, 0] + p[t, y, x, 1]
    if x > 0:
        d -= p[t, y, x - 1, 0]
    if y > 0:
        d -= p[t, y - 1, x, 1]
    return d


# ----------------------------------------------------------------------------
# Kernels: one thread per image row (row = t * H + y), looping over x
# ----------------------------------------------------------------------------

@wp.kernel
def srgb_grey_rows(row_begin: int, rgb: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                   wr: float, wg: float, wb: float):
    r = row_begin + wp.tid()
    height = out.shape[1]
    t = r // height
    y = r - t * height
    for x in range(out.shape[2]):
        g = wr * srgb_encode(rgb[t, y, x, 0]) + wg * srgb_encode(rgb[t, y, x, 1]) \
            + wb * srgb_encode(rgb[t, y, x, 2])
        out[t, y, x] = 255.0 * g


@wp.kernel
def log_grey_rows(row_begin: int, rgb: wp.array4d(dtype=float), out: wp.array3d(dtype=float),
                  wr: float, wg: float, wb: float, floor: float):
    r = row_begin + wp.tid()
    height = out.shape[1]
    t = r // height
    y = r - t * height
    for x in range(out.shape[2]):
        g = wr * rgb[t, y, x, 0] + wg * rgb[t, y, x, 1] + wb * rgb[t, y, x, 2]
        out[t, y, x] = wp.log(wp.max(g, floor))


@wp.kernel
def min_max_rows(row_begin: int, src: wp.array4d(dtype=float), out: wp.array3d(dtype=float)):
    r = row_begin + wp.tid()
    height = src.shape[1]
    t = r // height
    y = r - t * height
    for c in range(src.shape[3]):
        lo = src[t, y, 0, c]
        hi = lo
        for x in range(1, src.shape[2]):
            v = src[t, y, x, c]
            lo = wp.min(lo, v)
            hi = wp.max(hi, v)
        out[r, c, 0] = lo
        out[r, c, 1] = hi


@wp.kernel
def scale_shift_rows(row_begin: int, src: wp.array4d(dtype=float), out: wp.array4d(dtype=float),
                     scale: wp.array(dtype=float), shift: wp.array(dtype=float)):
    r = row_begin + wp.tid()
    height = src.shape[1]
    t = r // height
    y = r - t * height
    for x in range(src.shape[2]):
        for c in range(src.shape[3]):
            out[t, y, x, c] = src[t, y, x, c] * scale[c] + shift[c]


@wp.kernel
def rof_dual_step_rows(row_begin: int, img: wp.array3d(dtype=float), p_in: wp.array4d(dtype=float),
                       p_out: wp.array4d(dtype=float), theta: float, delta: float):
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    # v = img + theta div(p) at (y, x); its value at x + 1 is carried to the next x
    v = float(0.0)
    if width > 0:
        v = img[t, y, 0] + theta * rof_divergence(p_in, t, y, 0)
    for x in range(width):
        gx = 0.0
        gy = 0.0
        v_right = float(0.0)
        if x < width - 1:
            v_right = img[t, y, x + 1] + theta * rof_divergence(p_in, t, y, x + 1)
            gx = v_right - v
        if y < height - 1:
            gy = img[t, y + 1, x] + theta * rof_divergence(p_in, t, y + 1, x) - v
        px = p_in[t, y, x, 0] + delta * gx
        py = p_in[t, y, x, 1] + delta * gy
        norm = wp.max(1.0, wp.sqrt(px * px + py * py))
        p_out[t, y, x, 0] = px / norm
        p_out[t, y, x, 1] = py / norm
        v = v_right


@wp.kernel
def rof_texture_rows(row_begin: int, img: wp.array3d(dtype=float), p: wp.array4d(dtype=float),
                     out: wp.array3d(dtype=float), theta: float, alpha: float):
    r = row_begin + wp.tid()
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(img.shape[2]):
        structure = img[t, y, x] + theta * rof_divergence(p, t, y, x)
        out[t, y, x] = img[t, y, x] - alpha * structure


@wp.kernel
def pack_image_gradient_rows(row_begin: int, img: wp.array3d(dtype=float), gx: wp.array3d(dtype=float),
                             gy: wp.array3d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(img.shape[2]):
        out[t, y, x, 0] = img[t, y, x]
        out[t, y, x, 1] = gx[t, y, x]
        out[t, y, x, 2] = gy[t, y, x]


@wp.kernel
def pack_gradient_rows(row_begin: int, gx: wp.array3d(dtype=float), gy: wp.array3d(dtype=float),
                       out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = gx.shape[1]
    t = r // height
    y = r - t * height
    for x in range(gx.shape[2]):
        out[t, y, x, 0] = gx[t, y, x]
        out[t, y, x, 1] = gy[t, y, x]


@wp.kernel
def data_coefficients_rows(row_begin: int, i1: wp.array3d(dtype=float), i1x: wp.array3d(dtype=float),
                           i1y: wp.array3d(dtype=float), warped: wp.array4d(dtype=float),
                           inside: wp.array3d(dtype=float), du: wp.array4d(dtype=float),
                           out: wp.array4d(dtype=float), blend: float, a: float, eps: float,
                           quad_frac: float, quad_weight: float):
    r = row_begin + wp.tid()
    height = i1.shape[1]
    t = r // height
    y = r - t * height
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


@wp.kernel
def soft_census_rows(row_begin: int, img: wp.array3d(dtype=float), out: wp.array4d(dtype=float),
                     radius: int, eps: float, scale: float):
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
        centre = img[t, y, x]
        k = int(0)
        for dy in range(-radius, radius + 1):
            yy = wp.clamp(y + dy, 0, height - 1)
            for dx in range(-radius, radius + 1):
                if dy != 0 or dx != 0:
                    d = img[t, yy, wp.clamp(x + dx, 0, width - 1)] - centre
                    out[t, y, x, k] = scale * d / wp.sqrt(d * d + eps * eps)
                    k += 1


@wp.kernel
def pack_channels_gradient_rows(row_begin: int, feat: wp.array4d(dtype=float), gx: wp.array4d(dtype=float),
                                gy: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = feat.shape[1]
    t = r // height
    y = r - t * height
    for x in range(feat.shape[2]):
        for c in range(feat.shape[3]):
            out[t, y, x, 3 * c] = feat[t, y, x, c]
            out[t, y, x, 3 * c + 1] = gx[t, y, x, c]
            out[t, y, x, 3 * c + 2] = gy[t, y, x, c]


@wp.kernel
def data_coefficients_channels_rows(row_begin: int, first: wp.array4d(dtype=float),
                                    warped: wp.array4d(dtype=float), inside: wp.array3d(dtype=float),
                                    du: wp.array4d(dtype=float), weights: wp.array(dtype=float),
                                    out: wp.array4d(dtype=float), blend: float, a: float, eps: float,
                                    quad_frac: float, quad_weight: float):
    r = row_begin + wp.tid()
    height = first.shape[1]
    t = r // height
    y = r - t * height
    for x in range(first.shape[2]):
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
def smoothness_weights_rows(row_begin: int, flow: wp.array4d(dtype=float), du: wp.array4d(dtype=float),
                            out: wp.array4d(dtype=float), a: float, eps: float,
                            quad_frac: float, quad_weight: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    width = flow.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
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


@wp.kernel
def assemble_system_rows(row_begin: int, flow: wp.array4d(dtype=float), data: wp.array4d(dtype=float),
                         smooth: wp.array4d(dtype=float), out: wp.array4d(dtype=float), lam: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    width = flow.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
        u = flow[t, y, x, 0]
        v = flow[t, y, x, 1]
        diag_u = float(0.0)
        diag_v = float(0.0)
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


@wp.kernel
def sor_sweep_rows(row_begin: int, du: wp.array4d(dtype=float), system: wp.array4d(dtype=float),
                   smooth: wp.array4d(dtype=float), lam: float, omega: float, parity: int):
    r = row_begin + wp.tid()
    height = du.shape[1]
    width = du.shape[2]
    t = r // height
    y = r - t * height
    x = (parity + y) % 2
    while x < width:
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
        x += 2


@wp.kernel
def apply_update_rows(row_begin: int, flow: wp.array4d(dtype=float), du: wp.array4d(dtype=float),
                      out: wp.array4d(dtype=float), limit: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(flow.shape[2]):
        for c in range(2):
            d = du[t, y, x, c]
            if limit > 0.0:
                d = wp.clamp(d, -limit, limit)
            out[t, y, x, c] = flow[t, y, x, c] + d


@wp.kernel
def select_masked_rows(row_begin: int, mask: wp.array3d(dtype=float), inside_mask: wp.array4d(dtype=float),
                       outside_mask: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = mask.shape[1]
    t = r // height
    y = r - t * height
    for x in range(mask.shape[2]):
        for c in range(out.shape[3]):
            if mask[t, y, x] >= 0.5:
                out[t, y, x, c] = inside_mask[t, y, x, c]
            else:
                out[t, y, x, c] = outside_mask[t, y, x, c]


@wp.func
def sobel_at(flow: wp.array4d(dtype=float), t: int, y: int, x: int, c: int):
    """Sobel derivatives ``(gx, gy)`` of flow component ``c``, kernels / 8, replicate border."""
    height = flow.shape[1]
    width = flow.shape[2]
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    xm = wp.max(x - 1, 0)
    xp = wp.min(x + 1, width - 1)
    gx = (flow[t, ym, xp, c] + 2.0 * flow[t, y, xp, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, y, xm, c] - flow[t, yp, xm, c]) / 8.0
    gy = (flow[t, yp, xm, c] + 2.0 * flow[t, yp, x, c] + flow[t, yp, xp, c]
          - flow[t, ym, xm, c] - 2.0 * flow[t, ym, x, c] - flow[t, ym, xp, c]) / 8.0
    return gx, gy


@wp.kernel
def flow_sobel_components_rows(row_begin: int, flow: wp.array4d(dtype=float), out: wp.array4d(dtype=float),
                               row_energy: wp.array2d(dtype=float)):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    sum_u = float(0.0)
    sum_v = float(0.0)
    for x in range(flow.shape[2]):
        gxu, gyu = sobel_at(flow, t, y, x, 0)
        gxv, gyv = sobel_at(flow, t, y, x, 1)
        out[t, y, x, 0] = gxu
        out[t, y, x, 1] = gyu
        out[t, y, x, 2] = gxv
        out[t, y, x, 3] = gyv
        sum_u += gxu * gxu + gyu * gyu
        sum_v += gxv * gxv + gyv * gyv
    row_energy[r, 0] = sum_u
    row_energy[r, 1] = sum_v


@wp.func
def sobel_energy(sobel: wp.array4d(dtype=float), t: int, y: int, x: int, c: int):
    gx = sobel[t, y, x, 2 * c]
    gy = sobel[t, y, x, 2 * c + 1]
    return gx * gx + gy * gy


@wp.kernel
def thin_edges_rows(row_begin: int, sobel: wp.array4d(dtype=float), cutoff: wp.array2d(dtype=float),
                    out: wp.array3d(dtype=float)):
    r = row_begin + wp.tid()
    height = sobel.shape[1]
    width = sobel.shape[2]
    t = r // height
    y = r - t * height
    ym = wp.max(y - 1, 0)
    yp = wp.min(y + 1, height - 1)
    for x in range(width):
        xm = wp.max(x - 1, 0)
        xp = wp.min(x + 1, width - 1)
        edge = float(0.0)
        for c in range(2):
            b = sobel_energy(sobel, t, y, x, c)
            if b > cutoff[t, c]:
                ax = wp.abs(sobel[t, y, x, 2 * c])
                ay = wp.abs(sobel[t, y, x, 2 * c + 1])
                if ax >= ay and b > sobel_energy(sobel, t, y, xm, c) and b >= sobel_energy(sobel, t, y, xp, c):
                    edge = 1.0
                if ay >= ax and b > sobel_energy(sobel, t, ym, x, c) and b >= sobel_energy(sobel, t, yp, x, c):
                    edge = 1.0
        out[t, y, x] = edge


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _rows(a) -> int:
    return a.shape[0] * a.shape[1]


@host("srgb_grey")
def srgb_grey(rgb, out) -> None:
    """Grey level of linear RGB frames, sRGB-encoded and scaled to [0, 255].

    ``out = 255 * (0.2989 R' + 0.5870 G' + 0.1140 B')`` with ``X'`` the
    sRGB encoding of the linear value clamped to [0, 1] (MATLAB's ``rgb2gray``
    of the 8-bit image, the input of the public Classic+NL code).

    rgb : (T, H, W, 3) float32, linear RGB in [0, 1].
    out : (T, H, W) float32, grey in [0, 255] (gamma-encoded, not linear).
    """
    t, h, w, _ = rgb.shape
    launch_rows(srgb_grey_rows, t * h, [rgb, out, *GREY_WEIGHTS], rgb.device)


@host("log_grey")
def log_grey(rgb, out, floor: float = 1e-3) -> None:
    """Natural log of the linear grey level: ``out = log(max(0.2989 R + 0.5870 G + 0.1140 B, floor))``.

    Under the image model ``i = a * s`` the log turns the shading into an
    additive term, which the ROF structure part then absorbs where it is smooth.

    rgb : (T, H, W, 3) float32, linear RGB.
    out : (T, H, W) float32, log grey (<= 0 for input in [0, 1]).
    """
    t, h, w, _ = rgb.shape
    launch_rows(log_grey_rows, t * h, [rgb, out, *GREY_WEIGHTS, float(floor)], rgb.device)


@host("row_min_max")
def row_min_max(src, out) -> None:
    """Minimum and maximum of every image row and channel.

    src : (T, H, W, C) float32.
    out : (T*H, C, 2) float32; ``out[t*H + y, c] = (min, max)`` of ``src[t, y, :, c]``.
    The host finishes the reduction over rows (``out.min(0)``, ``out.max(0)``).
    """
    t, h, w, c = src.shape
    launch_rows(min_max_rows, t * h, [src, out], src.device)


@host("scale_shift")
def scale_shift(src, out, scale, shift) -> None:
    """Per-channel affine map ``out[..., c] = src[..., c] * scale[c] + shift[c]``.

    src, out : (T, H, W, C) float32 (may be the same array).
    scale, shift : (C,) float32 arrays on the same device.
    """
    t, h, w, c = src.shape
    launch_rows(scale_shift_rows, t * h, [src, out, scale, shift], src.device)


@host("rof_dual_step")
def rof_dual_step(img, p_in, p_out, theta: float, delta: float) -> None:
    """One step of Chambolle's projection for the ROF structure image.

    With ``v = img + theta * div(p_in)`` (forward-difference gradient,
    replicate border; backward-difference divergence, zero outside):
    ``p_out = (p_in + delta * grad v) / max(1, |p_in + delta * grad v|)``.
    Iterating from ``p = 0`` converges to the dual of
    ``min_S |grad S|_TV + |S - img|^2 / (2 theta)`` for ``delta <= 1 / (4 theta)``.

    img : (T, H, W) float32 (the public code scales it to [-1, 1]).
    p_in, p_out : (T, H, W, 2) float32 dual field; must be different arrays.
    """
    t, h, w = img.shape
    launch_rows(rof_dual_step_rows, t * h, [img, p_in, p_out, float(theta), float(delta)], img.device)


@host("rof_texture")
def rof_texture(img, p, out, theta: float, alpha: float) -> None:
    """Texture part of the ROF decomposition: ``out = img - alpha * (img + theta * div p)``.

    ``img + theta * div p`` is the structure image; ``alpha = 0.95`` keeps
    5 % of it (Classic+NL's texture weight).

    img : (T, H, W) float32; p : (T, H, W, 2) float32 from :func:`rof_dual_step`;
    out : (T, H, W) float32 (may be ``img``).
    """
    t, h, w = img.shape
    launch_rows(rof_texture_rows, t * h, [img, p, out, float(theta), float(alpha)], img.device)


@host("pack_image_gradient")
def pack_image_gradient(img, gx, gy, out) -> None:
    """Stack an image and its two derivatives as channels: ``out = (img, gx, gy)``.

    img, gx, gy : (T, H, W) float32; out : (T, H, W, 3) float32.
    """
    t, h, w = img.shape
    launch_rows(pack_image_gradient_rows, t * h, [img, gx, gy, out], img.device)


@host("pack_gradient")
def pack_gradient(gx, gy, out) -> None:
    """Stack two derivatives as channels: ``out = (gx, gy)``, the feature of a gradient-constancy term.

    gx, gy : (T, H, W) float32 (e.g. from
    :func:`ivkernels.kernels.warp.derivatives.image_gradient`); out : (T, H, W, 2) float32.
    """
    t, h, w = gx.shape
    launch_rows(pack_gradient_rows, t * h, [gx, gy, out], gx.device)


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
    """
    t, h, w = i1.shape
    dev = i1.device
    launch_rows(data_coefficients_rows, t * h,
                [i1, i1x, i1y, warped, inside, du, out, float(blend), float(a), float(eps),
                 float(quad_frac), float(quad_weight)], dev)


@host("soft_census")
def soft_census(img, out, radius: int = 1, eps: float = 4.0, scale: float = 1.0) -> None:
    """Soft ternary (census) transform: one channel per neighbour of a window.

    ``out[t, y, x, k] = scale * d_k / sqrt(d_k^2 + eps^2)`` with
    ``d_k = img(y + dy_k, x + dx_k) - img(y, x)`` over the ``(2 radius + 1)^2 - 1``
    offsets of the window in row-major order, the centre left out; neighbour
    indices clamped (replicate border).  A smooth stand-in for the ternary
    census of Stein (2004) / Zabih & Woodfill (1994): it keeps the sign of each
    local difference and saturates its size, so it is unchanged by a gain or
    an offset of the image that is constant over the window.

    img : (T, H, W) float32.
    out : (T, H, W, C) float32, ``C = (2 radius + 1)^2 - 1``.
    """
    t, h, w = img.shape
    launch_rows(soft_census_rows, t * h, [img, out, radius, float(eps), float(scale)], img.device)


@host("pack_channels_gradient")
def pack_channels_gradient(feat, gx, gy, out) -> None:
    """Interleave C channels with their derivatives: ``out[..., 3c : 3c + 3] = (feat_c, gx_c, gy_c)``.

    feat, gx, gy : (T, H, W, C) float32; out : (T, H, W, 3C) float32.
    """
    t, h, w, c = feat.shape
    launch_rows(pack_channels_gradient_rows, t * h, [feat, gx, gy, out], feat.device)


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
    """
    t, h, w, _ = first.shape
    dev = first.device
    launch_rows(data_coefficients_channels_rows, t * h,
                [first, warped, inside, du, weights, out, float(blend), float(a), float(eps),
                 float(quad_frac), float(quad_weight)], dev)


@host("smoothness_weights")
def smoothness_weights(flow, du, out, a: float = 0.45, eps: float = 1e-3, quad_frac: float = 0.0,
                       quad_weight: float = 2e6) -> None:
    """IRLS weights of the first-order smoothness term on ``u + du``.

    flow, du : (T, H, W, 2) float32.
    out : (T, H, W, 4) float32: ``psi`` of the difference to the right
        neighbour and to the neighbour below, for u (channels 0, 1) and
        v (channels 2, 3); 0 where that neighbour does not exist.
    """
    t, h, w, _ = flow.shape
    launch_rows(smoothness_weights_rows, t * h,
                [flow, du, out, float(a), float(eps), float(quad_frac), float(quad_weight)], flow.device)


@host("assemble_system")
def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """The 2x2 block and right-hand side of every pixel's IRLS equations.

    ``out = (a11, a12, a22, b_u, b_v)`` with ``a11 = psi_D Ix^2 + lam sum_n w^u_n``,
    ``a12 = psi_D Ix Iy``, ``a22 = psi_D Iy^2 + lam sum_n w^v_n`` and
    ``b_u = -psi_D Ix It + lam sum_n w^u_n (u_n - u)`` (likewise ``b_v``), so
    that the equations read ``A_p du_p - lam sum_n w_n du_n = b_p``.

    flow : (T, H, W, 2) float32, flow ``u`` the increment is added to.
    data : (T, H, W, 5) float32 from :func:`data_coefficients`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights`.
    out : (T, H, W, 5) float32.
    """
    t, h, w, _ = flow.shape
    dev = flow.device
    launch_rows(assemble_system_rows, t * h, [flow, data, smooth, out, float(lam)], dev)


@host("sor_sweep")
def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """One half-sweep of red-black block SOR on the IRLS system, in place on ``du``.

    Updates the pixels with ``(x + y) % 2 == parity``: solves their 2x2 block
    ``A_p du_p = b_p + lam sum_n w_n du_n`` with the neighbours fixed, and
    relaxes by ``omega`` (1 = Gauss-Seidel).  Call with parity 0 then 1 for a
    full sweep.

    du : (T, H, W, 2) float32, increment, read and written.
    system : (T, H, W, 5) float32 from :func:`assemble_system`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights` (the same
        ``lam`` as given to :func:`assemble_system`).
    """
    t, h, w, _ = du.shape
    dev = du.device
    launch_rows(sor_sweep_rows, t * h, [du, system, smooth, float(lam), float(omega), int(parity)], dev)


@host("apply_update")
def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """``out = flow + clip(du, -limit, limit)`` (no clipping when ``limit <= 0``).

    flow, du, out : (T, H, W, 2) float32; ``out`` may be ``flow``.
    """
    t, h, w, _ = flow.shape
    launch_rows(apply_update_rows, t * h, [flow, du, out, float(limit)], flow.device)


@host("select_masked")
def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """``out = inside_mask`` where ``mask >= 0.5``, else ``outside_mask``.

    mask : (T, H, W) float32; inside_mask, outside_mask, out : (T, H, W, C) float32
    (``out`` may alias either input).
    """
    t, h, w = mask.shape
    launch_rows(select_masked_rows, t * h, [mask, inside_mask, outside_mask, out], mask.device)


@host("flow_sobel_components")
def flow_sobel_components(flow, out, row_energy) -> None:
    """Sobel derivatives of both flow components and their per-row energy.

    Kernels ``[[-1 0 1], [-2 0 2], [-1 0 1]] / 8`` and its transpose, replicate
    border (MATLAB's ``edge(u, 'sobel')`` gradients).

    flow : (T, H, W, 2) float32.
    out : (T, H, W, 4) float32 ``(du/dx, du/dy, dv/dx, dv/dy)``.
    row_energy : (T*H, 2) float32, ``sum_x |grad u|^2`` and ``sum_x |grad v|^2``
        of each row (the host averages them into the edge thresholds).
    """
    t, h, w, _ = flow.shape
    launch_rows(flow_sobel_components_rows, t * h, [flow, out, row_energy], flow.device)


@host("thin_edges")
def thin_edges(sobel, cutoff, out) -> None:
    """Thinned Sobel edges of a flow field (MATLAB ``edge(., 'sobel')`` of u OR of v).

    A pixel is an edge of component ``c`` where ``b = gx^2 + gy^2`` exceeds
    ``cutoff[t, c]`` and is a local maximum across the edge: along x where
    ``|gx| >= |gy|`` (``b > b(x-1)`` and ``b >= b(x+1)``), along y where
    ``|gy| >= |gx|``; neighbour indices clamped.  The public code takes
    ``cutoff = 4 * mean(b)`` per frame and component.

    sobel : (T, H, W, 4) float32 from :func:`flow_sobel_components`.
    cutoff : (T, 2) float32 squared-magnitude thresholds (pixels^2 / pixel^2).
    out : (T, H, W) float32, 1 on an edge of u or v, else 0.
    """
    t, h, w, _ = sobel.shape
    launch_rows(thin_edges_rows, t * h, [sobel, cutoff, out], sobel.device)
