"""The flow's intrinsic images: occlusion w_occ (Eq. 6-7), motion boundaries w_bnd,
and where Eq. 9's local shading term is cut at a flow discontinuity.

The first two are computed once per window at full resolution on the backend
and resampled per pyramid level; the cut is computed from each level's own
flow (:func:`shading_cut_gate`).
"""
from __future__ import annotations

import math

import numpy as np

from ivkernels.params import Params
from ivkernels.solver.pyramid import resize


def motion_maps(be, frames_linear, flow, params: Params, *, back_flow=None, workspace=None):
    """Occlusion and motion-boundary weights of a window.

    Parameters
    ----------
    be : backend.
    frames_linear : (T, H, W, 3) backend array, linear RGB in [0, 1].
    flow : (T-1, H, W, 2) backend array, forward flow in pixels (x, y).
    back_flow : optional (T-1, H, W, 2) backend array, the backward flow
        (frame t+1 -> t, on frame t+1's grid); with
        it and ``params.flow_round_trip_max`` > 0, the forward-backward check
        (``maps.round_trip_consistency``) also clears the occlusion map.
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` of the
        caller for the kernels' scratch; without one it is allocated for this
        call and freed on return.

    Returns
    -------
    occlusion : (T-1, H, W) backend array, Eq. 6: 1 where ``x + u`` stays in
        the image, ``o(x) >= params.occlusion_threshold`` (Eq. 7; its colour
        term only with ``params.occlusion_colour``) and the
        bilinear warp there is reliable (``maps.warp_reliability`` with
        ``params.warp_spread_max``) and the input's chromaticity stays the
        same along the flow (``maps.chroma_consistency`` with
        ``params.chroma_change_max``; skipped when that is 0) and, with
        ``back_flow``, the flow comes back within
        ``params.flow_round_trip_max`` pixels, else 0.
    boundary : (T-1, H, W) backend array, 1 within ``params.boundary_radius``
        pixels of a flow Sobel magnitude above ``params.boundary_threshold``.
    """
    T, H, W, _ = frames_linear.shape
    n = flow.shape[0]
    lab = be.empty((T, H, W, 3))
    be.colour.linear_rgb_to_lab(frames_linear, lab)
    div_neg = be.empty((n, H, W))
    be.derivatives.divergence_negative(flow, div_neg)
    occlusion = be.empty((n, H, W))
    # Without Eq. 7's colour term (Params.occlusion_colour) its factor is exp(0) = 1.
    sigma_e = params.sigma_e if params.occlusion_colour else math.inf
    be.maps.occlusion_binary(lab, flow, div_neg, occlusion, sigma_e=sigma_e,
                             sigma_d=params.sigma_d, threshold=params.occlusion_threshold)
    log_image = be.empty((T, H, W, 3))
    be.colour.log_floor(frames_linear, log_image, params.log_floor)
    be.maps.warp_reliability(log_image, flow, occlusion, params.warp_spread_max)
    if params.chroma_change_max > 0.0:
        be.maps.chroma_consistency(log_image, flow, occlusion, params.chroma_change_max)
    if back_flow is not None and params.flow_round_trip_max > 0.0:
        be.maps.round_trip_consistency(flow, back_flow, occlusion, params.flow_round_trip_max)
    sobel = be.empty((n, H, W))
    be.derivatives.flow_sobel_magnitude(flow, sobel)
    boundary = be.empty((n, H, W))
    be.maps.motion_boundary(sobel, boundary, params.boundary_threshold, int(params.boundary_radius),
                            workspace=workspace)
    return occlusion, boundary


def resample_mask(be, mask, shape: tuple[int, int]):
    """Bilinear resize of a (T, H, W) 0/1 map to ``shape``, re-binarised at 0.5."""
    if tuple(mask.shape[1:]) == tuple(shape):
        return mask
    small = resize(be, mask.reshape((*mask.shape, 1)), shape)
    values = be.numpy(small)[..., 0]
    return be.asarray((values >= 0.5).astype(np.float32))


