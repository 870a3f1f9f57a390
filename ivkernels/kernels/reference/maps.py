"""``maps``: the declared contract of its host functions, and the NumPy references (float64)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Array, Family, Int, NonNegative, Out, Positive, Real, Rule, Workspace
from ivkernels.kernels.reference.sampling import _corners, _sample_points, warp_bilinear

FAMILY = Family("maps", "Occlusion, warp reliability, motion boundaries and the shading gate.")


def _two_frames(sizes, args):
    if sizes["F"] < 2:
        raise ValueError(f"lab must hold at least two frames (T+1, H, W, 3), got {tuple(args['lab'].shape)}")


_OCCLUSION = dict(lab=Array("F H W 3", layout="(T+1, H, W, 3)"),
                  flow=Array("F-1 H W 2", layout="(T, H, W, 2) with T = lab frames - 1"),
                  div_neg=Array("F-1 H W", layout="(T, H, W)"), out=Out("F-1 H W", layout="(T, H, W)"),
                  sigma_e=Positive, sigma_d=Positive, rules=(Rule(_two_frames, after="lab"),))
FAMILY.declare("occlusion_soft(lab, flow, div_neg, out, sigma_e=20.0, sigma_d=0.3)",
               "Eq. 7's occlusion likelihood times the inside-the-image indicator.", **_OCCLUSION)
FAMILY.declare("occlusion_binary(lab, flow, div_neg, out, sigma_e=20.0, sigma_d=0.3, threshold=0.5)",
               "Eq. 6's ``w_occ`` (0/1).", threshold=Real, **_OCCLUSION)
FAMILY.declare("warp_reliability(log_image, flow, occ, max_spread)",
               "Clear occ where the warp of log_image by flow straddles an edge; ``max_spread > 0``.",
               log_image="T H W 3", flow="T-1 H W 2", occ=Out("T-1 H W"), max_spread=Positive)
FAMILY.declare("chroma_consistency(log_image, flow, occ, max_change)",
               "Clear occ where the log chromaticity of log_image changes along flow; ``max_change > 0``.",
               log_image="T H W 3", flow="T-1 H W 2", occ=Out("T-1 H W"), max_change=Positive)
FAMILY.declare("luminance_consistency(log_image, flow, near, offsets, occ, max_change)",
               "Clear occ where near is set and the mean log of log_image changes along flow by max_change "
               "or more beyond the pair's offset; ``max_change > 0``.",
               log_image="T H W 3", flow="T-1 H W 2", near="T-1 H W", offsets="T-1", occ=Out("T-1 H W"),
               max_change=Positive)
FAMILY.declare("round_trip_consistency(flow, back_flow, occ, max_distance)",
               "Clear occ where following flow and then back_flow misses the start by max_distance pixels or "
               "more; ``max_distance > 0``.",
               flow="T H W 2", back_flow="T H W 2", occ=Out("T H W"), max_distance=Positive)
FAMILY.declare("still_surface(log_image, out, tau, radius, share, *, workspace=None)",
               "1 where the frames' log-luminance gradients agree with their median over the frames (within tau, "
               "as a mean over a (2 radius + 1)^2 window) in at least share of the frames; ``tau, share > 0``.",
               log_image="T H W 3", out=Out("H W"), tau=Positive, radius=Int(0), share=Positive,
               workspace=Workspace())
FAMILY.declare("shading_gate(log_image, flow, gate, tau, tau_chroma=0.0)",
               "Gate of Eq. 9's local term from the input's log change along the flow; ``tau > 0``.",
               log_image="T H W 3", flow="T-1 H W 2", gate=Out("T H W"), tau=Positive, tau_chroma=NonNegative,
               separate=(("gate", "log_image", "the gate is written while log_image is read"),
                         ("gate", "flow", "the gate is written while flow is read")))
FAMILY.declare("motion_boundary(sobel_mag, out, threshold, radius, *, workspace=None)",
               "``w_bnd``: sobel_mag above threshold, dilated by radius pixels.",
               sobel_mag="T H W", out=Out("T H W"), threshold=Real, radius=Int(0), workspace=Workspace(),
               separate=(("out", "sobel_mag", "the dilation reads neighbours of sobel_mag",
                          lambda args: args["radius"]),))


def occlusion_soft(lab, flow, div_neg, sigma_e: float = 20.0, sigma_d: float = 0.3) -> np.ndarray:
    """Eq. 7 ``o(x)`` times the inside-the-image indicator."""
    lab = np.asarray(lab, np.float64)
    warped, inside = warp_bilinear(lab[1:], flow)
    dist2 = ((lab[:-1] - warped) ** 2).sum(-1)
    d = np.asarray(div_neg, np.float64)
    return np.exp(-dist2 / (2 * sigma_e**2) - d**2 / (2 * sigma_d**2)) * inside


def occlusion_binary(lab, flow, div_neg, sigma_e: float = 20.0, sigma_d: float = 0.3,
                     threshold: float = 0.5) -> np.ndarray:
    """Eq. 6 ``w_occ``: 1 where ``o >= threshold`` and ``x + u`` is inside the image."""
    _, inside = warp_bilinear(np.asarray(lab, np.float64)[1:, ..., :1], flow)
    o = occlusion_soft(lab, flow, div_neg, sigma_e, sigma_d)
    return ((o >= threshold) & (inside > 0)).astype(np.float64)


def corner_spread(img, flow) -> np.ndarray:
    """(T-1, H, W): mean over channels of ``sum_k w_k |img_{t+1}(corner_k) - img_{t+1}(x + u)|``."""
    img = np.asarray(img, np.float64)
    _, h, w, _ = img.shape
    px, py = _sample_points(np.asarray(flow, np.float64))
    x0, x1, fx = _corners(np.clip(px, -2, w + 1), w)
    y0, y1, fy = _corners(np.clip(py, -2, h + 1), h)
    nxt = img[1:]
    tt = np.arange(nxt.shape[0])[:, None, None]
    corners = [(nxt[tt, y0, x0], (1 - fx) * (1 - fy)), (nxt[tt, y0, x1], fx * (1 - fy)),
               (nxt[tt, y1, x0], (1 - fx) * fy), (nxt[tt, y1, x1], fx * fy)]
    v = sum(c * wk[..., None] for c, wk in corners)
    return sum(wk[..., None] * np.abs(c - v) for c, wk in corners).mean(-1)


def warp_reliability(log_image, flow, occ, max_spread: float) -> np.ndarray:
    """``occ`` with 0 where :func:`corner_spread` of the log image reaches ``max_spread``."""
    return np.where(corner_spread(log_image, flow) >= max_spread, 0.0, np.asarray(occ, np.float64))


def chroma_change(log_image, flow) -> np.ndarray:
    """(T-1, H, W): ``max_c |C_{t+1}(x + u)_c - C_t(x)_c|``, ``C`` the log chromaticity
    ``log_image - mean over channels``, ``C_{t+1}`` sampled bilinearly (clamped corners)."""
    img = np.asarray(log_image, np.float64)
    C = img - img.mean(-1, keepdims=True)
    warped, _ = warp_bilinear(C[1:], np.asarray(flow, np.float64))
    return np.abs(warped - C[:-1]).max(-1)


def chroma_consistency(log_image, flow, occ, max_change: float) -> np.ndarray:
    """``occ`` with 0 where :func:`chroma_change` reaches ``max_change``."""
    return np.where(chroma_change(log_image, flow) >= max_change, 0.0, np.asarray(occ, np.float64))


def luminance_consistency(log_image, flow, near, offsets, occ, max_change: float) -> np.ndarray:
    """``occ`` with 0 where ``near >= 0.5`` and ``|D - offsets[t]| >= max_change``, ``D`` of
    :func:`log_change` (the change of the mean log along the flow)."""
    D, _ = log_change(log_image, flow)
    change = np.abs(D - np.asarray(offsets, np.float64)[:, None, None])
    clear = (np.asarray(near) >= 0.5) & (change >= max_change)
    return np.where(clear, 0.0, np.asarray(occ, np.float64))


def round_trip_distance(flow, back_flow) -> np.ndarray:
    """(T, H, W): ``|u_t(x) + b_t(x + u_t(x))|`` (pixels), ``b_t`` the backward flow from frame
    t+1 to frame t sampled bilinearly (clamped corners) where the forward flow ``u_t`` lands."""
    flow = np.asarray(flow, np.float64)
    back, _ = warp_bilinear(back_flow, flow)
    return np.sqrt(((flow + back) ** 2).sum(-1))


def round_trip_consistency(flow, back_flow, occ, max_distance: float) -> np.ndarray:
    """``occ`` with 0 where :func:`round_trip_distance` reaches ``max_distance``."""
    return np.where(round_trip_distance(flow, back_flow) >= max_distance, 0.0, np.asarray(occ, np.float64))


def log_luminance_gradients(log_image) -> np.ndarray:
    """(T, H, W, 2): the forward differences ``L(x + 1) - L(x)``, ``L(y + 1) - L(y)`` of
    ``L = mean_c log_image`` (0 on the last column / row)."""
    L = np.asarray(log_image, np.float64).mean(-1)
    g = np.zeros((*L.shape, 2))
    g[:, :, :-1, 0] = L[:, :, 1:] - L[:, :, :-1]
    g[:, :-1, :, 1] = L[:, 1:, :] - L[:, :-1, :]
    return g


def median_residual(log_image) -> np.ndarray:
    """(T, H, W): ``|g_t(x) - m(x)|_1``, ``g`` :func:`log_luminance_gradients` and ``m`` their
    median over the frames (the mean of the two middle values for an even count)."""
    g = log_luminance_gradients(log_image)
    return np.abs(g - np.median(g, axis=0)).sum(-1)


def still_window_means(log_image, radius: int) -> np.ndarray:
    """(T, H, W): :func:`median_residual` averaged over the ``(2 radius + 1)^2`` window
    (the pixels of it inside the image)."""
    r = median_residual(log_image)
    t, h, w = r.shape
    total = np.zeros_like(r)
    count = np.zeros((h, w))
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            ys, xs, yn, xn = _pair_slices(dy, dx, h, w)
            total[:, ys, xs] += r[:, yn, xn]
            count[ys, xs] += 1.0
    return total / count


def still_surface(log_image, tau: float, radius: int, share: float) -> np.ndarray:
    """(H, W): 1 where the frames whose :func:`still_window_means` is under ``tau`` number
    at least ``share * T``, else 0."""
    means = still_window_means(log_image, radius)
    return ((means < tau).sum(0) >= share * means.shape[0]).astype(np.float64)


def motion_boundary(sobel_mag, threshold: float, radius: int) -> np.ndarray:
    """1 where the (2r+1)^2 window (clipped to the image) holds a magnitude above threshold."""
    edge = np.asarray(sobel_mag) > threshold
    t, h, w = edge.shape
    p = np.pad(edge, [(0, 0), (radius, radius), (radius, radius)], constant_values=False)
    out = np.zeros_like(edge)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out |= p[:, dy:dy + h, dx:dx + w]
    return out.astype(np.float64)


def log_change(log_image, flow):
    """``(D, valid)``, both (T-1, H, W): ``D = L_{t+1}(x + u) - L_t(x)`` with ``L`` the
    mean over channels of the log image (bilinear sample, clamped corners), and
    ``valid`` = 1 where ``x + u`` lies inside the image."""
    L = np.asarray(log_image, np.float64).mean(-1)
    warped, inside = warp_bilinear(L[1:, ..., None], np.asarray(flow, np.float64))
    return warped[..., 0] - L[:-1], inside


def chroma_step(log_image) -> np.ndarray:
    """(T, H, W): ``max_{y in N3(x)} |C(x) - C(y)|`` (Euclidean over channels), ``C`` the log
    chromaticity ``log_image - mean over channels``."""
    img = np.asarray(log_image, np.float64)
    C = img - img.mean(-1, keepdims=True)
    t, h, w, _ = img.shape
    out = np.zeros((t, h, w))
    for dy, dx in _NEIGHBOURS:
        ys, xs, yn, xn = _pair_slices(dy, dx, h, w)
        out[:, ys, xs] = np.maximum(out[:, ys, xs], np.sqrt(((C[:, ys, xs] - C[:, yn, xn]) ** 2).sum(-1)))
    return out


def shading_gate(log_image, flow, tau: float, tau_chroma: float = 0.0) -> np.ndarray:
    """The temporal gate of the local shading smoothness (T, H, W), in (0, 1].

    ``gate = exp(-(e / tau)^2)`` with ``e(x) = max_{y in N3(x)} |D(x) - D(y)|``
    over the neighbours ``y`` whose sample is valid too (:func:`log_change` of
    the frame's pair with the next frame; the last frame uses the pair before
    it); e = 0 (gate 1) where ``x``'s own sample is not valid, and gate 1
    everywhere for T = 1.  With ``tau_chroma > 0``, ``e`` is multiplied by
    ``exp(-(c / tau_chroma)^2)``, ``c`` the frame's :func:`chroma_step`: a
    change of contrast where the chromaticity changes too is not taken for
    a shading edge.
    """
    img = np.asarray(log_image, np.float64)
    t, h, w, _ = img.shape
    if t < 2:
        return np.ones((t, h, w))
    D, valid = log_change(img, flow)
    e = np.zeros(D.shape)
    for dy, dx in _NEIGHBOURS:
        ys, xs, yn, xn = _pair_slices(dy, dx, h, w)
        d = np.abs(D[:, ys, xs] - D[:, yn, xn]) * valid[:, yn, xn]
        e[:, ys, xs] = np.maximum(e[:, ys, xs], d)
    e *= valid
    e = np.concatenate([e, e[-1:]], 0)
    if tau_chroma > 0:
        e *= np.exp(-(chroma_step(img) / tau_chroma) ** 2)
    return np.exp(-(e / tau) ** 2)


_NEIGHBOURS = tuple((dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0))


def _pair_slices(dy: int, dx: int, h: int, w: int):
    """Slices of the pixels ``x`` whose neighbour ``x + (dy, dx)`` is inside, and of those neighbours."""
    return (slice(max(0, -dy), h - max(0, dy)), slice(max(0, -dx), w - max(0, dx)),
            slice(max(0, dy), h + min(0, dy)), slice(max(0, dx), w + min(0, dx)))
