"""The guide solve: a window solved at reduced size, whose albedo the next flow pass is estimated on.

Kong, Gehler & Black (ECCV 2014, Sec. 5.1, 6) note that the recovered albedo
obeys brightness constancy where the input does not.  :func:`ivkernels.decompose`
uses that inside every window (``flow_passes``): the passes before the last
solve the window here, at ``Params.flow_guide_scale`` times its size, and
:func:`guide_albedo` turns that solve into the full-size albedo the next flow
is estimated on; the last solve may start from the guide's shading
(``Params.start_from_guide``).
"""
from __future__ import annotations

import time

import numpy as np

from ivkernels.solver.motion_maps import motion_maps
from ivkernels.solver.pyramid import downsample, resize, resize_flow
from ivkernels.solver.window_solver import SolveLog, solve_window

__all__ = ["MIN_GUIDE_SIZE", "guide_albedo", "guide_shape", "guide_solve", "scaled_shape"]

#: The guide solve never goes below this many pixels on its shorter side.
MIN_GUIDE_SIZE = 16


def guide_albedo(be, frames, flow, params, prior, *, log=None) -> np.ndarray:
    """The albedo a window's next flow pass is estimated on (:func:`guide_solve`'s first output)."""
    return guide_solve(be, frames, flow, params, prior, log=log)[0]


def guide_shape(height: int, width: int, params) -> tuple[int, int]:
    """(h, w) of the guide solve for frames of ``height`` x ``width``:
    ``params.flow_guide_scale`` times their size, the shorter side kept at
    :data:`MIN_GUIDE_SIZE` pixels or the frames' own, if smaller."""
    return scaled_shape(height, width, float(params.flow_guide_scale))


def scaled_shape(height: int, width: int, scale: float) -> tuple[int, int]:
    """(h, w): ``scale`` (in (0, 1]) times ``height`` x ``width``, the shorter side kept
    at :data:`MIN_GUIDE_SIZE` pixels or the frames' own, if smaller."""
    floor = min(MIN_GUIDE_SIZE, height, width)
    scale = max(float(scale), floor / min(height, width))
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
