"""How many independent shadings a window holds: the weight of its albedo prior.

Eq. 2 sums every term over the frames of a window.  For the shading priors
that is right when each frame's shading is a new draw; for the albedo prior
it is not: the temporal albedo term (Eq. 4) ties a scene point's albedo over
the window, so the window holds one albedo, and summing its prior over ``T``
frames counts it ``T`` times.  When the light does not change (one light, a
moving camera) the ``T`` shadings are one draw too, the two over-counts
cancel, and the single-image balance of ``lambda_As`` against ``lambda_Ss``
holds.  When the light changes between frames (a static object under a
moving lamp) each frame adds evidence about the shading that the albedo
prior does not share; this is what lets the temporal median of Weiss (ICCV
2001) read an albedo edge off many lights.  Dividing the albedo prior by the
window's number of independent shadings ``n`` restores the single-image
balance in both cases:

    n = 1 + gain * (T - 1) * r,   r = mean over pairs t of r_t,
    r_t = max(0, 1 - c_0 / c_t),   c_t = Var(S_{t+1}(x + u) - S_t(x))

``c_t`` is read off the input, before any solve: along the flow, where
the albedo is constant, the change of the log luminance *is* the change of
the log shading; its median is taken out (a global change of the light's
strength is no new shading), and the variance is the squared MAD scaled by
1.4826.  The log luminance is blurred first (``CHANGE_BLUR_PX``): the
change of the shading is smooth, a camera's pixel noise is not, and
unblurred, a noise of 1% of white alone gives ``c_t`` of 0.02-0.12 on a
scene under one lamp (0.001-0.016 blurred; perf/RESULTS.md).  Every pixel
whose ``x + u`` lies in the image counts: the occlusion map ``w_occ`` is
not used, because its colour test (Eq. 7) marks as occluded exactly the
pixels whose light changes most, while true occlusions are a minority the
median ignores.

``r_t`` is the share of that change above ``c_0``
(``SHADING_CHANGE_FLOOR``), the change that flow error and a lamp's slow
drift give without any new shading: 0 when the light does not change,
towards 1 when the change is many times that.  The floor is absolute (log
units) on purpose.  A ratio to the frame's own spread (the variance of the
blurred log luminance, the first form of this count) holds the albedo's
variation as well as the shading's, and on a strongly patterned object (a
printed label) the albedo's dominates, so that ratio read a light swinging
across ten directions as almost no new shading.  Measured on the training
data (perf/RESULTS.md, "The count against a fixed floor"): ``c_t`` is
0.000-0.025 per pair on the synthetic training sequences (one lamp, or a
lamp moving slowly; true and estimated flow) and 0.07-0.48 on average on
the MIT training objects (ten very different lights).  The gain
(``Params.independent_shading_gain``) sets how far a changing light
weakens the prior; both are chosen on training data.

Only lit pixels count (blurred luminance of at least ``LIT_LUMINANCE`` in
both frames): in black backgrounds and deep shadows the log is noise.
"""
from __future__ import annotations

import numpy as np

#: Gaussian sigma (pixels) of the blur of the log luminance before the change
#: is measured: it averages pixel noise out of ``c_t`` (module docstring).
CHANGE_BLUR_PX = 2.0
#: ``c_0``: the variance of the log-shading change between two frames that
#: flow error and a slowly moving lamp give without new shading (module
#: docstring); chosen on training data.
SHADING_CHANGE_FLOOR = 0.025
#: Pixels darker than this linear luminance in either frame of a pair are left out.
LIT_LUMINANCE = 0.02
#: A pair with fewer usable pixels than this says nothing and is skipped.
MIN_PIXELS = 64
#: Scales a median absolute deviation to a standard deviation (Gaussian).
MAD_TO_STD = 1.4826


def _robust_variance(values: np.ndarray) -> float:
    """``(1.4826 * MAD)^2`` of a 1-D array: a variance that ignores outliers."""
    return float((MAD_TO_STD * np.median(np.abs(values - np.median(values)))) ** 2)


def shading_changes(be, frames_linear, flow, log_floor: float) -> np.ndarray:
    """``c_t`` of each frame pair (module docstring), NaN where a pair has too few pixels.

    Parameters
    ----------
    be : backend.
    frames_linear : (T, H, W, 3) backend array, linear RGB in [0, 1].
    flow : (T-1, H, W, 2) backend array, forward flow in pixels.
    log_floor : floor of the luminance before the log.

    Returns
    -------
    (T-1,) float64 NumPy array, ``c_t >= 0`` in squared log units.
    """
    T, H, W, _ = frames_linear.shape
    lum = be.empty((T, H, W))
    be.colour.luminance(frames_linear, lum)
    log_lum = be.empty((T, H, W, 1))
    be.colour.log_floor(lum.reshape((T, H, W, 1)), log_lum, log_floor)
    blurred, scratch = be.empty((T, H, W, 1)), be.empty((T, H, W, 1))
    be.pyramid.gaussian_blur(log_lum, blurred, scratch, CHANGE_BLUR_PX)
    warped = be.empty((T - 1, H, W, 1))
    inside = be.empty((T - 1, H, W))
    be.sampling.warp_bilinear(blurred[1:], flow, warped, inside)

    B = be.numpy(blurred)[..., 0]
    B_next = be.numpy(warped)[..., 0]
    valid = be.numpy(inside) > 0.5
    lit = np.log(LIT_LUMINANCE)
    changes = np.full(T - 1, np.nan)
    for t in range(T - 1):
        use = valid[t] & (B[t] >= lit) & (B_next[t] >= lit)
        if np.count_nonzero(use) >= MIN_PIXELS:
            changes[t] = _robust_variance((B_next[t] - B[t])[use])
    return changes


