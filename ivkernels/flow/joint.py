"""Flow and intrinsic video estimated together, in outer passes.

Kong, Gehler & Black (ECCV 2014) pre-compute the flow on the input video and
note (Sec. 5.1, 6) that the recovered albedo obeys brightness constancy where
the input does not, so that estimating flow and intrinsic video together is
the way forward.

:func:`ivkernels.decompose` does it by default inside every window
(``flow_passes``): the passes before the last solve the window at reduced
size, and :func:`guide_albedo` turns that solve into the full-size albedo
the next flow is estimated on.  :func:`joint_decompose` is the whole-video
form used to measure the passes: it alternates full decompositions and
flows,

    pass 1:   u_1 = flow(I);                  (A_1, S_1) = decompose(I, u_1)
    pass k:   u_k = flow(J_{k-1}, init u_{k-1}); (A_k, S_k) = decompose(I, u_k)

with ``J`` the flow input of ``source``: ``"albedo"`` the current albedo
``A`` (clipped to [0, 1]), ``"relit"`` the albedo re-lit by the temporal
median of the current shading (``A_t * median_t S``: one light for every
frame, so shading structure that does not move with the light -- creases,
contours -- helps the flow as well), or ``"input"`` the input itself (the
flow does not change; only useful as a control).  It stops after ``passes``
passes or when the mean change of the flow between passes falls below
``tol`` pixels.

Every pass is recorded in :class:`JointPass` (the flow's change and, given
the truth of a synthetic sequence, flow EPE, occlusion IoU and LMSE).

>>> from ivkernels.flow.joint import joint_decompose
>>> result = joint_decompose(frames, passes=2)              # doctest: +SKIP
>>> result.video.flow.shape, [p.flow_change for p in result.history]
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["JointPass", "JointResult", "joint_decompose", "guide_albedo", "guide_shape", "guide_solve", "occlusion_iou",
           "FLOW_SOURCES", "DEFAULT_PASSES"]

#: The guide solve never goes below this many pixels on its shorter side.
MIN_GUIDE_SIZE = 16

#: What the flow of passes after the first is computed on.
FLOW_SOURCES = ("albedo", "relit", "input")

#: Measured default number of passes (perf/eval_joint.py and
#: perf/eval_flow_passes.py, training seed 1, 8 frames at 320x240): the second
#: pass on the albedo lowers flow EPE, false occlusions and LMSE on every
#: synthetic kind; a third changes the flow by under 0.07 px.  Also the
#: default of :func:`ivkernels.decompose`'s ``flow_passes``.
DEFAULT_PASSES = 2


@dataclass
class JointPass:
    """One outer pass: its flow's mean change from the previous pass (pixels;
    ``nan`` for the first), seconds spent in the flow and in the
    decomposition, and, when the truth was given, ``epe`` (flow end-point
    error, pixels), ``epe_visible`` (on pixels visible in the next frame),
    ``occlusion_iou`` (see :func:`occlusion_iou`), ``occluded`` (fraction of
    pixels the occlusion map marks occluded; the truth's fraction is
    ``occluded_true``) and ``lmse`` (dict of
    :func:`ivkernels.metrics.intrinsic_lmse`)."""

    index: int
    flow_change: float
    flow_seconds: float
    decompose_seconds: float
    epe: float | None = None
    epe_visible: float | None = None
    occlusion_iou: float | None = None
    occluded: float | None = None
    occluded_true: float | None = None
    lmse: dict | None = None


@dataclass
class JointResult:
    """The last pass's :class:`ivkernels.IntrinsicVideo` and every pass's record."""

    video: object
    history: list = field(default_factory=list)


def occlusion_iou(occlusion, visibility) -> float:
    """Intersection over union of the occluded pixels.

    occlusion : (T-1, H, W) the paper's w_occ (1 = visible in t+1, 0 = occluded
        or leaving the image), as :class:`ivkernels.IntrinsicVideo` returns it.
    visibility : (T-1, H, W) ground truth (1 = seen at ``x + u`` in t+1).
    Pixels below 0.5 are occluded.  Returns 1.0 when neither has an occluded
    pixel (nothing to find, nothing found).
    """
    est = np.asarray(occlusion) < 0.5
    gt = np.asarray(visibility) < 0.5
    if est.shape != gt.shape:
        raise ValueError(f"occlusion {est.shape} and visibility {gt.shape} differ in shape")
    union = np.logical_or(est, gt).sum()
    if union == 0:
        return 1.0
    return float(np.logical_and(est, gt).sum() / union)


def guide_albedo(be, frames, flow, params, prior, *, log=None) -> np.ndarray:
    """The albedo a window's next flow pass is estimated on (:func:`guide_solve`'s first output)."""
    return guide_solve(be, frames, flow, params, prior, log=log)[0]


def guide_shape(height: int, width: int, params) -> tuple[int, int]:
    """(h, w) of the guide solve for frames of ``height`` x ``width``:
    ``params.flow_guide_scale`` times their size, the shorter side kept at
    :data:`MIN_GUIDE_SIZE` pixels or the frames' own, if smaller."""
    floor = min(MIN_GUIDE_SIZE, height, width)
    scale = max(float(params.flow_guide_scale), floor / min(height, width))
    return max(1, int(round(height * scale))), max(1, int(round(width * scale)))


