"""The step evidence on Eq. 9's local shading term (Retinex's and Weiss's cues), on the backend's arrays.

* :func:`offset_log`: the log image read with a linear offset, ``log(i + offset)``,
* :func:`typical_steps` and :func:`temporal_steps`: per pixel, the larger step
  of its right and lower pairs, of the frame itself or of what changes from
  one frame to the next along the flow (their 5x5 median is the noise floor),
* :func:`step_histogram`, :func:`level_medians` and :func:`cap_at_level`: the
  window's noise level function (the median step per brightness bin, on the
  device) and the floor capped at a multiple of it,
* :func:`step_counts`: per row, the sharp and the chromatic steps of the
  horizontal and vertical pairs it starts (the chromatic share's counts),
* :func:`pixel_counts`: per pixel, the same counts read in float64 (the
  share read around each pixel),
* :func:`share_weight`: ``weight *= (1 - s)^2``, ``s`` the share of the
  window around each pixel (running window sums of the per-pixel counts),
* :func:`step_gate`: ``gate *= 1 + gain (1 - s)^2 weight evidence``, the share
  ``s`` summed from the counts on the device (no host round trip),
* :func:`still_stability`: Weiss's stability cue (``maps.shading_gate``) where
  the scene holds still, 1 where it moves.
* :func:`stable_pairs`: Weiss's stable-step evidence of each pixel's right and
  lower pair over the window's frames (the median of the pair's step and its
  largest deviation from it), where the pair holds still.
* :func:`moving_steps`: the light's own edges, per pixel and frame: the
  smallest over its still pairs of ``exp(-((s_t - m) / w)^2)``, the width
  ``w = sqrt(tau^2 + (spread MAD)^2)`` grown by the pair's own spread.

The formula, its constants and the NumPy reference:
:mod:`ivkernels.kernels.reference.step_evidence`; its use in the energy:
:mod:`ivkernels.solver.step_evidence`.  One thread per row ``t * H + y`` (per column ``t * W + x``
for the vertical window sums).
"""
from __future__ import annotations

import numpy as np
import warp as wp

from ivkernels.kernels.cache import cached
from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import gpu_layout, launch_rows, row_tiles
from ivkernels.kernels.thread_count import get_threads
from ivkernels.kernels.reference.step_evidence import (FAMILY, MAX_STABLE_STEP, NOISE_LEVEL_MIN_COUNT,
                                                       least_stable_step, level_axis, level_edges, step_edges)
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.maps import log_change_at
from ivkernels.kernels.warp.row_tiles import frame_row, row_span

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

#: Below this argument ``exp(-a)`` and ``1 - exp(-a)`` are read from their series to ``a^3``:
#: in a video most neighbours differ little, and an ``exp`` costs about as much as the rest of a pair.
SERIES_BELOW = wp.constant(1.0e-3)

#: :data:`ivkernels.kernels.reference.step_evidence.MAX_STABLE_STEP` on the device.
STABLE_STEP_MAX = wp.constant(MAX_STABLE_STEP)


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def exp_neg(a: float):
    """``exp(-a)`` for ``a >= 0``; below :data:`SERIES_BELOW` its series to ``a^3`` (off by
    under ``a^4 / 24``, 4e-14), the case of most pairs, which skips the ``exp``."""
    if a < SERIES_BELOW:
        return 1.0 - a * (1.0 - a * (0.5 - a * (1.0 / 6.0)))
    return wp.exp(-a)


@wp.func
def one_minus_exp_neg(a: float):
    """``1 - exp(-a)`` for ``a >= 0``, by its series below :data:`SERIES_BELOW` (as :func:`exp_neg`;
    more accurate in float32 than the difference, which cancels)."""
    if a < SERIES_BELOW:
        return a * (1.0 - a * (0.5 - a * (1.0 / 6.0)))
    return 1.0 - wp.exp(-a)


@wp.func
def vec_step(a: wp.vec3, b: wp.vec3):
    """``(dL, dC)`` of two 3-channel log values: the step of the mean over channels and the
    largest change of the rest (the log chromaticity)."""
    d = a - b
    m = (d[0] + d[1] + d[2]) / 3.0
    return wp.abs(m), wp.max(wp.max(wp.abs(d[0] - m), wp.abs(d[1] - m)), wp.abs(d[2] - m))


@wp.func
def pixel(img: wp.array4d(dtype=float), t: int, y: int, x: int):
    """The 3 channels of a pixel."""
    return wp.vec3(img[t, y, x, 0], img[t, y, x, 1], img[t, y, x, 2])


@wp.func
def pair_step(img: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int, xx: int):
    """:func:`vec_step` of the pixels ``(y, x)`` and ``(yy, xx)`` of frame ``t``."""
    return vec_step(pixel(img, t, y, x), pixel(img, t, yy, xx))


@wp.func
def rounded_target(position: int, shift: float, size: int):
    """The pixel ``position + shift`` rounds to, ``floor(. + 0.5)``, clamped to ``[0, size - 1]``
    (a NaN shift gives 0)."""
    target = wp.floor(float(position) + shift + 0.5)
    index = int(0)
    if target > 0.0:
        index = int(wp.min(target, float(size - 1)))
    return index


@wp.func
def change_along_flow(img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float), p: int, y: int, x: int):
    """``img[p + 1, x + round(u(x))] - img[p, x]`` (3 channels), the target clamped to the frame."""
    ty = rounded_target(y, flow[p, y, x, 1], img.shape[1])
    tx = rounded_target(x, flow[p, y, x, 0], img.shape[2])
    return pixel(img, p + 1, ty, tx) - pixel(img, p, y, x)


@wp.func
def net_of_floor(d: float, floor: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int, xx: int, c: int,
                 k: float):
    """``sqrt(max(d^2 - k^2 (f(y, x)^2 + f(yy, xx)^2) / 2, 0))`` with ``f = floor[t, ..., c]``; ``d`` for ``k = 0``."""
    if k <= 0.0:
        return d
    fa = floor[t, y, x, c]
    fb = floor[t, yy, xx, c]
    return wp.sqrt(wp.max(d * d - k * k * (fa * fa + fb * fb) / 2.0, 0.0))


@wp.func
def net_step(img: wp.array4d(dtype=float), floor: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int,
             xx: int, k: float):
    """:func:`pair_step` net of the noise ``floor`` (channel 0 for ``dL``, 1 for ``dC``) at ``k``."""
    dl, dc = pair_step(img, t, y, x, yy, xx)
    return net_of_floor(dl, floor, t, y, x, yy, xx, 0, k), net_of_floor(dc, floor, t, y, x, yy, xx, 1, k)


