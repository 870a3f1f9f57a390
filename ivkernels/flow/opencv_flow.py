"""OpenCV optical flow (DIS, Farneback): fast alternatives to Classic+NL.

Both run on 8-bit sRGB grey frames, the input OpenCV's flow methods are
tuned for; the linear RGB frames are sRGB-encoded, converted to grey with
the ITU-R BT.601 weights and rounded to 8 bits.

* DIS: Kroeger et al., "Fast optical flow using dense inverse search",
  ECCV 2016, ``cv2.DISOpticalFlow`` with ``PRESET_MEDIUM``.
* Farneback: "Two-frame motion estimation based on polynomial expansion",
  SCIA 2003, ``cv2.calcOpticalFlowFarneback``.
"""
from __future__ import annotations

import cv2
import numpy as np

from ivkernels.colour import srgb_encode

#: Farneback parameters: pyramid scale, levels, window, iterations, poly_n, poly_sigma, flags.
FARNEBACK_DEFAULTS = dict(pyr_scale=0.5, levels=5, winsize=15, iterations=3, poly_n=5, poly_sigma=1.2, flags=0)

#: Smallest frame side DIS accepts here (OpenCV 4.x/5.x crash on e.g. 15x40 frames).
DIS_MIN_SIZE = 16

_DIS_PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


def grey8(frames: np.ndarray) -> np.ndarray:
    """(T, H, W, 3) linear RGB in [0, 1] -> (T, H, W) uint8 sRGB grey."""
    grey = srgb_encode(frames, np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
    return np.clip(np.rint(grey * 255.0), 0, 255).astype(np.uint8)


def dis_flow(frames: np.ndarray, preset: str = "medium") -> np.ndarray:
    """DIS flow between consecutive frames.

    frames : (T, H, W, 3) float32 linear RGB in [0, 1], T >= 2.
    preset : "ultrafast", "fast" or "medium" (default, ``PRESET_MEDIUM``).
    Returns (T-1, H, W, 2) float32 forward flow in pixels.
    """
    if preset not in _DIS_PRESETS:
        raise ValueError(f"preset must be one of {tuple(_DIS_PRESETS)}, got {preset!r}")
    if min(frames.shape[1:3]) < DIS_MIN_SIZE:
        # OpenCV's DIS raises on some smaller frames and crashes the process on others
        # (e.g. 15x40), so refuse them all.
        raise ValueError(f"DIS needs frames of at least {DIS_MIN_SIZE}x{DIS_MIN_SIZE} pixels, got "
                         f"{frames.shape[1]}x{frames.shape[2]}; use 'classic_nl_fast' or 'farneback'")
    grey = grey8(frames)
    dis = cv2.DISOpticalFlow_create(_DIS_PRESETS[preset])
    out = np.empty((grey.shape[0] - 1, *grey.shape[1:], 2), np.float32)
    for t in range(out.shape[0]):
        out[t] = dis.calc(grey[t], grey[t + 1], None)
    return out


def farneback_flow(frames: np.ndarray, **params) -> np.ndarray:
    """Farneback flow between consecutive frames.

    frames : (T, H, W, 3) float32 linear RGB in [0, 1], T >= 2.
    params : overrides of :data:`FARNEBACK_DEFAULTS`.
    Returns (T-1, H, W, 2) float32 forward flow in pixels.
    """
    unknown = sorted(set(params) - set(FARNEBACK_DEFAULTS))
    if unknown:
        raise TypeError(f"unknown Farneback option(s) {unknown}; valid: {sorted(FARNEBACK_DEFAULTS)}")
    p = {**FARNEBACK_DEFAULTS, **params}
    grey = grey8(frames)
    out = np.empty((grey.shape[0] - 1, *grey.shape[1:], 2), np.float32)
    for t in range(out.shape[0]):
        out[t] = cv2.calcOpticalFlowFarneback(grey[t], grey[t + 1], None, p["pyr_scale"], p["levels"],
                                              p["winsize"], p["iterations"], p["poly_n"],
                                              p["poly_sigma"], p["flags"])
    return out
