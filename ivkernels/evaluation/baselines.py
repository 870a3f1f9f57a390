"""Baselines the paper compares against, and the ones a video method must beat.

* :func:`color_retinex` is the colour Retinex of Grosse, Johnson, Adelson &
  Freeman, "Ground truth dataset and baseline evaluations for intrinsic image
  algorithms", ICCV 2009 (the paper's CRET), applied to each frame on its own.
  Its two thresholds default to values chosen on training data
  (:data:`TUNED_THRESHOLDS`, by ``perf/tune_baselines.py``); Grosse et al.'s
  own are :data:`GROSSE_THRESHOLDS` (``thresholds="grosse"``).
* :func:`luminance_retinex` is the same per-frame Retinex on the luminance
  alone: one threshold on the size of a log-luminance step, no colour test
  (the floor for greyscale footage, where colour Retinex has no cue left).
* :func:`weiss` is the temporal median of log-derivatives of Weiss, "Deriving
  intrinsic images from image sequences", ICCV 2001: for a static scene
  under changing light, the reflectance derivative at a pixel is the median
  over time of the image derivative there.
* :func:`weiss_flow` generalises it to moving scenes: every frame is aligned
  to every other along the (composed) optical flow before the median.

All take frames as :func:`ivkernels.decompose` does (uint8 / uint16 sRGB, or
float linear RGB in [0, 1]; :mod:`ivkernels.validation`) and return linear
RGB; shading is grey (white illuminant), as in :func:`ivkernels.decompose`.
"""
from __future__ import annotations

import numpy as np

from ivkernels.validation import check_frames, linear_frames

__all__ = ["color_retinex", "luminance_retinex", "weiss", "weiss_flow", "GROSSE_THRESHOLDS", "TUNED_THRESHOLDS",
           "LUMINANCE_TUNED_THRESHOLD"]

#: Grosse et al.'s thresholds for colour Retinex: (grey, chromaticity), log units.
GROSSE_THRESHOLDS = (0.075, 1.0)

#: Thresholds (grey, chromaticity) chosen by ``perf/tune_baselines.py`` on
#: training data only: synthetic seeds 1 and 2 of every kind (6 frames,
#: 160x120) and the ten MIT-Berkeley training objects (ten lights each, at
#: half size); the evaluation seed 0 was never run during the search.  The
#: criterion is the mean of two averages, the synthetic sequences' mean LMSE
#: (albedo and shading) and the MIT objects' albedo LMSE inside the mask: 0.0486
#: here (synthetic 0.0432, MIT 0.0540) against 0.0912 (0.0759, 0.1065) with
#: :data:`GROSSE_THRESHOLDS`.  A grey threshold of 2.0 (a factor e^2 = 7.4)
#: leaves almost every edge to the chromaticity test: on these data a change
#: of chromaticity is the reliable sign of a reflectance edge, and a grey
#: step more often a shadow or a fold.
TUNED_THRESHOLDS = (2.0, 0.1)

_THRESHOLD_PRESETS = {"grosse": GROSSE_THRESHOLDS, "tuned": TUNED_THRESHOLDS}

#: Threshold of :func:`luminance_retinex` on |log-luminance step| (log units),
#: chosen by ``perf/tune_baselines.py --skip-weiss`` on training data only:
#: seeds 1 and 2 of every kind of ``synthetic.SCENE_KINDS`` (6 frames,
#: 160x120) and the ten MIT-Berkeley training objects in colour and in grey
#: (half size); seed 0 was never run.  Criterion (mean of the synthetic mean
#: LMSE and the MIT albedo LMSE): 0.0767 at 0.5 (synthetic 0.0810, MIT 0.0724),
#: against 0.0798 at 0.3, 0.0829 at 1.0 and 0.0961 at 0.1.  A step of 0.5 is
#: a factor 1.65: smaller steps are mostly shading (smooth falloff, soft
#: penumbrae), larger ones mostly paint, print and material boundaries.
LUMINANCE_TUNED_THRESHOLD = 0.5


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


