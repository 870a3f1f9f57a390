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

A light that moves fast lengthens the first pass's flow on a static scene
(the light's steps pulled along, in every direction), so that its median
may pass :data:`STILL_CAMERA_FLOW` while no surface moves.  Such a window
is still read as filmed by a still camera when, over its still surfaces,
the flow's vector median (the median of each component) stays under
:data:`STILL_SURFACE_DRIFT`: a camera that pans drags every surface one way,
by its own speed; the light's pull cancels out.  A camera that zooms or
rolls about the centre slowly enough (median flow under
:data:`MOVING_CAMERA_FLOW`) would pass that test too, and is held.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.reference.step_evidence import DARK_OFFSET
from ivkernels.params import Params

#: Pixels: a window whose median flow length is under this is filmed by a still camera.
STILL_CAMERA_FLOW = 0.1
#: Pixels: a window whose median flow length is this or more is filmed by a moving camera.
MOVING_CAMERA_FLOW = 0.5
#: Pixels: the vector median of the flow over the still surfaces under which a window
#: between the two bounds above is filmed by a still camera.
STILL_SURFACE_DRIFT = 0.03
#: Pixels: the radius of the window over which the gradients' agreement is averaged.
STILL_SURFACE_RADIUS = 2


def median_flow_length(flow: np.ndarray) -> float:
    """The median length, pixels, of the vectors of ``flow`` (T-1, H, W, 2); inf without a pair."""
    flow = np.asarray(flow)
    if flow.shape[0] == 0:
        return float("inf")
    return float(np.median(np.hypot(flow[..., 0], flow[..., 1])))


def still_surface_drift(flow: np.ndarray, still: np.ndarray) -> float:
    """The length, pixels, of the vector median of ``flow`` (T-1, H, W, 2) over the
    ``still`` (H, W) pixels of every pair: the median of each component; inf where
    no pixel is still."""
    flow = np.asarray(flow)
    if flow.shape[0] == 0 or not still.any():
        return float("inf")
    on_still = flow[:, still]                   # (T-1, N, 2)
    return float(np.hypot(np.median(on_still[..., 0]), np.median(on_still[..., 1])))


def camera_holds_still(flow: np.ndarray, still: np.ndarray | None = None) -> bool:
    """Whether ``flow`` (T-1, H, W, 2), pixels, was filmed by a still camera: its median
    length is under :data:`STILL_CAMERA_FLOW`, or under :data:`MOVING_CAMERA_FLOW` with the
    vector median over the ``still`` (H, W) pixels under :data:`STILL_SURFACE_DRIFT`
    (:func:`still_surface_drift`; not tested where ``still`` is None).  False without a pair."""
    length = median_flow_length(flow)
    if length < STILL_CAMERA_FLOW:
        return True
    return still is not None and length < MOVING_CAMERA_FLOW \
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


def hold_still_surfaces(flow: np.ndarray | None, still: np.ndarray | None) -> np.ndarray | None:
    """``flow`` (T-1, H, W, 2) with the vectors of the ``still`` (H, W) pixels set to 0 in
    every pair (a new array); ``flow`` itself where ``still`` or ``flow`` is None."""
    if flow is None or still is None:
        return flow
    return np.where(still[None, :, :, None], np.zeros((), flow.dtype), flow)
