"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_shading` (Eq. 9 local
smoothness, ungated, gated, and with the weighted axis pairs, Eq. 13 coupling): same host
functions and signatures, NumPy arrays passed as ``ti.types.ndarray()``.  The outermost loop runs over rows in parallel.
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


@ti.func
def axis_pair_weight(pairs: ti.template(), y, x, j: ti.template(), i: ti.template()):
    """The stable-pair weight of ``(y, x)`` with its neighbour ``(y + j - 1, x + i - 1)`` (see the
    Warp module); diagonal pairs get 0."""
    out = 0.0
    if ti.static(j == 1 and i == 2):
        out = pairs[y, x, 0]
    if ti.static(j == 1 and i == 0):
        out = pairs[y, x - 1, 0]
    if ti.static(j == 2 and i == 1):
        out = pairs[y, x, 1]
    if ti.static(j == 0 and i == 1):
        out = pairs[y - 1, x, 1]
    return out


@ti.kernel
def shading_smoothness_rows(S: nd3, gate: nd3, gated: ti.template(), pairs: nd3, paired: ti.template(), gS: nd3,
                            energy_rows: nd1_f64, lam: ti.f32, half_pair_gain: ti.f32, eps: ti.f32):
    """Eq. 9's local term; with ``gated`` (compile time) each pair is weighted by
    the mean of its two ``gate`` values (``gate`` is not read otherwise); with ``paired`` an
    axis pair's weight also gets ``half_pair_gain`` times its ``pairs`` weight."""
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
                                    if ti.static(paired and (i == 1 or j == 1)):
                                        wgt += half_pair_gain * axis_pair_weight(pairs, y, x, j, i)
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


@host("shading_smoothness_paired")
def shading_smoothness_paired(S, gate, pairs, gS, energy_rows, lam: float = 2.0, pair_gain: float = 1.0,
                              eps: float = 0.001) -> None:
    """Add Eq. 9's gated local smoothness with weighted axis pairs, and its gradient; see
    :func:`ivkernels.kernels.warp.energy_shading.shading_smoothness_paired`."""
    _local_term(S, gate, gS, energy_rows, lam, eps, pairs, pair_gain)


def _local_term(S, gate, gS, energy_rows, lam: float, eps: float, pairs=None, pair_gain: float = 0.0) -> None:
    """Launch of Eq. 9's local term (arguments checked), gated unless ``gate`` is None, with the
    axis pairs' weights when ``pairs`` is given (``S`` stands in for the arrays not read)."""
    t, h, w = S.shape
    if t * h * w == 0:
        return
    shading_smoothness_rows(S, S if gate is None else gate, gate is not None, S if pairs is None else pairs,
                            pairs is not None, gS, energy_rows, float(lam), 0.5 * float(pair_gain), float(eps))


@host("coupling_term")
def coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
    """Add the coupling term of Eq. 13 and its gradient in S; see
    :func:`ivkernels.kernels.warp.energy_shading.coupling_term`."""
    t, h, w = S.shape
    if w_bnd.shape[0] * h * w == 0:
        return
    coupling_rows(S, S_tilde, w_bnd, gS, energy_rows, float(lam))
