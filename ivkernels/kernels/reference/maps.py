"""NumPy reference of :mod:`ivkernels.kernels.warp.maps` (float64)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.reference.sampling import warp_bilinear


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
