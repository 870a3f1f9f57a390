"""Temporal coherence terms of the intrinsic-video energy (Eq. 4, 5, 8), log domain.

``E_T = lam * sum_{t<T-1} sum_{x,c} occ_t(x) rho(X_{t+1}(x + u_t(x), c) - X_t(x, c))``

for the albedo (Eq. 4, ``X = A``, C = 3, lambda_TA = 10) and the shading
(Eq. 8, ``X = S`` as a (T, H, W, 1) view, lambda_TS = 1).  ``X_{t+1}(x + u)`` is
the bilinear sample with corners clamped to the image (the convention of
:mod:`ivkernels.kernels.warp.sampling`, whose ``@wp.func`` helpers are used).

``rho`` is the *continuous* Tukey biweight (Eq. 5 as printed jumps from 1/3 to
1/alpha^2 at |z| = alpha)::

    rho(z)  = z^2/a^2 - z^4/a^4 + z^6/(3 a^6)   for |z| <= a,   1/3 outside
    rho'(z) = (2/a^2) z (1 - z^2/a^2)^2          for |z| <= a,   0 outside

The gradient in ``X_t`` is a gather; the gradient in ``X_{t+1}`` lands on the
four corners of ``x + u`` (a bilinear splat with atomic adds).  They are two
launches: the gather over all rows, which also stores each pixel's
``lam occ rho'(d)`` in a scratch buffer (from the caller's workspace,
:mod:`ivkernels.kernels.workspace`), then the splat of the stored values,
split only at frame boundaries so concurrent CPU launches never write the
same gradient frame.
Energies go to the rows of frame ``t`` (conventions in :mod:`ivkernels.kernels`).

:func:`temporal_terms` adds both terms, the albedo's and the shading's, in
one gather and one splat: they share the flow, the occlusion weights and the
bilinear corners, which each pixel then reads and computes once instead of
twice (640x480, 8 frames, 2 threads: 101 against 130 ms for the two
``temporal_term`` calls, with bitwise the same result).
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.energy_temporal import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span
from ivkernels.kernels.warp.sampling import bilinear_at, clamped_corners
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.func
def tukey(z: float, alpha: float):
    """Continuous Tukey penalty (Eq. 5 made continuous), saturating at 1/3."""
    q = z * z / (alpha * alpha)
    result = 1.0 / 3.0
    if q <= 1.0:
        result = q - q * q + q * q * q / 3.0
    return result


@wp.func
def tukey_derivative(z: float, alpha: float):
    """``(2/a^2) z (1 - z^2/a^2)^2`` inside ``|z| <= a``, else 0."""
    q = z * z / (alpha * alpha)
    result = 0.0
    if q <= 1.0:
        result = 2.0 / (alpha * alpha) * z * (1.0 - q) * (1.0 - q)
    return result


@wp.func
def gather_channel(X: wp.array4d(dtype=float), gX: wp.array4d(dtype=float), weight: wp.array4d(dtype=float),
                   weight_channel: int, t: int, y: int, x: int, c: int, x0: int, x1: int, fx: float,
                   y0: int, y1: int, fy: float, o: float, lam: float, alpha: float):
    """One channel of one pixel of the gather: ``d = X_{t+1}(x + u, c) - X_t(x, c)``;
    stores ``lam o rho'(d)`` in ``weight[..., weight_channel]``, subtracts it from
    ``gX_t``, and returns ``o rho(d)`` (the energy before ``lam``)."""
    d = bilinear_at(X, t + 1, c, x0, x1, fx, y0, y1, fy) - X[t, y, x, c]
    g = lam * o * tukey_derivative(d, alpha)
    weight[t, y, x, weight_channel] = g
    gX[t, y, x, c] = gX[t, y, x, c] - g
    return o * tukey(d, alpha)


@wp.kernel
def temporal_gather_rows(row_begin: int, tiles: int, X: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                         occ: wp.array3d(dtype=float), gX: wp.array4d(dtype=float),
                         weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64),
                         lam: float, alpha: float):
    """Energy of frame ``t`` rows and the gradient in ``X_t`` (rows of frames 0 .. T-2);
    stores ``weight = lam occ rho'(d)`` per pixel and channel for the splat."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, X.shape[2])
    height = X.shape[1]
    width = X.shape[2]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(x_begin, x_end):
        o = occ[t, y, x]
        if o == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(X.shape[3]):
            e += wp.float64(gather_channel(X, gX, weight, c, t, y, x, c, x0, x1, fx, y0, y1, fy, o, lam, alpha))
    wp.atomic_add(energy_rows, r, wp.float64(lam) * e)


