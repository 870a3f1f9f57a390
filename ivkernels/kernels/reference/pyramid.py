"""``pyramid``: the declared contract of its host functions, and the NumPy references (float64)."""
from __future__ import annotations

import math

import numpy as np

from ivkernels.kernels.contract import Array, Family, Finite, Out, Rule

FAMILY = Family("pyramid", "Gaussian blur and bilinear resizing of frames and flows.")


def _sizes(sizes, args):
    if min(sizes["h"], sizes["w"], sizes["H"], sizes["W"]) < 1:
        raise ValueError(f"image sizes must be >= 1, got src {tuple(args['src'].shape)}, "
                         f"out {tuple(args['out'].shape)}")


FAMILY.declare("gaussian_kernel(sigma)", "Normalised 1-D Gaussian taps, float32 (2r+1,), r = max(1, ceil(3 sigma)).")
FAMILY.declare("gaussian_blur(src, out, scratch, sigma)",
               "Separable blur of src into out (``out`` may be ``src``; ``sigma <= 0`` copies).",
               src="T H W C", out=Out("T H W C"), scratch=Out("T H W C"), sigma=Finite,
               separate=(("scratch", "src", "it holds the x-blurred image"),
                         ("scratch", "out", "it holds the x-blurred image")))
FAMILY.declare("resize_bilinear(src, out)", "Resize src to out's size, pixel-centre mapping.",
               src=Array("T h w C"), out=Out("T H W C"), rules=(Rule(_sizes),))
FAMILY.declare("resize_flow(src, out)", "Resize a flow to out's size, vectors rescaled.",
               src=Array("T h w 2", layout="(T, h, w, 2)"), out=Out("T H W 2"), rules=(Rule(_sizes),))


def gaussian_blur(src: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian, taps k = -r..r with r = max(1, ceil(3 sigma)), normalised, replicate border."""
    src = np.asarray(src, np.float64)
    if sigma <= 0:
        return src.copy()
    r = max(1, math.ceil(3 * sigma))
    k = np.arange(-r, r + 1)
    w = np.exp(-0.5 * (k / sigma) ** 2)
    w /= w.sum()
    h, wd = src.shape[1], src.shape[2]
    p = np.pad(src, [(0, 0), (0, 0), (r, r), (0, 0)], mode="edge")
    tmp = sum(w[i] * p[:, :, i:i + wd] for i in range(2 * r + 1))
    p = np.pad(tmp, [(0, 0), (r, r), (0, 0), (0, 0)], mode="edge")
    return sum(w[i] * p[:, i:i + h] for i in range(2 * r + 1))


def _axis(n_out: int, n_in: int):
    p = (np.arange(n_out) + 0.5) * n_in / n_out - 0.5
    f = np.floor(p)
    i0 = f.astype(np.int64)
    return np.clip(i0, 0, n_in - 1), np.clip(i0 + 1, 0, n_in - 1), p - f


def resize_bilinear(src: np.ndarray, size) -> np.ndarray:
    """Resize (T, h, w, C) to (T, H, W, C), ``size = (H, W)``, pixel-centre mapping, clamped corners."""
    src = np.asarray(src, np.float64)
    H, W = size
    y0, y1, fy = _axis(H, src.shape[1])
    x0, x1, fx = _axis(W, src.shape[2])
    fy, fx = fy[:, None, None], fx[None, :, None]
    rows0, rows1 = src[:, y0], src[:, y1]
    top = (1 - fx) * rows0[:, :, x0] + fx * rows0[:, :, x1]
    bottom = (1 - fx) * rows1[:, :, x0] + fx * rows1[:, :, x1]
    return (1 - fy) * top + fy * bottom


def resize_flow(src: np.ndarray, size) -> np.ndarray:
    """:func:`resize_bilinear`, then dx times W / w and dy times H / h."""
    out = resize_bilinear(src, size)
    out[..., 0] *= size[1] / src.shape[2]
    out[..., 1] *= size[0] / src.shape[1]
    return out
