"""``colour``: the declared contract of its host functions, and the NumPy references (float64)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Family, Out, Positive

FAMILY = Family("colour", "Transfer curves, log, Lab and luminance, element-wise.")

FAMILY.declare("srgb_to_linear(src, out)", "sRGB-encoded -> linear, any shape (``out`` may be ``src``).",
               src="...", out=Out("...", contiguous=True, layout="(same shape as src)"))
FAMILY.declare("linear_to_srgb(src, out)", "Linear -> sRGB-encoded, any shape (``out`` may be ``src``).",
               src="...", out=Out("...", contiguous=True, layout="(same shape as src)"))
FAMILY.declare("log_floor(src, out, floor)", "``out = log(max(src, floor))``, any shape; ``floor > 0``.",
               src="...", out=Out("...", contiguous=True, layout="(same shape as src)"), floor=Positive)
FAMILY.declare("linear_rgb_to_lab(rgb, out)", "Linear RGB -> CIE Lab, D65 white (``out`` may be ``rgb``).",
               rgb="T H W 3", out=Out("T H W 3"))
FAMILY.declare("luminance(rgb, out)", "Linear RGB -> Rec. 709 luminance.", rgb="T H W 3", out=Out("T H W"))

# Linear sRGB (D65) -> CIE XYZ (IEC 61966-2-1) and the D65 white it maps (1, 1, 1) to.
RGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375],
                       [0.2126729, 0.7151522, 0.0721750],
                       [0.0193339, 0.1191920, 0.9503041]])
WHITE_D65 = np.array([0.95047, 1.0, 1.08883])
REC709 = np.array([0.2126, 0.7152, 0.0722])


def srgb_to_linear(src: np.ndarray) -> np.ndarray:
    c = np.asarray(src, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((np.maximum(c, 0.04045) + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(src: np.ndarray) -> np.ndarray:
    c = np.asarray(src, np.float64)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.maximum(c, 0.0031308) ** (1 / 2.4) - 0.055)


def linear_rgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    xyz = np.asarray(rgb, np.float64) @ RGB_TO_XYZ.T / WHITE_D65
    d = 6 / 29
    f = np.where(xyz > d**3, np.cbrt(xyz), xyz / (3 * d * d) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


def luminance(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, np.float64) @ REC709


def log_floor(src: np.ndarray, floor: float) -> np.ndarray:
    return np.log(np.maximum(np.asarray(src, np.float64), floor))