def guide_solve(be, frames, flow, params, prior, *, log=None) -> tuple[np.ndarray, np.ndarray]:
    """The albedo a window's next flow pass is estimated on, from a solve at reduced size.

    The window's frames and flow are resized to ``params.flow_guide_scale``
    times their size (antialiased; the shorter side kept at
    :data:`MIN_GUIDE_SIZE` pixels or the frames' own, if smaller), the motion
    maps are made there and Eq. 2 is minimised there
    (:func:`ivkernels.solver.window_solver.solve_window`) with
    ``min(lbfgs_iterations, guide_lbfgs_iterations)`` L-BFGS iterations per
    alternation.  The guide's log shading is up-sampled bilinearly to full
    size, and the albedo is ``I - S`` at full size: shading is smooth and
    survives the resampling, while the albedo keeps the input's finest
    texture, which the flow needs.
    The albedo is scaled so that its 99th percentile is 1 and clipped to
    [0, 1], as the flow expects.

    Parameters
    ----------
    be : backend.
    frames : (T, H, W, 3) backend array, linear RGB in [0, 1].
    flow : (T-1, H, W, 2) float32 NumPy array, the current flow.
    params : :class:`ivkernels.Params`; prior : the albedo prior.
    log : optional :class:`ivkernels.solver.window_solver.SolveLog`; the
        guide's seconds are added to it as ``"guide"``.

    Returns
    -------
    albedo : (T, H, W, 3) float32 NumPy array in [0, 1].
    log_shading : (T, h, w) float32 NumPy array, the guide's log shading at
        its own (reduced) size: the start the window's last solve can take
        (``solve_window(..., start_shading=...)``).
    """
    from ivkernels.solver.motion_maps import motion_maps
    from ivkernels.solver.pyramid import downsample, resize, resize_flow
    from ivkernels.solver.window_solver import SolveLog, solve_window

    t0 = time.perf_counter()
    T, H, W, _ = frames.shape
    shape = guide_shape(H, W, params)
    if shape == (H, W):
        small, small_flow = frames, be.asarray(np.ascontiguousarray(flow, np.float32))
    else:
        small = downsample(be, frames, shape)
        small_flow = resize_flow(be, be.asarray(np.ascontiguousarray(flow, np.float32)), shape)
    occlusion, boundary = motion_maps(be, small, small_flow, params)
    iterations = min(int(params.lbfgs_iterations), int(params.guide_lbfgs_iterations))
    _, S_small = solve_window(be, small, small_flow, occlusion, boundary,
                              params.replace(lbfgs_iterations=iterations), prior, log=SolveLog())
    S = S_small
    if shape != (H, W):
        S = be.numpy(resize(be, be.asarray(np.ascontiguousarray(S_small[..., None])), (H, W)))[..., 0]
    log_image = np.log(np.maximum(be.numpy(frames), params.log_floor))
    albedo = np.exp(log_image - S[..., None])
    albedo /= float(np.percentile(albedo, 99.0)) or 1.0
    if log is not None:
        log.add_time("guide", time.perf_counter() - t0)
    return np.ascontiguousarray(np.clip(albedo, 0.0, 1.0), np.float32), S_small


