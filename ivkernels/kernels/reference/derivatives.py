"""``derivatives``: the declared contract of its host functions, and the NumPy references
(float64, replicate border)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Family, Out

FAMILY = Family("derivatives", "Image gradients, flow Sobel magnitude, divergence.")

FAMILY.declare("image_gradient(src, gx, gy)", "5-point x and y derivatives of src.",
               src="T H W C", gx=Out("T H W C"), gy=Out("T H W C"),
               separate=(("gx", "src", "the stencil reads neighbours of src while writing gx"),
                         ("gy", "src", "the stencil reads neighbours of src while writing gy")))
FAMILY.declare("flow_sobel_magnitude(flow, out)", "Sobel magnitude of a flow.", flow="T H W 2", out=Out("T H W"))
FAMILY.declare("divergence_negative(flow, out)", "``min(div u, 0)`` of a flow (Eq. 7).",
               flow="T H W 2", out=Out("T H W"))


def correlate_xy(img: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """2-D correlation of every (T, H, W[, C]) frame with ``kernel`` (kh, kw), replicate border."""
    img = np.asarray(img, np.float64)
    kh, kw = kernel.shape
    ry, rx = kh // 2, kw // 2
    pad = [(0, 0), (ry, ry), (rx, rx)] + [(0, 0)] * (img.ndim - 3)
    p = np.pad(img, pad, mode="edge")
    h, w = img.shape[1], img.shape[2]
    out = np.zeros_like(img)
    for j in range(kh):
        for i in range(kw):
            if kernel[j, i] != 0:
                out += kernel[j, i] * p[:, j:j + h, i:i + w]
    return out


#: The 5-point derivative's taps times 12 (integers, so a constant image gives exactly 0).
FIVE_POINT_TIMES_12 = np.array([1.0, -8.0, 0.0, 8.0, -1.0])
SOBEL_X = np.array([[-1.0, 0, 1], [-2, 0, 2], [-1, 0, 1]]) / 8.0


def image_gradient(src: np.ndarray):
    """Return ``(gx, gy)``: correlation with ``[1 -8 0 8 -1] / 12`` along x and y."""
    return (correlate_xy(src, FIVE_POINT_TIMES_12[None, :]) / 12.0,
            correlate_xy(src, FIVE_POINT_TIMES_12[:, None]) / 12.0)


def flow_sobel_magnitude(flow: np.ndarray) -> np.ndarray:
    sx = correlate_xy(flow, SOBEL_X)
    sy = correlate_xy(flow, SOBEL_X.T)
    return np.sqrt((sx**2 + sy**2).sum(-1))


def divergence_negative(flow: np.ndarray) -> np.ndarray:
    central = np.array([[-0.5, 0.0, 0.5]])
    div = correlate_xy(flow[..., 0], central) + correlate_xy(flow[..., 1], central.T)
    return np.minimum(div, 0.0)
