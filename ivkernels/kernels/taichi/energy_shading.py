"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_shading` (Eq. 9 local
smoothness, ungated and gated, the weighted axis pairs, Eq. 13 coupling): same host functions and signatures, NumPy arrays
passed as ``ti.types.ndarray()``.  The outermost loop runs over rows in parallel.
The local term's Charbonnier penalty is the data term's (:mod:`ivkernels.kernels.taichi.energy_data`).
"""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_shading import FAMILY
from ivkernels.kernels.taichi.energy_data import charbonnier

host = implements(FAMILY, FRONT)

nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)


@ti.kernel
def shading_smoothness_rows(S: nd3, gate: nd3, gated: ti.template(), gS: nd3, energy_rows: nd1_f64,
                            lam: ti.f32, eps: ti.f32):
    """Eq. 9's local term; with ``gated`` (compile time) each pair is weighted by
    the mean of its two ``gate`` values (``gate`` is not read otherwise)."""
    height = S.shape[1]
    width = S.shape[2]
    for r in range(S.shape[0] * height):
        t = r // height
        y = r - t * height
        e = ti.f64(0.0)
        for x in range(width):
            s = S[t, y, x]
            g = 0.0
            for j in ti.static(range(3)):
                yy = y + j - 1
                if 0 <= yy < height:
                    for i in ti.static(range(3)):
                        xx = x + i - 1
                        if ti.static(i != 1 or j != 1):
                            if 0 <= xx < width:
                                d = s - S[t, yy, xx]
                                rho = charbonnier(d, eps)
                                if ti.static(gated):
                                    wgt = 0.5 * (gate[t, y, x] + gate[t, yy, xx])     # the pair's weight, symmetric
                                    e += ti.cast(wgt * rho, ti.f64)
                                    g += wgt * d / rho
                                else:
                                    e += ti.cast(rho, ti.f64)
                                    g += d / rho
            # S(x) appears in the pair (x, y) and in (y, x): twice the derivative
            gS[t, y, x] += 2.0 * lam * g
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@ti.kernel
def coupling_rows(S: nd3, S_tilde: nd3, w_bnd: nd3, gS: nd3, energy_rows: nd1_f64, lam: ti.f32):
    height = S.shape[1]
    for r in range(w_bnd.shape[0] * height):
        t = r // height
        y = r - t * height
        e = ti.f64(0.0)
        for x in range(S.shape[2]):
            w = w_bnd[t, y, x]
            d = S[t, y, x] - S_tilde[t, y, x]
            e += ti.cast(w * d * d, ti.f64)
            gS[t, y, x] += 2.0 * lam * w * d
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@host("shading_smoothness")
def shading_smoothness(S, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add the local shading smoothness of Eq. 9 and its gradient; see
    :func:`ivkernels.kernels.warp.energy_shading.shading_smoothness`."""
    _local_term(S, None, gS, energy_rows, lam, eps)


@host("shading_smoothness_gated")
def shading_smoothness_gated(S, gate, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add Eq. 9's local shading smoothness with a per-pixel gate on its pair terms; see
    :func:`ivkernels.kernels.warp.energy_shading.shading_smoothness_gated`."""
    _local_term(S, gate, gS, energy_rows, lam, eps)


def _local_term(S, gate, gS, energy_rows, lam: float, eps: float) -> None:
    """Launch of Eq. 9's local term (arguments checked), gated unless ``gate`` is None."""
    t, h, w = S.shape
    if t * h * w == 0:
        return
    shading_smoothness_rows(S, S if gate is None else gate, gate is not None, gS, energy_rows,
                            float(lam), float(eps))


@ti.kernel
def pair_smoothness_rows(S: nd3, pairs: nd3, gS: nd3, energy_rows: nd1_f64, lam: ti.f32, eps: ti.f32):
    """The weighted axis pairs (see the Warp module): each pixel adds its right and lower pairs'
    energy to its row and gathers the derivative of its four axis pairs."""
    height = S.shape[1]
    width = S.shape[2]
    for r in range(S.shape[0] * height):
        t = r // height
        y = r - t * height
        e = ti.f64(0.0)
        for x in range(width):
            s = S[t, y, x]
            g = 0.0
            if x + 1 < width:
                wgt = pairs[y, x, 0]
                if wgt > 0.0:
                    d = S[t, y, x + 1] - s
                    rho = charbonnier(d, eps)
                    e += ti.cast(wgt * rho, ti.f64)
                    g -= wgt * d / rho
            if y + 1 < height:
                wgt = pairs[y, x, 1]
                if wgt > 0.0:
                    d = S[t, y + 1, x] - s
                    rho = charbonnier(d, eps)
                    e += ti.cast(wgt * rho, ti.f64)
                    g -= wgt * d / rho
            if x >= 1:
                wgt = pairs[y, x - 1, 0]
                if wgt > 0.0:
                    d = s - S[t, y, x - 1]
                    g += wgt * d / charbonnier(d, eps)
            if y >= 1:
                wgt = pairs[y - 1, x, 1]
                if wgt > 0.0:
                    d = s - S[t, y - 1, x]
                    g += wgt * d / charbonnier(d, eps)
            gS[t, y, x] += lam * g
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@host("shading_pair_smoothness")
def shading_pair_smoothness(S, pairs, gS, energy_rows, lam: float, eps: float = 0.001) -> None:
    """Add a term of Eq. 9's kind on weighted axis pairs, and its gradient; see
    :func:`ivkernels.kernels.warp.energy_shading.shading_pair_smoothness`."""
    if S.size:
        pair_smoothness_rows(S, pairs, gS, energy_rows, float(lam), float(eps))


@host("coupling_term")
def coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
    """Add the coupling term of Eq. 13 and its gradient in S; see
    :func:`ivkernels.kernels.warp.energy_shading.coupling_term`."""
    t, h, w = S.shape
    if w_bnd.shape[0] * h * w == 0:
        return
    coupling_rows(S, S_tilde, w_bnd, gS, energy_rows, float(lam))
