"""Optical flow between consecutive frames of a video.

>>> from ivkernels.flow import estimate_flow
>>> flow = estimate_flow(frames)                       # doctest: +SKIP
>>> flow.shape                                         # (T-1, H, W, 2), pixels, (dx, dy)

Methods (:data:`FLOW_METHODS`):

``"classic_nl_fast"`` (default), ``"classic_nl"``
    Classic+NL (Sun, Roth & Black, IJCV 2014), the flow the intrinsic-video
    paper uses, on this package's kernels (:mod:`ivkernels.flow.classic_nl`);
    the fast setting has 2 GNC stages and 3 warps per level, the full one 3
    and 10.  Runs on the chosen backend ("warp" on "cpu" or "cuda", or
    "taichi").
``"dis"``, ``"farneback"``
    OpenCV's DIS (medium preset) and Farneback flows
    (:mod:`ivkernels.flow.opencv_flow`), on the CPU whatever the backend.
"""
from __future__ import annotations

import numpy as np

from ivkernels.flow.classic_nl import PRESETS, ClassicNL, ClassicNLSettings, settings_for

FLOW_METHODS = ("classic_nl_fast", "classic_nl", "dis", "farneback")

__all__ = ["estimate_flow", "FLOW_METHODS", "ClassicNL", "ClassicNLSettings", "PRESETS", "as_linear_rgb"]

MIN_SIZE = 4


def as_linear_rgb(frames, backend: str = "warp", device: str = "cpu") -> np.ndarray:
    """Validate video frames and return them as float32 linear RGB, (T, H, W, 3).

    frames : (T, H, W, 3) uint8 sRGB (converted with the sRGB curve), or float
        linear RGB in [0, 1] (values outside are clipped by the methods).
    Raises TypeError for other dtypes, ValueError for a wrong shape, fewer than
    2 frames, frames smaller than 4x4 or non-finite values.
    """
    if not isinstance(frames, np.ndarray):
        if isinstance(frames, (list, tuple)) or hasattr(frames, "__array__"):
            frames = np.asarray(frames)
        else:
            raise TypeError(f"frames must be a numpy array (T, H, W, 3), got {type(frames).__name__}")
    if frames.ndim != 4 or frames.shape[-1] != 3:
        raise ValueError(f"frames must have shape (T, H, W, 3), got {frames.shape}")
    t, h, w, _ = frames.shape
    if t < 2:
        raise ValueError(f"flow needs at least 2 frames, got T = {t}")
    if h < MIN_SIZE or w < MIN_SIZE:
        raise ValueError(f"frames must be at least {MIN_SIZE}x{MIN_SIZE} pixels, got {h}x{w}")
    if frames.dtype == np.uint8:
        from ivkernels.backends import get_backend

        be = get_backend(backend, device)
        enc = be.asarray(np.ascontiguousarray(frames, np.float32) / np.float32(255.0))
        lin = be.empty(frames.shape)
        be.colour.srgb_to_linear(enc, lin)
        return np.array(be.numpy(lin), np.float32, copy=True)
    if not np.issubdtype(frames.dtype, np.floating):
        raise TypeError(f"frames must be uint8 sRGB or float linear RGB in [0, 1], got dtype {frames.dtype}")
    frames = np.ascontiguousarray(frames, np.float32)
    if not np.isfinite(frames).all():
        raise ValueError("frames contain NaN or infinite values")
    return frames


def estimate_flow(frames, method: str = "classic_nl_fast", backend: str = "warp", device: str = "cpu",
                  **options) -> np.ndarray:
    """Forward optical flow ``u_t`` from frame ``t`` to frame ``t + 1``.

    Parameters
    ----------
    frames : (T, H, W, 3), T >= 2: float linear RGB in [0, 1] or uint8 sRGB.
    method : one of :data:`FLOW_METHODS`.
    backend, device : kernels the Classic+NL methods run on ("warp" on "cpu" or
        "cuda[:N]", or "taichi" on "cpu"); the OpenCV methods ignore them
        except to convert uint8 input.
    options : Classic+NL: fields of :class:`ClassicNLSettings` (e.g.
        ``sor_sweeps=40``, ``warps=5``) and ``init``, an initial flow
        (T-1, H, W, 2); "dis": ``preset`` ("medium", "fast", "ultrafast");
        "farneback": the parameters of ``cv2.calcOpticalFlowFarneback``.

    Returns
    -------
    (T-1, H, W, 2) float32 flow in pixels; channel 0 = dx (columns),
    channel 1 = dy (rows); pixel ``x`` of frame ``t`` moves to ``x + u_t(x)``.
    """
    if method not in FLOW_METHODS:
        raise ValueError(f"unknown flow method {method!r}; expected one of {FLOW_METHODS}")
    frames = as_linear_rgb(frames, backend, device)
    if method == "dis":
        from ivkernels.flow.opencv_flow import dis_flow

        return dis_flow(frames, **options)
    if method == "farneback":
        from ivkernels.flow.opencv_flow import farneback_flow

        return farneback_flow(frames, **options)
    from ivkernels.backends import get_backend

    init = options.pop("init", None)
    if init is not None:
        init = np.asarray(init)
        want = (frames.shape[0] - 1, *frames.shape[1:3], 2)
        if init.shape != want:
            raise ValueError(f"init must have shape (T-1, H, W, 2) = {want}, got {init.shape}")
        if not np.issubdtype(init.dtype, np.floating) or not np.isfinite(init).all():
            raise ValueError("init must be a finite float array")
    settings = settings_for(method, **options)
    return ClassicNL(get_backend(backend, device), settings)(frames, init)
