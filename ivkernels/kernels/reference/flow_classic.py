"""``flow_classic``: the declared contract of its host functions, and the NumPy references, float64.

Vectorised where the operation is a plain map; the red-black sweep is written
as the two masked Jacobi-like half steps it is.  Each function returns its
outputs.
"""
from __future__ import annotations

import numpy as np

from ivkernels.colour import srgb_encode
from ivkernels.kernels.contract import Array, Choice, Family, Int, Out, Positive, Real, Rule
from ivkernels.kernels.host import GREY_WEIGHTS

FAMILY = Family("flow_classic", "The Classic+NL optical flow's per-pixel steps.")


def _columns(sizes, args):
    if sizes["W"] < 1:
        raise ValueError(f"src must have at least one column, got shape {tuple(args['src'].shape)}")


_IRLS = "a=0.45, eps=0.001, quad_frac=0.0, quad_weight=2000000.0"
_ROBUST = dict(a=Real, eps=Real, quad_frac=Real, quad_weight=Real)

FAMILY.declare("srgb_grey(rgb, out)", "Grey level of sRGB-encoded rgb in [0, 255].", rgb="T H W 3", out=Out("T H W"))
FAMILY.declare("log_grey(rgb, out, floor=0.001)", "``log(max(grey(rgb), floor))``; ``floor > 0``.",
               rgb="T H W 3", out=Out("T H W"), floor=Positive)
FAMILY.declare("row_min_max(src, out)", "Per row and channel (min, max) of src.",
               src="T H W C", out=Out("T*H C 2"), rules=(Rule(_columns, after="src"),))
FAMILY.declare("scale_shift(src, out, scale, shift)", "``out = src * scale[c] + shift[c]``.",
               src="T H W C", out=Out("T H W C"), scale="C", shift="C")
FAMILY.declare("rof_dual_step(img, p_in, p_out, theta, delta)", "One Chambolle step of the ROF dual.",
               img="T H W", p_in="T H W 2", p_out=Out("T H W 2"), theta=Real, delta=Real,
               separate=(("p_in", "p_out", "the step reads neighbours of p_in"),))
FAMILY.declare("rof_texture(img, p, out, theta, alpha)", "``out = img - alpha (img + theta div p)``.",
               img="T H W", p="T H W 2", out=Out("T H W"), theta=Real, alpha=Real)
FAMILY.declare("pack_image_gradient(img, gx, gy, out)", "``out = (img, gx, gy)``.",
               img="T H W", gx="T H W", gy="T H W", out=Out("T H W 3"))
FAMILY.declare("pack_gradient(gx, gy, out)", "``out = (gx, gy)``.", gx="T H W", gy="T H W", out=Out("T H W 2"))
FAMILY.declare(f"data_coefficients(i1, i1x, i1y, warped, inside, du, out, blend=0.5, {_IRLS})",
               "IRLS data coefficients of brightness constancy.",
               i1="T H W", i1x="T H W", i1y="T H W", warped="T H W 3", inside="T H W", du="T H W 2",
               out=Out("T H W 5"), blend=Real, **_ROBUST)
FAMILY.declare("soft_census(img, out, radius=1, eps=4.0, scale=1.0)", "Soft census of img, one channel per neighbour.",
               img="T H W", out=Out("T H W (2*radius+1)**2-1", layout="(T, H, W, (2r+1)^2 - 1)"),
               radius=Int(1), eps=Positive, scale=Real)
FAMILY.declare("pack_channels_gradient(feat, gx, gy, out)", "Interleave feat, gx, gy into out.",
               feat="T H W C", gx="T H W C", gy="T H W C", out=Out("T H W 3*C", layout="(T, H, W, 3C)"))
FAMILY.declare(f"data_coefficients_channels(first, warped, inside, du, weights, out, blend=0.5, {_IRLS})",
               "IRLS data coefficients of C feature channels.", order=("weights",),
               weights="C", first=Array("T H W 3*C", layout="(T, H, W, 3C)"),
               warped=Array("T H W 3*C", layout="(T, H, W, 3C)"), inside="T H W", du="T H W 2", out=Out("T H W 5"),
               blend=Real, **_ROBUST)
