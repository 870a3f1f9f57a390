"""Flow and intrinsic video estimated together, in outer passes, over a whole video.

Kong, Gehler & Black (ECCV 2014) pre-compute the flow on the input video and
note (Sec. 5.1, 6) that the recovered albedo obeys brightness constancy where
the input does not, so that estimating flow and intrinsic video together is
the way forward.

:func:`ivkernels.decompose` does it by default inside every window
(``flow_passes``): the passes before the last solve the window at reduced
size, and :func:`ivkernels.solver.guide.guide_albedo` turns that solve into
the full-size albedo the next flow is estimated on.  :func:`joint_decompose`
is the whole-video
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

>>> from ivkernels.evaluation.joint import joint_decompose
>>> result = joint_decompose(frames, passes=2)              # doctest: +SKIP
>>> result.video.flow.shape, [p.flow_change for p in result.history]
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ivkernels.decompose import DEFAULT_FLOW_PASSES, decompose
from ivkernels.evaluation import metrics
from ivkernels.flow import FLOW_METHODS, as_linear_rgb, estimate_flow

__all__ = ["JointPass", "JointResult", "joint_decompose", "occlusion_iou", "FLOW_SOURCES"]

#: What the flow of passes after the first is computed on.
FLOW_SOURCES = ("albedo", "relit", "input")

@dataclass
class JointPass:
    """One outer pass: its flow's mean change from the previous pass (pixels;
    ``nan`` for the first), seconds spent in the flow and in the
    decomposition, and, when the truth was given, ``epe`` (flow end-point
    error, pixels), ``epe_visible`` (on pixels visible in the next frame),
    ``occlusion_iou`` (see :func:`occlusion_iou`), ``occluded`` (fraction of
    pixels the occlusion map marks occluded; the truth's fraction is
    ``occluded_true``) and ``lmse`` (dict of
    :func:`ivkernels.evaluation.metrics.intrinsic_lmse`)."""

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


def _flow_input(video, source: str, frames) -> np.ndarray:
    if source == "input":
        return frames
    albedo = np.clip(video.albedo, 0.0, 1.0)
    if source == "albedo":
        return np.ascontiguousarray(albedo, np.float32)
    shading = np.median(video.shading, axis=0)
    return np.ascontiguousarray(np.clip(albedo * shading[None, :, :, None], 0.0, 1.0), np.float32)


def joint_decompose(frames, passes: int = DEFAULT_FLOW_PASSES, method: str = "classic_nl_fast", source: str = "albedo",
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
    truth : optional :class:`ivkernels.evaluation.synthetic.SyntheticSequence` of these
        frames; each pass then records its flow EPE, occlusion IoU and LMSE.

    Returns
    -------
    JointResult
        ``video``: the last pass's :class:`ivkernels.IntrinsicVideo`, whose
        ``flow`` is the joint flow and ``diagnostics["flow_method"]`` says
        how it was made; ``history``: a :class:`JointPass` per pass.
    """
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
