"""Data term of the intrinsic-video energy (Eq. 3), log domain.

``E_D = lam * sum_{t,x,c} rho_charb(w_lum(x) * (I(x,c) - A(x,c) - S(x)))`` with
``rho_charb(z) = sqrt(z^2 + eps^2)``.  Like every energy host function, it
*adds* its gradient into the given buffers and its energy per row into
``energy_rows`` (see :mod:`ivkernels.kernels`).
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.warp._checks import check_array

wp.set_module_options({"enable_backward": False})


@wp.func
def charbonnier(z: float, eps: float):
    """``sqrt(z^2 + eps^2)``, the differentiable L1 of Eq. 3 (and of the local shading smoothness, Eq. 9)."""
    return wp.sqrt(z * z + eps * eps)


@wp.kernel
def data_term_rows(row_begin: int, I: wp.array4d(dtype=float), A: wp.array4d(dtype=float),
                   S: wp.array3d(dtype=float), w_lum: wp.array3d(dtype=float),
                   gA: wp.array4d(dtype=float), gS: wp.array3d(dtype=float),
                   energy_rows: wp.array(dtype=wp.float64), lam: float, eps: float):
    r = row_begin + wp.tid()
    height = S.shape[1]
    t = r // height
    y = r - t * height
    e = wp.float64(0.0)
    for x in range(S.shape[2]):
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
    energy_rows[r] = energy_rows[r] + wp.float64(lam) * e


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
    check_array("I", I, (None, None, None, 3), "(T, H, W, 3)")
    t, h, w, _ = I.shape
    dev = I.device
    check_array("A", A, (t, h, w, 3), "(T, H, W, 3)", dev)
    check_array("S", S, (t, h, w), "(T, H, W)", dev)
    check_array("w_lum", w_lum, (t, h, w), "(T, H, W)", dev)
    check_array("gA", gA, (t, h, w, 3), "(T, H, W, 3)", dev)
    check_array("gS", gS, (t, h, w), "(T, H, W)", dev)
    check_array("energy_rows", energy_rows, (t * h,), "(T*H,)", dev, dtype=wp.float64)
    launch_rows(data_term_rows, t * h, [I, A, S, w_lum, gA, gS, energy_rows, float(lam), float(eps)],
                device=dev)