def _check_frames(frames, name: str, min_frames: int = 1):
    """Float64 ``(T, H, W, 3)`` linear RGB, and whether one ``(H, W, 3)`` image was given.

    The frames pass the rules of :mod:`ivkernels.validation`, the same as for
    :func:`ivkernels.decompose`: uint8 / uint16 are sRGB and decoded, float
    frames are linear RGB in ``[0, 1]``; a stack, one frame or a list of frames.
    """
    single = not isinstance(frames, (list, tuple)) and np.ndim(frames) == 3
    checked = check_frames(frames, name, min_frames=min_frames, what=name)
    return linear_frames(checked).astype(np.float64), single


def _check_positive(name: str, **values) -> None:
    for key, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name}: {key} must be a positive number, got {v!r}")


def color_retinex(frames, threshold_gray: float | None = None, threshold_color: float | None = None,
                  eps: float = 1e-3, *, thresholds: str = "tuned"):
    """Colour Retinex (Grosse et al., ICCV 2009), frame by frame.

    Per frame, in the log domain (the rule of Grosse et al.'s reference
    ``color_retinex``):

    1. ``l_c = log max(i_c, eps)`` per channel; forward differences ``∇l_c``
       between horizontal and between vertical neighbours.
    2. Split each difference into a grey part ``g = mean_c ∇l_c`` and a
       chromatic part ``∇l_c - g``.  The edge is a **reflectance** change if
       ``|g| > threshold_gray`` **or** ``||∇l - g||_2 (over c) >
       threshold_color``.
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
    frames : ``(T, H, W, 3)`` or ``(H, W, 3)``: float linear RGB in [0, 1], or uint8 / uint16 sRGB.
    threshold_gray, threshold_color : thresholds on log-differences (see 2);
        ``None`` takes the value of the preset ``thresholds``.
    eps : floor applied before taking logs (linear units).
    thresholds : ``"tuned"`` (default, :data:`TUNED_THRESHOLDS`, chosen on
        training data by ``perf/tune_baselines.py``) or ``"grosse"``
        (:data:`GROSSE_THRESHOLDS` = (0.075, 1.0), Grosse et al.'s values).

    Returns
    -------
    albedo ``(T, H, W, 3)`` float32 (or ``(H, W, 3)``), shading ``(T, H, W)``
    float32 (or ``(H, W)``), both linear.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.full((8, 12, 3), 0.5); image[:, 6:] *= 2.0      # a reflectance step
    >>> a, s = color_retinex(image, thresholds="grosse")
    >>> a.shape, s.shape, bool(np.ptp(s) < 1e-6)
    ((8, 12, 3), (8, 12), True)
    """
    if thresholds not in _THRESHOLD_PRESETS:
        raise ValueError(f"color_retinex: thresholds must be one of {sorted(_THRESHOLD_PRESETS)}, got {thresholds!r}")
    preset_gray, preset_color = _THRESHOLD_PRESETS[thresholds]
    threshold_gray = preset_gray if threshold_gray is None else threshold_gray
    threshold_color = preset_color if threshold_color is None else threshold_color
    img, single = _check_frames(frames, "color_retinex")
    _check_positive("color_retinex", threshold_gray=threshold_gray, threshold_color=threshold_color, eps=eps)

    log_c = np.log(np.maximum(img, eps))                                   # (T,H,W,3)
    log_l = np.log(np.maximum(img.mean(axis=-1), eps))                     # (T,H,W)

    def reflectance_edges(d):                                               # d (..., 3)
        grey = d.mean(axis=-1)
        chroma = np.sqrt(np.sum((d - grey[..., None]) ** 2, axis=-1))
        return (np.abs(grey) > threshold_gray) | (chroma > threshold_color)

    edge_x = reflectance_edges(log_c[:, :, 1:] - log_c[:, :, :-1])         # (T,H,W-1)
    edge_y = reflectance_edges(log_c[:, 1:] - log_c[:, :-1])               # (T,H-1,W)
    return _split_by_edges(img, log_l, edge_x, edge_y, single)