@wp.func
def pair_counts(img: wp.array4d(dtype=float), floor: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int,
                xx: int, tau: float, tau_chroma: float, k: float):
    """``(sharp, chromatic)``, each 0 or 1, of one pair of neighbours."""
    dl, dc = net_step(img, floor, t, y, x, yy, xx, k)
    chromatic = int(0)
    if tau_chroma > 0.0:
        if dc > tau_chroma:
            chromatic = 1
    sharp = chromatic
    if dl > tau:
        sharp = 1
    return sharp, chromatic


@wp.func
def pair_evidence(img: wp.array4d(dtype=float), floor: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int,
                  xx: int, tau: float, tau_chroma: float, k: float):
    """``(1 - exp(-(dL / tau)^2)) * exp(-(dC / tau_chroma)^2)`` (the second factor 1 for ``tau_chroma = 0``),
    the steps net of the noise ``floor`` at ``k``."""
    dl, dc = net_step(img, floor, t, y, x, yy, xx, k)
    q = dl / tau
    ev = one_minus_exp_neg(q * q)
    if tau_chroma > 0.0:
        qc = dc / tau_chroma
        ev = ev * exp_neg(qc * qc)
    return ev


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@wp.kernel
def typical_steps_rows(row_begin: int, img: wp.array4d(dtype=float), steps: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
        sl = float(0.0)
        sc = float(0.0)
        if x + 1 < width:
            dl, dc = pair_step(img, t, y, x, y, x + 1)
            sl = wp.max(sl, dl)
            sc = wp.max(sc, dc)
        if y + 1 < height:
            dl, dc = pair_step(img, t, y, x, y + 1, x)
            sl = wp.max(sl, dl)
            sc = wp.max(sc, dc)
        steps[t, y, x, 0] = sl
        steps[t, y, x, 1] = sc


@wp.kernel
def temporal_steps_rows(row_begin: int, img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                        steps: wp.array4d(dtype=float)):
    """Row ``t * H + y``: :func:`typical_steps_rows` of the change along the flow of the frame's pair
    (the last frame's: the pair before), over ``sqrt 2``; 0 without a pair."""
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    n_pairs = flow.shape[0]
    p = wp.min(t, n_pairs - 1)
    for x in range(width):
        sl = float(0.0)
        sc = float(0.0)
        if n_pairs > 0:
            e = change_along_flow(img, flow, p, y, x)
            if x + 1 < width:
                dl, dc = vec_step(e, change_along_flow(img, flow, p, y, x + 1))
                sl = wp.max(sl, dl)
                sc = wp.max(sc, dc)
            if y + 1 < height:
                dl, dc = vec_step(e, change_along_flow(img, flow, p, y + 1, x))
                sl = wp.max(sl, dl)
                sc = wp.max(sc, dc)
        steps[t, y, x, 0] = sl / wp.sqrt(2.0)
        steps[t, y, x, 1] = sc / wp.sqrt(2.0)


@wp.func
def bin_of(value: float, edges: wp.array(dtype=float)):
    """How many inner edges ``edges[1:-1]`` are ``<= value`` (a binary search; NaN: 0)."""
    lo = int(0)
    hi = edges.shape[0] - 2                 # the answer lies in [lo, hi]
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if edges[mid] <= value:
            lo = mid
        else:
            hi = mid - 1
    return lo


@wp.func
def mean_channel(img: wp.array4d(dtype=float), t: int, y: int, x: int):
    """The mean over the 3 channels of pixel ``(t, y, x)``: the log luminance ``L``."""
    return (img[t, y, x, 0] + img[t, y, x, 1] + img[t, y, x, 2]) / 3.0


@wp.kernel
def step_histogram_rows(row_begin: int, band_rows: int, per_band: int, img: wp.array4d(dtype=float),
                        steps: wp.array4d(dtype=float), levels: wp.array(dtype=float),
                        bins: wp.array(dtype=float), partial: wp.array4d(dtype=wp.int32)):
    """Thread ``band``: rows ``[band * band_rows, (band + 1) * band_rows)`` counted into the histogram
    ``partial[band * per_band]``.  On a GPU one row a thread, every thread into ``partial[0]``
    (``per_band = 0``) with atomics; on the CPU, where Warp's atomics are plain adds, a band a
    thread, each into its own histogram (``per_band = 1``)."""
    band = row_begin + wp.tid()
    slot = band * per_band
    height = img.shape[1]
    r_end = wp.min((band + 1) * band_rows, img.shape[0] * height)
    for r in range(band * band_rows, r_end):
        t = r // height
        y = r - t * height
        for x in range(img.shape[2]):
            b = bin_of(mean_channel(img, t, y, x), levels)
            for c in range(2):
                wp.atomic_add(partial, slot, c, b, bin_of(steps[t, y, x, c], bins), 1)


@wp.kernel
def sum_bands(partial: wp.array4d(dtype=wp.int32), counts: wp.array3d(dtype=wp.int32)):
    """Thread ``(c, b, j)``: ``counts[c, b, j]``, the sum of the bands' histograms."""
    c, b, j = wp.tid()
    total = int(0)
    for band in range(partial.shape[0]):
        total += partial[band, c, b, j]
    counts[c, b, j] = total


@wp.kernel
def level_medians_channels(counts: wp.array3d(dtype=wp.int32), log_edges: wp.array(dtype=float),
                           min_count: int, table: wp.array2d(dtype=float)):
    """Thread ``c``: the median step of each brightness bin (the bins under ``min_count`` pixels
    marked -1), then the marked bins interpolated between their nearest counted neighbours.
    Medians are positive, so the sign tells a counted bin: a filled bin holds ``-2 - value``
    until every bin is filled (the bins after it look past it, as ``np.interp`` over the
    counted bins does), then its value."""
    c = wp.tid()
    n_levels = counts.shape[1]
    n_steps = counts.shape[2]
    for b in range(n_levels):
        n = int(0)
        for j in range(n_steps):
            n += counts[c, b, j]
        value = float(-1.0)
        if n >= min_count:
            half = float(n) / 2.0
            cumulative = int(0)
            j = int(0)
            while float(cumulative + counts[c, b, j]) < half:
                cumulative += counts[c, b, j]
                j += 1
            frac = (half - float(cumulative)) / float(counts[c, b, j])
            value = wp.exp(log_edges[j] + frac * (log_edges[j + 1] - log_edges[j]))
        table[c, b] = value
    for b in range(n_levels):
        if table[c, b] < 0.0:
            below = int(b - 1)
            while below >= 0 and table[c, below] < 0.0:
                below -= 1
            above = int(b + 1)
            while above < n_levels and table[c, above] < 0.0:
                above += 1
            value = float(0.0)
            if below >= 0 and above < n_levels:
                f = float(b - below) / float(above - below)
                value = table[c, below] * (1.0 - f) + table[c, above] * f
            elif below >= 0:
                value = table[c, below]
            elif above < n_levels:
                value = table[c, above]
            # a filled bin is not a counted one: the bins after it look past it
            table[c, b] = -2.0 - value
    for b in range(n_levels):
        if table[c, b] <= -2.0:
            table[c, b] = -2.0 - table[c, b]


@wp.kernel
def cap_at_level_rows(row_begin: int, img: wp.array4d(dtype=float), table: wp.array2d(dtype=float),
                      lo: float, width: float, scale: float, floor: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = img.shape[1]
    t = r // height
    y = r - t * height
    last = table.shape[1] - 1
    for x in range(img.shape[2]):
        u = (mean_channel(img, t, y, x) - lo) / width - 0.5
        if not (u > 0.0):                   # below the first centre, or NaN
            u = 0.0
        u = wp.min(u, float(last))
        i0 = wp.min(int(wp.floor(u)), last)
        i1 = wp.min(i0 + 1, last)
        f = u - float(i0)
        for c in range(2):
            level = table[c, i0] * (1.0 - f) + table[c, i1] * f
            floor[t, y, x, c] = wp.min(floor[t, y, x, c], scale * level)


@wp.kernel
def offset_log_rows(row_begin: int, img: wp.array4d(dtype=float), out: wp.array4d(dtype=float), offset: float):
    r = row_begin + wp.tid()
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(img.shape[2]):
        for c in range(3):
            out[t, y, x, c] = wp.log(wp.exp(img[t, y, x, c]) + offset)


@wp.kernel
def step_counts_rows(row_begin: int, img: wp.array4d(dtype=float), counts: wp.array2d(dtype=wp.int32),
                     tau: float, tau_chroma: float, floor: wp.array4d(dtype=float), k: float):
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    sharp = int(0)
    chromatic = int(0)
    for x in range(width):
        if x + 1 < width:
            s, c = pair_counts(img, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
            sharp += s
            chromatic += c
        if y + 1 < height:
            s, c = pair_counts(img, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
            sharp += s
            chromatic += c
    counts[r, 0] = sharp
    counts[r, 1] = chromatic


@wp.kernel
def luminance_chroma_rows(row_begin: int, img: wp.array4d(dtype=float), lc: wp.array4d(dtype=wp.float64),
                          offset: wp.float64):
    """``lc[t, y, x] = (L, C_0, C_1, C_2)`` of ``I' = log(exp(img) + offset)`` in float64, the operations
    of the NumPy reference in its order: ``L = (I'_0 + I'_1 + I'_2) / 3``, ``C_c = I'_c - L``."""
    r = row_begin + wp.tid()
    height = img.shape[1]
    t = r // height
    y = r - t * height
    for x in range(img.shape[2]):
        i0 = wp.log(wp.exp(wp.float64(img[t, y, x, 0])) + offset)
        i1 = wp.log(wp.exp(wp.float64(img[t, y, x, 1])) + offset)
        i2 = wp.log(wp.exp(wp.float64(img[t, y, x, 2])) + offset)
        m = (i0 + i1 + i2) / wp.float64(3.0)
        lc[t, y, x, 0] = m
        lc[t, y, x, 1] = i0 - m
        lc[t, y, x, 2] = i1 - m
        lc[t, y, x, 3] = i2 - m


@wp.func
def net_of_floor64(d: wp.float64, floor: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int, xx: int,
                   c: int, k: wp.float64):
    """:func:`net_of_floor` in float64 (the floor read as float64)."""
    if k <= wp.float64(0.0):
        return d
    fa = wp.float64(floor[t, y, x, c])
    fb = wp.float64(floor[t, yy, xx, c])
    return wp.sqrt(wp.max(d * d - k * k * (fa * fa + fb * fb) / wp.float64(2.0), wp.float64(0.0)))


@wp.func
def pair_counts64(lc: wp.array4d(dtype=wp.float64), floor: wp.array4d(dtype=float), t: int, y: int, x: int,
                  yy: int, xx: int, tau: wp.float64, tau_chroma: wp.float64, k: wp.float64):
    """``(sharp, chromatic)``, each 0 or 1, of one pair from the float64 ``(L, C)`` of :func:`luminance_chroma_rows`,
    the steps net of the noise ``floor`` at ``k``."""
    dc = wp.max(wp.max(wp.abs(lc[t, y, x, 1] - lc[t, yy, xx, 1]), wp.abs(lc[t, y, x, 2] - lc[t, yy, xx, 2])),
                wp.abs(lc[t, y, x, 3] - lc[t, yy, xx, 3]))
    dc = net_of_floor64(dc, floor, t, y, x, yy, xx, 1, k)
    dl = net_of_floor64(wp.abs(lc[t, y, x, 0] - lc[t, yy, xx, 0]), floor, t, y, x, yy, xx, 0, k)
    chromatic = int(0)
    if tau_chroma > wp.float64(0.0):
        if dc > tau_chroma:
            chromatic = 1
    sharp = chromatic
    if dl > tau:
        sharp = 1
    return sharp, chromatic


@wp.kernel
def pixel_counts_rows(row_begin: int, lc: wp.array4d(dtype=wp.float64), counts: wp.array4d(dtype=wp.int32),
                      tau: wp.float64, tau_chroma: wp.float64, floor: wp.array4d(dtype=float), k: wp.float64):
    r = row_begin + wp.tid()
    height = lc.shape[1]
    width = lc.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
        sharp = int(0)
        chromatic = int(0)
        if x + 1 < width:
            s, c = pair_counts64(lc, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
            sharp += s
            chromatic += c
        if y + 1 < height:
            s, c = pair_counts64(lc, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
            sharp += s
            chromatic += c
        counts[t, y, x, 0] = sharp
        counts[t, y, x, 1] = chromatic


@wp.kernel
def row_window_rows(row_begin: int, counts: wp.array4d(dtype=wp.int32), sums: wp.array4d(dtype=wp.int32),
                    totals: wp.array2d(dtype=wp.int32), radius: int):
    """``sums[t, y, x]``: the counts of row ``t * H + y`` over ``[x - radius, x + radius]`` (inside the
    row), by a running sum; ``totals[t * H + y]``: the row's."""
    r = row_begin + wp.tid()
    height = counts.shape[1]
    width = counts.shape[2]
    t = r // height
    y = r - t * height
    for k in range(2):
        run = int(0)
        for x in range(wp.min(radius, width - 1) + 1):
            run += counts[t, y, x, k]
        total = int(0)
        for x in range(width):
            sums[t, y, x, k] = run
            total += counts[t, y, x, k]
            if x + radius + 1 < width:
                run += counts[t, y, x + radius + 1, k]
            if x - radius >= 0:
                run -= counts[t, y, x - radius, k]
        totals[r, k] = total


@wp.kernel
def prior_share(totals: wp.array2d(dtype=wp.int32), prior_steps: wp.float64, out: wp.array(dtype=wp.float64)):
    """One thread: ``out[0] = prior_steps * whole``, ``whole`` the chromatic share of the row ``totals``
    (0 without sharp steps); the product once, as the NumPy reference forms it."""
    sharp = wp.int64(0)
    chromatic = wp.int64(0)
    for r in range(totals.shape[0]):
        sharp += wp.int64(totals[r, 0])
        chromatic += wp.int64(totals[r, 1])
    whole = wp.float64(0.0)
    if sharp > wp.int64(0):
        whole = wp.float64(chromatic) / wp.float64(sharp)
    out[0] = prior_steps * whole


@wp.kernel
def share_weight_columns(col_begin: int, sums: wp.array4d(dtype=wp.int32), weight: wp.array3d(dtype=float),
                         radius: int, prior_whole: wp.array(dtype=wp.float64), prior_steps: wp.float64):
    """Down column ``t * W + x``: the window sums of :func:`row_window_rows` over ``[y - radius, y + radius]``
    by a running sum, ``s = (chromatic + prior_whole) / (sharp + prior_steps)`` in float64 rounded
    to float32, and ``weight *= (1 - s)^2`` in float32."""
    c = col_begin + wp.tid()
    height = sums.shape[1]
    width = sums.shape[2]
    t = c // width
    x = c - t * width
    pw = prior_whole[0]
    sharp = int(0)
    chromatic = int(0)
    for y in range(wp.min(radius, height - 1) + 1):
        sharp += sums[t, y, x, 0]
        chromatic += sums[t, y, x, 1]
    for y in range(height):
        s = float((wp.float64(chromatic) + pw) / (wp.float64(sharp) + prior_steps))
        keep = 1.0 - s
        weight[t, y, x] = weight[t, y, x] * (keep * keep)
        if y + radius + 1 < height:
            sharp += sums[t, y + radius + 1, x, 0]
            chromatic += sums[t, y + radius + 1, x, 1]
        if y - radius >= 0:
            sharp -= sums[t, y - radius, x, 0]
            chromatic -= sums[t, y - radius, x, 1]


@wp.kernel
def scaled_gain(counts: wp.array2d(dtype=wp.int32), gain: float, out: wp.array(dtype=float)):
    """One thread: ``out[0] = gain (1 - s)^2``, ``s`` the chromatic share of ``counts`` (0 without sharp steps)."""
    sharp = wp.int64(0)
    chromatic = wp.int64(0)
    for r in range(counts.shape[0]):
        sharp += wp.int64(counts[r, 0])
        chromatic += wp.int64(counts[r, 1])
    s = wp.float64(0.0)
    if sharp > wp.int64(0):
        s = wp.float64(chromatic) / wp.float64(sharp)
    keep = wp.float64(1.0) - s
    out[0] = float(wp.float64(gain) * keep * keep)


@wp.kernel
def half_pair_evidence_rows(row_begin: int, img: wp.array4d(dtype=float), pairs: wp.array4d(dtype=float),
                            tau: float, tau_chroma: float, floor: wp.array4d(dtype=float), k: float):
    """``pairs[t, y, x, k]``: the evidence of the pair of ``(y, x)`` with its neighbour
    ``(y, x) + HALF_NEIGHBOURS[k]`` = (0, 1), (1, 0), (1, 1), (1, -1); 0 where it lies outside."""
    r = row_begin + wp.tid()
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    below = y + 1 < height
    for x in range(width):
        right = x + 1 < width
        e0 = float(0.0)
        e1 = float(0.0)
        e2 = float(0.0)
        e3 = float(0.0)
        if right:
            e0 = pair_evidence(img, floor, t, y, x, y, x + 1, tau, tau_chroma, k)
        if below:
            e1 = pair_evidence(img, floor, t, y, x, y + 1, x, tau, tau_chroma, k)
            if right:
                e2 = pair_evidence(img, floor, t, y, x, y + 1, x + 1, tau, tau_chroma, k)
            if x >= 1:
                e3 = pair_evidence(img, floor, t, y, x, y + 1, x - 1, tau, tau_chroma, k)
        pairs[t, y, x, 0] = e0
        pairs[t, y, x, 1] = e1
        pairs[t, y, x, 2] = e2
        pairs[t, y, x, 3] = e3


@wp.kernel
def step_gate_rows(row_begin: int, pairs: wp.array4d(dtype=float), weight: wp.array3d(dtype=float),
                   gate: wp.array3d(dtype=float), gain: wp.array(dtype=float)):
    """``gate *= 1 + gain[0] weight ev``, ``ev`` the largest evidence of the pixel's 8 pairs:
    its own four of ``pairs`` and the four its neighbours above and to the left hold."""
    r = row_begin + wp.tid()
    height = pairs.shape[1]
    width = pairs.shape[2]
    t = r // height
    y = r - t * height
    g = gain[0]
    for x in range(width):
        ev = wp.max(wp.max(pairs[t, y, x, 0], pairs[t, y, x, 1]), wp.max(pairs[t, y, x, 2], pairs[t, y, x, 3]))
        if x >= 1:
            ev = wp.max(ev, pairs[t, y, x - 1, 0])
        if y >= 1:
            ev = wp.max(ev, pairs[t, y - 1, x, 1])
            if x >= 1:
                ev = wp.max(ev, pairs[t, y - 1, x - 1, 2])
            if x + 1 < width:
                ev = wp.max(ev, pairs[t, y - 1, x + 1, 3])
        gate[t, y, x] = gate[t, y, x] * (1.0 + g * weight[t, y, x] * ev)


@wp.kernel
def log_change_rows(row_begin: int, img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                    change: wp.array4d(dtype=float)):
    """``change[p, y, x] = (D, valid)`` of ``maps.log_change_at``: the change of the mean log along
    the flow of pair ``p`` and whether its sample lies inside the image."""
    r = row_begin + wp.tid()
    height = img.shape[1]
    p = r // height
    y = r - p * height
    for x in range(img.shape[2]):
        d, valid = log_change_at(img, flow, p, y, x)
        change[p, y, x, 0] = d
        change[p, y, x, 1] = valid


@wp.kernel
def still_stability_rows(row_begin: int, flow: wp.array4d(dtype=float), change: wp.array4d(dtype=float),
                         weight: wp.array3d(dtype=float), tau: float, static_flow: float):
    """``weight = 1`` where the flow of a pair touching the frame moves, else ``maps.shading_gate``'s
    ``exp(-(e / tau)^2)`` (``tau_chroma = 0``) from the changes of ``log_change_rows``, the same
    operations in the same order."""
    r = row_begin + wp.tid()
    height = weight.shape[1]
    width = weight.shape[2]
    t = r // height
    y = r - t * height
    n_pairs = flow.shape[0]
    p = wp.min(t, n_pairs - 1)              # the frame's pair with the next frame; the last uses the one before
    for x in range(width):
        moving = int(0)
        for k in range(2):
            pk = t - k                      # the pair the frame starts (k = 0) and the one ending on it
            if pk >= 0 and pk < n_pairs:
                fx = flow[pk, y, x, 0]
                fy = flow[pk, y, x, 1]
                if wp.sqrt(fx * fx + fy * fy) >= static_flow:
                    moving = 1
        if moving != 0:
            weight[t, y, x] = 1.0
        else:
            d = change[p, y, x, 0]
            e = float(0.0)
            if change[p, y, x, 1] > 0.0:
                for j in range(3):
                    yy = y + j - 1
                    if yy >= 0 and yy < height:
                        for i in range(3):
                            xx = x + i - 1
                            if xx >= 0 and xx < width and (i != 1 or j != 1):
                                if change[p, yy, xx, 1] > 0.0:
                                    e = wp.max(e, wp.abs(d - change[p, yy, xx, 0]))
            q = e / tau
            weight[t, y, x] = wp.exp(-q * q)


@wp.kernel
def luminance_steps_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float),
                         steps: wp.array4d(dtype=float)):
    """``steps[t, y, x, k] = L(t, x + d_k) - L(t, x)``, ``L`` the mean over channels, for the right
    (k = 0) and lower (k = 1) neighbour; 0 where it lies outside."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, img.shape[2])
    height = img.shape[1]
    width = img.shape[2]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        here = mean_channel(img, t, y, x)
        right = float(0.0)
        below = float(0.0)
        if x + 1 < width:
            right = mean_channel(img, t, y, x + 1) - here
        if y + 1 < height:
            below = mean_channel(img, t, y + 1, x) - here
        steps[t, y, x, 0] = right
        steps[t, y, x, 1] = below


@wp.func
def moves(flow: wp.array4d(dtype=float), y: int, x: int, static_flow: float):
    """1 when the flow of pixel ``(y, x)`` in any frame pair is ``static_flow`` px or longer, else 0."""
    out = int(0)
    for p in range(flow.shape[0]):
        fx = flow[p, y, x, 0]
        fy = flow[p, y, x, 1]
        if wp.sqrt(fx * fx + fy * fy) >= static_flow:
            out = 1
    return out


@wp.func
def still_pair(flow: wp.array4d(dtype=float), here: int, y: int, x: int, k: int, height: int, width: int,
               static_flow: float):
    """1 when the pair of ``(y, x)`` with its right (k = 0) or lower (k = 1) neighbour lies in the
    image and holds still: ``here`` (:func:`moves` of ``(y, x)``) is 0 and so is the neighbour's."""
    yy = y + k
    xx = x + 1 - k
    out = int(0)
    if here == 0 and yy < height and xx < width:
        if moves(flow, yy, xx, static_flow) == 0:
            out = 1
    return out


@wp.func
def median_of(values: wp.array4d(dtype=float), y: int, x: int, k: int, centre: float, absolute: int):
    """The median over ``t`` of ``values[t, y, x, k] - centre`` (of its magnitude where
    ``absolute`` is 1): the mean of the order statistics ``(T - 1) // 2`` and ``T // 2``, found by
    each value's rank (ties broken by ``t``), with no buffer per thread."""
    n = values.shape[0]
    lo = float(0.0)
    hi = float(0.0)
    for i in range(n):
        v = values[i, y, x, k] - centre
        if absolute == 1:
            v = wp.abs(v)
        rank = int(0)
        for j in range(n):
            u = values[j, y, x, k] - centre
            if absolute == 1:
                u = wp.abs(u)
            if u < v or (u == v and j < i):
                rank += 1
        if rank == (n - 1) // 2:
            lo = v
        if rank == n // 2:
            hi = v
    return 0.5 * (lo + hi)


@wp.func
def largest_step(values: wp.array4d(dtype=float), y: int, x: int, k: int, centre: float):
    """``max_t |values[t, y, x, k] - centre|``."""
    out = float(0.0)
    for i in range(values.shape[0]):
        out = wp.max(out, wp.abs(values[i, y, x, k] - centre))
    return out


@wp.kernel
def stable_pairs_pixels(row_begin: int, tiles: int, steps: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                        pairs: wp.array3d(dtype=float), tau: float, stability: float, floor: float,
                        static_flow: float, least_step: float):
    """``pairs[y, x, k]``: the stable-step evidence of the pair of ``(y, x)`` with its right (k = 0)
    or lower (k = 1) neighbour from its ``T`` steps (:func:`luminance_steps_rows`); one row
    ``y`` per thread (``tiles`` per row on a GPU).  A pair none of whose steps reaches
    ``least_step`` has a median under it, so an evidence under ``floor``: 0 without the medians."""
    y, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, pairs.shape[1])
    height = pairs.shape[0]
    width = pairs.shape[1]
    for x in range(x_begin, x_end):
        here = moves(flow, y, x, static_flow)
        for k in range(2):
            ev = float(0.0)
            if still_pair(flow, here, y, x, k, height, width, static_flow) == 1:
                if largest_step(steps, y, x, k, 0.0) >= least_step:
                    m = median_of(steps, y, x, k, 0.0, 0)
                    if wp.abs(m) < STABLE_STEP_MAX:
                        q = m / tau
                        qs = largest_step(steps, y, x, k, m) / stability
                        ev = (1.0 - wp.exp(-q * q)) * wp.exp(-qs * qs)
                        if ev < floor:
                            ev = 0.0
            pairs[y, x, k] = ev


@wp.kernel
def light_edge_pairs(row_begin: int, tiles: int, steps: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                     tau: float, spread: float, static_flow: float):
    """Pass 1, each pair once: ``steps[:, y, x, k]`` (the steps of the pair of ``(y, x)`` with its
    right (k = 0) or lower (k = 1) neighbour, :func:`luminance_steps_rows`) replaced in place by
    ``exp(-((s_t - m) / w)^2)``, ``w = sqrt(tau^2 + (spread MAD)^2)``, where both pixels lie in
    the image and hold still, and by 1 elsewhere; one row ``y`` per thread (``tiles`` per row on
    a GPU).  A thread reads and writes only its own pairs' steps."""
    y, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, steps.shape[2])
    height = steps.shape[1]
    width = steps.shape[2]
    for x in range(x_begin, x_end):
        here = moves(flow, y, x, static_flow)
        for k in range(2):
            if still_pair(flow, here, y, x, k, height, width, static_flow) == 1:
                m = median_of(steps, y, x, k, 0.0, 0)
                w = tau
                if spread > 0.0:
                    widen = spread * median_of(steps, y, x, k, m, 1)
                    w = wp.sqrt(tau * tau + widen * widen)
                for t in range(steps.shape[0]):
                    q = (steps[t, y, x, k] - m) / w
                    steps[t, y, x, k] = wp.exp(-q * q)
            else:
                for t in range(steps.shape[0]):
                    steps[t, y, x, k] = 1.0


@wp.kernel
def light_edge_pixels(row_begin: int, tiles: int, pairs: wp.array4d(dtype=float), factor: wp.array3d(dtype=float)):
    """Pass 2, each pixel: ``factor[t, y, x]``, the smallest of 1 and its right, lower, left and
    upper pairs' factors of :func:`light_edge_pairs` (a pair with a moving pixel holds 1); one
    row ``t * H + y`` per thread (``tiles`` per row on a GPU)."""
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, factor.shape[2])
    t, y = frame_row(r, factor.shape[1])
    for x in range(x_begin, x_end):
        f = wp.min(float(1.0), wp.min(pairs[t, y, x, 0], pairs[t, y, x, 1]))
        if x >= 1:
            f = wp.min(f, pairs[t, y, x - 1, 0])
        if y >= 1:
            f = wp.min(f, pairs[t, y - 1, x, 1])
        factor[t, y, x] = f


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("offset_log")
def offset_log(log_image, out, offset: float) -> None:
    """``out = log(exp(log_image) + offset)``: ``log(i + offset)`` from ``log i``.

    log_image : wp.array float32 (T, H, W, 3), ``log i``.
    out : wp.array float32 (T, H, W, 3), written (may be ``log_image``).
    offset : linear offset added to the intensity, > 0 (``DARK_OFFSET`` for the step evidence).
    """
    t, h, _, _ = log_image.shape
    launch_rows(offset_log_rows, t * h, [log_image, out, offset], device=log_image.device)


def _floor_args(floor, k: float, device) -> list:
    """The kernels' ``floor, k``: without a floor, ``k = 0`` (the steps as read, as the reference
    does) and one shared (1, 1, 1, 2) placeholder that is never read."""
    if floor is not None:
        return [floor, k]
    return [cached((__name__, "no_floor", str(device)), lambda: wp.zeros((1, 1, 1, 2), dtype=float, device=device)),
            0.0]


@host("typical_steps")
def typical_steps(log_image, steps) -> None:
    """Per pixel, the larger step of its right and lower pairs: ``steps[..., 0]`` the log-luminance
    step ``dL``, ``steps[..., 1]`` the log-chromaticity change ``dC`` (0 without a pair).  Their
    5x5 median (``median.median5x5``) is the noise floor of :func:`step_counts`,
    :func:`pixel_counts` and :func:`step_gate`.

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    steps : wp.array float32 (T, H, W, 2), written.
    """
    t, h, _, _ = log_image.shape
    launch_rows(typical_steps_rows, t * h, [log_image, steps], device=log_image.device)


@host("temporal_steps")
def temporal_steps(log_image, flow, steps) -> None:
    """The steps of what changes between frames: per pixel of frame ``t``, :func:`typical_steps` of
    ``e(x) = log_image[t + 1, x + round(u(x))] - log_image[t, x]`` (the target clamped to the frame),
    over ``sqrt 2`` (a difference of two frames doubles the noise's variance); the last frame takes
    the pair before, one frame alone 0.  Sensor noise is new in every frame, while print and edges
    move with the flow and cancel: the 5x5 median of these steps is a noise floor that fine print
    does not raise.

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    flow : wp.array float32 (T-1, H, W, 2), pixels, ``(dx, dy)`` from frame ``t`` to ``t + 1``.
    steps : wp.array float32 (T, H, W, 2), written.
    """
    t, h, _, _ = log_image.shape
    launch_rows(temporal_steps_rows, t * h, [log_image, flow, steps], device=log_image.device)


def _noise_edges(device):
    """The brightness bins' edges, the step bins' edges and the log of the latter
    (:func:`~ivkernels.kernels.reference.step_evidence.level_edges`, ``step_edges``) on ``device``,
    made once."""
    return cached((__name__, "noise_edges", str(device)),
                  lambda: (wp.array(level_edges(), dtype=float, device=device),
                           wp.array(step_edges(), dtype=float, device=device),
                           wp.array(np.log(step_edges().astype(np.float64)).astype(np.float32), dtype=float,
                                    device=device)))


@host("step_histogram")
def step_histogram(log_image, steps, counts) -> None:
    """The histogram of the steps per brightness bin: ``counts[c, b, j]`` is the number of pixels
    whose log luminance ``(I_0 + I_1 + I_2) / 3`` falls in brightness bin ``b`` and whose step
    ``steps[..., c]`` falls in step bin ``j`` (fixed bins, ``reference.step_evidence.level_edges``
    and ``step_edges``; values beyond the end edges go to the end bins).  On a GPU the rows add
    with atomics; on the CPU, whose Warp atomics are plain adds, each thread counts a band of
    rows into its own histogram and the bands are summed (integers: the same counts either way).

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    steps : wp.array float32 (T, H, W, 2), :func:`temporal_steps` or :func:`typical_steps`.
    counts : wp.array int32 (2, NOISE_LEVEL_BINS, NOISE_STEP_BINS), written.
    """
    t, h, _, _ = log_image.shape
    dev = log_image.device
    levels, bins, _ = _noise_edges(dev)
    if gpu_layout(dev):
        counts.zero_()
        wp.launch(step_histogram_rows, dim=t * h,
                  inputs=[0, 1, 0, log_image, steps, levels, bins, counts.reshape((1, *counts.shape))], device=dev)
        return
    n_bands = max(1, min(get_threads(), t * h))
    partial = wp.zeros((n_bands, *counts.shape), dtype=wp.int32, device=dev)
    launch_rows(step_histogram_rows, n_bands, [-(-(t * h) // n_bands), 1, log_image, steps, levels, bins, partial],
                device=dev)
    wp.launch(sum_bands, dim=counts.shape, inputs=[partial, counts], device=dev)


@host("level_medians")
def level_medians(counts, table) -> None:
    """The noise level function from the histogram of :func:`step_histogram`: ``table[c, b]`` is
    the median step of brightness bin ``b`` (linear in the log of the step inside its step bin);
    a bin with fewer than ``NOISE_LEVEL_MIN_COUNT`` pixels takes the value interpolated between
    the nearest counted bins (the nearest one's beyond the last), 0 with none counted.

    counts : wp.array int32 (2, NOISE_LEVEL_BINS, NOISE_STEP_BINS).
    table : wp.array float32 (2, NOISE_LEVEL_BINS), written.
    """
    _, _, log_edges = _noise_edges(counts.device)
    wp.launch(level_medians_channels, dim=2, inputs=[counts, log_edges, NOISE_LEVEL_MIN_COUNT, table],
              device=counts.device)


@host("cap_at_level")
def cap_at_level(log_image, table, scale: float, floor) -> None:
    """``floor[..., c] = min(floor[..., c], scale * f_c(L))``: the floor capped at ``scale`` times
    the noise level function ``table`` (its values at the centres of the brightness bins) read at
    the pixel's log luminance ``L = (I_0 + I_1 + I_2) / 3``, linearly between the centres and flat
    beyond the first and last.

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    table : wp.array float32 (2, NOISE_LEVEL_BINS), :func:`level_medians`.
    scale : >= 0.
    floor : wp.array float32 (T, H, W, 2), capped in place.
    """
    t, h, _, _ = log_image.shape
    lo, width = level_axis()
    launch_rows(cap_at_level_rows, t * h, [log_image, table, lo, width, float(scale), floor], device=log_image.device)


@host("step_counts")
def step_counts(log_image, counts, tau: float, tau_chroma: float = 0.0, floor=None, k: float = 0.0) -> None:
    """Counts of the steps of the chromatic share.

    For each row ``r = t * H + y``, over the pairs ``(x, x + (0, 1))`` and
    ``(x, x + (1, 0))`` of its pixels ``x`` (inside the image): ``counts[r, 0]``
    the sharp steps (log-luminance step ``> tau`` or chromatic),
    ``counts[r, 1]`` the chromatic ones (log-chromaticity change
    ``> tau_chroma``; none with ``tau_chroma = 0``).

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    counts : wp.array int32 (T*H, 2), written.
    tau, tau_chroma : log units.
    floor, k : the steps are read net of the noise ``floor`` (T, H, W, 2) at ``k``
        (:func:`ivkernels.kernels.reference.step_evidence.net_steps`); ``None`` or 0: as they are.
    """
    t, h, _, _ = log_image.shape
    dev = log_image.device
    launch_rows(step_counts_rows, t * h, [log_image, counts, tau, tau_chroma, *_floor_args(floor, k, dev)],
                device=dev)


@host("pixel_counts")
def pixel_counts(log_image, counts, offset: float, tau: float, tau_chroma: float = 0.0, floor=None,
                 k: float = 0.0) -> None:
    """Counts of the steps of the chromatic share, per pixel and in float64.

    For each pixel ``x``, over its pairs ``(x, x + (0, 1))`` and ``(x, x + (1, 0))``
    inside the image: ``counts[..., 0]`` the sharp steps (log-luminance step
    ``> tau`` or chromatic), ``counts[..., 1]`` the chromatic ones
    (log-chromaticity change ``> tau_chroma``; none with ``tau_chroma = 0``),
    read on ``I' = log(exp(log_image) + offset)`` computed in float64 (a
    (T, H, W, 4) float64 buffer of this call holds its ``L`` and ``C``), as
    :func:`ivkernels.kernels.reference.step_evidence.pixel_counts` does: the
    counts equal the reference's but for a pair within a last place of
    ``exp`` or ``log`` of a threshold.

    log_image : wp.array float32 (T, H, W, 3), ``log i`` (not offset).
    counts : wp.array int32 (T, H, W, 2), written.
    offset : > 0 (``DARK_OFFSET``); tau, tau_chroma : log units.
    floor, k : as for :func:`step_counts` (the floor of the offset log image's steps).
    """
    t, h, w, _ = log_image.shape
    dev = log_image.device
    lc = wp.empty((t, h, w, 4), dtype=wp.float64, device=dev)
    launch_rows(luminance_chroma_rows, t * h, [log_image, lc, offset], device=dev)
    launch_rows(pixel_counts_rows, t * h, [lc, counts, tau, tau_chroma, *_floor_args(floor, k, dev)], device=dev)


@host("share_weight")
def share_weight(counts, weight, radius: int, prior_steps: float) -> None:
    """``weight *= (1 - s)^2`` with ``s`` the chromatic share read around each pixel.

    ``s = (chromatic + prior_steps * whole) / (sharp + prior_steps)``, ``sharp``
    and ``chromatic`` the sums of :func:`pixel_counts` ``counts`` over the
    (2 radius + 1)^2 window of the pixel's frame cut at the borders, ``whole``
    the share of the whole video (0 without sharp steps).  Window sums in
    int32 (exact: a frame holds at most ``2 H W`` steps), the division in
    float64 rounded to float32, the rest in float32: bit for bit
    :func:`ivkernels.kernels.reference.step_evidence.share_weight`.  Running
    sums along the rows (a (T, H, W, 2) int32 buffer of this call, and each
    row's total), the whole video's share from the row totals on one thread,
    then running sums down the columns.

    counts : wp.array int32 (T, H, W, 2), :func:`pixel_counts`.
    weight : wp.array float32 (T, H, W), updated.
    radius : >= 0, half-side of the window in pixels; prior_steps : > 0, steps.
    """
    t, h, w, _ = counts.shape
    if weight.size == 0:
        return
    dev = counts.device
    radius = min(radius, max(h, w))                       # the same windows, and no overflow of y + radius
    sums = wp.empty((t, h, w, 2), dtype=wp.int32, device=dev)
    totals = wp.empty((t * h, 2), dtype=wp.int32, device=dev)
    prior_whole = wp.empty(1, dtype=wp.float64, device=dev)
    launch_rows(row_window_rows, t * h, [counts, sums, totals, radius], device=dev)
    wp.launch(prior_share, dim=1, inputs=[totals, prior_steps, prior_whole], device=dev)
    launch_rows(share_weight_columns, t * w, [sums, weight, radius, prior_whole, prior_steps], device=dev)


@host("step_gate")
def step_gate(log_image, counts, weight, gate, gain: float, tau: float, tau_chroma: float = 0.0, floor=None,
              k: float = 0.0) -> None:
    """Multiply the step weight of Eq. 9's local term into ``gate``.

    ``gate *= 1 + gain (1 - s)^2 weight evidence`` with ``s`` the chromatic
    share ``sum counts[:, 1] / sum counts[:, 0]`` (0 without sharp steps),
    summed on the device, and ``evidence`` the largest over the pixel's 8
    neighbours of ``(1 - exp(-(dL / tau)^2)) exp(-(dC / tau_chroma)^2)``
    (:mod:`ivkernels.kernels.reference.step_evidence`).  Two passes: each pair
    of neighbours once into a (T, H, W, 4) buffer of this call, then each
    pixel's largest of its eight.

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    counts : wp.array int32 (T*H, 2), :func:`step_counts` of ``log_image``.
    weight : wp.array float32 (T, H, W), per pixel factor on the evidence (Weiss's cue, or 1); may be ``gate``.
    gate : wp.array float32 (T, H, W), updated.
    gain : >= 0; tau, tau_chroma : log units (``tau_chroma = 0``: colour is not looked at).
    floor, k : as for :func:`step_counts`.
    """
    t, h, w, _ = log_image.shape
    dev = log_image.device
    scaled = wp.empty(1, dtype=float, device=dev)
    wp.launch(scaled_gain, dim=1, inputs=[counts, gain, scaled], device=dev)
    # each pair once (a (T, H, W, 4) float32 buffer for this call), then each pixel's largest
    pairs = wp.empty((t, h, w, 4), dtype=float, device=dev)
    launch_rows(half_pair_evidence_rows, t * h, [log_image, pairs, tau, tau_chroma, *_floor_args(floor, k, dev)],
                device=dev)
    launch_rows(step_gate_rows, t * h, [pairs, weight, gate, scaled], device=dev)


@host("still_stability")
def still_stability(log_image, flow, weight, tau: float, static_flow: float) -> None:
    """Weiss's cue on the step evidence where the scene holds still, 1 where it moves.

    A pixel of frame ``t`` moves when the flow of the pair it starts
    (``t -> t+1``) or of the one ending on it (``t-1 -> t``) is
    ``static_flow`` pixels or longer: there ``weight = 1`` (a bilinear warp
    of a sharp step changes its contrast by itself, and the cue would take
    every moving albedo edge for light).  Elsewhere ``weight`` is
    :func:`ivkernels.kernels.warp.maps.shading_gate` with ``tau`` (and no
    colour test), bit for bit: each pixel's change along the flow is
    computed once (a (T-1, H, W, 2) buffer of this call), not once per
    neighbour.  A single frame gets 1.

    log_image : wp.array float32 (T, H, W, 3), ``log i``.
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    weight : wp.array float32 (T, H, W), written; in (0, 1].
    tau : log-contrast change at which the cue falls to 1/e, > 0.
    static_flow : pixels, > 0.
    """
    t, h, w, _ = log_image.shape
    dev = log_image.device
    if t <= 1:
        weight.fill_(1.0)
        return
    change = wp.empty((t - 1, h, w, 2), dtype=float, device=dev)
    launch_rows(log_change_rows, (t - 1) * h, [log_image, flow, change], device=dev)
    launch_rows(still_stability_rows, t * h, [flow, change, weight, tau, static_flow], device=dev)


def _luminance_steps(log_image):
    """The (T, H, W, 2) steps of the log luminance to the right and lower neighbour
    (:func:`luminance_steps_rows`) in a buffer of this call, and the row tiles of the device."""
    t, h, w, _ = log_image.shape
    dev = log_image.device
    steps = wp.empty((t, h, w, 2), dtype=float, device=dev)
    tiles = row_tiles(w, dev)
    launch_rows(luminance_steps_rows, t * h * tiles, [tiles, log_image, steps], device=dev)
    return steps, tiles


@host("stable_pairs")
def stable_pairs(log_image, flow, pairs, tau: float, stability: float, floor: float, static_flow: float) -> None:
    """Weiss's stable-step evidence of each pixel's right and lower pair.

    Over the ``T`` frames, the step of the pair's log luminance (the mean
    over channels) ``s_t = L(t, x + d) - L(t, x)``, its median ``m`` (the mean
    of the middle two for even ``T``) and its largest deviation from it
    ``D = max_t |s_t - m|``: ``pairs[y, x, k] = (1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)``,
    0 when ``|m| >= MAX_STABLE_STEP``, when under ``floor``, when the pair
    leaves the image, or when either pixel's flow in any frame pair is
    ``static_flow`` px or longer (:func:`ivkernels.kernels.reference.step_evidence.stable_pairs`).
    The steps go into a (T, H, W, 2) buffer of this call; each median is
    found by ranks, ``O(T^2)`` per pair, and skipped where no step reaches
    :func:`~ivkernels.kernels.reference.step_evidence.least_stable_step` (the evidence is then under ``floor`` anyway: most
    pairs of a video, which are flat).

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    pairs : wp.array float32 (H, W, 2), written; in [0, 1).
    tau, stability : log units, > 0; floor : >= 0; static_flow : pixels, > 0.
    """
    if pairs.size == 0:
        return
    steps, tiles = _luminance_steps(log_image)
    h, dev = log_image.shape[1], log_image.device
    launch_rows(stable_pairs_pixels, h * tiles,
                [tiles, steps, flow, pairs, tau, stability, floor, static_flow, least_stable_step(tau, floor)], device=dev)


@host("moving_steps")
def moving_steps(log_image, flow, factor, tau: float, spread: float, static_flow: float) -> None:
    """Weiss's cue for the light's own edges, a factor on Eq. 9's local weight.

    For each horizontal or vertical pair that holds still (neither pixel's
    flow in any frame pair is ``static_flow`` px or longer), the step of the
    log luminance (the mean over channels) ``s_t = L(t, x + d) - L(t, x)``
    against its median ``m`` over the ``T`` frames (the mean of the middle two
    for even ``T``): ``exp(-((s_t - m) / w)^2)``, small in the frames where
    an edge of the light crosses the pair.  The width
    ``w = sqrt(tau^2 + (spread MAD)^2)`` grows with the pair's own spread,
    ``MAD`` the median of ``|s_t - m|`` over the frames.  ``factor[t, y, x]``
    is the smallest over the pixel's still pairs, 1 where it has none
    (:func:`ivkernels.kernels.reference.step_evidence.moving_steps`).  Two
    passes: each pair once (its median and MAD by ranks, ``O(T^2)``) into a
    (T, H, W, 2) buffer of this call that first holds the steps, then each
    pixel's smallest of its four pairs.

    log_image : wp.array float32 (T, H, W, 3), the offset log image (:func:`offset_log`).
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    factor : wp.array float32 (T, H, W), written; in (0, 1].
    tau : log units, > 0; spread : a multiple of the MAD, >= 0 (0: ``w = tau``);
    static_flow : pixels, > 0.
    """
    if factor.size == 0:
        return
    steps, tiles = _luminance_steps(log_image)
    t, h, _, _ = log_image.shape
    launch_rows(light_edge_pairs, h * tiles, [tiles, steps, flow, tau, spread, static_flow], device=log_image.device)
    launch_rows(light_edge_pixels, t * h * tiles, [tiles, steps, factor], device=log_image.device)
