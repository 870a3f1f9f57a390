"""``denoise``: the declared contract of its host functions, and the NumPy references (float64).

Sensor noise has nowhere to go in ``A + S = I``: the solve puts it into the
albedo and the shading.  These two functions take it out of them again, at
the level the input's noise level function measures:

* ``range_sigma`` turns the noise level function read at each pixel (a step
  of the offset log image ``log(i + offset)``, ``step_evidence.cap_at_level``)
  into the noise's step in ``log i``, times ``scale``: a step of ``d`` in
  ``log(i + offset)`` is one of ``d (i + offset) / i`` in ``log i``, with
  ``i`` held at least ``offset / 10`` (the factor at most 11);
* ``bilateral`` smooths a log layer with a bilateral filter (Tomasi &
  Manduchi 1998) whose range at each pixel is that step: neighbours that
  differ from the pixel by much more than the noise (an albedo edge, a cast
  shadow) keep their own values, and the noise between them averages out.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Family, FinitePositive, Int, NonNegative, Out, Rule

FAMILY = Family("denoise", "Edge-preserving smoothing of the solved layers at the input's noise level.")

#: Smallest brightness, as a fraction of ``offset``, at which ``range_sigma`` converts a step.
DARK_FRACTION = 0.1

FAMILY.declare("range_sigma(offset_image, level, out, scale, offset)",
               "``out = scale * level[..., 0] * e / max(e - offset, offset / 10)``, ``e = exp(mean_c "
               "offset_image)``: the noise level's log-luminance step in units of ``log i``.",
               offset_image="T H W 3", level="T H W 2", out=Out("T H W"), scale=NonNegative, offset=FinitePositive)


def _channels(sizes, args):
    if not 1 <= sizes["C"] <= 3:
        raise ValueError(f"src must have 1 to 3 channels (a log shading or a log albedo), "
                         f"got shape {tuple(args['src'].shape)}")


FAMILY.declare("bilateral(src, range_sigma, out, radius, sigma_space)",
               "``out(x) = sum_y w src(y) / sum_y w`` over the ``(2 radius + 1)^2`` window inside the frame, "
               "``w = exp(-|y - x|^2 / (2 sigma_space^2) - mean_c (src(y) - src(x))^2 / (2 range_sigma(x)^2))``; "
               "a pixel with ``range_sigma <= 0`` keeps its value.",
               src="T H W C", range_sigma="T H W", out=Out("T H W C"), radius=Int(0), sigma_space=FinitePositive,
               rules=(Rule(_channels),),
               separate=(("out", "src", "every output pixel reads its neighbours in src"),
                         ("out", "range_sigma", "the output is written while range_sigma is read")))


def range_sigma(offset_image, level, scale: float, offset: float) -> np.ndarray:
    """(T, H, W) float64: ``scale`` times the log-luminance channel of ``level`` (T, H, W, 2), a
    step of ``log(i + offset)``, as a step of ``log i`` at the pixel's brightness ``i = e - offset``,
    ``e = exp(mean_c offset_image)``, with ``i`` held at least ``DARK_FRACTION * offset``."""
    e = np.exp(np.asarray(offset_image, np.float64).mean(axis=-1))
    brightness = np.maximum(e - offset, DARK_FRACTION * offset)
    return scale * np.asarray(level, np.float64)[..., 0] * e / brightness


def bilateral(src, range_sigma, radius: int, sigma_space: float) -> np.ndarray:
    """(T, H, W, C) float64: the bilateral filter of ``src`` (T, H, W, C) with a range of
    ``range_sigma`` (T, H, W) at each centre pixel and a spatial Gaussian of ``sigma_space``
    pixels over the ``(2 radius + 1)^2`` window, neighbours outside the frame left out; the
    range compares the mean over channels of the squared differences.  Where ``range_sigma <= 0``
    the pixel keeps its value."""
    src = np.asarray(src, np.float64)
    rs = np.asarray(range_sigma, np.float64)
    T, H, W, _ = src.shape
    num = np.zeros_like(src)
    den = np.zeros((T, H, W))
    inv_range = np.where(rs > 0, 1.0 / (2.0 * np.where(rs > 0, rs, 1.0) ** 2), 0.0)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            ys, yd = slice(max(dy, 0), H + min(dy, 0)), slice(max(-dy, 0), H + min(-dy, 0))
            xs, xd = slice(max(dx, 0), W + min(dx, 0)), slice(max(-dx, 0), W + min(-dx, 0))
            centre = src[:, yd, xd]
            other = src[:, ys, xs]
            d2 = ((other - centre) ** 2).mean(axis=-1)
            w = np.exp(-(dy * dy + dx * dx) / (2.0 * sigma_space ** 2) - d2 * inv_range[:, yd, xd])
            num[:, yd, xd] += w[..., None] * other
            den[:, yd, xd] += w
    out = num / den[..., None]
    return np.where((rs > 0)[..., None], out, src)
