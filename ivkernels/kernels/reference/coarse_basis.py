"""``coarse_basis``: the declared contract of its host functions, and the NumPy references (float64, vectorised).

The edge-aware coarse basis: a grid of nodes every ``spacing`` pixels per
frame, and for each pixel 16 interpolation weights over the 4 x 4 nodes
around it (tent of half-width two node spacings, times an albedo affinity,
normalised).  ``prolong`` is ``P z`` and ``restrict`` its transpose ``P^T r``.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Array, Family, Int, Out, Positive, Rule
from ivkernels.kernels.host import MAX_EXPONENT, grid_shape

FAMILY = Family("coarse_basis", "The solver's edge-aware coarse basis (nodes every ``spacing`` pixels).")

_GRID = Array("T (H-1)//spacing+2 (W-1)//spacing+2",
              layout="(T, Hc, Wc) = (T, (H-1)//spacing + 2, (W-1)//spacing + 2)")

FAMILY.declare("coarse_weights(A, weights, spacing, sigma)", "16 tap weights per pixel from the guide A.",
               A="T H W C", weights=Out("T H W 16"), spacing=Int(1), sigma=Positive,
               separate=(("weights", "A", "the weights are written while A is read at the nodes"),))
FAMILY.declare("prolong_add(z, weights, out, spacing)", "``out += P z``.", order=("weights",),
               z=_GRID, weights="T H W 16", out=Acc("T H W"), spacing=Int(1),
               separate=(("out", "z", "each pixel reads 16 nodes of z"),))
FAMILY.declare("restrict_add(values, weights, out, spacing)", "``out += P^T values``.", order=("weights",),
               values="T H W", weights="T H W 16", out=Acc(_GRID.dims, layout=_GRID.layout), spacing=Int(1),
               separate=(("out", "values", "each node sums values over 4 x 4 node spacings"),))

_NODES = Array("T (H-1)//spacing+2 (W-1)//spacing+2 C",
               layout="(T, Hc, Wc, C) = (T, (H-1)//spacing + 2, (W-1)//spacing + 2, C)")


def _frame_has_pixels(sizes, args):
    if sizes["H"] == 0 or sizes["W"] == 0:
        raise ValueError(f"src has frames of {sizes['H']} x {sizes['W']} pixels; the nodes need at least one "
                         "pixel to sit on (H, W >= 1)")


FAMILY.declare("node_samples(src, out, spacing)", "``src`` at the pixels the nodes sit on.",
               src="T H W C", out=Out(_NODES.dims, layout=_NODES.layout), spacing=Int(1),
               rules=(Rule(_frame_has_pixels, after="src"),),
               separate=(("out", "src", "out is gathered from src"),))

#: Node offsets of the 4 x 4 taps along one axis, relative to ``floor(y / spacing)``.
TAP_OFFSETS = (-1, 0, 1, 2)


def _taps(n: int, spacing: int, n_nodes: int):
    """Per pixel along one axis: node index (4, n), tent weight (4, n) (0 off the grid)."""
    p = np.arange(n, dtype=np.float64)
    f = p / spacing
    j0 = np.arange(n) // spacing
    nodes, tent = [], []
    for d in TAP_OFFSETS:
        j = j0 + d
        b = np.maximum(0.0, 1.0 - np.abs(f - j) / 2.0)
        b = np.where((j >= 0) & (j < n_nodes), b, 0.0)
        nodes.append(np.clip(j, 0, n_nodes - 1))
        tent.append(b)
    return np.stack(nodes), np.stack(tent)


def coarse_weights(A: np.ndarray, spacing: int, sigma: float) -> np.ndarray:
    """Weights (T, H, W, 16) of each pixel's 4 x 4 nodes, tap ``k = 4 * iy + ix``.

    ``w_k = b_k a_k / sum_k b_k a_k`` with ``b_k`` the product of the two
    axes' tents ``max(0, 1 - |y / spacing - j| / 2)`` (0 for a node off the
    grid) and ``a_k = exp(-min(|A(y, x) - A(node_k)|^2 / sigma^2, 30))``, the
    distance over the channels of ``A`` (T, H, W, C) between the pixel and the
    pixel the node sits on.
    """
    A = np.asarray(A, np.float64)
    t, h, w, _ = A.shape
    hc, wc = grid_shape(h, w, spacing)
    ny, by = _taps(h, spacing, hc)
    nx, bx = _taps(w, spacing, wc)
    py = np.minimum(ny * spacing, h - 1)
    px = np.minimum(nx * spacing, w - 1)
    out = np.zeros((t, h, w, 16))
    for iy in range(4):
        for ix in range(4):
            node = A[:, py[iy][:, None], px[ix][None, :], :]          # (T, H, W, C)
            d2 = ((A - node) ** 2).sum(-1) / sigma**2
            out[..., 4 * iy + ix] = by[iy][:, None] * bx[ix][None, :] * np.exp(-np.minimum(d2, MAX_EXPONENT))
    return out / out.sum(-1, keepdims=True)


def _node_index(h: int, w: int, spacing: int):
    """Flat node index (16, H, W) of each tap within a frame's grid."""
    hc, wc = grid_shape(h, w, spacing)
    ny, _ = _taps(h, spacing, hc)
    nx, _ = _taps(w, spacing, wc)
    return np.stack([ny[iy][:, None] * wc + nx[ix][None, :] for iy in range(4) for ix in range(4)])


def prolong(z: np.ndarray, weights: np.ndarray, spacing: int) -> np.ndarray:
    """``(P z)[t, y, x] = sum_k weights[t, y, x, k] z[t, node_k]``: z (T, Hc, Wc) -> (T, H, W)."""
    z = np.asarray(z, np.float64)
    weights = np.asarray(weights, np.float64)
    t, h, w, _ = weights.shape
    flat = z.reshape(t, -1)
    idx = _node_index(h, w, spacing)
    out = np.zeros((t, h, w))
    for k in range(16):
        out += weights[..., k] * flat[:, idx[k]]
    return out


def restrict(values: np.ndarray, weights: np.ndarray, spacing: int) -> np.ndarray:
    """``P^T values``: values (T, H, W) -> (T, Hc, Wc), the transpose of :func:`prolong`."""
    values = np.asarray(values, np.float64)
    weights = np.asarray(weights, np.float64)
    t, h, w, _ = weights.shape
    hc, wc = grid_shape(h, w, spacing)
    idx = _node_index(h, w, spacing)
    out = np.zeros((t, hc * wc))
    for k in range(16):
        for f in range(t):
            np.add.at(out[f], idx[k].ravel(), (weights[f, ..., k] * values[f]).ravel())
    return out.reshape(t, hc, wc)


def node_samples(src: np.ndarray, spacing: int) -> np.ndarray:
    """``src`` (T, H, W, C) at the pixels the grid's nodes sit on: (T, Hc, Wc, C), node
    ``(j, i)`` on pixel ``(min(j spacing, H - 1), min(i spacing, W - 1))``."""
    src = np.asarray(src)
    t, h, w, _ = src.shape
    hc, wc = grid_shape(h, w, spacing)
    rows = np.minimum(np.arange(hc) * spacing, h - 1)
    cols = np.minimum(np.arange(wc) * spacing, w - 1)
    return src[:, rows][:, :, cols]
