"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_temporal` (Eq. 4, 5, 8):
same host function and signature, NumPy arrays passed as ``ti.types.ndarray()``.

One kernel does both halves of the gradient: the gather into ``X_t`` and the
bilinear splat into ``X_{t+1}``.  Its outermost loop runs over the rows in
parallel and ``+=`` on an ndarray there is atomic, so unlike the Warp CPU
launches nothing needs to be split at frame boundaries.  Bilinear sampling
uses corners clamped to the image and weights from the unclamped fractional
position, as :mod:`ivkernels.kernels.warp.sampling` does.
"""
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_temporal import FAMILY

host = implements(FAMILY, FRONT)

nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.func
def tukey(z, alpha):
    """Continuous Tukey penalty (Eq. 5 made continuous), saturating at 1/3."""
    q = z * z / (alpha * alpha)
    result = 1.0 / 3.0
    if q <= 1.0:
        result = q - q * q + q * q * q / 3.0
    return result


@ti.func
def tukey_derivative(z, alpha):
    """``(2/a^2) z (1 - z^2/a^2)^2`` inside ``|z| <= a``, else 0."""
    q = z * z / (alpha * alpha)
    result = 0.0
    if q <= 1.0:
        result = 2.0 / (alpha * alpha) * z * (1.0 - q) * (1.0 - q)
    return result


@ti.func
def corner_index(i, n):
    """Clamp a corner index to ``[0, n-1]``."""
    return ti.min(ti.max(i, 0), n - 1)


@ti.func
def bilinear_corners(flow: nd4, t, y, x, height, width):
    """Clamped corners and fractional weights of ``(x, y) + flow[t, y, x]``."""
    # p clamped to [-2, n+1]: same samples, no float-to-int overflow
    px = ti.min(ti.max(x + flow[t, y, x, 0], -2.0), width + 1.0)
    py = ti.min(ti.max(y + flow[t, y, x, 1], -2.0), height + 1.0)
    bx = ti.floor(px)
    by = ti.floor(py)
    x0 = corner_index(ti.cast(bx, ti.i32), width)
    x1 = corner_index(ti.cast(bx, ti.i32) + 1, width)
    y0 = corner_index(ti.cast(by, ti.i32), height)
    y1 = corner_index(ti.cast(by, ti.i32) + 1, height)
    return x0, x1, px - bx, y0, y1, py - by


@ti.func
def channel_term(X: ti.template(), gX: ti.template(), t, y, x, c, x0, x1, fx, y0, y1, fy, o, lam, alpha):
    """One channel of one pixel: ``d = X_{t+1}(x + u, c) - X_t(x, c)``; adds
    ``lam o rho'(d)`` to ``gX`` (gathered into ``X_t``, splatted onto the
    corners in ``X_{t+1}``) and returns ``o rho(d)`` (the energy before ``lam``)."""
    top = (1.0 - fx) * X[t + 1, y0, x0, c] + fx * X[t + 1, y0, x1, c]
    bottom = (1.0 - fx) * X[t + 1, y1, x0, c] + fx * X[t + 1, y1, x1, c]
    d = (1.0 - fy) * top + fy * bottom - X[t, y, x, c]
    g = lam * o * tukey_derivative(d, alpha)
    if g != 0.0:
        gX[t, y, x, c] -= g
        gX[t + 1, y0, x0, c] += (1.0 - fx) * (1.0 - fy) * g
        gX[t + 1, y0, x1, c] += fx * (1.0 - fy) * g
        gX[t + 1, y1, x0, c] += (1.0 - fx) * fy * g
        gX[t + 1, y1, x1, c] += fx * fy * g
    return o * tukey(d, alpha)


@ti.kernel
def temporal_rows(X: nd4, flow: nd4, occ: nd3, gX: nd4, energy_rows: nd1_f64, lam: ti.f32, alpha: ti.f32):
    height = X.shape[1]
    width = X.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        e = ti.f64(0.0)
        for x in range(width):
            o = occ[t, y, x]
            if o != 0.0:
                x0, x1, fx, y0, y1, fy = bilinear_corners(flow, t, y, x, height, width)
                for c in range(X.shape[3]):
                    e += ti.cast(channel_term(X, gX, t, y, x, c, x0, x1, fx, y0, y1, fy, o, lam, alpha), ti.f64)
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@ti.kernel
def temporal_pair_rows(A: nd4, S: nd4, flow: nd4, occ: nd3, gA: nd4, gS: nd4, energy_rows: nd1_f64,
                       lam_albedo: ti.f32, lam_shading: ti.f32, alpha: ti.f32):
    """:func:`temporal_rows` for the albedo (3 channels) and the shading (a
    (T, H, W, 1) view) at once, sharing each pixel's flow, occlusion weight and corners."""
    height = A.shape[1]
    width = A.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        e_albedo = ti.f64(0.0)
        e_shading = ti.f64(0.0)
        for x in range(width):
            o = occ[t, y, x]
            if o != 0.0:
                x0, x1, fx, y0, y1, fy = bilinear_corners(flow, t, y, x, height, width)
                for c in ti.static(range(3)):
                    e_albedo += ti.cast(channel_term(A, gA, t, y, x, c, x0, x1, fx, y0, y1, fy, o, lam_albedo,
                                                     alpha), ti.f64)
                e_shading += ti.cast(channel_term(S, gS, t, y, x, 0, x0, x1, fx, y0, y1, fy, o, lam_shading,
                                                  alpha), ti.f64)
        energy_rows[r] += ti.cast(lam_albedo, ti.f64) * e_albedo + ti.cast(lam_shading, ti.f64) * e_shading


@host("temporal_term")
def temporal_term(X, flow, occ, gX, energy_rows, lam: float, alpha: float = 5.0, *,
                  workspace=None) -> None:
    """Add the temporal term of Eq. 4 (albedo) or Eq. 8 (shading) and its gradient; see
    :func:`ivkernels.kernels.warp.energy_temporal.temporal_term` (NumPy arrays here;
    ``X`` (T, H, W, C) or (T, H, W), ``gX`` shaped like ``X``).  The single
    kernel needs no scratch: ``workspace`` is accepted, checked and unused."""
    if X.ndim == 3:
        X = X.reshape(*X.shape, 1)
        gX = gX.reshape(*gX.shape, 1)
    t, h, w, c = X.shape
    if t < 2 or h * w * c == 0:
        return
    temporal_rows(X, flow, occ, gX, energy_rows, float(lam), float(alpha))


@host("temporal_terms")
def temporal_terms(A, S, flow, occ, gA, gS, energy_rows, lam_albedo: float, lam_shading: float,
                   alpha: float = 5.0, *, workspace=None) -> None:
    """Add both temporal terms, Eq. 4 on ``A`` (T, H, W, 3) and Eq. 8 on ``S``
    (T, H, W), in one kernel; see
    :func:`ivkernels.kernels.warp.energy_temporal.temporal_terms` (NumPy arrays
    here; ``workspace`` is accepted, checked and unused)."""
    t, h, w, _ = A.shape
    if t < 2 or h * w == 0:
        return
    temporal_pair_rows(A, S.reshape(t, h, w, 1), flow, occ, gA, gS.reshape(t, h, w, 1), energy_rows,
                       float(lam_albedo), float(lam_shading), float(alpha))