def _split_by_edges(img: np.ndarray, log_l: np.ndarray, edge_x: np.ndarray, edge_y: np.ndarray, single: bool):
    """Integrate the log-luminance differences that are not reflectance edges
    into a grey shading, divide it out, fix the scale (99th percentile of the
    albedo = 1 per frame); steps 3-5 of :func:`color_retinex`."""
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


def luminance_retinex(frames, threshold: float | None = None, eps: float = 1e-3):
    """Retinex on the luminance alone, frame by frame.

    Per frame: ``l = log max(mean_c i_c, eps)``; a forward difference of
    ``l`` between horizontal or vertical neighbours is a **reflectance**
    edge when ``|∇l| > threshold``, else shading; the shading differences
    are integrated by least squares (Neumann boundary, as in
    :func:`color_retinex`), ``albedo = image / shading`` per channel (so the
    input's chromaticity stays in the albedo) and each frame's albedo is
    scaled so its 99th percentile is 1.  The only cue is the size of the
    step, the cue that still holds on grey materials and greyscale footage.

    Parameters
    ----------
    frames : ``(T, H, W, 3)`` or ``(H, W, 3)``: float linear RGB in [0, 1], or uint8 / uint16 sRGB.
    threshold : log-luminance step above which an edge is reflectance;
        ``None``: :data:`LUMINANCE_TUNED_THRESHOLD` (chosen on training data).
    eps : floor applied before taking logs (linear units).

    Returns
    -------
    albedo ``(T, H, W, 3)`` float32 (or ``(H, W, 3)``), shading ``(T, H, W)``
    float32 (or ``(H, W)``), both linear; ``albedo * shading[..., None]``
    equals the input.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.full((8, 12, 3), 0.2); image[:, 6:] *= 3.0        # a grey reflectance step
    >>> a, s = luminance_retinex(image, threshold=0.5)
    >>> bool(np.ptp(s) < 1e-6), round(float(a[0, 11, 0] / a[0, 0, 0]), 3)
    (True, 3.0)
    """
    threshold = LUMINANCE_TUNED_THRESHOLD if threshold is None else threshold
    img, single = _check_frames(frames, "luminance_retinex")
    _check_positive("luminance_retinex", threshold=threshold, eps=eps)
    log_l = np.log(np.maximum(img.mean(axis=-1), eps))                     # (T,H,W)
    edge_x = np.abs(log_l[:, :, 1:] - log_l[:, :, :-1]) > threshold
    edge_y = np.abs(log_l[:, 1:] - log_l[:, :-1]) > threshold
    return _split_by_edges(img, log_l, edge_x, edge_y, single)


# ----------------------------------------------------------------------------
# Weiss (ICCV 2001): temporal median of log-derivatives
# ----------------------------------------------------------------------------

_WEISS_COLOURS = ("chromaticity", "channels")


def _median_log_reflectance(logs: np.ndarray, valid: np.ndarray | None, colour: str) -> np.ndarray:
    """Weiss's estimator on a stack of aligned log images.

    ``logs`` ``(S, H, W, 3)`` are log images in one pixel grid; ``valid``
    ``(S, H, W)`` bool marks the pixels each holds (``None``: all).  A
    derivative counts where both of its pixels are valid.  Returns the log
    reflectance ``(H, W, 3)``, defined up to an additive constant
    (``"chromaticity"``: its grey part has mean 0; ``"channels"``: each
    channel has mean 0).
    """
    def median(d, ok):                               # d (S, ...); ok broadcastable bool or None
        if ok is None:
            return np.median(d, axis=0)
        return np.nanmedian(np.where(ok, d, np.nan), axis=0)

    ok_x = ok_y = ok_p = None
    if valid is not None:
        ok_x = (valid[:, :, 1:] & valid[:, :, :-1])[..., None]
        ok_y = (valid[:, 1:] & valid[:, :-1])[..., None]
        ok_p = valid[..., None]
    if colour == "chromaticity":
        grey = logs.mean(axis=-1, keepdims=True)                           # (S,H,W,1)
        gx = median(grey[:, :, 1:] - grey[:, :, :-1], ok_x)[..., 0]       # (H,W-1)
        gy = median(grey[:, 1:] - grey[:, :-1], ok_y)[..., 0]             # (H-1,W)
        g = _poisson_neumann(gx[None], gy[None])[0]                        # (H,W)
        chroma = median(logs - grey, ok_p)                                 # (H,W,3), sums to 0 over c
        return g[..., None] + chroma
    gx = median(logs[:, :, 1:] - logs[:, :, :-1], ok_x)                    # (H,W-1,3)
    gy = median(logs[:, 1:] - logs[:, :-1], ok_y)                          # (H-1,W,3)
    return np.moveaxis(_poisson_neumann(np.moveaxis(gx, -1, 0), np.moveaxis(gy, -1, 0)), 0, -1)


