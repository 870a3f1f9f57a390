"""Data term of the intrinsic-video energy (Eq. 3), log domain.

``E_D = lam * sum_{t,x,c} rho_charb(w_lum(x) * (I(x,c) - A(x,c) - S(x)))`` with
``rho_charb(z) = sqrt(z^2 + eps^2)``.  Like every energy host function, it
*adds* its gradient into the given buffers and its energy per row into
``energy_rows`` (see :mod:`ivkernels.kernels`).

The solver enforces Eq. 3 as the constraint ``A = I - S`` (its limit for a
stiff data term, see :mod:`ivkernels.solver.energy`); :func:`constrained_albedo`
and :func:`constrained_gradient` are that change of variables and its chain
rule.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.energy_data import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


@wp.func
def charbonnier(z: float, eps: float):
    """``sqrt(z^2 + eps^2)``, the differentiable L1 of Eq. 3 (and of the local shading smoothness, Eq. 9)."""
    return wp.sqrt(z * z + eps * eps)


@wp.kernel
def data_term_rows(row_begin: int, tiles: int, I: wp.array4d(dtype=float), A: wp.array4d(dtype=float),
                   S: wp.array3d(dtype=float), w_lum: wp.array3d(dtype=float),
                   gA: wp.array4d(dtype=float), gS: wp.array3d(dtype=float),
                   energy_rows: wp.array(dtype=wp.float64), lam: float, eps: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, S.shape[2])
    height = S.shape[1]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(x_begin, x_end):
        w = w_lum[t, y, x]
        s = S[t, y, x]
        g_s = float(0.0)
        for c in range(3):
            z = w * (I[t, y, x, c] - A[t, y, x, c] - s)
            rho = charbonnier(z, eps)
            e += wp.float64(rho)
            g = -lam * w * z / rho
            gA[t, y, x, c] = gA[t, y, x, c] + g
            g_s += g
        gS[t, y, x] = gS[t, y, x] + g_s
    wp.atomic_add(energy_rows, r, wp.float64(lam) * e)


@host("data_term")
def data_term(I, A, S, w_lum, gA, gS, energy_rows, lam: float = 10.0, eps: float = 0.001) -> None:
    """Add the data term of Eq. 3 and its gradient.

    ``E = lam * sum_{t,y,x,c} sqrt(z^2 + eps^2)``, ``z = w_lum * (I - A - S)``.

    Parameters
    ----------
    I : wp.array float32 (T, H, W, 3), log input image.
    A : wp.array float32 (T, H, W, 3), log albedo.
    S : wp.array float32 (T, H, W), log shading.
    w_lum : wp.array float32 (T, H, W), ``lum(i) + 0.001`` (linear luminance).
    gA : wp.array float32 (T, H, W, 3), accumulated: ``gA += dE/dA``.
    gS : wp.array float32 (T, H, W), accumulated: ``gS += dE/dS``.
    energy_rows : wp.array float64 (T*H,), accumulated: row ``t*H + y`` gets
        the energy of image row ``y`` of frame ``t``.
    lam : lambda_D.  eps : Charbonnier epsilon.
    """
    t, h, w, _ = I.shape
    dev = I.device
    tiles = row_tiles(w, dev)
    launch_rows(data_term_rows, t * h * tiles,
                [tiles, I, A, S, w_lum, gA, gS, energy_rows, float(lam), float(eps)], device=dev)


@wp.kernel
def constrained_albedo_rows(row_begin: int, tiles: int, I: wp.array4d(dtype=float),
                            S: wp.array3d(dtype=float), A: wp.array4d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, S.shape[2])
    height = S.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        s = S[t, y, x]
        for c in range(3):
            A[t, y, x, c] = I[t, y, x, c] - s


@wp.kernel
def constrained_gradient_rows(row_begin: int, tiles: int, gA: wp.array4d(dtype=float),
                              gS: wp.array3d(dtype=float), out: wp.array3d(dtype=float)):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gS.shape[2])
    height = gS.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        out[t, y, x] = gS[t, y, x] - (gA[t, y, x, 0] + gA[t, y, x, 1] + gA[t, y, x, 2])


@host("constrained_albedo")
def constrained_albedo(I, S, A) -> None:
    """Write ``A = I - S`` (log albedo on the data-consistent set of Eq. 3).

    Parameters
    ----------
    I : wp.array float32 (T, H, W, 3), log input image.
    S : wp.array float32 (T, H, W), log shading.
    A : wp.array float32 (T, H, W, 3), output (may not alias ``I``).
    """
    t, h, w, _ = I.shape
    dev = I.device
    tiles = row_tiles(w, dev)
    launch_rows(constrained_albedo_rows, t * h * tiles, [tiles, I, S, A], device=dev)


@host("constrained_gradient")
def constrained_gradient(gA, gS, out) -> None:
    """Chain rule of ``A = I - S``: ``out = gS - sum_c gA[..., c]``.

    ``gA`` (T, H, W, 3) and ``gS`` (T, H, W) are dE/dA and dE/dS of any energy
    in (A, S); ``out`` (T, H, W) receives dE/dS along the constraint (it may
    be ``gS`` itself: each pixel reads before it writes).
    """
    t, h, w, _ = gA.shape
    dev = gA.device
    tiles = row_tiles(w, dev)
    launch_rows(constrained_gradient_rows, t * h * tiles, [tiles, gA, gS, out], device=dev)