FAMILY.declare(f"smoothness_weights(flow, du, out, {_IRLS})", "IRLS smoothness weights of flow + du.",
               flow="T H W 2", du="T H W 2", out=Out("T H W 4"), **_ROBUST)
FAMILY.declare("assemble_system(flow, data, smooth, lam, out)", "Per-pixel 2x2 system from data and smooth.",
               flow="T H W 2", data="T H W 5", smooth="T H W 4", lam=Real, out=Out("T H W 5"))
FAMILY.declare("sor_sweep(du, system, smooth, lam, omega, parity)", "Red-black SOR half sweep on du in place.",
               du=Out("T H W 2"), system="T H W 5", smooth="T H W 4", lam=Real, omega=Real, parity=Choice(0, 1))
FAMILY.declare("sor_full_sweep(du, system, smooth, lam, omega)",
               "Red-black SOR full sweep on du in place: the parity 0 then 1 half sweeps.",
               du=Out("T H W 2"), system="T H W 5", smooth="T H W 4", lam=Real, omega=Real)
FAMILY.declare("apply_update(flow, du, out, limit=1.0)", "``out = flow + clip(du, -limit, limit)``.",
               flow="T H W 2", du="T H W 2", out=Out("T H W 2"), limit=Real)
FAMILY.declare("select_masked(mask, inside_mask, outside_mask, out)",
               "``out = mask >= 0.5 ? inside_mask : outside_mask`` (out may alias either).",
               mask="T H W", inside_mask="T H W C", outside_mask="T H W C", out=Out("T H W C"))
FAMILY.declare("flow_sobel_components(flow, out, row_energy)",
               "Sobel x, y of both components and per-row energy of a flow.",
               flow="T H W 2", out=Out("T H W 4"), row_energy=Out("T*H 2"))
FAMILY.declare("thin_edges(sobel, cutoff, out)", "Thinned edges 0/1 of sobel above cutoff.",
               sobel="T H W 4", cutoff="T 2", out=Out("T H W"))


def robust_weight(z, a=0.45, eps=1e-3, quad_frac=0.0, quad_weight=2e6):
    """``psi = quad_frac * quad_weight + (1 - quad_frac) * 2 a (z^2 + eps^2)^(a-1)``."""
    z = np.asarray(z, np.float64)
    robust = 2.0 * a * np.power(z * z + eps * eps, a - 1.0) if quad_frac < 1.0 else np.zeros_like(z)
    return quad_frac * quad_weight + (1.0 - quad_frac) * robust


def srgb_grey(rgb):
    """(T, H, W, 3) linear RGB -> (T, H, W) sRGB grey in [0, 255]."""
    enc = srgb_encode(rgb)
    return 255.0 * (enc @ np.asarray(GREY_WEIGHTS))


def row_min_max(src):
    """(T, H, W, C) -> (T*H, C, 2) per-row (min, max)."""
    src = np.asarray(src, np.float64)
    t, h, w, c = src.shape
    rows = src.reshape(t * h, w, c)
    return np.stack([rows.min(axis=1), rows.max(axis=1)], axis=-1)


def scale_shift(src, scale, shift):
    return np.asarray(src, np.float64) * np.asarray(scale, np.float64) + np.asarray(shift, np.float64)


def rof_divergence(p):
    """Backward-difference divergence of (T, H, W, 2), zero outside -> (T, H, W)."""
    p = np.asarray(p, np.float64)
    d = p[..., 0] + p[..., 1]
    d[:, :, 1:] -= p[:, :, :-1, 0]
    d[:, 1:, :] -= p[:, :-1, :, 1]
    return d


