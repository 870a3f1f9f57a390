"""Per-pixel evidence that an edge of the input is a grey albedo step (Retinex's cue).

Where albedo and light are both static no temporal term can tell a grey
albedo edge (a checkerboard, dark clothes, print) from a shading edge: the
per-frame prior decides.  Eq. 11's albedo prior is fitted on coloured
objects and prices any albedo change; a step whose chromaticity changes goes
to the albedo anyway (the shading is grey, so ``A = I - S`` must carry it),
but without help a step with no change of chromaticity ends in the shading.
Retinex's cue (Land & McCann; Grosse et al. 2009) separates them by the size
and sharpness of the step: shading varies smoothly, reflectance changes in
sharp steps.

:func:`step_gate` turns that cue into a weight on the pair terms of Eq. 9's
local shading smoothness, ``1 + gain * evidence``, with the evidence of a
pixel the largest, over its eight neighbours ``y``, of

    (1 - exp(-(dL / tau)^2)) * exp(-(dC / tau_chroma)^2)

``dL = |L(x) - L(y)|`` the step of the log luminance (a sharp step of ``d``
gives ``d``, a ramp of the same change over ``k`` pixels ``d / k``) and
``dC`` the change of the log chromaticity ``log I_c - mean_c log I`` (its
largest channel), both read on ``log(i + DARK_OFFSET)``.  Coloured steps keep
the calibrated balance of Eq. 9 and Eq. 11; a sharp grey step costs the
shading up to ``1 + gain`` times more, and goes to the albedo unless the data
or the temporal terms say otherwise.  The energy (:func:`multiply_step_gate`)
scales the gain by ``(1 - chromatic_share)^2`` (or, with
``Params.shading_step_share_radius`` > 0, by ``(1 - s(x))^2`` with the share
read around each pixel, :func:`local_chromatic_share`) and, where the scene
holds still, the evidence by Weiss's stability cue.

Weiss's cue is also read on the pairs themselves (:func:`stable_pair_weights`,
``Params.shading_stable_gain``): a horizontal or vertical pair whose step
keeps its contrast under every light of a window whose light changes
(``n > 1``) and whose scene holds still gets an extra term of Eq. 9's kind,
``lambda_Ss * gain * sum_t e sqrt((S(x + d) - S(x))^2 + eps^2)``, with ``e``
the pair's evidence (:func:`ivkernels.kernels.reference.step_evidence.stable_pairs`).
On the pair, not on its pixels: a per-pixel weight also stiffens the pairs
along the edge, and the shading's smooth variation along a printed edge then
goes into the albedo (perf/RESULTS.md, "What teabag2 loses to Weiss").
The other half of the cue, :func:`light_edge_factor`
(``Params.shading_light_edge_tau``): what a still pair's step does beyond its
median in one frame is the light's, and Eq. 9's weight of its pixels in that
frame falls by ``exp(-((s_t - m) / w)^2)``, the width ``w`` grown by the
pair's own spread over the frames (``Params.shading_light_edge_spread``).

With ``Params.shading_step_noise`` > 0 the steps of both the evidence and
the share are read net of the local noise floor (:func:`noise_floor`): in a
dark material a colour camera's noise changes every pair's colour and
brightness, which would otherwise make a grey edge look coloured and the
noise itself look like sharp steps.  The floor is read from what changes
between frames along the flow, where noise is new in every frame and fine
print, which moves with the surface, cancels; with
``Params.shading_step_noise_cap`` > 0 it is capped at that many times the
window's noise level function (the median step per brightness), so that
where the flow misses over a region the texture's change is not read as
noise.

The formula is computed by the kernels of the ``step_evidence`` family on
the backend's arrays (:mod:`ivkernels.kernels.warp.step_evidence`, the
Taichi mirror, and the NumPy reference
:mod:`ivkernels.kernels.reference.step_evidence`, which holds the constants),
the share read around each pixel included (per-pixel counts and their window
sums, ``pixel_counts`` and ``share_weight``); :func:`chromatic_share`,
:func:`local_chromatic_share`, :func:`step_evidence`, :func:`step_gate` and
:func:`grey_step_gate` are that reference on host NumPy arrays.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.reference import step_evidence as ref
from ivkernels.kernels.reference.step_evidence import AXIS_NEIGHBOURS, DARK_OFFSET, HALF_NEIGHBOURS  # noqa: F401
from ivkernels.params import Params

__all__ = ["chromatic_share", "local_chromatic_share", "grey_step_gate", "light_edge_factor", "multiply_step_gate",
           "share_radius_pixels", "stable_pair_weights", "step_evidence", "step_gate", "DARK_OFFSET", "SHARE_PRIOR_STEPS", "STATIC_FLOW"]

#: Flow (pixels) below which a pixel counts as holding still for Weiss's cue:
#: the default of ``Params.shading_step_static_flow``, read from there.
STATIC_FLOW = Params.shading_step_static_flow


#: Passes of the 5x5 median that make the noise floor (:func:`noise_floor`).
NOISE_FLOOR_PASSES = 2

#: Weight of the whole video's chromatic share in a window's (:func:`local_chromatic_share`),
#: in steps: a window with few sharp steps of its own leans on the video's share.
SHARE_PRIOR_STEPS = 4.0


def _check(gain: float, tau: float, tau_chroma: float) -> None:
    if not (np.isfinite(gain) and gain >= 0):
        raise ValueError(f"gain must be a non-negative number, got {gain!r}")
    if not (np.isfinite(tau) and tau > 0):
        raise ValueError(f"tau must be a positive number, got {tau!r}")
    if not tau_chroma > 0:
        raise ValueError(f"tau_chroma must be a positive number, got {tau_chroma!r}")


def _offset(log_image) -> np.ndarray:
    return ref.offset_log(log_image, DARK_OFFSET)


def chromatic_share(log_image: np.ndarray, tau: float, tau_chroma: float) -> float:
    """Share of the input's sharp steps whose chromaticity changes, in [0, 1].

    Over the horizontal and vertical neighbour pairs, a step is sharp when
    its log-luminance change exceeds ``tau`` or its log-chromaticity change
    ``tau_chroma``; it is chromatic in the second case.  A greyscale video
    gives 0; the coloured training scenes 0.6-0.9.  It says how much a grey
    step can be trusted to be shading: where the albedo changes colour at
    most of its edges, a grey step is mostly light; where it never does, a
    grey step is all the albedo edges there are.  0 when there is no sharp step.
    """
    return ref.share(ref.step_counts(_offset(log_image), tau, tau_chroma))


def share_radius_pixels(radius: float, h: int, w: int) -> int:
    """Half-side in pixels of the window of :func:`local_chromatic_share`: ``radius * min(h, w)``
    rounded, at least 1."""
    return max(1, int(round(radius * min(h, w))))


def local_chromatic_share(log_image: np.ndarray, tau: float, tau_chroma: float, radius: float) -> np.ndarray:
    """:func:`chromatic_share` read around each pixel, (T, h, w) float32 in [0, 1].

    The share of the sharp steps inside a square window of half-side
    ``radius * min(h, w)`` pixels (at least 1) of the pixel's frame that change
    colour, with :data:`SHARE_PRIOR_STEPS` steps of the whole video's share
    added, so that a window with few steps of its own leans on the video's.
    A grey floor beside coloured walls and objects keeps a low share where
    the floor is, which one number for the whole scene would not.
    """
    counts = ref.pixel_counts(log_image, DARK_OFFSET, tau, tau_chroma)
    return ref.local_share(counts, share_radius_pixels(radius, *counts.shape[1:3]), SHARE_PRIOR_STEPS)


def step_evidence(log_image: np.ndarray, tau: float, tau_chroma: float) -> np.ndarray:
    """Evidence in [0, 1) that a pixel lies on a sharp grey step, (T, h, w) float32.

    log_image : (T, h, w, 3) float, ``I = log i`` (read as ``log(i + DARK_OFFSET)``).
    tau : > 0, the log-luminance step at which a step counts ``1 - 1/e``.
    tau_chroma : > 0, the change of log chromaticity at which a step counts
        ``1/e`` as grey; ``inf``: chromaticity is not looked at.
    Border pixels compare with the neighbours they have.
    """
    return ref.evidence(_offset(log_image), tau, tau_chroma).astype(np.float32)


def step_gate(log_image: np.ndarray, gain: float, tau: float, tau_chroma: float = np.inf) -> np.ndarray:
    """Weight ``1 + gain * step_evidence(...)`` per pixel, (T, h, w) float32.

    gain : >= 0, how much more a sharp grey step costs the shading (0: weight 1).
    tau, tau_chroma : see :func:`step_evidence`.
    """
    _check(gain, tau, tau_chroma)
    return (1.0 + gain * ref.evidence(_offset(log_image), tau, tau_chroma)).astype(np.float32)


def grey_step_gate(log_image: np.ndarray, gain: float, tau: float, tau_chroma: float = np.inf,
                   share_radius: float = 0.0) -> np.ndarray:
    """The step weight without Weiss's cue: :func:`step_gate` with the gain scaled by
    ``(1 - share)^2`` (unscaled when ``tau_chroma`` is ``inf``), (T, h, w) float32; the share is
    :func:`local_chromatic_share` with ``share_radius`` > 0, else the whole video's
    :func:`chromatic_share`.  Host NumPy (the energy's is :func:`multiply_step_gate` on the backend)."""
    _check(gain, tau, tau_chroma)
    if not (np.isfinite(share_radius) and share_radius >= 0):
        raise ValueError(f"share_radius must be a non-negative number, got {share_radius!r}")
    evidence = step_evidence(log_image, tau, tau_chroma)
    if not np.isfinite(tau_chroma):
        return (1.0 + gain * evidence).astype(np.float32)
    # trust a grey step as albedo as much as the albedo edges around it are grey
    if share_radius > 0:
        return (1.0 + gain * (1.0 - local_chromatic_share(log_image, tau, tau_chroma, share_radius)) ** 2
                * evidence).astype(np.float32)
    return (1.0 + gain * (1.0 - chromatic_share(log_image, tau, tau_chroma)) ** 2 * evidence).astype(np.float32)


def noise_steps(be, offset_image, flow=None):
    """(T, h, w, 2) backend array: the steps the noise floor is read from (:func:`noise_floor`):
    ``step_evidence.temporal_steps`` along ``flow`` (T-1, h, w, 2) where there is one and more
    than one frame, else ``step_evidence.typical_steps`` of each frame."""
    T, h, w, _ = offset_image.shape
    steps = be.empty((T, h, w, 2))
    if flow is not None and T > 1:
        be.step_evidence.temporal_steps(offset_image, flow, steps)
    else:
        be.step_evidence.typical_steps(offset_image, steps)
    return steps


def noise_level_function(be, offset_image, steps):
    """(2, NOISE_LEVEL_BINS) backend array: the window's noise level function, per channel of
    ``steps`` (:func:`noise_steps`) the median step of each brightness bin of ``offset_image``
    (``step_evidence.step_histogram``, ``level_medians``)."""
    counts = be.empty((2, ref.NOISE_LEVEL_BINS, ref.NOISE_STEP_BINS), np.int32)
    be.step_evidence.step_histogram(offset_image, steps, counts)
    table = be.empty((2, ref.NOISE_LEVEL_BINS))
    be.step_evidence.level_medians(counts, table)
    return table


def noise_floor(be, offset_image, flow=None, cap: float = 0.0):
    """The local noise floor of the steps of ``offset_image`` (T, h, w, 3), ``log(i + DARK_OFFSET)``.

    Over frames joined by a ``flow`` (T-1, h, w, 2), per pixel the larger step of its right and
    lower pairs of what changes from one frame to the next along the flow, over ``sqrt 2``
    (``step_evidence.temporal_steps``): sensor noise is new in every frame, while print and
    edges move with the flow and cancel, so fine print does not raise the floor.  Without a
    flow or with one frame, the steps of the frame itself (``step_evidence.typical_steps``):
    in sensor noise every pair steps by about the floor, and along an edge the edge's pairs
    are a minority of the window.  ``dL`` in channel 0, ``dC`` in channel 1; then their median
    over the neighbourhood (``median.median5x5``, :data:`NOISE_FLOOR_PASSES` times).

    ``cap`` > 0: the floor is capped at ``cap`` times the window's noise level function, the
    median of the same steps in each brightness bin read at the pixel's brightness
    (``step_evidence.step_histogram``, ``level_medians``, ``cap_at_level``, all on the
    device): a camera's noise depends on the brightness, while where the flow misses over a
    region (a periodic texture, a large motion) the texture's change is large there but a
    minority of every bin.  Returns a (T, h, w, 2) backend array."""
    T, h, w, _ = offset_image.shape
    kernels = be.step_evidence
    steps = noise_steps(be, offset_image, flow)
    table = noise_level_function(be, offset_image, steps) if cap > 0 else None
    floor = be.empty((T, h, w, 2))
    for _ in range(NOISE_FLOOR_PASSES):
        be.median.median5x5(steps, floor)
        steps, floor = floor, steps
    if table is not None:
        kernels.cap_at_level(offset_image, table, cap, steps)
    return steps


def multiply_step_gate(be, log_image, gate, gain: float, tau: float, tau_chroma: float = 0.0, flow=None,
                       stability: float = 0.0, static_flow: float = STATIC_FLOW, share_radius: float = 0.0,
                       noise: float = 0.0, noise_cap: float = 0.0) -> None:
    """Multiply the step weight of Eq. 9's local term into ``gate``, on the backend's arrays.

    ``gate *= 1 + gain (1 - s)^2 w evidence``: ``s`` the chromatic share
    (:func:`chromatic_share`), ``evidence`` that of :func:`step_evidence`, and
    ``w`` Weiss's cue where the scene holds still: ``maps.shading_gate`` with
    ``tau = stability`` (a step whose contrast changes from frame to frame is
    light, not albedo), read only where the flow of the frame's pairs is
    under ``static_flow`` pixels (where it moves, a bilinear warp of a sharp
    step changes its contrast by itself, and the cue would mistake every
    moving albedo edge for light); ``w = 1`` elsewhere, and everywhere
    without a flow or with ``stability = 0``.  Every step is a kernel of the
    ``step_evidence`` family; nothing is read back to the host.

    be : backend.
    log_image : (T, h, w, 3) backend array, ``I = log i``.
    gate : (T, h, w) backend array, updated (all ones for the step weight alone).
    gain : >= 0; tau : > 0; tau_chroma : >= 0 (0: chromaticity not looked at), log units.
    flow : (T-1, h, w, 2) backend array, or ``None``.
    stability : >= 0, log-contrast change of Weiss's cue (0: not looked at).
    static_flow : > 0, pixels.
    share_radius : >= 0; > 0 (with ``tau_chroma > 0``): the share is read around each
        pixel (:func:`local_chromatic_share`, by the kernels ``pixel_counts`` and
        ``share_weight``, bit for bit) and ``(1 - s)^2`` goes into ``w`` instead of the
        gain (``Params.shading_step_share_radius``, 0.3 by default).
    noise : >= 0; > 0: every step is read net of ``noise`` times the local noise floor
        (:func:`noise_floor`, from what changes between frames along ``flow`` when there is
        one; ``Params.shading_step_noise``), 0: as it is.
    noise_cap : >= 0; > 0: that floor capped at ``noise_cap`` times the window's noise level
        function (``Params.shading_step_noise_cap``), 0: not capped.
    """
    T, h, w, _ = log_image.shape
    kernels = be.step_evidence
    offset = be.empty((T, h, w, 3))
    kernels.offset_log(log_image, offset, DARK_OFFSET)
    floor = noise_floor(be, offset, flow, noise_cap) if noise > 0 else None
    weight = be.empty((T, h, w))
    if flow is not None and T > 1 and stability > 0:
        kernels.still_stability(log_image, flow, weight, stability, static_flow)
    elif weight.size:
        be.vecops.fill(weight.reshape((T * h * w,)), 1.0)
    if share_radius > 0 and tau_chroma > 0:
        pixel_counts = be.empty((T, h, w, 2), np.int32)
        kernels.pixel_counts(log_image, pixel_counts, DARK_OFFSET, tau, tau_chroma, floor, noise)
        kernels.share_weight(pixel_counts, weight, share_radius_pixels(share_radius, h, w), SHARE_PRIOR_STEPS)
        counts = be.zeros((T * h, 2), np.int32)                 # the share is in the weight: none counted
    else:
        counts = be.empty((T * h, 2), np.int32)
        kernels.step_counts(offset, counts, tau, tau_chroma, floor, noise)
    kernels.step_gate(offset, counts, weight, gate, gain, tau, tau_chroma, floor, noise)


def stable_pair_weights(be, log_image, flow, tau: float, stability: float, floor: float,
                        static_flow: float = STATIC_FLOW):
    """Weiss's stable-step evidence of each pixel's right and lower pair, on the backend's arrays.

    ``(1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)`` of the median ``m``
    and the largest deviation from it ``D`` of the pair's log-luminance step over the
    window's frames, read on ``log(i + DARK_OFFSET)``; 0 under ``floor``, for
    steps of ``MAX_STABLE_STEP`` log units or more, and where either pixel's
    flow moves ``static_flow`` px or more (kernel ``step_evidence.stable_pairs``).

    be : backend.
    log_image : (T, h, w, 3) backend array, ``I = log i``.
    flow : (T-1, h, w, 2) backend array.
    tau, stability : log units, > 0; floor : >= 0; static_flow : pixels, > 0.

    Returns the (h, w, 2) backend array of pair weights in [0, 1).
    """
    T, h, w, _ = log_image.shape
    offset = be.empty((T, h, w, 3))
    be.step_evidence.offset_log(log_image, offset, DARK_OFFSET)
    pairs = be.empty((h, w, 2))
    be.step_evidence.stable_pairs(offset, flow, pairs, tau, stability, floor, static_flow)
    return pairs


def light_edge_factor(be, log_image, flow, tau: float, spread: float = 0.0, static_flow: float = STATIC_FLOW):
    """Weiss's cue for the light's own edges, per pixel and frame, on the backend's arrays.

    The other side of :func:`stable_pair_weights`: where the scene holds
    still, the log-luminance step of a horizontal or vertical pair that
    departs from its median over the window's frames by ``d`` in frame ``t``
    is the light's (a shadow's outline crossing the pair), so Eq. 9 should
    not smooth the shading across it there: ``exp(-(d / w)^2)``, the
    smallest over a pixel's still pairs, 1 without one (kernel
    ``step_evidence.moving_steps``, read on ``log(i + DARK_OFFSET)``).
    The width ``w = sqrt(tau^2 + (spread MAD)^2)`` grows with the pair's
    own spread over the frames (``MAD``, the median of ``|d|``): a relief
    whose steps change under every light keeps its smoothing, an outline
    that crosses the pair in a few frames does not.

    be : backend.
    log_image : (T, h, w, 3) backend array, ``I = log i``.
    flow : (T-1, h, w, 2) backend array.
    tau : log units, > 0; spread : a multiple of the MAD, >= 0 (0: ``w = tau``);
    static_flow : pixels, > 0.

    Returns the (T, h, w) backend array of factors in (0, 1].
    """
    T, h, w, _ = log_image.shape
    offset = be.empty((T, h, w, 3))
    be.step_evidence.offset_log(log_image, offset, DARK_OFFSET)
    factor = be.empty((T, h, w))
    be.step_evidence.moving_steps(offset, flow, factor, tau, spread, static_flow)
    return factor
