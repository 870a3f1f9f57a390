"""Error measures: LMSE for intrinsic images, EPE/AAE for flow, temporal coherence.

* :func:`lmse` — local mean squared error of Grosse et al. (ICCV 2009),
  scale-invariant per window; the standard intrinsic-image measure (used in
  the paper's Fig. 6, left).
* :func:`endpoint_error`, :func:`angular_error` — the Middlebury flow
  errors (Baker et al., IJCV 2011).
* :func:`temporal_incoherence` — the paper's measure (Sec. 5.1, Fig. 6
  right): estimate flow on the recovered albedo sequence with a fixed flow
  method and report its EPE against ground truth.
* :func:`albedo_consistency` — a direct check: log-albedo change along the
  ground-truth flow, each frame's scale left free.
* :func:`albedo_flicker` — the same change with one scale per sequence, so
  that a frame that brightens or darkens as a whole counts; ``flow=None``
  for static scenes, and an optional mask (e.g. an object).
* :func:`dark_ratio` and :func:`albedo_drift` — checks on footage without
  ground truth: whether the darkest input pixels keep a dark albedo (a
  split that puts dark materials in the shading gives a ratio near 1), and
  how fast the albedo's level creeps over the frames.
* :func:`tracked_albedo_change` — with ground-truth flow: how much the
  albedo of the same surface points changed from the first frame to the
  last, the points followed along the chained flow.

All inputs are NumPy arrays; computations run in float64.
"""
from __future__ import annotations

import cv2
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ivkernels.colour import REC709_LUMINANCE, linear_to_srgb
from ivkernels.flowio import valid_flow_mask

__all__ = [
    "lmse",
    "intrinsic_lmse",
    "endpoint_error",
    "angular_error",
    "flow_errors",
    "temporal_incoherence",
    "albedo_consistency",
    "albedo_flicker",
    "luminance",
    "dark_ratio",
    "albedo_drift",
    "tracked_albedo_change",
]

_REC709 = np.array(REC709_LUMINANCE)


# ----------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------

