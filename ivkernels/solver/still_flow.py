"""A still camera's flow held at zero on the surfaces that stay, where a moving shadow drags it.

With the camera on a tripod and a shadow sweeping over a still floor, the
flow estimator follows the shadow: its edges are the strongest the input
shows, and the last pass, which estimates on a guide albedo that still
holds the shadow, follows it too.  The temporal terms then tie the floor to
the wrong place, and Weiss's cue (``Params.shading_step_static_flow``) does
not see the floor as still (perf/RESULTS.md, "The flow a moving shadow drags
over a still surface": zeroing the flow of the truly still pixels removes a
third of the albedo error of the kind, as much as the true flow).

The frames themselves say which surfaces stay (``maps.still_surface``): a
still surface keeps its log-luminance gradients under any change of light,
except along a shadow's edge, which is somewhere else in every frame, so in
most frames they agree with their median over the window (Weiss 2001); a
surface moving past the pixel changes them from frame to frame.  In a window
whose camera holds still (:func:`camera_holds_still`), the flows of those
pixels are set to zero, forward and backward alike.  A flat moving region
agrees whether it moves or not and is held too; inside it the zero flow
joins the same flat albedo, as its own flow would.

A moving light lengthens the flow on a static scene (the light's steps
pulled along by a fraction of a pixel), so that its median may pass
:data:`STILL_CAMERA_FLOW` while no surface moves.  Such a window is still
read as filmed by a still camera when its still surfaces do not move in
common (:func:`still_surface_drift`): a camera that pans, zooms or rolls
moves every surface the same way pair after pair (the same translation,
the same radial or rotational rate about the centre); the light pulls them
one way in one pair and another in the next.

Where the light changes the gradients of a still surface too much for it to
be found still (the lit side of a curved object), its flow is the light's
pull, a fraction of a pixel; under a still camera the final flow's vectors
shorter than ``Params.flow_still_small`` are held at zero as well.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.reference.step_evidence import DARK_OFFSET
from ivkernels.params import Params

#: Pixels: a window whose median flow length is under this is filmed by a still camera.
STILL_CAMERA_FLOW = 0.1
#: Pixels: a window whose median flow length is this or more is filmed by a moving camera.
MOVING_CAMERA_FLOW = 0.5
#: Pixels: the common motion of the still surfaces (:func:`still_surface_drift`) under which
#: a window between the two bounds above is filmed by a still camera.
STILL_SURFACE_DRIFT = 0.03
#: A common drift of the still pixels counts as the camera's where it is larger than this
#: many times the pairs' scatter about it.
PAN_AGREEMENT = 2.0
#: Fewest pairs whose scatter the common drift is told from; a shorter window is still
#: only under :data:`STILL_CAMERA_FLOW` (two or three pairs of a moving camera can
#: scatter as much as a light's pull).
DRIFT_MIN_PAIRS = 4
#: Pixels: the radius of the window over which the gradients' agreement is averaged.
STILL_SURFACE_RADIUS = 2


def median_flow_length(flow: np.ndarray) -> float:
    """The median length, pixels, of the vectors of ``flow`` (T-1, H, W, 2); inf without a pair."""
    flow = np.asarray(flow)
    if flow.shape[0] == 0:
        return float("inf")
    return float(np.median(np.hypot(flow[..., 0], flow[..., 1])))


def pair_drifts(flow: np.ndarray, still: np.ndarray) -> np.ndarray:
    """(T-1, 4): per pair of ``flow`` (T-1, H, W, 2), how the ``still`` (H, W) pixels move in
    common, pixels: the vector median (the median of each component) of their flow, and the
    medians of its radial and rotational rates about the picture's centre,
    ``((x, y) . f) / r^2`` and ``((x, y) x f) / r^2``, times the half-diagonal (a zoom's and
    a roll's motion at the corners; read where ``r`` is at least a quarter of it);
    (0, 4) where none is still."""
    flow = np.asarray(flow)
    if flow.shape[0] == 0 or not still.any():
        return np.zeros((0, 4))
    H, W = still.shape
    y, x = np.mgrid[0:H, 0:W]
    x = x - (W - 1) / 2.0
    y = y - (H - 1) / 2.0
    half_diagonal = float(np.hypot(W, H)) / 2.0
    r2 = x * x + y * y
    outer = still & (r2 >= (half_diagonal / 4.0) ** 2)
    f = flow[:, still].astype(np.float64)               # (T-1, N, 2)
    drifts = np.median(f, axis=1)
    if not outer.any():
        return np.concatenate([drifts, np.zeros_like(drifts)], axis=1)
    u, v = flow[:, outer, 0].astype(np.float64), flow[:, outer, 1].astype(np.float64)
    xo, yo, r2o = x[outer], y[outer], r2[outer]
    radial = np.median((xo * u + yo * v) / r2o, axis=1) * half_diagonal
    rotational = np.median((xo * v - yo * u) / r2o, axis=1) * half_diagonal
    return np.concatenate([drifts, radial[:, None], rotational[:, None]], axis=1)


def still_surface_drift(flow: np.ndarray, still: np.ndarray) -> float:
    """How far the ``still`` (H, W) pixels of ``flow`` (T-1, H, W, 2) move in common, pixels:
    the length of the mean of the pairs' motions (:func:`pair_drifts`: translation, zoom and
    roll) where it exceeds :data:`PAN_AGREEMENT` times their scatter about it (a camera's
    motion, the same from pair to pair), else 0 (a light's pull, one way in one pair and
    another way in the next); inf where no pixel is still."""
    drifts = pair_drifts(flow, still)
    if not len(drifts):
        return float("inf")
    common = drifts.mean(axis=0)
    scatter = float(np.sqrt(np.mean(np.sum((drifts - common) ** 2, axis=1))))
    length = float(np.linalg.norm(common))
    return length if length > PAN_AGREEMENT * scatter else 0.0


def camera_holds_still(flow: np.ndarray, still: np.ndarray | None = None) -> bool:
    """Whether ``flow`` (T-1, H, W, 2), pixels, was filmed by a still camera: its median
    length is under :data:`STILL_CAMERA_FLOW`, or under :data:`MOVING_CAMERA_FLOW` with the
    common drift of the ``still`` (H, W) pixels under :data:`STILL_SURFACE_DRIFT`
    (:func:`still_surface_drift`; tested only with ``still`` and at least
    :data:`DRIFT_MIN_PAIRS` pairs).  False without a pair."""
    length = median_flow_length(flow)
    if length < STILL_CAMERA_FLOW:
        return True
    return still is not None and len(flow) >= DRIFT_MIN_PAIRS and length < MOVING_CAMERA_FLOW \
        and still_surface_drift(flow, still) < STILL_SURFACE_DRIFT


def still_surface_mask(be, frames_linear, params: Params, *, workspace=None) -> np.ndarray:
    """(H, W) bool: ``maps.still_surface`` of the window's frames (T, H, W, 3 backend array,
    linear RGB), read on ``log(i + DARK_OFFSET)`` as the step evidence reads its steps,
    with ``Params.flow_still_surface_tau`` and ``flow_still_surface_share``."""
    T, H, W, _ = frames_linear.shape
    log_image = be.empty((T, H, W, 3))
    be.colour.log_floor(frames_linear, log_image, params.log_floor)
    be.step_evidence.offset_log(log_image, log_image, DARK_OFFSET)
    still = be.empty((H, W))
    be.maps.still_surface(log_image, still, params.flow_still_surface_tau, STILL_SURFACE_RADIUS,
                          params.flow_still_surface_share, workspace=workspace)
    return np.asarray(be.numpy(still)) > 0.5


def hold_still_surfaces(flow: np.ndarray | None, still: np.ndarray | None,
                        small: float = 0.0) -> np.ndarray | None:
    """``flow`` (T-1, H, W, 2) with the vectors of the ``still`` (H, W) pixels set to 0 in
    every pair, and those shorter than ``small`` pixels (a new array); ``flow`` itself
    where ``still`` or ``flow`` is None."""
    if flow is None or still is None:
        return flow
    held = still[None, :, :, None]
    if small > 0:
        held = held | (np.hypot(flow[..., 0], flow[..., 1]) < small)[..., None]
    return np.where(held, np.zeros((), flow.dtype), flow)