def shading_cut_gate(be, flow, threshold: float, n_frames: int):
    """Per-pixel gate of Eq. 9's local term: 0 where the flow jumps, else 1.

    Eq. 9 smooths the shading over every 3x3 neighbourhood, across motion
    boundaries too, although a motion boundary is where one surface ends and
    another begins and the shading is discontinuous (Sec. 3.3; its non-local
    term already stops there).  A pixel whose flow Sobel magnitude exceeds
    ``threshold`` in a frame pair that includes its frame (the pair it starts,
    or the pair that ends on it) gets gate 0, so its local pair terms get
    weight ``(g(x) + g(y)) / 2`` of 0 or 1/2 (``energy_shading.
    shading_smoothness_gated``).  The flow is this level's, so the cut is as
    thin as the level's flow edge; no dilation.

    Parameters
    ----------
    be : backend.
    flow : (n_frames - 1, h, w, 2) backend array, forward flow in pixels of this level.
    threshold : Sobel magnitude of the flow (pixels per pixel, as
        ``Params.boundary_threshold``) above which the local term is cut; > 0.
    n_frames : T, the window's frame count (``flow.shape[0] + 1``).

    Returns
    -------
    (T, h, w) backend array, float32 0 or 1.
    """
    n, h, w, _ = flow.shape
    if n != n_frames - 1:
        raise ValueError(f"flow has {n} frame pairs, expected n_frames - 1 = {n_frames - 1}")
    sobel = be.empty((n, h, w))
    be.derivatives.flow_sobel_magnitude(flow, sobel)
    jumps = be.empty((n, h, w))
    be.maps.motion_boundary(sobel, jumps, threshold, 0)
    cut = be.numpy(jumps) > 0.5
    touched = np.zeros((n_frames, h, w), bool)
    touched[:-1] |= cut         # the pair t -> t+1 starts on frame t
    touched[1:] |= cut          # ... and ends on frame t+1
    return be.asarray((~touched).astype(np.float32))


def brightness_consistency(be, frames_linear, flow, occlusion, params: Params):
    """``occlusion`` with the brightness test of a window whose light holds still.

    Under a still light a surface keeps its brightness along the flow, up to
    a global change of exposure; near a flow jump, where parallax hides and
    uncovers surfaces, a pixel whose brightness changes is not the same
    surface in the two frames (``maps.luminance_consistency``).  Used only
    for a window of one independent shading (``Params.luminance_change_max``;
    :mod:`ivkernels.solver.independent_shadings`): where the light moves,
    brightness changes on every surface.

    Parameters
    ----------
    be : backend.
    frames_linear : (T, H, W, 3) backend array, linear RGB in [0, 1].
    flow : (T-1, H, W, 2) backend array, forward flow in pixels.
    occlusion : (T-1, H, W) backend array, w_occ of :func:`motion_maps`; not changed.
    params : ``luminance_change_max`` (> 0), ``luminance_change_radius``,
        ``boundary_threshold``, ``log_floor``.

    Returns
    -------
    (T-1, H, W) backend array, a new w_occ: 0 where ``occlusion`` is 0 or the test fails.
    """
    T, H, W, _ = frames_linear.shape
    n = T - 1
    log_image = be.empty((T, H, W, 3))
    be.colour.log_floor(frames_linear, log_image, params.log_floor)
    # Each pair's global change of the mean log: its median over the pixels that stay in the image.
    warped, inside = be.empty((n, H, W, 3)), be.empty((n, H, W))
    be.sampling.warp_bilinear(log_image[1:], flow, warped, inside)
    change = (be.numpy(warped) - be.numpy(log_image)[:-1]).mean(axis=3)
    valid = be.numpy(inside) > 0.5
    offsets = np.array([np.median(change[t][valid[t]]) if valid[t].any() else 0.0 for t in range(n)],
                       np.float32)
    sobel, near = be.empty((n, H, W)), be.empty((n, H, W))
    be.derivatives.flow_sobel_magnitude(flow, sobel)
    be.maps.motion_boundary(sobel, near, params.boundary_threshold, int(params.luminance_change_radius))
    out = be.empty((n, H, W))
    be.vecops.copy(occlusion.reshape((n * H * W,)), out.reshape((n * H * W,)))
    be.maps.luminance_consistency(log_image, flow, near, be.asarray(offsets), out, params.luminance_change_max)
    return out


def window_occlusion(be, frames_linear, flow, occlusion, params: Params, n_shadings: float):
    """The w_occ a window's temporal terms use: ``occlusion``, with :func:`brightness_consistency`
    where the window holds one independent shading (``n_shadings <= 1``) and
    ``Params.luminance_change_max`` > 0."""
    if flow is None or occlusion is None or n_shadings > 1.0 or params.luminance_change_max <= 0.0:
        return occlusion
    return brightness_consistency(be, frames_linear, flow, occlusion, params)
