"""Single-image baselines the paper compares against.

:func:`color_retinex` is the colour Retinex of Grosse, Johnson, Adelson &
Freeman, "Ground truth dataset and baseline evaluations for intrinsic image
algorithms", ICCV 2009 (the paper's CRET), applied to each frame on its own.
"""
from __future__ import annotations

import numpy as np

__all__ = ["color_retinex"]


def _poisson_neumann(gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """Least-squares integration of a gradient field, Neumann boundary.

    Solves ``min_s sum (s[y, x+1] - s[y, x] - gx[y, x])^2 + (s[y+1, x] -
    s[y, x] - gy[y, x])^2`` for ``s`` ``(T, H, W)`` given ``gx``
    ``(T, H, W-1)`` and ``gy`` ``(T, H-1, W)``.  The normal equations are
    ``L s = div g`` with ``L`` the 5-point Laplacian with reflecting
    (Neumann) boundary; ``L`` is diagonalised by the DCT-II, computed here as
    an FFT of the even-symmetric extension of size ``(2H, 2W)`` (no SciPy).
    The solution is exact; its mean is 0 (the free constant).
    """
    t = gx.shape[0]
    h, w = gx.shape[1], gy.shape[2]
    # Normal equations D^T D s = D^T g, i.e. L s = div g with L = -D^T D (Neumann
    # Laplacian) and div g = backward difference of g, zero flux across the border.
    div = np.zeros((t, h, w), np.float64)
    div[:, :, :-1] += gx
    div[:, :, 1:] -= gx
    div[:, :-1, :] += gy
    div[:, 1:, :] -= gy
    # Even-symmetric extension: the periodic Laplacian of the (2H, 2W) extension
    # equals the Neumann Laplacian on the original grid; eigenvalues 2cos(pi k/H) - 2.
    ext = np.concatenate([div, div[:, ::-1, :]], axis=1)
    ext = np.concatenate([ext, ext[:, :, ::-1]], axis=2)
    spec = np.fft.rfft2(ext, axes=(1, 2))
    ky = 2.0 * np.cos(np.pi * np.arange(2 * h) / h) - 2.0
    kx = 2.0 * np.cos(np.pi * np.arange(spec.shape[2]) / w) - 2.0
    denom = ky[:, None] + kx[None, :]
    denom[0, 0] = 1.0
    spec = spec / denom
    spec[:, 0, 0] = 0.0
    s = np.fft.irfft2(spec, s=ext.shape[1:], axes=(1, 2))[:, :h, :w]
    return s


def color_retinex(frames, threshold_gray: float = 0.075, threshold_color: float = 1.0,
                  eps: float = 1e-3):
    """Colour Retinex (Grosse et al., ICCV 2009), frame by frame.

    Per frame, in the log domain (the rule of Grosse et al.'s reference
    ``color_retinex``):

    1. ``l_c = log max(i_c, eps)`` per channel; forward differences ``∇l_c``
       between horizontal and between vertical neighbours.
    2. Split each difference into a grey part ``g = mean_c ∇l_c`` and a
       chromatic part ``∇l_c - g``.  The edge is a **reflectance** change if
       ``|g| > threshold_gray`` **or** ``||∇l - g||_2 (over c) >
       threshold_color``.  Grosse et al.'s thresholds for colour Retinex are
       0.075 (grey) and 1.0 (chromaticity), the defaults here.
    3. The log-luminance ``log max(mean_c i_c, eps)`` has its differences
       set to 0 at reflectance edges; what remains is the shading gradient,
       integrated by least squares with Neumann boundary (an exact
       DCT-domain Poisson solve, :func:`_poisson_neumann`).
    4. ``shading = exp(log shading)`` (grey), ``albedo = image / shading``
       per channel, so ``albedo * shading[..., None] == image`` exactly.
    5. Scale: the product leaves a global scale free per frame.  As in the
       solver's convention, each frame's albedo is divided by its 99th
       percentile over all pixels and channels (so that percentile is 1) and
       its shading multiplied by the same factor.

    Parameters
    ----------
    frames : ``(T, H, W, 3)`` or ``(H, W, 3)`` float, linear RGB ``>= 0``.
    threshold_gray, threshold_color : thresholds on log-differences (see 2).
    eps : floor applied before taking logs (linear units).

    Returns
    -------
    albedo ``(T, H, W, 3)`` float32 (or ``(H, W, 3)``), shading ``(T, H, W)``
    float32 (or ``(H, W)``), both linear.
    """
    x = np.asarray(frames)
    if not np.issubdtype(x.dtype, np.floating):
        raise TypeError(
            f"color_retinex: expected float linear RGB, got dtype {x.dtype} "
            "(convert uint8/uint16 sRGB with ivkernels.io.to_linear_float)"
        )
    single = x.ndim == 3
    if single:
        x = x[None]
    if x.ndim != 4 or x.shape[-1] != 3:
        raise ValueError(f"color_retinex: expected (T, H, W, 3) or (H, W, 3) linear RGB, got shape {np.shape(frames)}")
    if min(x.shape[:3]) == 0:
        raise ValueError(f"color_retinex: empty input, shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("color_retinex: input contains NaN or infinite values")
    if x.min() < 0:
        raise ValueError(f"color_retinex: linear RGB must be >= 0, got minimum {x.min():.4g}")
    for name, v in (("threshold_gray", threshold_gray), ("threshold_color", threshold_color), ("eps", eps)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"color_retinex: {name} must be a positive number, got {v}")

    img = x.astype(np.float64)
    log_c = np.log(np.maximum(img, eps))                                   # (T,H,W,3)
    log_l = np.log(np.maximum(img.mean(axis=-1), eps))                     # (T,H,W)

    def reflectance_edges(d):                                               # d (..., 3)
        grey = d.mean(axis=-1)
        chroma = np.sqrt(np.sum((d - grey[..., None]) ** 2, axis=-1))
        return (np.abs(grey) > threshold_gray) | (chroma > threshold_color)

    edge_x = reflectance_edges(log_c[:, :, 1:] - log_c[:, :, :-1])         # (T,H,W-1)
    edge_y = reflectance_edges(log_c[:, 1:] - log_c[:, :-1])               # (T,H-1,W)
    sx = np.where(edge_x, 0.0, log_l[:, :, 1:] - log_l[:, :, :-1])
    sy = np.where(edge_y, 0.0, log_l[:, 1:] - log_l[:, :-1])
    shading = np.exp(_poisson_neumann(sx, sy))                              # (T,H,W), log-mean 0
    albedo = img / shading[..., None]
    scale = np.percentile(albedo.reshape(albedo.shape[0], -1), 99, axis=1)
    scale = np.where(scale > 0, scale, 1.0)
    albedo /= scale[:, None, None, None]
    shading *= scale[:, None, None]
    albedo = albedo.astype(np.float32)
    shading = shading.astype(np.float32)
    if single:
        return albedo[0], shading[0]
    return albedo, shading
