"""Optical flow between consecutive frames of a video.

>>> from ivkernels.flow import estimate_flow
>>> flow = estimate_flow(frames)                       # doctest: +SKIP
>>> flow.shape                                         # (T-1, H, W, 2), pixels, (dx, dy)

Methods (:data:`FLOW_METHODS`):

``"classic_nl_fast"`` (default), ``"classic_nl"``
    Classic+NL (Sun, Roth & Black, IJCV 2014), the flow the intrinsic-video
    paper uses, on this package's kernels (:mod:`ivkernels.flow.classic_nl`);
    the fast setting has 2 GNC stages and 3 warps per level and a
    gradient-constancy data term that holds under changing light, the full
    one the public code's 3 stages, 10 warps and brightness constancy.
    Runs on the chosen backend ("warp" on "cpu" or "cuda", or
    "taichi").
``"dis"``, ``"farneback"``
    OpenCV's DIS (medium preset) and Farneback flows
    (:mod:`ivkernels.flow.opencv_flow`), on the CPU whatever the backend.
"""
from __future__ import annotations

import numpy as np

from ivkernels import validation as v
from ivkernels.backends import check_device, get_backend
from ivkernels.flow.classic_nl import DATA_TERMS, PRESETS, ClassicNL, ClassicNLSettings, settings_for
from ivkernels.flow.opencv_flow import dis_flow, farneback_flow
from ivkernels.kernels.memory import release_free_memory
from ivkernels.kernels.thread_count import check_threads, get_threads
from ivkernels.kernels.thread_count import threads as launch_threads

FLOW_METHODS = ("classic_nl_fast", "classic_nl", "dis", "farneback")

__all__ = ["estimate_flow", "FLOW_METHODS", "ClassicNL", "ClassicNLSettings", "PRESETS", "DATA_TERMS",
           "as_linear_rgb"]

MIN_SIZE = 4


def as_linear_rgb(frames, backend: str = "warp", device: str = "cpu") -> np.ndarray:
    """Validate video frames for the flow and return them as float32 linear RGB, (T, H, W, 3).

    The rules are those of :mod:`ivkernels.validation`, the same as
    :func:`ivkernels.decompose`'s: uint8 / uint16 sRGB, or float32 / float64
    linear RGB in [0, 1] (float frames in 0..255, negative or non-finite
    values are refused, never clipped); a list of (H, W, 3) frames is
    stacked.  At least 2 frames of at least 4x4 pixels.  ``backend`` and
    ``device`` are checked too.
    """
    check_device(backend, device)
    checked = v.check_frames(frames, min_frames=2, min_size=MIN_SIZE, what="flow")
    T, H, W = checked.shape
    v.check_memory(v.flow_nbytes(T, H, W), f"optical flow on {T} frames of {W}x{H}")
    return v.linear_frames(checked)


def estimate_flow(frames, method: str = "classic_nl_fast", backend: str = "warp", device: str = "cpu",
                  threads: int | None = None, **options) -> np.ndarray:
    """Forward optical flow ``u_t`` from frame ``t`` to frame ``t + 1``.

    Parameters
    ----------
    frames : (T, H, W, 3), T >= 2: float linear RGB in [0, 1], or uint8 /
        uint16 sRGB (the rules of :func:`ivkernels.decompose`, see
        :mod:`ivkernels.validation`).
    method : one of :data:`FLOW_METHODS`.
    backend, device : kernels the Classic+NL methods run on ("warp" on "cpu" or
        "cuda[:N]", or "taichi" on "cpu"); the OpenCV methods ignore them
        except to convert uint8 input.
    threads : CPU threads the Classic+NL kernels run on (an integer >= 1);
        ``None``: ``IVKERNELS_THREADS`` if set, else every core this process
        may use, as for :func:`ivkernels.decompose`.  The OpenCV methods run
        on OpenCV's own threads.
    options : Classic+NL: fields of :class:`ClassicNLSettings` (e.g.
        ``sor_sweeps=40``, ``warps=5``) and ``init``, an initial flow
        (T-1, H, W, 2); "dis": ``preset`` ("medium", "fast", "ultrafast");
        "farneback": the parameters of ``cv2.calcOpticalFlowFarneback``.

    Returns
    -------
    (T-1, H, W, 2) float32 flow in pixels; channel 0 = dx (columns),
    channel 1 = dy (rows); pixel ``x`` of frame ``t`` moves to ``x + u_t(x)``.
    """
    if not isinstance(method, str) or method not in FLOW_METHODS:
        raise ValueError(f"unknown flow method {method!r}; expected one of {FLOW_METHODS}")
    threads = get_threads() if threads is None else check_threads(threads)
    frames = as_linear_rgb(frames, backend, device)
    if method == "dis":
        return dis_flow(frames, **options)
    if method == "farneback":
        return farneback_flow(frames, **options)
    init = options.pop("init", None)
    if init is not None:
        init = v.check_flow(init, *frames.shape[:3], name="init")
    settings = settings_for(method, **options)
    with launch_threads(threads):
        be = get_backend(backend, device)
        be.use_threads(threads)
        flow = ClassicNL(be, settings)(frames, init)
    release_free_memory()       # the pyramid's scratch is freed: its heap pages go back (kernels/memory.py)
    return flow
