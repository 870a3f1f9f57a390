"""``energy_albedo_gsm``: the declared contract of its host functions, and the NumPy references (Eq. 11), float64."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Array, Family, Finite, FinitePositive, Int, Rule, Workspace

FAMILY = Family("energy_albedo_gsm", "The albedo's GSM smoothness (Eq. 11).")


def _table(sizes, args):
    if sizes["n"] < 2:
        raise ValueError(f"table_g must hold at least 2 entries, got {sizes['n']}")


FAMILY.declare("gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max, gA, energy_rows, lam, radius=2, *, "
               "workspace=None)", "Add Eq. 11 and its gradient; tables (n,) over r2 in [0, r2_max].",
               A="T H W 3", sigma_inv="3 3", table_g="n", table_dg=Array("n", layout="(n,) like table_g"),
               r2_max=FinitePositive, gA=Acc("T H W 3"), energy_rows=Acc("T*H", "float64"), lam=Finite,
               radius=Int(1, " (2 for the paper's 5x5 window)"), workspace=Workspace(),
               rules=(Rule(_table, after="table_g"),),
               separate=(("gA", "A", "the gradient is scattered into gA while A is read"),))


def gsm_lookup(r2, table_g, table_dg, r2_max: float):
    """``g(r2)`` and ``g'(r2)`` read from the table (grid of :mod:`ivkernels.priors`).

    The grid is ``r2_i = (i * sqrt(r2_max) / (n - 1))^2``; inside a cell both
    values are interpolated linearly in ``r2``; beyond ``r2_max`` ``g`` is
    extrapolated linearly with slope ``table_dg[-1]``.
    """
    r2 = np.asarray(r2, np.float64)
    tg = np.asarray(table_g, np.float64)
    tdg = np.asarray(table_dg, np.float64)
    n = len(tg)
    u = np.sqrt(r2) * ((n - 1) / np.sqrt(r2_max))
    inside = u < n - 1
    i = np.where(inside, np.floor(np.where(inside, u, 0.0)), 0).astype(np.int64)
    f = (u - i) * (u + i) / (2 * i + 1)
    g = np.where(inside, (1 - f) * tg[i] + f * tg[np.minimum(i + 1, n - 1)],
                 tg[-1] + tdg[-1] * (r2 - r2_max))
    dg = np.where(inside, (1 - f) * tdg[i] + f * tdg[np.minimum(i + 1, n - 1)], tdg[-1])
    return g, dg


def gsm_smoothness(A, sigma_inv, table_g, table_dg, r2_max: float, lam: float, radius: int = 2):
    """Eq. 11's GSM smoothness term and its gradient.

    ``E = lam * sum_x sum_{y in N(x)} g(d^T P d)``, ``d = A(x) - A(y)``,
    ``P = sigma_inv``, ``N(x)`` the other pixels of the ``(2 radius + 1)^2``
    window around ``x`` that lie inside the image.  Every unordered pair is
    counted twice, so ``dE/dA(x) = 4 lam sum_{y in N(x)} g'(r2) P d``.

    Parameters
    ----------
    A : (T, H, W, 3) log albedo.
    sigma_inv : (3, 3).
    table_g, table_dg : (n,) the tabulated ``g`` and ``g'``.

    Returns
    -------
    energy_rows : (T*H,) float64, the energy of row ``t*H + y``.
    gA : (T, H, W, 3) float64, dE/dA.
    """
    A = np.asarray(A, np.float64)
    P = np.asarray(sigma_inv, np.float64)
    T, H, W, _ = A.shape
    energy = np.zeros((T, H))
    gA = np.zeros_like(A)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            if (dy == 0 and dx == 0) or abs(dy) >= H or abs(dx) >= W:
                continue
            # x ranges over pixels whose neighbour x + (dy, dx) is inside the image
            ya, yb = slice(max(0, -dy), H - max(0, dy)), slice(max(0, dy), H - max(0, -dy))
            xa, xb = slice(max(0, -dx), W - max(0, dx)), slice(max(0, dx), W - max(0, -dx))
            d = A[:, ya, xa] - A[:, yb, xb]
            q = d @ P.T
            r2 = np.einsum("...c,...c->...", d, q)
            g, dg = gsm_lookup(r2, table_g, table_dg, r2_max)
            energy[:, ya] += lam * g.sum(axis=2)
            gA[:, ya, xa] += (4.0 * lam) * dg[..., None] * q
    return energy.reshape(T * H), gA