def _grey_offsets(log_r: np.ndarray, log_i: np.ndarray, eps: float, valid: np.ndarray | None = None) -> np.ndarray:
    """Per-channel constants ``(3,)`` (mean 0) making the shading grey.

    Integrating each channel separately leaves each with its own free
    constant.  Under a white illuminant ``log i_c - log r_c`` is the same for
    every channel, so the constants are the per-channel medians of that
    difference over the (aligned) frames ``log_i`` ``(S, H, W, 3)``, at the
    pixels that are ``valid`` and not at the ``eps`` floor (all valid pixels
    if none is above it).
    """
    d = log_i - log_r[None]                                                # (S,H,W,3)
    ok = np.ones(d.shape[:3], bool) if valid is None else valid
    lit = ok & np.all(log_i > np.log(eps) + 1e-9, axis=-1)
    off = np.median(d[lit] if np.any(lit) else d[ok], axis=0)
    return off - off.mean()


def _finish(log_r: np.ndarray, img: np.ndarray, eps: float):
    """Albedo ``exp(log_r)`` ``(T,H,W,3)`` normalised over the whole sequence
    (99th percentile = 1) and grey shading ``mean_c i / mean_c albedo``."""
    albedo = np.exp(log_r)
    scale = float(np.percentile(albedo, 99))
    albedo /= scale if scale > 0 else 1.0
    shading = np.maximum(img.mean(axis=-1), eps) / np.maximum(albedo.mean(axis=-1), 1e-12)
    return albedo.astype(np.float32), shading.astype(np.float32)


def _check_colour(name: str, colour) -> None:
    if colour not in _WEISS_COLOURS:
        raise ValueError(f"{name}: colour must be one of {_WEISS_COLOURS}, got {colour!r}")