def rof_dual_step(img, p, theta, delta):
    """One Chambolle projection step; returns the new (T, H, W, 2) dual field."""
    v = np.asarray(img, np.float64) + theta * rof_divergence(p)
    gx = np.zeros_like(v)
    gy = np.zeros_like(v)
    gx[:, :, :-1] = v[:, :, 1:] - v[:, :, :-1]
    gy[:, :-1, :] = v[:, 1:, :] - v[:, :-1, :]
    q = np.asarray(p, np.float64) + delta * np.stack([gx, gy], axis=-1)
    norm = np.maximum(1.0, np.sqrt((q * q).sum(-1)))
    return q / norm[..., None]


def rof_texture(img, p, theta, alpha):
    img = np.asarray(img, np.float64)
    return img - alpha * (img + theta * rof_divergence(p))


def pack_image_gradient(img, gx, gy):
    return np.stack([img, gx, gy], axis=-1).astype(np.float64)


def pack_gradient(gx, gy):
    """(T, H, W) x 2 -> (T, H, W, 2) ``(gx, gy)``."""
    return np.stack([gx, gy], axis=-1).astype(np.float64)


def data_coefficients(i1, i1x, i1y, warped, inside, du, blend=0.5, a=0.45, eps=1e-3,
                      quad_frac=0.0, quad_weight=2e6):
    """(T, H, W, 5) ``psi * (Ix Ix, Ix Iy, Iy Iy, Ix It, Iy It)``."""
    warped = np.asarray(warped, np.float64)
    ok = np.asarray(inside) > 0.5
    ix = np.where(ok, blend * warped[..., 1] + (1 - blend) * np.asarray(i1x, np.float64), 0.0)
    iy = np.where(ok, blend * warped[..., 2] + (1 - blend) * np.asarray(i1y, np.float64), 0.0)
    it = np.where(ok, warped[..., 0] - np.asarray(i1, np.float64), 0.0)
    du = np.asarray(du, np.float64)
    psi = robust_weight(it + ix * du[..., 0] + iy * du[..., 1], a, eps, quad_frac, quad_weight)
    return np.stack([psi * ix * ix, psi * ix * iy, psi * iy * iy, psi * ix * it, psi * iy * it], axis=-1)


def smoothness_weights(flow, du, a=0.45, eps=1e-3, quad_frac=0.0, quad_weight=2e6):
    """(T, H, W, 4): psi of right / down differences of u + du, then of v + dv."""
    f = np.asarray(flow, np.float64) + np.asarray(du, np.float64)
    out = np.zeros(f.shape[:3] + (4,))
    for c in range(2):
        out[:, :, :-1, 2 * c] = robust_weight(f[:, :, 1:, c] - f[:, :, :-1, c], a, eps, quad_frac, quad_weight)
        out[:, :-1, :, 2 * c + 1] = robust_weight(f[:, 1:, :, c] - f[:, :-1, :, c], a, eps, quad_frac, quad_weight)
    return out


def _neighbour_sums(values, smooth, lam, centre=None):
    """Per pixel and component: ``sum_n lam w_n`` and ``sum_n lam w_n (values_n - centre)``."""
    f = np.asarray(values, np.float64)
    c = np.zeros_like(f) if centre is None else np.asarray(centre, np.float64)
    s = lam * np.asarray(smooth, np.float64)
    diag = np.zeros(f.shape)
    acc = np.zeros(f.shape)
    for k in range(2):
        wr, wd = s[..., 2 * k], s[..., 2 * k + 1]
        pairs = [  # (weight slice, target slice, neighbour slice)
            (wr[:, :, :-1], (slice(None), slice(None), slice(0, -1)), (slice(None), slice(None), slice(1, None))),
            (wr[:, :, :-1], (slice(None), slice(None), slice(1, None)), (slice(None), slice(None), slice(0, -1))),
            (wd[:, :-1, :], (slice(None), slice(0, -1), slice(None)), (slice(None), slice(1, None), slice(None))),
            (wd[:, :-1, :], (slice(None), slice(1, None), slice(None)), (slice(None), slice(0, -1), slice(None))),
        ]
        for wgt, tgt, nbr in pairs:
            diag[tgt + (k,)] += wgt
            acc[tgt + (k,)] += wgt * (f[nbr + (k,)] - c[tgt + (k,)])
    return diag, acc


