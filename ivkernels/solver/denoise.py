"""The sensor noise taken out of the solved layers.

The solve keeps ``A + S = I`` exactly (:class:`ivkernels.solver.energy.ConstrainedEnergy`),
so the input's noise has nowhere to go but into the albedo and the shading:
on a noisy video both come out grainy, while the truth of neither holds the
noise.  After a window is solved, each layer is smoothed by a bilateral
filter (``denoise.bilateral``) whose range at every pixel is
``Params.layer_denoise`` times the noise's log-luminance step there: steps
much larger than the noise (albedo edges, cast shadows) keep their sides
apart, while the noise between them averages out over the ``7 x 7`` window
(:data:`RADIUS`, :data:`SIGMA_SPACE`).

The noise's step is the window's noise level function (the median step of
each brightness bin, :func:`ivkernels.solver.step_evidence.noise_level_function`),
read from what changes between frames along the flow where there is one
(print and edges move with the surface and cancel; noise is new in every
frame), else from each frame's own steps, and read at each pixel's
brightness, in ``log i`` (``denoise.range_sigma``): a camera's noise depends
on the brightness, and in ``log i`` it grows in the dark.

Where the window's median noise step is under :data:`NOISE_TO_SMOOTH`
(clean renders, well-exposed footage) the layers are returned as solved, bit
for bit, and nothing is filtered.  The layers no longer multiply back to the
input exactly there: ``albedo * shading`` is the input less the noise taken
out (:attr:`ivkernels.IntrinsicVideo.reconstruct`).
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.reference.step_evidence import DARK_OFFSET
from ivkernels.params import Params
from ivkernels.solver.step_evidence import noise_level_function, noise_steps

#: The bilateral window's half width and its spatial Gaussian's sigma, pixels.
RADIUS = 3
SIGMA_SPACE = 2.0

#: Median noise step (log units) under which a window's layers are left as solved: at 1%,
#: twice the step is a range under which the filter changes nothing measurable
#: (perf/RESULTS.md, "The noise taken out of the layers").
NOISE_TO_SMOOTH = 0.01


def noise_step(be, frames_linear, flow, params: Params, scale: float = 1.0):
    """(T, h, w) backend array: ``scale`` times the noise's log-luminance step at each pixel, in ``log i``.

    frames_linear : (T, h, w, 3) backend array, linear RGB.
    flow : (T-1, h, w, 2) backend array or ``None`` (then each frame's own steps).
    """
    T, h, w, _ = frames_linear.shape
    log_image = be.empty((T, h, w, 3))
    be.colour.log_floor(frames_linear, log_image, params.log_floor)
    offset = be.empty((T, h, w, 3))
    be.step_evidence.offset_log(log_image, offset, DARK_OFFSET)
    steps = noise_steps(be, offset, flow)
    table = noise_level_function(be, offset, steps)
    level = be.empty((T, h, w, 2))
    be.vecops.fill(level.reshape((T * h * w * 2,)), float(np.finfo(np.float32).max))
    be.step_evidence.cap_at_level(offset, table, 1.0, level)        # the function itself at each pixel
    out = be.empty((T, h, w))
    be.denoise.range_sigma(offset, level, out, scale, DARK_OFFSET)
    return out


def denoise_layers(be, frames_linear, flow, A: np.ndarray, S: np.ndarray, params: Params):
    """The window's log albedo ``A`` (T, h, w, 3) and log shading ``S`` (T, h, w) with the noise
    taken out, and the window's median noise step (log units).

    Returns ``(A, S, noise)``: ``A`` and ``S`` themselves where ``Params.layer_denoise`` is 0 or
    the median noise step is under :data:`NOISE_TO_SMOOTH`, else new filtered arrays.
    """
    if params.layer_denoise <= 0:
        return A, S, None
    rs = noise_step(be, frames_linear, flow, params, scale=params.layer_denoise)
    noise = float(np.median(be.numpy(rs))) / params.layer_denoise
    if not noise >= NOISE_TO_SMOOTH:
        return A, S, noise
    T, h, w = S.shape
    A_out, S_out = be.empty((T, h, w, 3)), be.empty((T, h, w, 1))
    be.denoise.bilateral(be.asarray(np.ascontiguousarray(A, np.float32)), rs, A_out, RADIUS, SIGMA_SPACE)
    be.denoise.bilateral(be.asarray(np.ascontiguousarray(S, np.float32).reshape(T, h, w, 1)), rs, S_out,
                         RADIUS, SIGMA_SPACE)
    return (np.array(be.numpy(A_out), copy=True), np.array(be.numpy(S_out), copy=True).reshape(T, h, w), noise)
