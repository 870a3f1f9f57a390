"""Taichi mirror of :mod:`ivkernels.kernels.warp.energy_shading` (Eq. 9 local
smoothness, Eq. 13 coupling): same host functions and signatures, NumPy arrays
passed as ``ti.types.ndarray()``.  The outermost loop runs over rows in parallel.
"""

import numpy as np
import taichi as ti

nd1_f64 = ti.types.ndarray(dtype=ti.f64, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)


@ti.func
def charbonnier(z, eps):
    """``sqrt(z^2 + eps^2)``."""
    return ti.sqrt(z * z + eps * eps)


@ti.kernel
def shading_smoothness_rows(S: nd3, gS: nd3, energy_rows: nd1_f64, lam: ti.f32, eps: ti.f32):
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


def _check(name: str, a, shape: tuple, layout: str, dtype=np.float32, output: bool = False) -> np.ndarray:
    """Raise unless ``a`` is a NumPy array of ``dtype`` and ``shape`` (None = any size).

    Returns a C-contiguous array: inputs are copied if needed, outputs must
    already be contiguous (they are updated in place).
    """
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name} must be a numpy.ndarray of {np.dtype(dtype).name} {layout}, got {type(a).__name__}")
    if a.dtype != dtype:
        raise TypeError(f"{name} must have dtype {np.dtype(dtype).name}, got {a.dtype.name}")
    if a.ndim != len(shape) or any(e is not None and e != s for e, s in zip(shape, a.shape)):
        want = tuple("?" if e is None else e for e in shape)
        raise ValueError(f"{name} must have shape {layout} = {want}, got {a.shape}")
    if not a.flags.c_contiguous:
        if output:
            raise ValueError(f"{name} is updated in place and must be C-contiguous")
        a = np.ascontiguousarray(a)
    return a


def shading_smoothness(S, gS, energy_rows, lam: float = 2.0, eps: float = 0.001) -> None:
    """Add the local shading smoothness of Eq. 9 and its gradient; see
    :func:`ivkernels.kernels.warp.energy_shading.shading_smoothness`."""
    S = _check("S", S, (None, None, None), "(T, H, W)")
    t, h, w = S.shape
    _check("gS", gS, (t, h, w), "(T, H, W)", output=True)
    _check("energy_rows", energy_rows, (t * h,), "(T*H,)", np.float64, output=True)
    if t * h * w == 0:
        return
    shading_smoothness_rows(S, gS, energy_rows, float(lam), float(eps))


def coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam: float = 10.0) -> None:
    """Add the coupling term of Eq. 13 and its gradient in S; see
    :func:`ivkernels.kernels.warp.energy_shading.coupling_term`."""
    S = _check("S", S, (None, None, None), "(T, H, W)")
    t, h, w = S.shape
    S_tilde = _check("S_tilde", S_tilde, (t, h, w), "(T, H, W)")
    w_bnd = _check("w_bnd", w_bnd, (None, h, w), "(T', H, W)")
    if w_bnd.shape[0] > t:
        raise ValueError(f"w_bnd has {w_bnd.shape[0]} frames but S only {t}; expected T' <= T")
    _check("gS", gS, (t, h, w), "(T, H, W)", output=True)
    _check("energy_rows", energy_rows, (t * h,), "(T*H,)", np.float64, output=True)
    if w_bnd.shape[0] * h * w == 0:
        return
    coupling_rows(S, S_tilde, w_bnd, gS, energy_rows, float(lam))