@wp.func
def splat_corners(gX: wp.array4d(dtype=float), t: int, c: int, x0: int, x1: int, fx: float,
                  y0: int, y1: int, fy: float, g: float):
    """Add ``g`` to the four corners of a bilinear sample of frame ``t``, channel ``c``."""
    wp.atomic_add(gX, t, y0, x0, c, (1.0 - fx) * (1.0 - fy) * g)
    wp.atomic_add(gX, t, y0, x1, c, fx * (1.0 - fy) * g)
    wp.atomic_add(gX, t, y1, x0, c, (1.0 - fx) * fy * g)
    wp.atomic_add(gX, t, y1, x1, c, fx * fy * g)


@wp.kernel
def temporal_splat_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                        weight: wp.array4d(dtype=float), gX: wp.array4d(dtype=float)):
    """Gradient in ``X_{t+1}``: splat the stored ``lam occ rho'(d)`` onto the
    corners of ``x + u_t(x)``."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gX.shape[2])
    height = gX.shape[1]
    width = gX.shape[2]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if occ[t, y, x] == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(gX.shape[3]):
            g = weight[t, y, x, c]
            if g != 0.0:
                splat_corners(gX, t + 1, c, x0, x1, fx, y0, y1, fy, g)


@wp.kernel
def temporal_pair_gather_rows(row_begin: int, tiles: int, A: wp.array4d(dtype=float), S: wp.array4d(dtype=float),
                              flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                              gA: wp.array4d(dtype=float), gS: wp.array4d(dtype=float),
                              weight: wp.array4d(dtype=float), energy_rows: wp.array(dtype=wp.float64),
                              lam_albedo: float, lam_shading: float, alpha: float):
    """:func:`temporal_gather_rows` for the albedo (3 channels) and the shading
    (1) at once; ``weight`` holds 4 channels, the albedo's then the shading's."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, A.shape[2])
    height = A.shape[1]
    width = A.shape[2]
    t = r // height
    y = r - t * height
    e_albedo = wp.float64(0.0)
    e_shading = wp.float64(0.0)
    for x in range(x_begin, x_end):
        o = occ[t, y, x]
        if o == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(3):
            e_albedo += wp.float64(gather_channel(A, gA, weight, c, t, y, x, c, x0, x1, fx, y0, y1, fy, o,
                                                  lam_albedo, alpha))
        e_shading += wp.float64(gather_channel(S, gS, weight, 3, t, y, x, 0, x0, x1, fx, y0, y1, fy, o,
                                               lam_shading, alpha))
    # two adds, in the order of the one-thread-per-row sum ``(rows + albedo) + shading``
    wp.atomic_add(energy_rows, r, wp.float64(lam_albedo) * e_albedo)
    wp.atomic_add(energy_rows, r, wp.float64(lam_shading) * e_shading)