def weiss(frames, eps: float = 1e-3, colour: str = "chromaticity"):
    """Weiss's temporal median of log-derivatives, for a static scene.

    Weiss (ICCV 2001) writes each frame as ``I_t = R + S_t`` in the log
    domain and notes that shading derivatives (edges of shadows and of
    lighting) are sparse and move when the light moves, while the reflectance
    derivative stays put.  The maximum-likelihood reflectance derivative under
    a Laplacian prior on the shading derivatives is the temporal median:

    1. ``I_t = log max(i_t, eps)``; forward differences ``f_x = I_t(y, x+1) -
       I_t(y, x)`` and ``f_y = I_t(y+1, x) - I_t(y, x)`` per frame.
    2. ``r_x = median_t f_x``, ``r_y = median_t f_y`` per pixel.
    3. ``R`` = least-squares integral of ``(r_x, r_y)`` (Weiss's
       pseudo-inverse filter; here the exact Neumann Poisson solve
       :func:`_poisson_neumann`).
    4. Shading per frame: the image over the reflectance, grey:
       ``s_t = mean_c i_t / mean_c r`` (``log s_t = log i_t - log r`` in
       luminance).

    **Colour** (the model's shading is grey, a white illuminant):

    * ``"chromaticity"`` (default): steps 1-3 on the grey log image
      ``mean_c I_c``; the chromaticity ``I_c - mean_c I_c``, which a grey
      shading leaves unchanged, is the temporal median per pixel and is added
      back.  One integration, no free per-channel constants (which would tint
      the albedo), and an error in one pixel's chromaticity stays local
      instead of spreading through the integral.
    * ``"channels"``: steps 1-3 per channel, the three constants of
      integration set so that the shading is grey (:func:`_grey_offsets`).

    Both are exact on Lambertian scenes under a white light when every
    shading edge is absent from more than half of the frames, and on the
    training data they score the same (``perf/tune_baselines.py``: mean LMSE
    0.0695 on the synthetic seeds 1-2 for both, albedo LMSE 0.0373 and 0.0372
    on the MIT objects); the default is the one with a single integration.  The albedo is one image, the same for every frame (a static
    scene), normalised so its 99th percentile is 1; ``albedo * shading`` is
    the input up to the part of its chromaticity that changes over time
    (specular highlights, coloured inter-reflections).

    Parameters
    ----------
    frames : ``(T, H, W, 3)`` float linear RGB in [0, 1] (or uint8 / uint16 sRGB), ``T >= 2``, a
        static scene (camera and objects still; light free).
    eps : floor applied before taking logs (linear units).
    colour : ``"chromaticity"`` or ``"channels"`` (see above).

    Returns
    -------
    albedo : ``(T, H, W, 3)`` float32, linear (one image repeated).
    shading : ``(T, H, W)`` float32, linear, grey.

    References
    ----------
    Y. Weiss, "Deriving intrinsic images from image sequences", ICCV 2001.

    Examples
    --------
    >>> from ivkernels.evaluation import synthetic
    >>> seq = synthetic.render_sequence("static_moving_light", n_frames=4, size=(24, 32))
    >>> albedo, shading = weiss(seq.frames)
    >>> albedo.shape, shading.shape
    ((4, 24, 32, 3), (4, 24, 32))
    """
    img, _ = _check_frames(frames, "weiss", min_frames=2)
    _check_positive("weiss", eps=eps)
    _check_colour("weiss", colour)
    log_i = np.log(np.maximum(img, eps))                                   # (T,H,W,3)
    log_r = _median_log_reflectance(log_i, None, colour)                   # (H,W,3)
    if colour == "channels":
        log_r = log_r + _grey_offsets(log_r, log_i, eps)
    return _finish(np.broadcast_to(log_r, img.shape), img, eps)


# ----------------------------------------------------------------------------
# Flow-aligned Weiss
# ----------------------------------------------------------------------------

