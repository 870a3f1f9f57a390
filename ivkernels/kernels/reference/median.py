"""``median``: the declared contract of its host functions, and the NumPy references, brute force, float64.

Written pixel by pixel for clarity; use on small images only.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Array, Family, Int, NonNegative, Out, Positive, Rule, Workspace
from ivkernels.kernels.host import KMEANS_ITERATIONS, MIN_SEPARATION

FAMILY = Family("median", "The flow's 5x5 median and the weighted medians (Eq. 10, 13).")


def _fewer_flow_frames(sizes, args):
    fewer, frames = sizes["T'"], sizes["T"]
    if fewer > frames:
        raise ValueError(f"flow has {fewer} frames but S only {frames}; expected T' <= T")


FAMILY.declare("shading_scratch_shape(S_shape, radius)",
               "Shape ``(T*H, 2*(2r+1)^2)`` of :meth:`weighted_median_shading`'s scratch.")
FAMILY.declare("flow_scratch_shape(flow_shape, radius)",
               "Shape ``(T*H, 3*(2r+1)^2)`` of :meth:`weighted_median_flow`'s scratch.")
FAMILY.declare("median5x5(src, out)", "5x5 median of every channel, replicate border.",
               src="T H W C", out=Out("T H W C"),
               separate=(("out", "src", "the median reads a window of src around each pixel"),))
FAMILY.declare("surface_centres(flow, w_bnd, centres, radius=7, *, workspace=None)",
               "Eq. 10's surf: the 2-means centres of each boundary pixel's window of flow vectors.",
               flow="T H W 2", w_bnd="T H W", centres=Out("T H W 4"), radius=Int(0), workspace=Workspace())
FAMILY.declare("weighted_median_shading(S, flow, w_bnd, out, radius=7, sigma_s=7.0, lam=0.001, *, centres=None, "
               "workspace=None)",
               "The S~ update of Eq. 13 (T' <= T flow frames).",
               S="T H W", flow="T' H W 2", w_bnd="T' H W", out=Out("T H W"), radius=Int(0), sigma_s=Positive,
               lam=NonNegative, centres=Array("T' H W 4", optional=True), workspace=Workspace(),
               rules=(Rule(_fewer_flow_frames, after="flow"),),
               separate=(("out", "S", "the median reads a window of S around each pixel"),))
FAMILY.declare("weighted_median_flow(flow, lab, occ, mask, out, radius=7, sigma_x=7.0, sigma_i=7.0, *, "
               "workspace=None)", "Classic+NL's weighted flow median.",
               flow="T H W 2", lab="T H W 3", occ="T H W", mask="T H W", out=Out("T H W 2"), radius=Int(0),
               sigma_x=Positive, sigma_i=Positive, workspace=Workspace(),
               separate=(("out", "flow", "the median reads a window of flow around each pixel"),))


def median5x5(src):
    """5x5 median of every channel of ``src`` (T, H, W, C), replicate border."""
    src = np.asarray(src, np.float64)
    padded = np.pad(src, ((0, 0), (2, 2), (2, 2), (0, 0)), mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, (5, 5), axis=(1, 2))
    return np.median(windows.reshape(*src.shape, 25), axis=-1)


def l1_quadratic_minimiser(values, weights, s: float, lam: float) -> float:
    """``argmin_u sum_i w_i |u - v_i| + lam (u - s)^2`` (entries with ``w_i <= 0`` ignored).

    ``lam > 0``: Li & Osher's formula, the median of the ``n`` values and the
    ``n + 1`` points ``s + (W - 2 W_k) / (2 lam)``, ``W_k`` the weight of the
    ``k`` smallest values.  ``lam = 0``: the lower weighted median (the
    smallest ``v_k`` with ``W_k >= W / 2``).  No positive weight: ``s``.
    """
    values = np.asarray(values, np.float64)
    weights = np.asarray(weights, np.float64)
    keep = weights > 0
    values, weights = values[keep], weights[keep]
    if values.size == 0:
        return float(s)
    order = np.argsort(values, kind="stable")
    v, wts = values[order], weights[order]
    total = wts.sum()
    cum = np.concatenate([[0.0], np.cumsum(wts)])
    if lam > 0:
        points = s + (total - 2.0 * cum) / (2.0 * lam)
        return float(np.median(np.concatenate([v, points])))
    return float(v[np.searchsorted(cum[1:], 0.5 * total, side="left")])


def window_centres(flow_t, y: int, x: int, radius: int,
                   iterations: int = KMEANS_ITERATIONS, min_separation: float = MIN_SEPARATION):
    """The 2-means of the flow vectors in the window of ``(y, x)`` (pixels inside the image) of one
    flow field (H, W, 2): centres start at ``flow(x)`` and at the window vector farthest from it
    (the first one in row-major order on ties); Lloyd iterations (a vector goes to centre 1 only
    if strictly nearer to it) until the centres stop moving or ``iterations`` passes; an emptied
    cluster keeps its centre.  Returns the final centres ``(c0, c1)`` (2-vectors), or ``None``
    if they are closer than ``min_separation`` pixels (the window holds one surface)."""
    flow_t = np.asarray(flow_t, np.float64)
    vec, inside = _flow_window(flow_t, y, x, radius)
    c0 = flow_t[y, x].copy()
    d = ((vec - c0) ** 2).sum(-1)
    d[~inside] = -1.0
    c1 = vec.reshape(-1, 2)[int(np.argmax(d))].copy()
    for _ in range(iterations):
        near1 = (((vec - c1) ** 2).sum(-1) < ((vec - c0) ** 2).sum(-1)) & inside
        near0 = ~near1 & inside
        n0 = vec[near0].mean(0) if near0.any() else c0
        n1 = vec[near1].mean(0) if near1.any() else c1
        moved = not (np.array_equal(n0, c0) and np.array_equal(n1, c1))
        c0, c1 = n0, n1
        if not moved:
            break
    if ((c0 - c1) ** 2).sum() < min_separation**2:
        return None
    return c0, c1


def _flow_window(flow_t, y: int, x: int, radius: int):
    """The (2r+1, 2r+1, 2) window of flow vectors around (y, x) and where it lies inside the image."""
    h, w, _ = flow_t.shape
    n = 2 * radius + 1
    inside = np.zeros((n, n), bool)
    vec = np.zeros((n, n, 2))
    for j in range(n):
        for i in range(n):
            yy, xx = y + j - radius, x + i - radius
            if 0 <= yy < h and 0 <= xx < w:
                inside[j, i] = True
                vec[j, i] = flow_t[yy, xx]
    return vec, inside


def surf_from_centres(flow_t, y: int, x: int, radius: int, centres):
    """``surf(x, .)`` of Eq. 10 over the window of ``(y, x)``: a (2r+1, 2r+1) float array, 1 where
    the window pixel is inside the image and, if ``centres = (c0, c1)`` is not ``None``, in the
    cluster of ``flow(x)`` (strictly nearer to ``c1`` or not); 0 elsewhere."""
    flow_t = np.asarray(flow_t, np.float64)
    vec, inside = _flow_window(flow_t, y, x, radius)
    if centres is None:
        return inside.astype(np.float64)
    c0, c1 = (np.asarray(c, np.float64) for c in centres)
    near1 = ((vec - c1) ** 2).sum(-1) < ((vec - c0) ** 2).sum(-1)
    own1 = ((flow_t[y, x] - c1) ** 2).sum() < ((flow_t[y, x] - c0) ** 2).sum()
    return (inside & (near1 == own1)).astype(np.float64)


def flow_two_means(flow_t, y: int, x: int, radius: int,
                   iterations: int = KMEANS_ITERATIONS, min_separation: float = MIN_SEPARATION):
    """``surf(x, .)`` of Eq. 10 over the window of ``(y, x)`` in one flow field (H, W, 2): the
    cluster of ``flow(x)`` by :func:`window_centres` (:func:`surf_from_centres`), or every pixel
    inside the image where the window holds one surface."""
    return surf_from_centres(flow_t, y, x, radius, window_centres(flow_t, y, x, radius, iterations, min_separation))


def surface_centres(flow, w_bnd, radius: int = 7):
    """Per flow pixel with ``w_bnd >= 0.5`` whose window splits (:func:`window_centres`), its two
    centres ``(c0x, c0y, c1x, c1y)`` (c0: the cluster started at ``flow(x)``); zeros elsewhere.
    ``flow`` (T', H, W, 2), ``w_bnd`` (T', H, W); returns (T', H, W, 4)."""
    flow = np.asarray(flow, np.float64)
    out = np.zeros((*flow.shape[:3], 4))
    for t in range(flow.shape[0]):
        for y, x in zip(*np.nonzero(np.asarray(w_bnd[t]) >= 0.5)):
            found = window_centres(flow[t], y, x, radius)
            if found is not None:
                out[t, y, x] = np.concatenate(found)
    return out


def _spatial_weights(radius: int, sigma_s: float):
    """``exp(-|d|^2 / (2 sigma_s^2))`` over the (2r+1, 2r+1) window offsets ``d``."""
    j, i = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    return np.exp(-(i * i + j * j) / (2.0 * sigma_s**2))


def shading_weights(flow_t, y: int, x: int, radius: int = 7, sigma_s: float = 7.0):
    """Non-local weights ``w_nl(x, .)`` of Eq. 10 over the window of ``(y, x)``: (2r+1, 2r+1)."""
    return _spatial_weights(radius, sigma_s) * flow_two_means(flow_t, y, x, radius)


def _window(img, y: int, x: int, radius: int):
    """(2r+1, 2r+1) window of ``img`` (H, W) around (y, x); outside pixels are 0."""
    h, w = img.shape
    out = np.zeros((2 * radius + 1, 2 * radius + 1))
    y0, y1 = max(0, y - radius), min(h, y + radius + 1)
    x0, x1 = max(0, x - radius), min(w, x + radius + 1)
    out[y0 - y + radius:y1 - y + radius, x0 - x + radius:x1 - x + radius] = img[y0:y1, x0:x1]
    return out


def weighted_median_shading(S, flow, w_bnd, radius: int = 7, sigma_s: float = 7.0, lam: float = 0.001,
                            centres=None):
    """S~ update of Eq. 13: see :func:`ivkernels.kernels.warp.median.weighted_median_shading`.

    ``S`` (T, H, W), ``flow`` (T', H, W, 2), ``w_bnd`` (T', H, W), ``centres``
    (T', H, W, 4) as :func:`surface_centres` gives them, or ``None`` to find
    them here.  Returns (T, H, W).
    """
    S = np.asarray(S, np.float64)
    out = S.copy()
    for t in range(flow.shape[0]):
        for y, x in zip(*np.nonzero(np.asarray(w_bnd[t]) >= 0.5)):
            if centres is None:
                found = window_centres(flow[t], y, x, radius)
            else:                                   # equal centres (zeros): one surface
                c = np.asarray(centres[t, y, x], np.float64)
                found = None if np.array_equal(c[:2], c[2:]) else (c[:2], c[2:])
            wts = _spatial_weights(radius, sigma_s) * surf_from_centres(flow[t], y, x, radius, found)
            vals = _window(S[t], y, x, radius)
            out[t, y, x] = l1_quadratic_minimiser(vals.ravel(), wts.ravel(), S[t, y, x], lam)
    return out


def flow_weights(lab_t, occ_t, y: int, x: int, radius: int = 7, sigma_x: float = 7.0, sigma_i: float = 7.0):
    """Classic+NL weights over the window of ``(y, x)``: spatial * colour * occlusion, (2r+1, 2r+1)."""
    lab_t = np.asarray(lab_t, np.float64)
    j, i = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    spatial = np.exp(-(i * i + j * j) / (2.0 * sigma_x**2))
    diff2 = sum((_window(lab_t[..., c], y, x, radius) - lab_t[y, x, c]) ** 2 for c in range(3))
    colour = np.exp(-diff2 / (2.0 * sigma_i**2))
    return spatial * colour * _window(np.asarray(occ_t, np.float64), y, x, radius)  # 0 outside the image


def weighted_median_flow(flow, lab, occ, mask, radius: int = 7, sigma_x: float = 7.0, sigma_i: float = 7.0):
    """Classic+NL non-local flow median: see :func:`ivkernels.kernels.warp.median.weighted_median_flow`.

    Returns (T, H, W, 2).
    """
    flow = np.asarray(flow, np.float64)
    out = flow.copy()
    for t in range(flow.shape[0]):
        for y, x in zip(*np.nonzero(np.asarray(mask[t]) >= 0.5)):
            wts = flow_weights(lab[t], occ[t], y, x, radius, sigma_x, sigma_i).ravel()
            for c in range(2):
                vals = _window(flow[t, ..., c], y, x, radius).ravel()
                out[t, y, x, c] = l1_quadratic_minimiser(vals, wts, flow[t, y, x, c], 0.0)
    return out
