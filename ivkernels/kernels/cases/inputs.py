"""Generated inputs shared by the case modules: realistic ranges, float32, C-contiguous.

Every builder takes a ``numpy.random.Generator`` and a shape; none keeps state.
"""
from __future__ import annotations

import numpy as np

F32 = np.float32


def pairs(T: int) -> int:
    """Frame pairs of a video of ``T`` frames (flows and per-pair maps)."""
    return max(T - 1, 0)


def uniform(rng, shape, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    return rng.uniform(lo, hi, shape).astype(F32)


def normal(rng, shape, mean: float = 0.0, sigma: float = 1.0) -> np.ndarray:
    return rng.normal(mean, sigma, shape).astype(F32)


def log_image(rng, shape) -> np.ndarray:
    """Log of linear intensities in [0.02, 1] (log albedo, log input): values in [-3.9, 0]."""
    return np.log(rng.uniform(0.02, 1.0, shape)).astype(F32)


def lab_frames(rng, T: int, H: int, W: int) -> np.ndarray:
    """CIE Lab frames (T, H, W, 3): L in [0, 100], a and b in [-40, 40], neighbouring frames alike."""
    lab = np.concatenate([rng.uniform(0, 100, (T, H, W, 1)), rng.uniform(-40, 40, (T, H, W, 2))], -1)
    lab = lab.astype(F32)
    lab[1:] = 0.9 * lab[:-1] + 0.1 * lab[1:]
    return lab


def flow(rng, P: int, H: int, W: int, scale: float = 2.0, far: float = 0.0) -> np.ndarray:
    """Forward flow (P, H, W, 2) in pixels: Gaussian vectors of ``scale`` pixels, the three
    left columns leaving the image, and a fraction ``far`` of vectors up to 3 widths long."""
    f = rng.normal(0.0, scale, (P, H, W, 2)).astype(F32)
    f[:, :, :3, 0] -= 4.0
    if far:
        mask = rng.random((P, H, W)) < far
        f[mask] = rng.uniform(-3 * W, 3 * W, (int(mask.sum()), 2)).astype(F32)
    return f


def mask(rng, shape, p: float = 0.5) -> np.ndarray:
    """0 / 1 float32 mask, 1 with probability ``p``."""
    return (rng.random(shape) < p).astype(F32)


def soft_mask(rng, shape, p: float = 0.8) -> np.ndarray:
    """Visibility-like weights: mostly 1, some 0, a regular sprinkle of 0.5."""
    m = mask(rng, shape, p)
    m[..., ::4, ::3] = 0.5
    return m


def vector_length(T: int, H: int, W: int) -> int:
    """Length of the flat vectors of ``vecops`` (the solver's 4 T H W unknowns, odd)."""
    return max(4 * T * H * W - 1, 0)


def nans(shape, dtype=F32) -> np.ndarray:
    """An output buffer that the function must overwrite entirely."""
    return np.full(shape, np.nan, dtype)
