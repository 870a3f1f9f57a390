"""``energy_albedo_entropy``: the declared contract of its host functions, and the NumPy references (Eq. 12), float64.

Two references: :func:`entropy_term` follows the kernels' histogram algorithm
step by step (splat, separable blur, dot, sliced gradient), and
:func:`entropy_direct` evaluates Eq. 12's double sum over all pixel pairs,
O(N^2), for small inputs.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Array, Family, Finite, FinitePositive, Int, Out, Rule

FAMILY = Family("energy_albedo_entropy", "The albedo's global sparsity (Eq. 12).")


def _bins(name):
    def check(sizes, args):
        if sizes["B"] < 2:
            raise ValueError(f"{name} must have shape (T, B, B, B) with B >= 2, got {tuple(args[name].shape)}")
    return Rule(check, after=name)


def _odd_taps(sizes, args):
    if sizes["k"] % 2 != 1:
        raise ValueError(f"taps must have an odd length 2r+1, got {sizes['k']}")


def _rows_per_frame(sizes, args):
    if sizes["T"] == 0 or sizes["R"] % sizes["T"]:
        raise ValueError(f"energy_rows length {sizes['R']} is not a multiple of T = {sizes['T']}")


_SCATTER = (("gA", "A", "the gradient is scattered into gA while A is read"),)
_LIKE_HIST = "(T, B, B, B) like hist"

FAMILY.declare("allocate_entropy_scratch(n_frames, bins, device='cpu')",
               ":class:`ivkernels.kernels.host.EntropyScratch` of backend arrays for T frames, B^3 bins.")
FAMILY.declare("entropy_histogram(A, whiten, lo, h, hist, row_flags)",
               "Splat of ``W A`` into the histogram, flagging the rows it touched.",
               A="T H W 3", whiten="3 3", lo=Finite, h=FinitePositive, hist=Out("T B B B"),
               row_flags=Out("2 T B B", "int32"), rules=(_bins("hist"),))
FAMILY.declare("entropy_blur(hist, taps, row_flags, tmp, blurred)", "``blurred = G * hist`` per frame.",
               hist="T B B B", taps=Array("k", layout="(2r+1,)"), row_flags=Out("2 T B B", "int32"),
               tmp=Out("T B B B", layout=_LIKE_HIST), blurred=Out("T B B B", layout=_LIKE_HIST),
               rules=(_bins("hist"), Rule(_odd_taps, after="taps")),
               separate=(("tmp", "hist", "the blur reads neighbours of hist while writing tmp"),
                         ("blurred", "hist", "the blur reads neighbours of hist while writing blurred")))
FAMILY.declare("entropy_dot(hist, blurred, dots)", "``dots[t] = <hist_t, blurred_t>``.",
               hist="T B B B", blurred=Array("T B B B", layout=_LIKE_HIST), dots=Out("T", "float64"),
               rules=(_bins("hist"),))
FAMILY.declare("entropy_slice_gradient(A, whiten, lo, h, blurred, dots, gA, lam)", "Add Eq. 12's gradient into gA.",
               A="T H W 3", whiten="3 3", lo=Finite, h=FinitePositive, blurred="T B B B",
               dots=Array("T", "float64"), gA=Acc("T H W 3"), lam=Finite, rules=(_bins("blurred"),),
               separate=_SCATTER)
FAMILY.declare("entropy_energy(dots, sigma_p, n_pixels, energy_rows, lam)",
               "Add Eq. 12's energy of each frame into the first row of the frame.",
               dots=Array("T", "float64"), sigma_p=FinitePositive, n_pixels=Int(1),
               energy_rows=Acc("R", "float64", layout="(T*H,)"), lam=Finite,
               rules=(Rule(_rows_per_frame, after="energy_rows"),))
FAMILY.declare("entropy_term(A, whiten, lo, h, taps, sigma_p, scratch, gA, energy_rows, lam)",
               "Add Eq. 12's energy and gradient (the five steps above).",
               A="T H W 3", gA=Acc("T H W 3"), energy_rows=Acc("T*H", "float64"), separate=_SCATTER)


def _bin_coords(A, whiten, lo: float, h: float, bins: int):
    """Per-pixel ``(i0, f, inside)`` along the 3 axes of the histogram, shapes (T, N, 3)."""
    A = np.asarray(A, np.float64)
    T = A.shape[0]
    u = A.reshape(T, -1, 3) @ np.asarray(whiten, np.float64).T
    c = (u - lo) / h
    inside = (c >= 0) & (c <= bins - 1)
    c = np.clip(np.nan_to_num(c, nan=0.0), 0, bins - 1)
    i0 = np.minimum(np.floor(c).astype(np.int64), bins - 2)
    return i0, c - i0, inside


def _corners(i0, f):
    """Yield ``(index tuple, weight, (sign0, sign1, sign2))`` for the 8 trilinear corners."""
    for a in (0, 1):
        for b in (0, 1):
            for c in (0, 1):
                w = ((f[..., 0] if a else 1 - f[..., 0]) * (f[..., 1] if b else 1 - f[..., 1])
                     * (f[..., 2] if c else 1 - f[..., 2]))
                yield (i0[..., 0] + a, i0[..., 1] + b, i0[..., 2] + c), w, (a, b, c)


def entropy_histogram(A, whiten, lo: float, h: float, bins: int):
    """Trilinear splat of ``W A(x)`` into ``(T, bins, bins, bins)`` (float64).

    Bin ``(i, j, k)`` is centred at ``lo + (i, j, k) h``; coordinates outside
    the cube are clamped onto its faces.
    """
    i0, f, _ = _bin_coords(A, whiten, lo, h, bins)
    T = i0.shape[0]
    hist = np.zeros((T, bins, bins, bins))
    t = np.broadcast_to(np.arange(T)[:, None], i0.shape[:2])
    for (i, j, k), w, _ in _corners(i0, f):
        np.add.at(hist, (t, i, j, k), w)
    return hist


def entropy_blur(hist, taps):
    """Separable blur of every frame of ``hist`` with the 1-D ``taps`` (zero outside the cube)."""
    taps = np.asarray(taps, np.float64)
    r = (len(taps) - 1) // 2
    out = np.asarray(hist, np.float64)
    B = out.shape[1]
    for axis in (3, 2, 1):
        src, out = out, np.zeros_like(out)
        for o in range(-r, r + 1):
            lo_dst, hi_dst = max(0, -o), min(B, B - o)
            sl_dst = [slice(None)] * 4
            sl_src = [slice(None)] * 4
            sl_dst[axis] = slice(lo_dst, hi_dst)
            sl_src[axis] = slice(lo_dst + o, hi_dst + o)
            out[tuple(sl_dst)] += taps[o + r] * src[tuple(sl_src)]
    return out


def entropy_dot(hist, blurred):
    """``<hist_t, blurred_t>`` per frame, float64 (T,)."""
    return np.einsum("tijk,tijk->t", np.asarray(hist, np.float64), np.asarray(blurred, np.float64))


def entropy_energy(dots, sigma_p: float, n_pixels: int, lam: float, rows_per_frame: int):
    """``E_t = -lam log(dots[t] / (n_pixels^2 sqrt(4 pi sigma_p^2)))`` in row ``t * rows_per_frame``
    of a float64 ``(T * rows_per_frame,)`` array, zeros elsewhere."""
    dots = np.asarray(dots, np.float64)
    energy_rows = np.zeros(len(dots) * rows_per_frame)
    energy_rows[::rows_per_frame] = -lam * (np.log(dots) - 2 * np.log(n_pixels)
                                            - 0.5 * np.log(4 * np.pi * sigma_p ** 2))
    return energy_rows


def entropy_slice_gradient(A, whiten, lo: float, h: float, blurred, dots, lam: float):
    """``dE/dA(x) = -2 lam W^T grad(interp blurred)(W A(x)) / dots[t]``, float64 (T, H, W, 3).

    ``interp`` is the trilinear interpolant of ``blurred`` (T, B, B, B) on the
    histogram's grid; its gradient is zero along an axis where the coordinate
    was clamped onto the cube.
    """
    A = np.asarray(A, np.float64)
    blurred = np.asarray(blurred, np.float64)
    T = A.shape[0]
    i0, f, inside = _bin_coords(A, whiten, lo, h, blurred.shape[1])
    t = np.broadcast_to(np.arange(T)[:, None], i0.shape[:2])
    grad_c = np.zeros(i0.shape)
    for (i, j, k), _, signs in _corners(i0, f):
        v = blurred[t, i, j, k]
        for axis in range(3):
            others = [ax for ax in range(3) if ax != axis]
            w = np.ones(i0.shape[:2])
            for ax in others:
                w = w * (f[..., ax] if signs[ax] else 1 - f[..., ax])
            grad_c[..., axis] += (1.0 if signs[axis] else -1.0) * w * v
    grad_u = np.where(inside, grad_c / h, 0.0)
    scale = (-2.0 * lam / np.asarray(dots, np.float64))[:, None, None]
    return (scale * (grad_u @ np.asarray(whiten, np.float64))).reshape(A.shape)


def entropy_term(A, whiten, lo: float, h: float, taps, sigma_p: float, lam: float, bins: int):
    """Eq. 12 by the histogram algorithm, and its exact gradient.

    ``E_t = -lam log(<hist_t, blurred_t> / (N^2 sqrt(4 pi sigma_p^2)))`` with
    ``N = H W`` (:func:`entropy_energy`), and the gradient of
    :func:`entropy_slice_gradient`.

    Returns ``energy_rows`` (T*H,) float64 with ``E_t`` in row ``t*H`` and
    ``gA`` (T, H, W, 3) float64.
    """
    A = np.asarray(A, np.float64)
    T, H, W, _ = A.shape
    hist = entropy_histogram(A, whiten, lo, h, bins)
    blurred = entropy_blur(hist, taps)
    dots = entropy_dot(hist, blurred)
    return (entropy_energy(dots, sigma_p, H * W, lam, H),
            entropy_slice_gradient(A, whiten, lo, h, blurred, dots, lam))


def entropy_direct(A, whiten, sigma_p: float, lam: float):
    """Eq. 12 as printed, the O(N^2) double sum, and its gradient (small inputs only).

    ``E_t = -lam log(1 / (N^2 sqrt(4 pi sigma_p^2)) sum_x sum_y exp(-|W(A(x) - A(y))|^2 / (4 sigma_p^2)))``.
    Returns ``energy_rows`` (T*H,) with ``E_t`` in row ``t*H`` and ``gA`` (T, H, W, 3).
    """
    A = np.asarray(A, np.float64)
    Wm = np.asarray(whiten, np.float64)
    T, H, W, _ = A.shape
    N = H * W
    energy_rows = np.zeros(T * H)
    gA = np.zeros_like(A)
    for t in range(T):
        u = A[t].reshape(N, 3) @ Wm.T
        diff = u[:, None, :] - u[None, :, :]
        k = np.exp(-(diff ** 2).sum(-1) / (4 * sigma_p ** 2))
        s = k.sum()
        energy_rows[t * H] = -lam * np.log(s / (N * N * np.sqrt(4 * np.pi * sigma_p ** 2)))
        # d s / d u_x = 2 sum_y k(x, y) * (-(u_x - u_y) / (2 sigma_p^2))  (x as first and second index)
        ds_du = -(k[..., None] * diff).sum(axis=1) / sigma_p ** 2
        gA[t] = (-lam / s * ds_du @ Wm).reshape(H, W, 3)
    return energy_rows, gA