def assemble_system(flow, data, smooth, lam):
    """(T, H, W, 5): ``(a11, a12, a22, b_u, b_v)`` of every pixel's equations."""
    data = np.asarray(data, np.float64)
    diag, acc = _neighbour_sums(flow, smooth, lam, centre=flow)
    return np.stack([data[..., 0] + diag[..., 0], data[..., 1], data[..., 2] + diag[..., 1],
                     acc[..., 0] - data[..., 3], acc[..., 1] - data[..., 4]], -1)


def sor_sweep(du, system, smooth, lam, omega, parity):
    """Returns ``du`` after updating the pixels with ``(x + y) % 2 == parity``."""
    du = np.array(du, np.float64)
    system = np.asarray(system, np.float64)
    _, acc = _neighbour_sums(du, smooth, lam)
    a11, a12, a22 = system[..., 0], system[..., 1], system[..., 2]
    bu = system[..., 3] + acc[..., 0]
    bv = system[..., 4] + acc[..., 1]
    det = a11 * a22 - a12 * a12
    ok = det > 1e-20 * (a11 * a22 + 1e-30)
    safe = np.where(ok, det, 1.0)
    new_u = (a22 * bu - a12 * bv) / safe
    new_v = (a11 * bv - a12 * bu) / safe
    t, h, w, _ = du.shape
    yy, xx = np.mgrid[0:h, 0:w]
    colour = np.broadcast_to(((xx + yy) % 2 == parity), (t, h, w)) & ok
    du[..., 0] = np.where(colour, (1 - omega) * du[..., 0] + omega * new_u, du[..., 0])
    du[..., 1] = np.where(colour, (1 - omega) * du[..., 1] + omega * new_v, du[..., 1])
    return du


def sor_full_sweep(du, system, smooth, lam, omega):
    """Returns ``du`` after a full red-black sweep: :func:`sor_sweep` with parity 0, then 1."""
    du = sor_sweep(du, system, smooth, lam, omega, 0)
    return sor_sweep(du, system, smooth, lam, omega, 1)


def system_residual(du, system, smooth, lam):
    """Residual ``b + lam sum_n w_n du_n - A_p du_p`` of the IRLS equations (T, H, W, 2)."""
    system = np.asarray(system, np.float64)
    d = np.asarray(du, np.float64)
    _, acc = _neighbour_sums(d, smooth, lam)
    ru = system[..., 3] + acc[..., 0] - system[..., 0] * d[..., 0] - system[..., 1] * d[..., 1]
    rv = system[..., 4] + acc[..., 1] - system[..., 1] * d[..., 0] - system[..., 2] * d[..., 1]
    return np.stack([ru, rv], axis=-1)


def apply_update(flow, du, limit=1.0):
    d = np.asarray(du, np.float64)
    if limit > 0:
        d = np.clip(d, -limit, limit)
    return np.asarray(flow, np.float64) + d


def select_masked(mask, inside_mask, outside_mask):
    m = (np.asarray(mask) >= 0.5)[..., None]
    return np.where(m, np.asarray(inside_mask, np.float64), np.asarray(outside_mask, np.float64))


def flow_sobel_components(flow):
    """Returns ((T, H, W, 4) Sobel derivatives (du/dx, du/dy, dv/dx, dv/dy), (T*H, 2) row energies)."""
    f = np.pad(np.asarray(flow, np.float64), ((0, 0), (1, 1), (1, 1), (0, 0)), mode="edge")
    gx = (f[:, :-2, 2:] + 2 * f[:, 1:-1, 2:] + f[:, 2:, 2:] - f[:, :-2, :-2] - 2 * f[:, 1:-1, :-2] - f[:, 2:, :-2]) / 8
    gy = (f[:, 2:, :-2] + 2 * f[:, 2:, 1:-1] + f[:, 2:, 2:] - f[:, :-2, :-2] - 2 * f[:, :-2, 1:-1] - f[:, :-2, 2:]) / 8
    out = np.stack([gx[..., 0], gy[..., 0], gx[..., 1], gy[..., 1]], -1)
    t, h, w, _ = out.shape
    energy = np.stack([(gx[..., k] ** 2 + gy[..., k] ** 2).sum(axis=2).reshape(t * h) for k in range(2)], -1)
    return out, energy


