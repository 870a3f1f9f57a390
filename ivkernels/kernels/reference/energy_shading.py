"""``energy_shading``: the declared contract of its host functions, and the NumPy references (Eq. 9 local part,
ungated and gated, Eq. 13 coupling), float64."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Array, Family, Real, Rule

FAMILY = Family("energy_shading", "Local smoothness and coupling of the shading (Eq. 9, 13).")


def _fewer_boundary_frames(sizes, args):
    fewer, frames = sizes["T'"], sizes["T"]
    if fewer > frames:
        raise ValueError(f"w_bnd has {fewer} frames but S only {frames}; expected T' <= T")


FAMILY.declare("shading_smoothness(S, gS, energy_rows, lam=2.0, eps=0.001)",
               "Add the 3x3 Charbonnier smoothness of S and its gradient.",
               S="T H W", gS=Acc("T H W"), energy_rows=Acc("T*H", "float64"), lam=Real, eps=Real,
               separate=(("gS", "S", "the gradient is scattered into gS while S is read"),))
FAMILY.declare("shading_smoothness_gated(S, gate, gS, energy_rows, lam=2.0, eps=0.001)",
               "The same with pair weights ``(gate(x) + gate(y)) / 2``.",
               S="T H W", gate="T H W", gS=Acc("T H W"), energy_rows=Acc("T*H", "float64"), lam=Real, eps=Real,
               separate=(("gS", "S", "the gradient is scattered into gS while S is read"),
                         ("gS", "gate", "the gradient is scattered into gS while gate is read")))
FAMILY.declare("shading_smoothness_paired(S, gate, pairs, gS, energy_rows, lam=2.0, pair_gain=1.0, eps=0.001)",
               "The gated term plus ``lam pair_gain sum_t sum_x sum_k pairs[x, k] sqrt((S(x + d_k) - S(x))^2 + "
               "eps^2)`` over the right (k = 0) and lower (k = 1) pairs, and its gradient.",
               S="T H W", gate="T H W", pairs=Array("H W 2", layout="(H, W, 2)"), gS=Acc("T H W"),
               energy_rows=Acc("T*H", "float64"), lam=Real, pair_gain=Real, eps=Real,
               separate=(("gS", "S", "the gradient is scattered into gS while S is read"),
                         ("gS", "gate", "the gradient is scattered into gS while gate is read"),
                         ("gS", "pairs", "the gradient is scattered into gS while pairs is read")))
FAMILY.declare("coupling_term(S, S_tilde, w_bnd, gS, energy_rows, lam=10.0)",
               "Add ``lam w_bnd (S - S~)^2`` (T' <= T boundary frames) and its gradient.",
               S="T H W", S_tilde="T H W", w_bnd=Array("T' H W"), gS=Acc("T H W"),
               energy_rows=Acc("T*H", "float64"), lam=Real, rules=(Rule(_fewer_boundary_frames, after="w_bnd"),))

NEIGHBOURS_3X3 = tuple((dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0))


def shading_smoothness(S, lam: float = 2.0, eps: float = 0.001):
    """Local shading smoothness of Eq. 9 and its gradient.

    ``E = lam * sum_x sum_{y in N3(x)} sqrt((S(x) - S(y))^2 + eps^2)``, N3 the
    8 neighbours inside the image (every unordered pair counted twice).

    Returns ``(energy_rows (T*H,), gS (T, H, W))``, float64.
    """
    S = np.asarray(S, np.float64)
    return shading_smoothness_gated(S, np.ones(S.shape), lam, eps)


def shading_smoothness_gated(S, gate, lam: float = 2.0, eps: float = 0.001):
    """Eq. 9's local smoothness with a per-pixel gate on its pair terms, and its gradient.

    ``E = lam * sum_x sum_{y in N3(x)} w(x, y) sqrt((S(x) - S(y))^2 + eps^2)`` with
    ``w(x, y) = (gate(x) + gate(y)) / 2``; ``gate = 1`` gives :func:`shading_smoothness`.

    Returns ``(energy_rows (T*H,), gS (T, H, W))``, float64.
    """
    S, gate = np.asarray(S, np.float64), np.asarray(gate, np.float64)
    t, h, w = S.shape
    energy = np.zeros((t, h, w))
    grad = np.zeros((t, h, w))
    for dy, dx in NEIGHBOURS_3X3:
        ys = slice(max(0, -dy), h - max(0, dy))
        xs = slice(max(0, -dx), w - max(0, dx))
        yn = slice(max(0, dy), h + min(0, dy))
        xn = slice(max(0, dx), w + min(0, dx))
        d = S[:, ys, xs] - S[:, yn, xn]
        wgt = 0.5 * (gate[:, ys, xs] + gate[:, yn, xn])
        rho = np.sqrt(d * d + eps * eps)
        energy[:, ys, xs] += lam * wgt * rho
        psi = lam * wgt * d / rho
        grad[:, ys, xs] += psi
        grad[:, yn, xn] -= psi
    return energy.sum(axis=2).reshape(t * h), grad


def shading_smoothness_paired(S, gate, pairs, lam: float = 2.0, pair_gain: float = 1.0, eps: float = 0.001):
    """Eq. 9's gated local smoothness plus weighted axis pairs, and its gradient.

    ``E = gated + lam * pair_gain * sum_t sum_x sum_k pairs[x, k] sqrt((S(t, x + d_k) - S(t, x))^2 + eps^2)``,
    ``gated`` :func:`shading_smoothness_gated`, ``d_0 = (0, 1)`` (right), ``d_1 = (1, 0)`` (down),
    each axis pair once with the same weight in every frame, pairs leaving the image skipped
    (the stable steps' pairs, ``step_evidence.stable_pairs``); a pair's energy goes half to the
    row of each of its pixels, as the local term's.

    Returns ``(energy_rows (T*H,), gS (T, H, W))``, float64.
    """
    S, pairs = np.asarray(S, np.float64), np.asarray(pairs, np.float64)
    energy_rows, grad = shading_smoothness_gated(S, gate, lam, eps)
    t, h, w = S.shape
    energy = np.zeros((t, h, w))
    for k, (dy, dx) in enumerate(((0, 1), (1, 0))):
        a = (slice(None), slice(0, h - dy), slice(0, w - dx))
        b = (slice(None), slice(dy, h), slice(dx, w))
        wgt = lam * pair_gain * pairs[None, : h - dy, : w - dx, k]
        d = S[b] - S[a]
        rho = np.sqrt(d * d + eps * eps)
        energy[a] += 0.5 * wgt * rho                 # half in each pixel's row, as the local term's visits
        energy[b] += 0.5 * wgt * rho
        grad[b] += wgt * d / rho
        grad[a] -= wgt * d / rho
    return energy_rows + energy.sum(axis=2).reshape(t * h), grad


def coupling_term(S, S_tilde, w_bnd, lam: float = 10.0):
    """Coupling term of Eq. 13: ``E = lam * sum_{t < T'} sum_x w_bnd (S - S~)^2``.

    ``w_bnd`` is (T', H, W) with ``T' <= T``; frames ``t >= T'`` get no term.
    Returns ``(energy_rows (T*H,), gS (T, H, W))``, float64.
    """
    S, St, w = (np.asarray(a, np.float64) for a in (S, S_tilde, w_bnd))
    t, h, wd = S.shape
    tp = w.shape[0]
    energy = np.zeros((t, h))
    grad = np.zeros((t, h, wd))
    d = S[:tp] - St[:tp]
    energy[:tp] = lam * (w * d * d).sum(axis=2)
    grad[:tp] = 2.0 * lam * w * d
    return energy.reshape(t * h), grad
