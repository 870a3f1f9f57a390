"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_data` (Eq. 3): same host
function, same signature, NumPy arrays passed as ``ti.types.ndarray()``.

The outermost loop runs over the ``T * H`` rows in parallel, each iteration
looping over ``x``; the gradient and row energy of a row are written by the
iteration that owns it.
"""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.energy_data import FAMILY

host = implements(FAMILY, FRONT)

nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.func
def charbonnier(z, eps):
    """``sqrt(z^2 + eps^2)``, the differentiable L1 of Eq. 3 (and of the local shading smoothness, Eq. 9)."""
    return ti.sqrt(z * z + eps * eps)


@ti.kernel
def data_term_rows(I: nd4, A: nd4, S: nd3, w_lum: nd3, gA: nd4, gS: nd3, energy_rows: nd1_f64,
                   lam: ti.f32, eps: ti.f32):
    height = S.shape[1]
    for r in range(S.shape[0] * height):
        t = r // height
        y = r - t * height
        e = ti.f64(0.0)
        for x in range(S.shape[2]):
            w = w_lum[t, y, x]
            s = S[t, y, x]
            g_s = 0.0
            for c in ti.static(range(3)):
                z = w * (I[t, y, x, c] - A[t, y, x, c] - s)
                rho = charbonnier(z, eps)
                e += ti.cast(rho, ti.f64)
                g = -lam * w * z / rho
                gA[t, y, x, c] += g
                g_s += g
            gS[t, y, x] += g_s
        energy_rows[r] += ti.cast(lam, ti.f64) * e


@host("data_term")
def data_term(I, A, S, w_lum, gA, gS, energy_rows, lam: float = 10.0, eps: float = 0.001) -> None:
    """Add the data term of Eq. 3 and its gradient; see
    :func:`ivkernels.kernels.warp.energy_data.data_term` (NumPy arrays here)."""
    t, h, w, _ = I.shape
    if t * h * w == 0:
        return
    data_term_rows(I, A, S, w_lum, gA, gS, energy_rows, float(lam), float(eps))


@ti.kernel
def constrained_albedo_rows(I: nd4, S: nd3, A: nd4):
    for t, y, x in ti.ndrange(S.shape[0], S.shape[1], S.shape[2]):
        s = S[t, y, x]
        for c in ti.static(range(3)):
            A[t, y, x, c] = I[t, y, x, c] - s


@ti.kernel
def constrained_gradient_rows(gA: nd4, gS: nd3, out: nd3):
    for t, y, x in ti.ndrange(gS.shape[0], gS.shape[1], gS.shape[2]):
        out[t, y, x] = gS[t, y, x] - (gA[t, y, x, 0] + gA[t, y, x, 1] + gA[t, y, x, 2])


@host("constrained_albedo")
def constrained_albedo(I, S, A) -> None:
    """``A = I - S``; see :func:`ivkernels.kernels.warp.energy_data.constrained_albedo`."""
    t, h, w, _ = I.shape
    if t * h * w == 0:
        return
    constrained_albedo_rows(I, S, A)


@host("constrained_gradient")
def constrained_gradient(gA, gS, out) -> None:
    """``out = gS - sum_c gA``; see :func:`ivkernels.kernels.warp.energy_data.constrained_gradient`."""
    t, h, w, _ = gA.shape
    if t * h * w == 0:
        return
    constrained_gradient_rows(gA, gS, out)
