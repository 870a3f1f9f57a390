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

__all__ = ["chromatic_share", "step_evidence", "step_gate", "DARK_OFFSET"]

NEIGHBOURS_8 = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]

#: Linear offset added before the log when reading steps: ``log(i + DARK_OFFSET)``.
#: In the darkest pixels a log step says little (sensor noise and compression
#: there are large relative changes, and chromaticity is noise); the offset
#: damps them, as Retinex implementations do.
DARK_OFFSET = 0.02


def _offset_log(log_image: np.ndarray) -> np.ndarray:
    return np.log(np.exp(np.asarray(log_image, np.float32)) + np.float32(DARK_OFFSET))


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
    I = _offset_log(log_image)
    L = I.mean(axis=-1)
    C = I - L[..., None]
    sharp_steps = chromatic_steps = 0
    for dy, dx in ((0, 1), (1, 0)):
        h, w = L.shape[1] - dy, L.shape[2] - dx
        dL = np.abs(L[:, :h, :w] - L[:, dy:, dx:])
        dC = np.abs(C[:, :h, :w] - C[:, dy:, dx:]).max(axis=-1)
        chromatic = dC > tau_chroma
        sharp_steps += int(np.count_nonzero(chromatic | (dL > tau)))
        chromatic_steps += int(np.count_nonzero(chromatic))
    return chromatic_steps / sharp_steps if sharp_steps else 0.0


def step_evidence(log_image: np.ndarray, tau: float, tau_chroma: float) -> np.ndarray:
    """Evidence in [0, 1) that a pixel lies on a sharp grey step, (T, h, w) float32.

    log_image : (T, h, w, 3) float, ``I = log i``.
    tau : > 0, the log-luminance step at which a step counts ``1 - 1/e``.
    tau_chroma : > 0, the change of log chromaticity at which a step counts
        ``1/e`` as grey; ``inf``: chromaticity is not looked at.
    Border pixels compare with the neighbours they have.
    """
    I = _offset_log(log_image)
    L = I.mean(axis=-1)
    C = I - L[..., None]
    T, h, w = L.shape
    out = np.zeros((T, h, w), np.float32)
    for dy, dx in NEIGHBOURS_8:
        ys, yn = slice(max(0, -dy), h - max(0, dy)), slice(max(0, dy), h + min(0, dy))
        xs, xn = slice(max(0, -dx), w - max(0, dx)), slice(max(0, dx), w + min(0, dx))
        dL = L[:, ys, xs] - L[:, yn, xn]
        ev = 1.0 - np.exp(-(dL / np.float32(tau)) ** 2)
        if np.isfinite(tau_chroma):
            dC = np.abs(C[:, ys, xs] - C[:, yn, xn]).max(axis=-1)
            ev *= np.exp(-(dC / np.float32(tau_chroma)) ** 2)
        np.maximum(out[:, ys, xs], ev, out=out[:, ys, xs])
    return out


def step_gate(log_image: np.ndarray, gain: float, tau: float, tau_chroma: float = np.inf) -> np.ndarray:
    """Weight ``1 + gain * step_evidence(...)`` per pixel, (T, h, w) float32.

    gain : >= 0, how much more a sharp grey step costs the shading (0: weight 1).
    tau, tau_chroma : see :func:`step_evidence`.
    """
    for name, value, low_open in (("gain", gain, False), ("tau", tau, True), ("tau_chroma", tau_chroma, True)):
        bad = not (value > 0 if low_open else value >= 0) or (name != "tau_chroma" and not np.isfinite(value))
        if bad or np.isnan(value):
            raise ValueError(f"{name} must be a {'positive' if low_open else 'non-negative'} number, got {value!r}")
    return (1.0 + gain * step_evidence(log_image, tau, tau_chroma)).astype(np.float32)