def _float_array(x, name: str) -> np.ndarray:
    x = np.asarray(x)
    if not (np.issubdtype(x.dtype, np.floating) or np.issubdtype(x.dtype, np.integer)) or x.dtype == np.bool_:
        raise TypeError(f"{name}: expected a real numeric array, got dtype {x.dtype}")
    if x.size == 0:
        raise ValueError(f"{name}: empty array, shape {x.shape}")
    x = x.astype(np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return x


def _as_bool_mask(mask, shape: tuple, name: str = "mask") -> np.ndarray:
    """Mask -> bool array broadcast to ``shape``; nonzero / >= 0.5 is True."""
    m = np.asarray(mask)
    if m.dtype != np.bool_:
        if not (np.issubdtype(m.dtype, np.floating) or np.issubdtype(m.dtype, np.integer)):
            raise TypeError(f"{name}: expected a boolean or numeric array, got dtype {m.dtype}")
        if not np.all(np.isfinite(m)):
            raise ValueError(f"{name}: contains NaN or infinite values")
        m = m >= 0.5
    if m.ndim < 2 or m.shape != shape[len(shape) - m.ndim:]:
        raise ValueError(f"{name}: shape {m.shape} does not match {shape} (expected {shape} or {shape[-2:]})")
    return np.broadcast_to(m, shape)


def _as_image_stack(x, name: str) -> np.ndarray:
    """(H,W) | (H,W,3) | (T,H,W) | (T,H,W,C) -> float64 (T,H,W,C).

    A 3-D array whose last axis has length 3 is read as one colour image.
    """
    x = _float_array(x, name)
    if x.ndim == 2:
        return x[None, :, :, None]
    if x.ndim == 3:
        return x[None] if x.shape[-1] == 3 else x[..., None]
    if x.ndim == 4:
        return x
    raise ValueError(f"{name}: expected (H, W), (H, W, 3), (T, H, W) or (T, H, W, 3), got shape {x.shape}")


# ----------------------------------------------------------------------------
# LMSE (Grosse et al. 2009)
# ----------------------------------------------------------------------------

def _lmse_frame(est: np.ndarray, truth: np.ndarray, mask: np.ndarray, wy: int, wx: int, step: int):
    """Per-channel (ssq, total) of one frame.  est/truth (H,W,C), mask (H,W) float."""
    m_w = sliding_window_view(mask, (wy, wx))[::step, ::step]            # (ny, nx, wy, wx)
    out = []
    for c in range(est.shape[-1]):
        e_w = sliding_window_view(est[..., c] * mask, (wy, wx))[::step, ::step]
        t_w = sliding_window_view(truth[..., c] * mask, (wy, wx))[::step, ::step]
        ee = np.sum(e_w * e_w, axis=(-2, -1))
        te = np.sum(t_w * e_w, axis=(-2, -1))
        alpha = np.divide(te, ee, out=np.zeros_like(te), where=ee > 0)
        resid = (t_w - alpha[..., None, None] * e_w) * m_w
        out.append((float(np.sum(resid * resid)), float(np.sum(t_w * t_w))))
    return out


def lmse(estimate, truth, window: int = 20, step: int = 10, mask=None) -> float:
    """Local mean squared error (Grosse et al., ICCV 2009), scale-invariant per window.

    For every ``window x window`` patch whose top-left corner lies on the
    grid ``(0, step, 2 step, ...)`` and that fits inside the image, the
    scale ``alpha = <t, e> / <e, e>`` minimising ``||t - alpha e||^2`` over
    the masked pixels of the patch is fitted (``alpha = 0`` where the
    estimate is zero), and::

        LMSE = sum_windows ||t - alpha_w e||^2  /  sum_windows ||t||^2

    (same windows, masked pixels only).  A perfect estimate, or one off by a
    scale per window, scores 0; an estimate of 0 scores 1.  Images smaller
    than the window use one window as large as the image along that axis.

    Parameters
    ----------
    estimate, truth : same shape: ``(H, W)``, ``(H, W, 3)``, ``(T, H, W)``
        or ``(T, H, W, 3)``, linear values.  A 3-D array with last axis 3 is
        one colour image.  **Colour**: the LMSE is computed for each channel
        separately and the channels are averaged (channels whose truth is 0
        in every window are left out of the average).  **Stacks**: the mean
        of the per-frame values.
    window, step : window size and stride in pixels (Grosse: 20 and 10).
    mask : optional bool ``(H, W)`` or ``(T, H, W)``; pixels outside the
        mask count neither in the fit nor in the sums.

    Returns
    -------
    float, >= 0.
    """
    e = _as_image_stack(estimate, "lmse: estimate")
    t = _as_image_stack(truth, "lmse: truth")
    if e.shape != t.shape:
        raise ValueError(f"lmse: estimate shape {np.shape(estimate)} != truth shape {np.shape(truth)}")
    for name, v in (("window", window), ("step", step)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
            raise ValueError(f"lmse: {name} must be a positive int, got {v!r}")
    n, h, w, _ = t.shape
    m = np.ones((n, h, w)) if mask is None else _as_bool_mask(mask, (n, h, w)).astype(np.float64)
    wy, wx = min(window, h), min(window, w)
    scores = []
    for f in range(n):
        per_channel = _lmse_frame(e[f], t[f], m[f], wy, wx, step)
        ratios = [ssq / tot for ssq, tot in per_channel if tot > 0]
        if not ratios:
            raise ValueError(f"lmse: ground truth of frame {f} is zero inside every window (mask); LMSE undefined")
        scores.append(float(np.mean(ratios)))
    return float(np.mean(scores))


def intrinsic_lmse(albedo_est, shading_est, albedo_gt, shading_gt, mask=None,
                   window: int = 20, step: int = 10) -> dict:
    """LMSE of albedo and of shading, and their mean (Grosse et al.'s score).

    Shapes as in :func:`lmse` (e.g. albedo ``(T, H, W, 3)``, shading
    ``(T, H, W)``).  Returns ``{"albedo": float, "shading": float,
    "mean": (albedo + shading) / 2}``.
    """
    a = lmse(albedo_est, albedo_gt, window=window, step=step, mask=mask)
    s = lmse(shading_est, shading_gt, window=window, step=step, mask=mask)
    return {"albedo": a, "shading": s, "mean": 0.5 * (a + s)}


# ----------------------------------------------------------------------------
# Flow errors (Baker et al., IJCV 2011)
# ----------------------------------------------------------------------------

def _flow_pair(flow, flow_gt, mask):
    """Validated float64 flows and the bool mask of pixels to evaluate."""
    flow = np.asarray(flow)
    flow_gt = np.asarray(flow_gt)
    for name, f in (("flow", flow), ("flow_gt", flow_gt)):
        if f.ndim < 3 or f.shape[-1] != 2:
            raise ValueError(f"{name}: expected shape (..., H, W, 2), got {f.shape}")
        if not (np.issubdtype(f.dtype, np.floating) or np.issubdtype(f.dtype, np.integer)) or f.dtype == np.bool_:
            raise TypeError(f"{name}: expected a real numeric array, got dtype {f.dtype}")
    if flow.shape != flow_gt.shape:
        raise ValueError(f"flow shape {flow.shape} != flow_gt shape {flow_gt.shape}")
    sel = valid_flow_mask(flow_gt)
    if mask is not None:
        sel = sel & _as_bool_mask(mask, sel.shape)
    if not np.any(sel):
        raise ValueError("no pixel to evaluate: the mask is empty or the ground truth is unknown everywhere")
    if not np.all(np.isfinite(flow[sel])):
        raise ValueError("flow: contains NaN or infinite values at evaluated pixels")
    return flow.astype(np.float64), flow_gt.astype(np.float64), sel


def endpoint_error(flow, flow_gt, mask=None) -> float:
    """Mean end-point error ``|u - u_gt|`` (pixels).

    ``flow``, ``flow_gt``: ``(..., H, W, 2)``; ``mask``: optional bool
    ``(..., H, W)`` (or ``(H, W)``, shared).  Pixels with unknown ground
    truth (components > 1e9 or non-finite) are ignored.
    """
    f, g, sel = _flow_pair(flow, flow_gt, mask)
    d = f[sel] - g[sel]
    return float(np.mean(np.sqrt(np.sum(d * d, axis=-1))))


def angular_error(flow, flow_gt, mask=None) -> float:
    """Mean angular error in degrees (Barron et al. 1994; Middlebury).

    The angle between the space-time vectors ``(u, v, 1)`` and
    ``(u_gt, v_gt, 1)``::

        arccos( (u u_gt + v v_gt + 1) / sqrt((u^2 + v^2 + 1)(u_gt^2 + v_gt^2 + 1)) )

    Same shapes, mask and unknown-flow handling as :func:`endpoint_error`.
    """
    f, g, sel = _flow_pair(flow, flow_gt, mask)
    u, v = f[sel][:, 0], f[sel][:, 1]
    ug, vg = g[sel][:, 0], g[sel][:, 1]
    num = u * ug + v * vg + 1.0
    den = np.sqrt((u * u + v * v + 1.0) * (ug * ug + vg * vg + 1.0))
    ang = np.arccos(np.clip(num / den, -1.0, 1.0))
    return float(np.degrees(np.mean(ang)))


def flow_errors(flow, flow_gt, mask=None) -> dict:
    """``{"epe": endpoint_error(...), "aae": angular_error(...)}``."""
    return {"epe": endpoint_error(flow, flow_gt, mask), "aae": angular_error(flow, flow_gt, mask)}


# ----------------------------------------------------------------------------
# Temporal coherence of an albedo sequence
# ----------------------------------------------------------------------------

def _check_albedo_stack(albedo, name: str = "albedo") -> np.ndarray:
    a = _float_array(albedo, name)
    if a.ndim != 4 or a.shape[-1] != 3:
        raise ValueError(f"{name}: expected (T, H, W, 3) linear RGB, got shape {a.shape}")
    if a.shape[0] < 2:
        raise ValueError(f"{name}: need at least 2 frames, got {a.shape[0]}")
    if a.min() < 0:
        raise ValueError(f"{name}: linear albedo must be >= 0, got minimum {a.min():.4g}")
    return a


def _albedo_to_uint8_luminance(albedo: np.ndarray) -> np.ndarray:
    """(T,H,W,3) linear -> (T,H,W) uint8 sRGB luminance, normalised per sequence.

    Luminance uses Rec. 709 weights; the whole sequence is divided by its
    99th-percentile luminance (so the global scale of an albedo estimate does
    not matter, but frame-to-frame scale changes do), clipped to [0, 1],
    sRGB-encoded and rounded to 8 bits.
    """
    lum = albedo @ _REC709
    p = float(np.percentile(lum, 99))
    if p > 0:
        lum = lum / p
    return np.round(linear_to_srgb(np.clip(lum, 0.0, 1.0)) * 255.0).astype(np.uint8)


def _dis_flow(frames) -> np.ndarray:
    """Forward flow ``(T-1, H, W, 2)`` float32 between consecutive frames.

    OpenCV DIS optical flow (Kroeger et al., ECCV 2016), preset MEDIUM, on
    the 8-bit sRGB luminance of ``frames`` ``(T, H, W, 3)`` (linear RGB)
    normalised per sequence (see :func:`_albedo_to_uint8_luminance`).
    """
    a = _check_albedo_stack(frames, "frames")
    grey = np.ascontiguousarray(_albedo_to_uint8_luminance(a))   # DIS needs contiguous images
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    t, h, w = grey.shape
    out = np.empty((t - 1, h, w, 2), np.float32)
    for t in range(grey.shape[0] - 1):
        out[t] = dis.calc(grey[t], grey[t + 1], None)
    return out


def _check_flow_visibility(flow_gt, visibility, t: int, h: int, w: int):
    flow_gt = np.asarray(flow_gt)
    if flow_gt.shape != (t - 1, h, w, 2):
        raise ValueError(f"flow_gt: expected shape {(t - 1, h, w, 2)} for {t} frames of {h}x{w}, got {flow_gt.shape}")
    if not (np.issubdtype(flow_gt.dtype, np.floating) or np.issubdtype(flow_gt.dtype, np.integer)):
        raise TypeError(f"flow_gt: expected a real numeric array, got dtype {flow_gt.dtype}")
    vis = None
    if visibility is not None:
        visibility = np.asarray(visibility)
        if visibility.shape != (t - 1, h, w):
            raise ValueError(f"visibility: expected shape {(t - 1, h, w)}, got {visibility.shape}")
        vis = _as_bool_mask(visibility, (t - 1, h, w), "visibility")
    return flow_gt, vis


def temporal_incoherence(albedo, flow_gt, visibility=None, flow_method=None) -> dict:
    """The paper's temporal incoherence measure (Sec. 5.1, Fig. 6 right).

    Flow is estimated between consecutive frames of the albedo sequence with
    a fixed method and compared with the ground-truth flow: an albedo that
    is constant over time obeys brightness constancy and gives a lower EPE.

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB, ``T >= 2``.
    flow_gt : ``(T-1, H, W, 2)`` forward ground-truth flow (unknown values
        > 1e9 are ignored).
    visibility : optional ``(T-1, H, W)``, 1 (or >= 0.5) where pixel ``x`` of
        frame ``t`` is visible in frame ``t+1``.
    flow_method : callable ``(T, H, W, 3) float -> (T-1, H, W, 2)``; default
        :func:`_dis_flow` (OpenCV DIS, preset MEDIUM, on the sequence-
        normalised 8-bit sRGB luminance).  The paper used Classic+NL on
        brightness.

    Returns
    -------
    ``{"epe": mean EPE over all known pixels of all frame pairs,
    "epe_visible": the same over visible pixels only (NaN when
    ``visibility`` is None)}``.
    """
    a = _check_albedo_stack(albedo)
    t, h, w, _ = a.shape
    flow_gt, vis = _check_flow_visibility(flow_gt, visibility, t, h, w)
    method = _dis_flow if flow_method is None else flow_method
    if not callable(method):
        raise TypeError(f"flow_method must be callable (T,H,W,3) -> (T-1,H,W,2), got {type(method).__name__}")
    flow = np.asarray(method(a.astype(np.float32)))
    if flow.shape != (t - 1, h, w, 2):
        raise ValueError(f"flow_method returned shape {flow.shape}, expected {(t - 1, h, w, 2)}")
    epe = endpoint_error(flow, flow_gt)
    epe_vis = float("nan") if vis is None else endpoint_error(flow, flow_gt, mask=vis)
    return {"epe": epe, "epe_visible": epe_vis}


def _warped_abs_difference(log_a: np.ndarray, flow: np.ndarray, vis, sel_mask=None):
    """``(sum, count)`` of ``|L_{t+1}(x + u_t(x)) - L_t(x)|`` over channels and the pixels
    with known flow that land inside frame ``t+1`` and are visible (``vis``)
    and selected (``sel_mask``, frames ``t``); bilinear ``cv2.remap``."""
    t, h, w, _ = log_a.shape
    known = valid_flow_mask(flow)
    fl = np.where(known[..., None], flow, 0.0).astype(np.float64)
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    total, count = 0.0, 0
    for k in range(t - 1):
        mx = gx + fl[k, ..., 0]
        my = gy + fl[k, ..., 1]
        sel = known[k] & (mx >= 0) & (mx <= w - 1) & (my >= 0) & (my <= h - 1)
        if vis is not None:
            sel &= vis[k]
        if sel_mask is not None:
            sel &= sel_mask[k]
        if not np.any(sel):
            continue
        warped = cv2.remap(log_a[k + 1], mx.astype(np.float32), my.astype(np.float32),
                           interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        diff = np.abs(warped[sel].astype(np.float64) - log_a[k][sel].astype(np.float64))
        total += float(diff.sum())
        count += diff.size
    return total, count


def albedo_consistency(albedo, flow_gt, visibility=None, eps: float = 1e-3) -> float:
    """Mean absolute change of log albedo along the ground-truth flow.

    ``mean |L_{t+1}(x + u_t(x)) - L_t(x)|`` over RGB channels and over the
    pixels ``x`` that are visible (``visibility >= 0.5``; all if None), have
    known flow, and land inside frame ``t+1``.  ``L_t = log(max(A_t, eps))
    - median(log(max(A_t, eps)))``: each frame's log albedo has its median
    (over pixels and channels) removed, so a per-frame global scale does not
    count.  ``L_{t+1}(x + u)`` is bilinear (``cv2.remap``).

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB, ``T >= 2``.
    flow_gt : ``(T-1, H, W, 2)``; visibility : ``(T-1, H, W)`` or None.

    Returns
    -------
    float (log units; 0 for an albedo that is exactly constant along the
    flow up to a per-frame scale).
    """
    a = _check_albedo_stack(albedo)
    t, h, w, _ = a.shape
    flow_gt, vis = _check_flow_visibility(flow_gt, visibility, t, h, w)
    if not (np.isfinite(eps) and eps > 0):
        raise ValueError(f"eps must be a positive number, got {eps}")
    log_a = np.log(np.maximum(a, eps))
    log_a -= np.median(log_a.reshape(t, -1), axis=1)[:, None, None, None]
    log_a = log_a.astype(np.float32)
    total, count = _warped_abs_difference(log_a, flow_gt, vis)
    if count == 0:
        raise ValueError("albedo_consistency: no visible pixel with known flow lands inside the next frame")
    return total / count


def albedo_flicker(albedo, flow=None, visibility=None, mask=None, eps: float = 1e-3) -> float:
    """Albedo flicker: mean change of log albedo from frame to frame along the flow.

    ::

        flicker = mean_{t, x, c} | L_{t+1, c}(x + u_t(x)) - L_{t, c}(x) |,
        L = log max(A / p99(A), eps)

    over the frame pairs ``t, t+1``, the RGB channels, and the pixels ``x``
    of frame ``t`` that are visible in frame ``t+1`` (``visibility >= 0.5``),
    have known flow, land inside frame ``t+1``, and lie in ``mask``.
    ``L_{t+1}(x + u)`` is bilinear (``cv2.remap``); with ``flow=None``
    (a static scene) ``u = 0`` and no interpolation is involved.

    Scale: the whole sequence is divided by one number, its 99th percentile
    over pixels, channels and frames.  A global scale cancels in the
    differences anyway; dividing by it makes the ``eps`` floor mean the same
    for estimates of any scale.  Unlike :func:`albedo_consistency`, a frame
    whose albedo changes by a factor as a whole (e.g. a per-frame
    normalisation) counts as flicker: the viewer sees it.

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB, ``T >= 2``.
    flow : ``(T-1, H, W, 2)`` forward flow (ground truth; unknown values
        > 1e9 are ignored), or ``None`` for a static scene.
    visibility : ``(T-1, H, W)`` or ``None`` (all visible).
    mask : bool ``(H, W)`` or ``(T, H, W)`` (pixels of frame ``t`` to
        count), or ``None`` (all).
    eps : floor on the normalised albedo before the log.

    Returns
    -------
    float, log units: 0 for an albedo constant along the flow;
    ``log(1.1) = 0.095`` if every other frame is 10% brighter.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.ones((3, 4, 5, 3)); a[1] *= 1.1          # the middle frame 10% brighter
    >>> round(albedo_flicker(a), 4)                        # |log 1.1| on both pairs
    0.0953
    """
    a = _check_albedo_stack(albedo)
    t, h, w, _ = a.shape
    if not (np.isfinite(eps) and eps > 0):
        raise ValueError(f"eps must be a positive number, got {eps}")
    sel_mask = None if mask is None else _as_bool_mask(mask, (t, h, w))
    p = float(np.percentile(a, 99))
    if p <= 0:
        raise ValueError("albedo_flicker: albedo is zero almost everywhere (99th percentile is 0)")
    log_a = np.log(np.maximum(a / p, eps))
    if flow is None:
        if visibility is not None:
            raise ValueError("albedo_flicker: visibility needs a flow (flow=None means a static scene)")
        sel = np.ones((t - 1, h, w), bool) if sel_mask is None else sel_mask[:-1]
        if not np.any(sel):
            raise ValueError("albedo_flicker: the mask is empty")
        return float(np.mean(np.abs(log_a[1:] - log_a[:-1])[sel]))
    flow, vis = _check_flow_visibility(flow, visibility, t, h, w)
    total, count = _warped_abs_difference(log_a.astype(np.float32), flow, vis, sel_mask)
    if count == 0:
        raise ValueError("albedo_flicker: no visible pixel with known flow lands inside the next frame")
    return total / count


# ----------------------------------------------------------------------------
# footage without ground truth: dark materials and drift
# ----------------------------------------------------------------------------

def luminance(x) -> np.ndarray:
    """Rec. 709 luminance ``0.2126 R + 0.7152 G + 0.0722 B`` of linear RGB
    ``(..., 3)``, float64 ``(...)``."""
    x = _float_array(x, "luminance")
    if x.ndim < 1 or x.shape[-1] != 3:
        raise ValueError(f"luminance: expected linear RGB with a last axis of 3, got shape {x.shape}")
    return x @ _REC709


def _luminance_stack(x, name: str) -> np.ndarray:
    """``(T, H, W, 3)`` linear RGB or ``(T, H, W)`` grey -> float64 ``(T, H, W)``."""
    x = _float_array(x, name)
    if x.ndim == 4 and x.shape[-1] == 3:
        return x @ _REC709
    if x.ndim == 3:
        return x
    raise ValueError(f"{name}: expected (T, H, W, 3) linear RGB or (T, H, W) grey, got shape {x.shape}")


def dark_ratio(albedo, frames, fraction: float = 0.1, mask=None) -> float:
    """Whether dark materials stay dark in the albedo.

    ::

        dark_ratio = median{ lum(A)(x) : lum(I)(x) <= q_fraction(lum(I)) } / median{ lum(A)(x) }

    over every pixel of every frame (inside ``mask``), ``q_fraction`` the
    ``fraction`` quantile of the input luminance.  The darkest input pixels
    are dark materials, shadows or both; a split that keeps the materials in
    the albedo gives a small ratio (a dark coat on a pale floor: 0.1-0.4),
    one that explains every dark pixel as shading gives about 1.  The ratio
    is scale-invariant (the albedo's global scale cancels).

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB or ``(T, H, W)`` grey.
    frames : the input, same layout and size (linear).
    fraction : share of the input's pixels counted as dark, in (0, 1).
    mask : bool ``(H, W)`` or ``(T, H, W)``, or None (all pixels).

    Examples
    --------
    >>> import numpy as np
    >>> frames = np.full((2, 10, 10), 0.6); frames[:, :, :2] = 0.06   # a dark material, 20% of the image
    >>> round(dark_ratio(frames, frames), 3), round(dark_ratio(np.ones_like(frames), frames), 3)
    (0.1, 1.0)
    """
    a = _luminance_stack(albedo, "dark_ratio: albedo")
    i = _luminance_stack(frames, "dark_ratio: frames")
    if a.shape != i.shape:
        raise ValueError(f"dark_ratio: albedo {a.shape} and frames {i.shape} differ in size")
    if isinstance(fraction, bool) or not (0.0 < float(fraction) < 1.0):
        raise ValueError(f"dark_ratio: fraction must be in (0, 1), got {fraction!r}")
    sel = np.ones(a.shape, bool) if mask is None else _as_bool_mask(mask, a.shape)
    if not sel.any():
        raise ValueError("dark_ratio: the mask is empty")
    dark = sel & (i <= np.quantile(i[sel], fraction))
    overall = float(np.median(a[sel]))
    if overall <= 0:
        raise ValueError("dark_ratio: the albedo's median luminance is not positive")
    return float(np.median(a[dark])) / overall


def albedo_drift(albedo, mask=None, reference=None) -> float:
    """Drift of the albedo's level, in percent per 100 frames.

    The level of frame ``t`` is the median albedo luminance ``m_t`` (inside
    ``mask``); a least-squares line ``log m_t = c + b t`` is fitted over the
    frames and ``drift = 100 * b * 100`` (the relative change per 100
    frames, in percent, signed).  Under constant light a good split holds its
    level (``|drift| <= 0.5``); an albedo that brightens 1% a frame drifts
    about 100% per 100 frames.

    With a ``reference`` (the true albedo) the level of a frame is the median
    of ``lum(albedo) / lum(reference)`` instead: the method's own drift, free
    of what enters and leaves the view.

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB or ``(T, H, W)`` grey, ``T >= 2``.
    mask : bool ``(H, W)`` or ``(T, H, W)``, or None.
    reference : the same shape as ``albedo`` (or broadcastable to it), positive, or None.

    Examples
    --------
    >>> import numpy as np
    >>> a = 0.5 * np.exp(0.001 * np.arange(5))[:, None, None] * np.ones((5, 4, 6))   # +0.1% a frame
    >>> round(albedo_drift(a), 6)
    10.0
    """
    a = _luminance_stack(albedo, "albedo_drift: albedo")
    if reference is not None:
        ref = _luminance_stack(np.broadcast_to(reference, np.shape(albedo)), "albedo_drift: reference")
        if np.any(~(ref > 0)):
            raise ValueError("albedo_drift: the reference albedo must be positive everywhere")
        a = a / ref
    t = a.shape[0]
    if t < 2:
        raise ValueError(f"albedo_drift: needs at least 2 frames, got {t}")
    sel = np.ones(a.shape, bool) if mask is None else _as_bool_mask(mask, a.shape)
    levels = np.array([np.median(a[k][sel[k]]) if sel[k].any() else np.nan for k in range(t)])
    if np.sum(np.isfinite(levels)) < 2 or np.any(levels[np.isfinite(levels)] <= 0):
        raise ValueError("albedo_drift: needs a positive median level in at least 2 frames")
    ok = np.isfinite(levels)
    slope = np.polyfit(np.arange(t)[ok], np.log(levels[ok]), 1)[0]
    return float(slope * 100.0 * 100.0)


def _track_points(flow: np.ndarray, vis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follow every pixel of frame 0 along the chained forward flow.

    Returns ``(x, y, alive)``, each ``(H, W)``: where pixel ``(row, col)``
    of frame 0 lies in the last frame, and whether it stayed visible, with
    known flow and inside the frame, over every pair.  The flow and the
    visibility of pair ``k`` are read at the point's position in frame ``k``
    (bilinear for the flow, nearest for the visibility).
    """
    _, h, w, _ = flow.shape
    known = valid_flow_mask(flow)
    fl = np.where(known[..., None], flow, 0.0).astype(np.float32)
    x, y = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    alive = np.ones((h, w), bool)
    for k in range(flow.shape[0]):
        ok = known[k] if vis is None else known[k] & vis[k]
        alive &= cv2.remap(ok.astype(np.uint8), x, y, cv2.INTER_NEAREST,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0).astype(bool)
        dx = cv2.remap(fl[k, ..., 0], x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        dy = cv2.remap(fl[k, ..., 1], x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        x, y = x + dx, y + dy
        alive &= (x >= 0) & (x <= w - 1) & (y >= 0) & (y <= h - 1)
    return x, y, alive


def tracked_albedo_change(albedo, flow=None, visibility=None) -> dict:
    """Change of the albedo of the same surface points from the first frame to the last.

    Every pixel ``x`` of frame 0 is followed along the chained ground-truth
    flow to its position ``p(x)`` in the last frame ``T-1`` (kept only if it
    stays visible, with known flow and inside the frame, in every pair); its
    change is ``d(x) = log Y_{T-1}(p(x)) - log Y_0(x)``, ``Y`` the albedo's
    luminance (bilinear at ``p(x)``).  A split whose albedo holds along the
    flow gives ``d = 0`` everywhere, whatever its error against the truth.

    Unlike :func:`albedo_drift` with a ``reference``, which compares the
    median error of the first and the last frame, this follows points: the
    median error can sit on the edge between two regions of different
    error (say a wall too dark and a floor about right) and move with the
    small changes of the darker region alone, and on a moving camera it
    moves with what enters and leaves the view.

    Parameters
    ----------
    albedo : ``(T, H, W, 3)`` linear RGB or ``(T, H, W)`` grey, ``T >= 2``, positive.
    flow : ``(T-1, H, W, 2)`` forward ground-truth flow (unknown values
        > 1e9 are ignored), or ``None`` for a static scene (every pixel
        followed in place).
    visibility : ``(T-1, H, W)`` (``>= 0.5``: pixel ``x`` of frame ``t`` is
        visible in frame ``t+1``), or ``None`` (all visible).

    Returns
    -------
    ``{"median": exp(median d) - 1, "mean_abs": exp(mean |d|) - 1,
    "tracked": fraction of frame 0's pixels followed to the last frame}``;
    the first two are relative changes (0.01 = 1%).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.full((3, 4, 6), 0.5); a[-1] *= 1.02                  # the last frame 2% brighter
    >>> round(tracked_albedo_change(a)["median"], 6)
    0.02
    """
    y = _luminance_stack(albedo, "tracked_albedo_change: albedo")
    t, h, w = y.shape
    if t < 2:
        raise ValueError(f"tracked_albedo_change: needs at least 2 frames, got {t}")
    if np.any(~(y > 0)):
        raise ValueError("tracked_albedo_change: the albedo must be positive everywhere")
    log_y = np.log(y).astype(np.float32)
    if flow is None:
        if visibility is not None:
            raise ValueError("tracked_albedo_change: visibility needs a flow (flow=None means a static scene)")
        d = (log_y[-1] - log_y[0]).astype(np.float64).ravel()
        alive_fraction = 1.0
    else:
        flow, vis = _check_flow_visibility(flow, visibility, t, h, w)
        x, yy, alive = _track_points(np.asarray(flow, np.float64), vis)
        if not alive.any():
            raise ValueError("tracked_albedo_change: no point of the first frame is visible in the last "
                             "along the flow")
        last = cv2.remap(log_y[-1], x, yy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        d = (last[alive].astype(np.float64) - log_y[0][alive].astype(np.float64))
        alive_fraction = float(alive.mean())
    return {"median": float(np.expm1(np.median(d))), "mean_abs": float(np.expm1(np.mean(np.abs(d)))),
            "tracked": alive_fraction}