def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``img`` ``(H, W[, C])`` sampled at ``(x, y)`` ``(H', W')``, bilinear,
    coordinates clamped to the image (exact at integer coordinates)."""
    h, w = img.shape[:2]
    x = np.clip(x, 0.0, w - 1.0)
    y = np.clip(y, 0.0, h - 1.0)
    x0 = np.floor(x).astype(np.intp)
    y0 = np.floor(y).astype(np.intp)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx = x - x0
    fy = y - y0
    if img.ndim == 3:
        fx = fx[..., None]
        fy = fy[..., None]
    top = img[y0, x0] * (1.0 - fx) + img[y0, x1] * fx
    bottom = img[y1, x0] * (1.0 - fx) + img[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy


def _inside(x: np.ndarray, y: np.ndarray, h: int, w: int) -> np.ndarray:
    return (x >= 0) & (x <= w - 1) & (y >= 0) & (y <= h - 1)


def _invert_flow(u: np.ndarray, vis: np.ndarray, iterations: int = 20, tol: float = 0.5):
    """Backward flow ``v`` (frame t+1 -> t) and its visibility from forward ``u``.

    Fixed point of ``v(y) = -u(y + v(y))`` from ``v = -u`` (bilinear).  A
    pixel ``y`` of frame t+1 is visible in frame t when ``p = y + v(y)`` lies
    inside, the round trip ``|p + u(p) - y| < tol`` px holds (it fails where
    ``y`` was hidden in frame t: no point of frame t lands on it) and ``p``
    is forward-visible (``vis(p) >= 0.5``).
    """
    h, w = u.shape[:2]
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    v = -u.copy()
    for _ in range(iterations):
        v = -_bilinear(u, gx + v[..., 0], gy + v[..., 1])
    px, py = gx + v[..., 0], gy + v[..., 1]
    back = _bilinear(u, px, py)
    err = np.hypot(px + back[..., 0] - gx, py + back[..., 1] - gy)
    ok = _inside(px, py, h, w) & (err < tol) & (_bilinear(vis, px, py) >= 0.5)
    return v, ok


def _check_flow(name: str, flow, visibility, t: int, h: int, w: int):
    flow = np.asarray(flow)
    if not (np.issubdtype(flow.dtype, np.floating) or np.issubdtype(flow.dtype, np.integer)) \
            or flow.dtype == np.bool_:
        raise TypeError(f"{name}: flow must be a real numeric array, got dtype {flow.dtype}")
    if flow.shape != (t - 1, h, w, 2):
        raise ValueError(f"{name}: flow must have shape (T-1, H, W, 2) = {(t - 1, h, w, 2)}, got {flow.shape}")
    if not np.all(np.isfinite(flow)):
        raise ValueError(f"{name}: flow contains NaN or infinite values")
    if visibility is None:
        vis = np.ones((t - 1, h, w))
    else:
        vis = np.asarray(visibility)
        if vis.shape != (t - 1, h, w):
            raise ValueError(f"{name}: visibility must have shape (T-1, H, W) = {(t - 1, h, w)}, got {vis.shape}")
        if not (vis.dtype == np.bool_ or np.issubdtype(vis.dtype, np.number)):
            raise TypeError(f"{name}: visibility must be boolean or numeric, got dtype {vis.dtype}")
        vis = vis.astype(np.float64)
        if not np.all(np.isfinite(vis)):
            raise ValueError(f"{name}: visibility contains NaN or infinite values")
    return flow.astype(np.float64), vis


def weiss_flow(frames, flow, visibility=None, eps: float = 1e-3, colour: str = "chromaticity",
               radius: int | None = None):
    """Weiss's temporal median along the optical flow, for moving scenes.

    A reflectance derivative is the same on the same surface point in every
    frame; with motion that point sits at different pixels.  For **each
    frame** ``t`` the other frames ``s`` (``|s - t| <= radius``) are aligned
    to frame ``t``'s pixel grid and Weiss's median (:func:`weiss`, same
    ``colour`` handling) is taken over the frames in which the pixel is
    visible:

    1. Positions: pixel ``x`` of frame ``t`` is followed to frame ``s`` along
       the composed flow, ``x_{k+1} = x_k + u_k(x_k)`` (bilinear) forward and
       the same with the backward flow (the fixed-point inverse of ``u``,
       :func:`_invert_flow`) backward.  It is visible in ``s`` when it is
       visible at every step (``visibility >= 0.5`` at the sampled point,
       inside the image, and for backward steps the forward-backward check).
    2. The log image of frame ``s`` is sampled there (bilinear), and its
       derivatives are taken **in frame t's grid** (a derivative counts where
       both of its pixels are visible).  Differentiating the aligned image,
       rather than aligning the derivatives, keeps them right under rotation
       and zoom, where warped derivatives would have to be turned and scaled
       by the flow's Jacobian.
    3. Median over the visible frames (frame ``t`` itself always counts),
       integrate (:func:`_poisson_neumann`): the log albedo of frame ``t``.
    4. The free constant of each frame's integral is fixed along the flow:
       frame ``t+1``'s log albedo is shifted by the median over visible
       pixels of ``log A_t(x) - log A_{t+1}(x + u_t(x))`` (grey part), so the
       albedo does not change brightness from frame to frame; then the whole
       sequence is normalised (99th percentile = 1) and the shading is
       ``mean_c i_t / mean_c a_t``.

    Why a median per frame over its aligned neighbours rather than one median
    in a reference frame carried back along the flow: every frame keeps the
    pixels it sees (parts that enter the view or are disoccluded are not in
    the reference frame), and no backward carrying of the result is needed.
    The price is ``T * (2 radius + 1)`` alignments instead of ``T``.  With
    zero flow every frame's stack is the whole sequence and the result equals
    :func:`weiss`.

    Parameters
    ----------
    frames : ``(T, H, W, 3)`` float linear RGB in [0, 1] (or uint8 / uint16 sRGB), ``T >= 2``.
    flow : ``(T-1, H, W, 2)`` forward flow t -> t+1 in pixels, ``(dx, dy)``
        (ground truth or estimated, e.g. :func:`ivkernels.estimate_flow`).
    visibility : optional ``(T-1, H, W)``, 1 (or ``>= 0.5``) where pixel
        ``x`` of frame t is visible at ``x + u`` in frame t+1; ``None``: all
        pixels whose flow lands inside the image.
    eps : floor applied before taking logs (linear units).
    colour : ``"chromaticity"`` or ``"channels"``, as in :func:`weiss`.
    radius : frames on each side taken into each frame's median; ``None``
        (default): all frames.

    Returns
    -------
    albedo : ``(T, H, W, 3)`` float32, linear, one image per frame.
    shading : ``(T, H, W)`` float32, linear, grey.

    References
    ----------
    Y. Weiss, "Deriving intrinsic images from image sequences", ICCV 2001.
    N. Kong, P. V. Gehler, M. J. Black, "Intrinsic Video", ECCV 2014
    (albedo constant along the flow, Eq. 4).

    Examples
    --------
    >>> import numpy as np
    >>> from ivkernels.evaluation import synthetic
    >>> seq = synthetic.render_sequence("objects_camera", n_frames=3, size=(24, 32))
    >>> albedo, shading = weiss_flow(seq.frames, seq.flow, seq.visibility)
    >>> albedo.shape, shading.shape
    ((3, 24, 32, 3), (3, 24, 32))
    """
    img, _ = _check_frames(frames, "weiss_flow", min_frames=2)
    t_n, h, w, _ = img.shape
    u, vis = _check_flow("weiss_flow", flow, visibility, t_n, h, w)
    _check_positive("weiss_flow", eps=eps)
    _check_colour("weiss_flow", colour)
    if radius is None:
        radius = t_n - 1
    if isinstance(radius, bool) or not isinstance(radius, (int, np.integer)) or radius < 0:
        raise ValueError(f"weiss_flow: radius must be a non-negative int or None, got {radius!r}")

    log_i = np.log(np.maximum(img, eps))                                   # (T,H,W,3)
    backward = [_invert_flow(u[k], vis[k]) for k in range(t_n - 1)]       # v_k: frame k+1 -> k
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))

    log_r = np.empty_like(log_i)
    for t in range(t_n):
        lo, hi = max(0, t - radius), min(t_n - 1, t + radius)
        logs = np.empty((hi - lo + 1, h, w, 3))
        valid = np.zeros((hi - lo + 1, h, w), bool)
        logs[t - lo] = log_i[t]
        valid[t - lo] = True
        for step, stop in ((1, hi + 1), (-1, lo - 1)):
            x, y = gx.copy(), gy.copy()
            ok = np.ones((h, w), bool)
            for s in range(t + step, stop, step):
                if step > 0:                                               # frame s-1 -> s, forward
                    ok &= _inside(x, y, h, w) & (_bilinear(vis[s - 1], x, y) >= 0.5)
                    d = _bilinear(u[s - 1], x, y)
                else:                                                      # frame s+1 -> s, backward
                    v, vis_b = backward[s]
                    ok &= _inside(x, y, h, w) & (_bilinear(vis_b.astype(np.float64), x, y) >= 0.5)
                    d = _bilinear(v, x, y)
                x = x + d[..., 0]
                y = y + d[..., 1]
                ok &= _inside(x, y, h, w)
                logs[s - lo] = _bilinear(log_i[s], x, y)
                valid[s - lo] = ok
        log_r[t] = _median_log_reflectance(logs, valid, colour)
        if colour == "channels":
            log_r[t] += _grey_offsets(log_r[t], logs, eps, valid)

    # one constant per frame, chained along the flow
    for t in range(t_n - 1):
        grey_t = log_r[t].mean(axis=-1)
        x, y = gx + u[t, ..., 0], gy + u[t, ..., 1]
        sel = _inside(x, y, h, w) & (vis[t] >= 0.5)
        if np.any(sel):
            nxt = _bilinear(log_r[t + 1].mean(axis=-1), x, y)
            log_r[t + 1] += float(np.median(grey_t[sel] - nxt[sel]))
    return _finish(log_r, img, eps)