def thin_edges(sobel, cutoff):
    """(T, H, W) thinned edges of u OR v, written pixel by pixel."""
    sobel = np.asarray(sobel, np.float64)
    t_n, h, w, _ = sobel.shape
    out = np.zeros((t_n, h, w))
    for t in range(t_n):
        for c in range(2):
            gx, gy = sobel[t, ..., 2 * c], sobel[t, ..., 2 * c + 1]
            b = gx * gx + gy * gy
            for y in range(h):
                for x in range(w):
                    if not b[y, x] > cutoff[t][c]:
                        continue
                    xm, xp, ym, yp = max(x - 1, 0), min(x + 1, w - 1), max(y - 1, 0), min(y + 1, h - 1)
                    ax, ay = abs(gx[y, x]), abs(gy[y, x])
                    if ax >= ay and b[y, x] > b[y, xm] and b[y, x] >= b[y, xp]:
                        out[t, y, x] = 1.0
                    if ay >= ax and b[y, x] > b[ym, x] and b[y, x] >= b[yp, x]:
                        out[t, y, x] = 1.0
    return out


def soft_census(img, radius=1, eps=4.0, scale=1.0):
    """(T, H, W) -> (T, H, W, (2r+1)^2 - 1): ``scale * d / sqrt(d^2 + eps^2)`` per neighbour,
    offsets in row-major order without the centre, replicate border."""
    img = np.asarray(img, np.float64)
    _, h, w = img.shape
    ys, xs = np.arange(h), np.arange(w)
    out = []
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            if dy == 0 and dx == 0:
                continue
            nb = img[:, np.clip(ys + dy, 0, h - 1)][:, :, np.clip(xs + dx, 0, w - 1)]
            d = nb - img
            out.append(scale * d / np.sqrt(d * d + eps * eps))
    return np.stack(out, axis=-1)


def pack_channels_gradient(feat, gx, gy):
    """(T, H, W, C) x 3 -> (T, H, W, 3C) with channels ``(feat_c, gx_c, gy_c)``."""
    t, h, w, c = np.shape(feat)
    return np.stack([feat, gx, gy], axis=-1).reshape(t, h, w, 3 * c).astype(np.float64)


def data_coefficients_channels(first, warped, inside, du, weights, blend=0.5, a=0.45, eps=1e-3,
                               quad_frac=0.0, quad_weight=2e6):
    """(T, H, W, 5): ``sum_c w_c psi_c (Ix Ix, Ix Iy, Iy Iy, Ix It, Iy It)_c`` over the channel triples."""
    weights = np.asarray(weights, np.float64)
    first = np.asarray(first, np.float64)
    warped = np.asarray(warped, np.float64)
    ok = np.asarray(inside) > 0.5
    du = np.asarray(du, np.float64)
    total = 0.0
    for c, wc in enumerate(weights):
        f, g = first[..., 3 * c:3 * c + 3], warped[..., 3 * c:3 * c + 3]
        ix = blend * g[..., 1] + (1 - blend) * f[..., 1]
        iy = blend * g[..., 2] + (1 - blend) * f[..., 2]
        it = g[..., 0] - f[..., 0]
        psi = wc * robust_weight(it + ix * du[..., 0] + iy * du[..., 1], a, eps, quad_frac, quad_weight)
        total = total + np.stack([psi * ix * ix, psi * ix * iy, psi * iy * iy, psi * ix * it, psi * iy * it], -1)
    return np.where(ok[..., None], total, 0.0)


def log_grey(rgb, floor=1e-3):
    """(T, H, W, 3) linear RGB -> (T, H, W) ``log(max(grey, floor))``."""
    return np.log(np.maximum(np.asarray(rgb, np.float64) @ np.asarray(GREY_WEIGHTS), floor))