@wp.kernel
def temporal_pair_splat_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                             weight: wp.array4d(dtype=float), gA: wp.array4d(dtype=float),
                             gS: wp.array4d(dtype=float)):
    """:func:`temporal_splat_rows` for the albedo and the shading at once."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gA.shape[2])
    height = gA.shape[1]
    width = gA.shape[2]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if occ[t, y, x] == 0.0:
            continue
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        for c in range(3):
            g = weight[t, y, x, c]
            if g != 0.0:
                splat_corners(gA, t + 1, c, x0, x1, fx, y0, y1, fy, g)
        g = weight[t, y, x, 3]
        if g != 0.0:
            splat_corners(gS, t + 1, 0, x0, x1, fx, y0, y1, fy, g)


def with_channel_axis(a):
    """A (T, H, W, 1) view of a (T, H, W) ``wp.array``, sharing its memory and strides.

    Unlike ``reshape`` it takes strided arrays too; an empty ``a`` gives a new empty array.
    """
    shape = (*a.shape, 1)
    if a.size == 0:
        return wp.empty(shape, dtype=a.dtype, device=a.device)
    view = wp.array(ptr=a.ptr, dtype=a.dtype, shape=shape, strides=(*a.strides, a.strides[-1]),
                    device=a.device, copy=False)
    view._ref = a               # keep the memory alive as long as the view
    return view


@host("temporal_term")
def temporal_term(X, flow, occ, gX, energy_rows, lam: float, alpha: float = 5.0, *,
                  workspace=None) -> None:
    """Add the temporal term of Eq. 4 (albedo) or Eq. 8 (shading) and its gradient.

    ``E = lam * sum_{t<T-1} sum_{x,c} occ_t(x) rho(X_{t+1}(x + u_t(x), c) - X_t(x, c))``,
    ``rho`` the continuous Tukey with scale ``alpha`` (module docstring).

    Parameters
    ----------
    X : wp.array float32 (T, H, W, C) log albedo (C = 3) or log shading
        (C = 1, a ``reshape((T, H, W, 1))`` view); a (T, H, W) array is
        accepted too and viewed that way.  Any strides.
    flow : wp.array float32 (T-1, H, W, 2), forward flow u_t (pixels).
    occ : wp.array float32 (T-1, H, W), w_occ (1 visible in t+1, 0 occluded).
    gX : wp.array float32, same shape as ``X``, accumulated: ``gX += dE/dX``.
        Must not overlap ``X`` (ValueError).
    energy_rows : wp.array float64 (T*H,), accumulated; the pair (t, t+1)
        adds to the rows of frame t, the last frame's rows get nothing.
    lam : lambda_TA (10) or lambda_TS (1).  alpha : Tukey scale (log units).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the (T-1, H, W, C) float32 splat weights between calls; without
        one they are allocated for this call.

    With T = 1, or no pixels, there is nothing to add.
    """
    if len(X.shape) == 3:
        X = with_channel_axis(X)
        gX = with_channel_axis(gX)
    t, h, w, c = X.shape
    dev = X.device
    if t < 2 or h * w * c == 0:
        return
    shape = (t - 1, h, w, c)
    weight = scratch_buffer(workspace, f"{__name__}.splat_weight", shape, float,
                            lambda: wp.empty(shape, dtype=float, device=dev), dev)
    tiles = row_tiles(w, dev)
    launch_rows(temporal_gather_rows, (t - 1) * h * tiles,
                [tiles, X, flow, occ, gX, weight, energy_rows, float(lam), float(alpha)], device=dev)
    launch_rows(temporal_splat_rows, (t - 1) * h * tiles, [tiles, flow, occ, weight, gX], device=dev,
                align=h * tiles)


@host("temporal_terms")
def temporal_terms(A, S, flow, occ, gA, gS, energy_rows, lam_albedo: float, lam_shading: float,
                   alpha: float = 5.0, *, workspace=None) -> None:
    """Add both temporal terms, Eq. 4 on the albedo and Eq. 8 on the shading, and their gradients.

    The same as ``temporal_term(A, flow, occ, gA, energy_rows, lam_albedo,
    alpha)`` followed by ``temporal_term(S, flow, occ, gS, energy_rows,
    lam_shading, alpha)``, bitwise, in one gather and one splat (module
    docstring).

    Parameters
    ----------
    A, gA : wp.array float32 (T, H, W, 3): log albedo, and its accumulated gradient.
    S, gS : wp.array float32 (T, H, W): log shading, and its accumulated gradient.
    flow : wp.array float32 (T-1, H, W, 2), forward flow u_t (pixels).
    occ : wp.array float32 (T-1, H, W), w_occ.
    energy_rows : wp.array float64 (T*H,), accumulated (pair (t, t+1) on frame t's rows).
    lam_albedo, lam_shading : lambda_TA and lambda_TS.  alpha : Tukey scale, shared.
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the (T-1, H, W, 4) float32 splat weights between calls.
    Neither gradient may overlap ``A`` or ``S`` (ValueError).
    """
    t, h, w, _ = A.shape
    dev = A.device
    if t < 2 or h * w == 0:
        return
    shape = (t - 1, h, w, 4)
    weight = scratch_buffer(workspace, f"{__name__}.pair_splat_weight", shape, float,
                            lambda: wp.empty(shape, dtype=float, device=dev), dev)
    S4, gS4 = with_channel_axis(S), with_channel_axis(gS)
    tiles = row_tiles(w, dev)
    launch_rows(temporal_pair_gather_rows, (t - 1) * h * tiles,
                [tiles, A, S4, flow, occ, gA, gS4, weight, energy_rows, float(lam_albedo), float(lam_shading),
                 float(alpha)], device=dev)
    launch_rows(temporal_pair_splat_rows, (t - 1) * h * tiles, [tiles, flow, occ, weight, gA, gS4], device=dev,
                align=h * tiles)