def _flow_input(video, source: str, frames) -> np.ndarray:
    if source == "input":
        return frames
    albedo = np.clip(video.albedo, 0.0, 1.0)
    if source == "albedo":
        return np.ascontiguousarray(albedo, np.float32)
    shading = np.median(video.shading, axis=0)
    return np.ascontiguousarray(np.clip(albedo * shading[None, :, :, None], 0.0, 1.0), np.float32)


def joint_decompose(frames, passes: int = DEFAULT_PASSES, method: str = "classic_nl_fast", source: str = "albedo",
                    warm_start: bool = True, tol: float = 0.0, backend: str = "warp", device: str = "cpu",
                    params=None, flow_options: dict | None = None, truth=None,
                    progress: bool = False) -> JointResult:
    """Alternate flow estimation and the intrinsic decomposition for ``passes`` outer passes.

    Parameters
    ----------
    frames : (T, H, W, 3), T >= 2: float linear RGB in [0, 1] or uint8 sRGB.
    passes : number of decompositions (>= 1); 1 is ``decompose(frames)``
        with flow from the input.
    method : a Classic+NL or OpenCV method of :func:`ivkernels.flow.estimate_flow`.
    source : flow input of passes 2.. (:data:`FLOW_SOURCES`, see the module docstring).
    warm_start : start each pass's Classic+NL flow from the previous flow.
    tol : stop early once the mean flow change between passes is below ``tol`` pixels.
    backend, device, params : passed to :func:`ivkernels.decompose`.
    flow_options : extra keyword arguments of :func:`estimate_flow`.
    truth : optional :class:`ivkernels.synthetic.SyntheticSequence` of these
        frames; each pass then records its flow EPE, occlusion IoU and LMSE.

    Returns
    -------
    JointResult
        ``video``: the last pass's :class:`ivkernels.IntrinsicVideo`, whose
        ``flow`` is the joint flow and ``diagnostics["flow_method"]`` says
        how it was made; ``history``: a :class:`JointPass` per pass.
    """
    from ivkernels import metrics
    from ivkernels.decompose import decompose
    from ivkernels.flow import FLOW_METHODS, as_linear_rgb, estimate_flow

    if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or passes < 1:
        raise ValueError(f"passes must be an int >= 1, got {passes!r}")
    if source not in FLOW_SOURCES:
        raise ValueError(f"source must be one of {FLOW_SOURCES}, got {source!r}")
    if method not in FLOW_METHODS:
        raise ValueError(f"unknown flow method {method!r}; expected one of {FLOW_METHODS}")
    frames = as_linear_rgb(frames, backend, device)
    options = dict(flow_options or {})
    classic = method.startswith("classic_nl")

    history, video, flow = [], None, None
    for k in range(passes):
        t0 = time.perf_counter()
        if k == 0:
            new_flow = estimate_flow(frames, method=method, backend=backend, device=device, **options)
        else:
            extra = {"init": flow} if (warm_start and classic) else {}
            new_flow = estimate_flow(_flow_input(video, source, frames), method=method, backend=backend,
                                     device=device, **options, **extra)
        t1 = time.perf_counter()
        change = float("nan") if flow is None else float(np.sqrt(((new_flow - flow) ** 2).sum(-1)).mean())
        flow = new_flow
        video = decompose(frames, flow=flow, backend=backend, device=device, params=params, progress=progress)
        t2 = time.perf_counter()
        record = JointPass(k + 1, change, t1 - t0, t2 - t1)
        if truth is not None:
            record.epe = metrics.endpoint_error(flow, truth.flow)
            record.epe_visible = metrics.endpoint_error(flow, truth.flow, mask=truth.visibility > 0.5)
            record.occlusion_iou = occlusion_iou(video.occlusion, truth.visibility)
            record.occluded = float((video.occlusion < 0.5).mean())
            record.occluded_true = float((truth.visibility < 0.5).mean())
            record.lmse = metrics.intrinsic_lmse(video.albedo, video.shading, truth.albedo, truth.shading)
        history.append(record)
        if k > 0 and change < tol:
            break
    label = method if len(history) == 1 else f"{method}, {len(history)} joint passes on the {source}"
    video.diagnostics["flow_method"] = label
    video.diagnostics["joint_passes"] = [vars(p).copy() for p in history]
    return JointResult(video, history)