def ratios_from_changes(changes: np.ndarray) -> np.ndarray:
    """``r_t = max(0, 1 - c_0 / c_t)`` in ``[0, 1)`` of the ``(T-1,)`` changes ``c_t``, NaN where ``c_t`` is."""
    changes = np.asarray(changes, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.maximum(0.0, 1.0 - SHADING_CHANGE_FLOOR / changes)     # c_t = 0: 1 - inf -> 0


def shading_change_ratios(be, frames_linear, flow, log_floor: float) -> np.ndarray:
    """``r_t`` in ``[0, 1)`` of each frame pair, NaN where ``c_t`` is; arguments as :func:`shading_changes`."""
    return ratios_from_changes(shading_changes(be, frames_linear, flow, log_floor))


def count_from_ratios(ratios: np.ndarray, gain: float, n_frames: int) -> float:
    """``n = min(T, 1 + gain (T - 1) r)`` with ``r`` the mean of the finite ``r_t``; 1 when none is."""
    ratios = np.asarray(ratios, np.float64)
    ratios = ratios[np.isfinite(ratios)]
    if ratios.size == 0 or gain == 0:
        return 1.0
    return float(min(n_frames, 1.0 + gain * (n_frames - 1) * float(np.mean(ratios))))


def independent_shadings(be, frames_linear, flow, gain: float, log_floor: float,
                         n_frames: int | None = None) -> float:
    """``n`` in ``[1, n_frames]``: the window's number of independent shadings (module docstring).

    ``r`` is read off the window's own frame pairs; ``n_frames`` (default:
    the window's ``T``) is the ``T`` of the count.  A window that carries
    frames continues an albedo the previous, full window estimated, and
    passes that window's length (``Params.window``).  1 without a flow (each
    frame is then solved on its own, and its albedo prior counts once), with
    ``gain`` 0, or when no pair has enough lit, visible pixels.  Shapes as
    :func:`shading_change_ratios`; ``flow`` may be ``None``.
    """
    T = frames_linear.shape[0]
    if flow is None or gain == 0 or T < 2:
        return 1.0
    ratios = shading_change_ratios(be, frames_linear, flow, log_floor)
    return count_from_ratios(ratios, gain, T if n_frames is None else int(n_frames))


def window_params(params, n: float):
    """``params`` for a window of ``n`` independent shadings.

    Both albedo priors (Eq. 11, 12) are divided by ``n``; and with
    ``Params.shading_step_stability_changing_light``, a window with no new
    shading (``n = 1``) does not read Weiss's cue (``shading_step_stability``
    0): with no light change to read, the cue would take a step whose
    contrast the flow's errors or a moving shadow change for light.  With
    ``Params.shading_stable_changing_light``, such a window
    has no stable-step pairs (``shading_stable_gain`` 0): under a still light
    every still step holds.  With ``Params.shading_light_edge_changing_light``
    (off by default) it has no light-edge factor either
    (``shading_light_edge_tau`` 0); off, a shadow swept by a moving object
    under a still lamp is read as the light's edge.  With
    ``Params.shading_light_edge_spread_changing_light``, the factor's width
    keeps to ``tau`` there (``shading_light_edge_spread`` 0): under a still
    light only an outline changes a still step.  Unchanged at ``n = 1``
    with every switch off.
    """
    changes = {}
    if n != 1.0:
        changes.update(lam_albedo_smooth=params.lam_albedo_smooth / n,
                       lam_albedo_sparsity=params.lam_albedo_sparsity / n)
    if params.shading_step_stability_changing_light and n <= 1.0:
        changes.update(shading_step_stability=0.0)
    if params.shading_stable_changing_light and n <= 1.0 and params.shading_stable_gain > 0:
        changes.update(shading_stable_gain=0.0)
    if params.shading_light_edge_changing_light and n <= 1.0 and params.shading_light_edge_tau > 0:
        changes.update(shading_light_edge_tau=0.0)
    if params.shading_light_edge_spread_changing_light and n <= 1.0 and params.shading_light_edge_spread > 0:
        changes.update(shading_light_edge_spread=0.0)
    return params.replace(**changes) if changes else params
