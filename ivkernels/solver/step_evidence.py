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
largest channel).  Coloured steps keep the calibrated balance of Eq. 9 and
Eq. 11; a sharp grey step costs the shading up to ``1 + gain`` times more,
and goes to the albedo unless the data or the temporal terms say otherwise.
"""
from __future__ import annotations

import numpy as np

__all__ = ["chromatic_share", "local_chromatic_share", "grey_step_gate", "step_evidence", "step_gate",
           "DARK_OFFSET", "SHARE_PRIOR_STEPS"]

#: Half of the eight neighbour offsets: with them every pair of neighbours is
#: seen once, and a pair's evidence, which does not depend on its order, goes
#: to both of its pixels.
HALF_NEIGHBOURS = ((0, 1), (1, 0), (1, 1), (1, -1))

#: The horizontal and vertical pairs, over which :func:`chromatic_share` counts.
AXIS_NEIGHBOURS = ((0, 1), (1, 0))

#: Linear offset added before the log when reading steps: ``log(i + DARK_OFFSET)``.
#: In the darkest pixels a log step says little (sensor noise and compression
#: there are large relative changes, and chromaticity is noise); the offset
#: damps them, as Retinex implementations do.
DARK_OFFSET = 0.02


def _luminance_chroma(log_image: np.ndarray):
    """``L`` (T, h, w) and ``C`` (T, h, w, 3): mean and chromaticity of ``log(i + DARK_OFFSET)``."""
    I = np.log(np.exp(np.asarray(log_image, np.float32)) + np.float32(DARK_OFFSET))
    L = I.mean(axis=-1)
    return L, I - L[..., None]


def _pair_slices(shape, dy: int, dx: int):
    """Index tuples of the pixels ``x`` and of their neighbours ``x + (dy, dx)`` (``dy >= 0``)."""
    _, h, w = shape
    xs, xn = slice(max(0, -dx), w - max(0, dx)), slice(max(0, dx), w + min(0, dx))
    return (slice(None), slice(0, h - dy), xs), (slice(None), slice(dy, h), xn)


#: Weight of the whole video's chromatic share in a window's (:func:`local_chromatic_share`),
#: in steps: a window with few sharp steps of its own leans on the video's share.
SHARE_PRIOR_STEPS = 4.0


def _chroma_change(C, a, b) -> np.ndarray:
    return np.abs(C[a] - C[b]).max(axis=-1)


def _share(L, C, tau: float, tau_chroma: float) -> float:
    sharp_steps = chromatic_steps = 0
    for dy, dx in AXIS_NEIGHBOURS:
        a, b = _pair_slices(L.shape, dy, dx)
        chromatic = _chroma_change(C, a, b) > tau_chroma
        sharp_steps += int(np.count_nonzero(chromatic | (np.abs(L[a] - L[b]) > tau)))
        chromatic_steps += int(np.count_nonzero(chromatic))
    return chromatic_steps / sharp_steps if sharp_steps else 0.0


def _step_counts(L, C, tau: float, tau_chroma: float):
    """Per pixel, its sharp and its chromatic steps to the right and below, (T, h, w) each."""
    sharp = np.zeros(L.shape, np.float64)
    chromatic = np.zeros(L.shape, np.float64)
    for dy, dx in AXIS_NEIGHBOURS:
        a, b = _pair_slices(L.shape, dy, dx)
        is_chromatic = _chroma_change(C, a, b) > tau_chroma
        sharp[a] += is_chromatic | (np.abs(L[a] - L[b]) > tau)
        chromatic[a] += is_chromatic
    return sharp, chromatic


def _box_sum(x: np.ndarray, r: int) -> np.ndarray:
    """Sum of each frame of ``x`` (T, h, w) over the (2r+1)^2 window at every pixel, cut at the borders."""
    _, h, w = x.shape
    c = np.zeros((x.shape[0], h + 1, w + 1), np.float64)
    c[:, 1:, 1:] = x.cumsum(1).cumsum(2)
    y0, y1 = np.clip(np.arange(h) - r, 0, h), np.clip(np.arange(h) + r + 1, 0, h)
    x0, x1 = np.clip(np.arange(w) - r, 0, w), np.clip(np.arange(w) + r + 1, 0, w)
    return (c[:, y1][:, :, x1] - c[:, y0][:, :, x1] - c[:, y1][:, :, x0] + c[:, y0][:, :, x0])


def _local_share(L, C, tau: float, tau_chroma: float, radius: float) -> np.ndarray:
    sharp, chromatic = _step_counts(L, C, tau, tau_chroma)
    total = sharp.sum()
    whole = chromatic.sum() / total if total else 0.0
    r = max(1, int(round(radius * min(L.shape[1:]))))
    return ((_box_sum(chromatic, r) + SHARE_PRIOR_STEPS * whole)
            / (_box_sum(sharp, r) + SHARE_PRIOR_STEPS)).astype(np.float32)


def _evidence(L, C, tau: float, tau_chroma: float) -> np.ndarray:
    out = np.zeros(L.shape, np.float32)
    for dy, dx in HALF_NEIGHBOURS:
        a, b = _pair_slices(L.shape, dy, dx)
        ev = 1.0 - np.exp(-((L[a] - L[b]) / np.float32(tau)) ** 2)
        if np.isfinite(tau_chroma):
            ev *= np.exp(-(_chroma_change(C, a, b) / np.float32(tau_chroma)) ** 2)
        np.maximum(out[a], ev, out=out[a])
        np.maximum(out[b], ev, out=out[b])
    return out


def _check(gain: float, tau: float, tau_chroma: float) -> None:
    if not (np.isfinite(gain) and gain >= 0):
        raise ValueError(f"gain must be a non-negative number, got {gain!r}")
    if not (np.isfinite(tau) and tau > 0):
        raise ValueError(f"tau must be a positive number, got {tau!r}")
    if not tau_chroma > 0:
        raise ValueError(f"tau_chroma must be a positive number, got {tau_chroma!r}")


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
    return _share(*_luminance_chroma(log_image), tau, tau_chroma)


def local_chromatic_share(log_image: np.ndarray, tau: float, tau_chroma: float, radius: float) -> np.ndarray:
    """:func:`chromatic_share` read around each pixel, (T, h, w) float32 in [0, 1].

    The share of the sharp steps inside a square window of half-side
    ``radius * min(h, w)`` pixels (at least 1) of the pixel's frame that change
    colour, with :data:`SHARE_PRIOR_STEPS` steps of the whole video's share
    added, so that a window with few steps of its own leans on the video's.
    A grey floor beside coloured walls and objects keeps a low share where
    the floor is, which one number for the whole scene would not.
    """
    return _local_share(*_luminance_chroma(log_image), tau, tau_chroma, radius)


def step_evidence(log_image: np.ndarray, tau: float, tau_chroma: float) -> np.ndarray:
    """Evidence in [0, 1) that a pixel lies on a sharp grey step, (T, h, w) float32.

    log_image : (T, h, w, 3) float, ``I = log i`` (read as ``log(i + DARK_OFFSET)``).
    tau : > 0, the log-luminance step at which a step counts ``1 - 1/e``.
    tau_chroma : > 0, the change of log chromaticity at which a step counts
        ``1/e`` as grey; ``inf``: chromaticity is not looked at.
    Border pixels compare with the neighbours they have.
    """
    return _evidence(*_luminance_chroma(log_image), tau, tau_chroma)


def step_gate(log_image: np.ndarray, gain: float, tau: float, tau_chroma: float = np.inf) -> np.ndarray:
    """Weight ``1 + gain * step_evidence(...)`` per pixel, (T, h, w) float32.

    gain : >= 0, how much more a sharp grey step costs the shading (0: weight 1).
    tau, tau_chroma : see :func:`step_evidence`.
    """
    _check(gain, tau, tau_chroma)
    return (1.0 + gain * step_evidence(log_image, tau, tau_chroma)).astype(np.float32)


def grey_step_gate(log_image: np.ndarray, gain: float, tau: float, tau_chroma: float = np.inf,
                   share_radius: float = 0.0) -> np.ndarray:
    """The weight Eq. 9's local term uses: :func:`step_gate` with the gain scaled
    by ``(1 - share)^2`` (unscaled when ``tau_chroma`` is ``inf``), reading the
    image once for both; (T, h, w) float32.  The share is
    :func:`local_chromatic_share` with ``share_radius`` > 0, else the whole
    video's :func:`chromatic_share`."""
    _check(gain, tau, tau_chroma)
    if not (np.isfinite(share_radius) and share_radius >= 0):
        raise ValueError(f"share_radius must be a non-negative number, got {share_radius!r}")
    L, C = _luminance_chroma(log_image)
    evidence = _evidence(L, C, tau, tau_chroma)
    if not np.isfinite(tau_chroma):
        return (1.0 + gain * evidence).astype(np.float32)
    # trust a grey step as albedo as much as the albedo edges around it are grey
    if share_radius > 0:
        return (1.0 + gain * (1.0 - _local_share(L, C, tau, tau_chroma, share_radius)) ** 2
                * evidence).astype(np.float32)
    return (1.0 + gain * (1.0 - _share(L, C, tau, tau_chroma)) ** 2 * evidence).astype(np.float32)
