"""``step_evidence``: the declared contract of its host functions, and the NumPy references (float64).

The per-pixel weight on Eq. 9's local shading pair terms, ``1 + gain' *
weight * evidence``: Retinex's cue (a sharp grey step of the log luminance is
an albedo edge) times Weiss's cue on still pixels (a step whose contrast
holds from frame to frame).  Why and how the weight is used:
:mod:`ivkernels.solver.step_evidence`, which composes these functions on a
backend.  The steps read ``I' = log(i + offset)`` (:func:`offset_log` of the
log input ``log i``): in the darkest pixels a log step says little.

Per pair of neighbours ``x, y`` with ``d = I'(x) - I'(y)`` (3 channels):

* ``dL = |mean_c d|``, the step of the log luminance ``L = mean_c I'``;
* ``dC = max_c |d_c - mean_c d|``, the change of the log chromaticity
  ``C = I' - L`` (its largest channel);
* a step is *sharp* when ``dL > tau`` or it is *chromatic*, ``dC > tau_chroma``
  (never with ``tau_chroma = 0``);
* its evidence is ``(1 - exp(-(dL / tau)^2)) * exp(-(dC / tau_chroma)^2)``
  (the second factor 1 with ``tau_chroma = 0``).

With a noise ``floor`` (T, H, W, 2) and ``k > 0``, ``dL`` and ``dC`` are read net
of it: ``dL' = sqrt(max(dL^2 - k^2 (f_L(x)^2 + f_L(y)^2) / 2, 0))`` and the same
for ``dC`` with ``f_C``, ``f`` the 5x5 median of :func:`typical_steps` (the
local typical step: in a region of sensor noise every pair steps by about it,
while an edge's pairs are a minority of the window and leave it near 0), or,
over frames joined by a flow, of :func:`temporal_steps`: the same steps of what
changes from one frame to the next along the flow, where the noise is new in
every frame and print and edges, which move with the flow, cancel.  The
local floor is then capped at a multiple of the window's noise level function
(:func:`step_histogram`, :func:`level_medians`, :func:`cap_at_level`): the
median step of each brightness bin, read at the pixel's brightness, as a
camera's noise depends on the brightness while a flow that misses over a
region (the texture's change read as noise) is a minority of every bin.

A pixel's evidence is the largest over its 8 neighbours inside the image.
Weiss's cue, the ``weight`` of the evidence, is ``maps.shading_gate`` of the
log input (:func:`still_stability`) where the scene holds still, 1 where it moves.
The share ``s`` of chromatic steps among the sharp ones, over the
horizontal and vertical pairs of the whole window (:func:`step_counts` per
row, :func:`share` of the counts), scales the gain: ``gain' = gain (1 - s)^2``.
Read around each pixel instead (``Params.shading_step_share_radius``), the
share is that of a square window of the pixel's frame with ``prior_steps``
steps of the whole video's share added (:func:`pixel_counts` per pixel,
:func:`local_share` of their window sums), and ``(1 - s)^2`` goes into the
weight (:func:`share_weight`) while the gain stays unscaled.

Weiss's cue also gives a second, separate weight (:func:`stable_pairs`), on
the horizontal and vertical pairs themselves rather than on pixels: over the
window's frames, the step ``s_t = L(t, x + d) - L(t, x)`` of a pair that
holds still, its median ``m`` and its largest deviation from it ``D``, and
the pair's evidence ``(1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)``: a
step that keeps its contrast under every light of the window is an albedo
edge (Weiss, ICCV 2001); one that a shadow crosses in some frames is not,
however many frames it holds in.  Steps of :data:`MAX_STABLE_STEP` log
units or more (an object's outline against a black background) and evidence
under ``floor`` (the small, stable steps a camera's noise gives every pair)
get 0.  The other half of the cue (:func:`moving_steps`): what a still
pair's step does beyond its median in frame ``t`` is the light's, so Eq. 9's
weight of its pixels in that frame is multiplied by
``exp(-((s_t - m) / w)^2)`` (a shadow's outline crossing the pair), with
``w = sqrt(tau^2 + (spread MAD)^2)`` wider for a pair whose step changes in
most frames (a relief under a moving light; ``MAD`` the median of
``|s_t - m|``).
"""
from __future__ import annotations

import math

import numpy as np

from ivkernels.kernels.contract import Array, Family, FinitePositive, Int, NonNegative, Out, Positive, Rule
from ivkernels.kernels.reference import maps as ref_maps

FAMILY = Family("step_evidence", "Retinex's sharp grey steps and Weiss's still steps on Eq. 9's local term.")

#: Linear offset added before the log when reading steps: ``log(i + DARK_OFFSET)``.
#: In the darkest pixels a log step says little (sensor noise and compression
#: there are large relative changes, and chromaticity is noise); the offset
#: damps them, as Retinex implementations do.
DARK_OFFSET = 0.02

#: Half of the eight neighbour offsets: with them every pair of neighbours is
#: seen once, and a pair's evidence, which does not depend on its order, goes
#: to both of its pixels.
HALF_NEIGHBOURS = ((0, 1), (1, 0), (1, 1), (1, -1))

#: The horizontal and vertical pairs, over which the chromatic share is counted;
#: a pair is counted in the row of its first pixel (the left or upper one).
AXIS_NEIGHBOURS = ((0, 1), (1, 0))

#: Largest median log-luminance step (log units) a stable pair may have
#: (:func:`stable_pairs`): larger steps are an outline against a black
#: background or a deep shadow's edge, which the cue cannot vouch for.
MAX_STABLE_STEP = 1.0

#: The noise level function (:func:`step_histogram`, :func:`level_medians`, :func:`cap_at_level`):
#: bins of the offset log luminance ``L`` over ``[log DARK_OFFSET, log(1 + DARK_OFFSET)]`` (the
#: range of a frame in [0, 1]; values outside go to the end bins), and log-spaced bins of a
#: step from ``NOISE_STEP_MIN`` (smaller steps, zeros included, go to the first) to
#: ``NOISE_STEP_MAX`` (larger ones to the last).
NOISE_LEVEL_BINS = 16
NOISE_STEP_BINS = 128
NOISE_STEP_MIN = 1e-4
NOISE_STEP_MAX = 1.0

#: Fewest pixels a brightness bin needs for its median to count; bins with fewer
#: take the function's value interpolated from their neighbours.
NOISE_LEVEL_MIN_COUNT = 64


def _finite(name: str, note: str = ""):
    """A rule refusing an infinite ``name`` (declared ``NonNegative``, which lets ``inf`` pass)."""
    def rule(sizes, args):
        if not math.isfinite(args[name]):
            raise ValueError(f"{name} must be a finite number >= 0{note}, got {args[name]!r}")
    return rule


FAMILY.declare("offset_log(log_image, out, offset)",
               "``out = log(exp(log_image) + offset)``: the log image read with a linear offset; ``offset > 0``.",
               log_image="T H W 3", out=Out("T H W 3"), offset=FinitePositive)
_FLOOR = Array("T H W 2", optional=True)

FAMILY.declare("typical_steps(log_image, steps)",
               "Per pixel, the larger log-luminance step and the larger log-chromaticity change of its right and "
               "lower pairs (0 without one); their 5x5 median is the local noise floor of the steps.",
               log_image="T H W 3", steps=Out("T H W 2"),
               separate=(("steps", "log_image", "the steps are written while log_image is read"),))
FAMILY.declare("temporal_steps(log_image, flow, steps)",
               "Per pixel of frame ``t``, :func:`typical_steps` of the change along the flow to frame ``t + 1``, "
               "``e(x) = log_image[t + 1, x + round(u(x))] - log_image[t, x]`` (clamped to the frame), over "
               "``sqrt 2``: the steps of the noise, new in every frame, while what moves with the flow cancels. "
               "The last frame takes the one before; one frame alone gives 0.",
               log_image="T H W 3", flow=Array("T-1 H W 2", layout="(T-1, H, W, 2)"), steps=Out("T H W 2"),
               separate=(("steps", "log_image", "the steps are written while log_image is read"),
                         ("steps", "flow", "the steps are written while flow is read")))
_COUNTS = f"2 {NOISE_LEVEL_BINS} {NOISE_STEP_BINS}"
_TABLE = f"2 {NOISE_LEVEL_BINS}"
FAMILY.declare("step_histogram(log_image, steps, counts)",
               "Per brightness bin of the pixels' log luminance (``NOISE_LEVEL_BINS`` fixed bins) and channel of "
               "``steps``, the histogram of the steps over ``NOISE_STEP_BINS`` log-spaced bins: ``counts[c, b, j]``.",
               log_image="T H W 3", steps="T H W 2",
               counts=Out(_COUNTS, "int32", layout=f"(2, {NOISE_LEVEL_BINS}, {NOISE_STEP_BINS})"))
FAMILY.declare("level_medians(counts, table)",
               "The noise level function: per channel, the median step of each brightness bin of ``counts`` "
               "(linear in the log of the step inside its bin); bins under ``NOISE_LEVEL_MIN_COUNT`` pixels "
               "interpolated between the nearest counted ones, 0 with none counted.",
               counts=Array(_COUNTS, "int32", layout=f"(2, {NOISE_LEVEL_BINS}, {NOISE_STEP_BINS})"),
               table=Out(_TABLE, layout=f"(2, {NOISE_LEVEL_BINS})"),
               separate=(("table", "counts", "the table is written while counts is read"),))
FAMILY.declare("cap_at_level(log_image, table, scale, floor)",
               "``floor[..., c] = min(floor[..., c], scale * f_c(L))``: the floor capped at ``scale`` times the "
               "noise level function ``table`` (its values at the brightness bins' centres) read at the pixel's "
               "log luminance ``L``, linearly between the centres and flat beyond them.",
               log_image="T H W 3", table=Array(_TABLE, layout=f"(2, {NOISE_LEVEL_BINS})"), scale=NonNegative,
               floor=Out("T H W 2"),
               separate=(("floor", "log_image", "the floor is written while log_image is read"),
                         ("floor", "table", "the floor is written while table is read")))
FAMILY.declare("step_counts(log_image, counts, tau, tau_chroma=0.0, floor=None, k=0.0)",
               "Per row, the sharp and the chromatic steps of the horizontal and vertical pairs it starts.",
               log_image="T H W 3", counts=Out("T*H 2", "int32", layout="(T*H, 2)"), tau=FinitePositive,
               tau_chroma=NonNegative, floor=_FLOOR, k=NonNegative)
FAMILY.declare("pixel_counts(log_image, counts, offset, tau, tau_chroma=0.0, floor=None, k=0.0)",
               "Per pixel, the sharp and the chromatic steps of its horizontal and vertical pairs, read in "
               "float64 on ``log(exp(log_image) + offset)``.",
               log_image="T H W 3", counts=Out("T H W 2", "int32", layout="(T, H, W, 2)"), offset=FinitePositive,
               tau=FinitePositive, tau_chroma=NonNegative, floor=_FLOOR, k=NonNegative)
FAMILY.declare("share_weight(counts, weight, radius, prior_steps)",
               "``weight *= (1 - s)^2``, ``s`` the chromatic share of ``counts`` in the (2 radius + 1)^2 window "
               "of each pixel with ``prior_steps`` steps of the whole video's share.",
               counts=Array("T H W 2", "int32", layout="(T, H, W, 2)"), weight=Out("T H W"),
               radius=Int(0, "(pixels)"), prior_steps=FinitePositive)
FAMILY.declare("step_gate(log_image, counts, weight, gate, gain, tau, tau_chroma=0.0, floor=None, k=0.0)",
               "``gate *= 1 + gain (1 - s)^2 weight evidence``, ``s`` the chromatic share of ``counts``.",
               log_image="T H W 3", counts=Array("T*H 2", "int32", layout="(T*H, 2)"), weight="T H W",
               gate=Out("T H W"), gain=NonNegative, tau=FinitePositive, tau_chroma=NonNegative, floor=_FLOOR,
               k=NonNegative,
               rules=(Rule(_finite("gain")),),
               separate=(("gate", "log_image", "the gate is written while log_image is read"),))
FAMILY.declare("still_stability(log_image, flow, weight, tau, static_flow)",
               "Weiss's cue ``maps.shading_gate(log_image, flow, tau)`` where the scene holds still, 1 where "
               "the flow of a pair touching the frame moves ``static_flow`` px or more.",
               log_image="T H W 3", flow=Array("T-1 H W 2", layout="(T-1, H, W, 2)"), weight=Out("T H W"),
               tau=Positive, static_flow=Positive,
               separate=(("weight", "log_image", "the weight is written while log_image is read"),
                         ("weight", "flow", "the weight is written while flow is read")))
FAMILY.declare("moving_steps(log_image, flow, factor, tau, spread, static_flow)",
               "Weiss's cue for the light's own edges: per pixel and frame, the smallest over its still "
               "horizontal and vertical pairs of ``exp(-((s_t - m) / w)^2)``, ``s_t`` the pair's "
               "log-luminance step in frame ``t``, ``m`` its median over the frames and "
               "``w = sqrt(tau^2 + (spread MAD)^2)``, ``MAD`` the median of ``|s_t - m|``; 1 without a still pair.",
               log_image="T H W 3", flow=Array("T-1 H W 2", layout="(T-1, H, W, 2)"), factor=Out("T H W"),
               tau=FinitePositive, spread=NonNegative, static_flow=Positive,
               rules=(Rule(_finite("spread", " (0: the width is tau)")),),
               separate=(("factor", "log_image", "the factor is written while log_image is read"),
                         ("factor", "flow", "the factor is written while flow is read")))
FAMILY.declare("stable_pairs(log_image, flow, pairs, tau, stability, floor, static_flow)",
               "Weiss's stable-step evidence of each pixel's right and lower pair over the frames: "
               "``(1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)`` of the median ``m`` and the largest deviation "
               "from it ``D`` of the pair's log-luminance step, 0 under ``floor``, for ``|m|`` of "
               "``MAX_STABLE_STEP`` or more, or where the flow of either pixel moves ``static_flow`` px or more.",
               log_image="T H W 3", flow=Array("T-1 H W 2", layout="(T-1, H, W, 2)"),
               pairs=Out("H W 2", layout="(H, W, 2)"), tau=FinitePositive, stability=FinitePositive,
               floor=NonNegative, static_flow=Positive,
               separate=(("pairs", "log_image", "the pairs are written while log_image is read"),
                         ("pairs", "flow", "the pairs are written while flow is read")))


# ----------------------------------------------------------------------------- the references

def offset_log(log_image, offset: float) -> np.ndarray:
    """``log(exp(log_image) + offset)`` (T, H, W, 3), float64."""
    return np.log(np.exp(np.asarray(log_image, np.float64)) + offset)


def luminance_chroma(log_image):
    """``L`` (T, H, W) and ``C`` (T, H, W, 3): the mean over channels of ``log_image`` and the rest."""
    I = np.asarray(log_image, np.float64)
    L = I.mean(axis=-1)
    return L, I - L[..., None]


def pair_slices(shape, dy: int, dx: int):
    """Index tuples of the pixels ``x`` and of their neighbours ``x + (dy, dx)`` (``dy >= 0``)
    of a (T, H, W) array."""
    _, h, w = shape
    xs, xn = slice(max(0, -dx), w - max(0, dx)), slice(max(0, dx), w + min(0, dx))
    return (slice(None), slice(0, h - dy), xs), (slice(None), slice(dy, h), xn)


def _chroma_change(C, a, b) -> np.ndarray:
    return np.abs(C[a] - C[b]).max(axis=-1)


def typical_steps(log_image) -> np.ndarray:
    """(T, H, W, 2) float64: per pixel the larger ``dL`` (channel 0) and the larger ``dC``
    (channel 1) of its pairs ``(x, x + (0, 1))`` and ``(x, x + (1, 0))`` inside the image, 0 without one.

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`).
    """
    L, C = luminance_chroma(log_image)
    out = np.zeros(L.shape + (2,))
    for dy, dx in AXIS_NEIGHBOURS:
        a, b = pair_slices(L.shape, dy, dx)
        np.maximum(out[a + (0,)], np.abs(L[a] - L[b]), out=out[a + (0,)])
        np.maximum(out[a + (1,)], _chroma_change(C, a, b), out=out[a + (1,)])
    return out


def rounded_target(position, flow_component, size: int) -> np.ndarray:
    """The pixel ``position + flow_component`` rounds to, ``floor(. + 0.5)``, clamped to
    ``[0, size - 1]`` (int64); a NaN flow gives 0, as the kernels read it."""
    target = np.floor(np.asarray(position, np.float64) + np.asarray(flow_component, np.float64) + 0.5)
    return np.clip(np.nan_to_num(target, nan=0.0, posinf=size - 1, neginf=0.0), 0, size - 1).astype(np.int64)


def temporal_steps(log_image, flow) -> np.ndarray:
    """(T, H, W, 2) float64: :func:`typical_steps` of the change between frames along the flow, over ``sqrt 2``.

    For frame ``t < T - 1``, ``e_t(x) = I'(t + 1, x + round(u_t(x))) - I'(t, x)`` (the target
    clamped to the frame, each pixel with its own flow); its steps are the noise's, twice
    its variance (a difference of two frames), hence the ``sqrt 2``; print and edges that
    move with the flow cancel.  Frame ``T - 1`` takes frame ``T - 2``'s; ``T = 1`` gives 0.

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`).
    flow : (T-1, H, W, 2), pixels, ``(dx, dy)`` from frame ``t`` to ``t + 1``.
    """
    img = np.asarray(log_image, np.float64)
    flow = np.asarray(flow, np.float64)
    T, H, W, _ = img.shape
    out = np.zeros((T, H, W, 2))
    if T < 2:
        return out
    yy, xx = np.mgrid[0:H, 0:W]
    change = np.empty((T - 1, H, W, 3))
    for t in range(T - 1):
        ty = rounded_target(yy, flow[t, ..., 1], H)
        tx = rounded_target(xx, flow[t, ..., 0], W)
        change[t] = img[t + 1][ty, tx] - img[t]
    out[: T - 1] = typical_steps(change) / math.sqrt(2.0)
    out[T - 1] = out[T - 2]
    return out


def level_edges() -> np.ndarray:
    """(NOISE_LEVEL_BINS + 1,) float32: the edges of the brightness bins, evenly spaced in ``L``."""
    return np.linspace(math.log(DARK_OFFSET), math.log(1.0 + DARK_OFFSET), NOISE_LEVEL_BINS + 1).astype(np.float32)


def step_edges() -> np.ndarray:
    """(NOISE_STEP_BINS + 1,) float32: the edges of the step bins, evenly spaced in the log of the step."""
    return np.exp(np.linspace(math.log(NOISE_STEP_MIN), math.log(NOISE_STEP_MAX), NOISE_STEP_BINS + 1)).astype(
        np.float32)


def bin_index(values, edges) -> np.ndarray:
    """The bin of each value: how many inner edges ``edges[1:-1]`` are ``<=`` it (below the
    first edge: bin 0, above the last: the last bin; NaN: bin 0), as the kernels count."""
    values = np.asarray(values, np.float32)
    index = np.searchsorted(edges[1:-1], np.nan_to_num(values, nan=-np.inf), side="right")
    return np.where(np.isnan(values), 0, index)


def frame_luminance(log_image) -> np.ndarray:
    """(T, H, W) float32: ``(I_0 + I_1 + I_2) / 3`` in float32, in the kernels' order."""
    img = np.asarray(log_image, np.float32)
    return (img[..., 0] + img[..., 1] + img[..., 2]) / np.float32(3.0)


def step_histogram(log_image, steps) -> np.ndarray:
    """(2, NOISE_LEVEL_BINS, NOISE_STEP_BINS) int64: ``counts[c, b, j]``, the pixels of brightness bin
    ``b`` (:func:`level_edges` of :func:`frame_luminance`) whose step ``steps[..., c]`` falls in step
    bin ``j`` (:func:`step_edges`).

    log_image : (T, H, W, 3), ``I'``; steps : (T, H, W, 2), :func:`temporal_steps` or :func:`typical_steps`.
    """
    level = bin_index(frame_luminance(log_image), level_edges()).reshape(-1)
    counts = np.zeros((2, NOISE_LEVEL_BINS, NOISE_STEP_BINS), np.int64)
    for c in range(2):
        step = bin_index(np.asarray(steps, np.float32)[..., c], step_edges()).reshape(-1)
        np.add.at(counts[c], (level, step), 1)
    return counts


def level_medians(counts) -> np.ndarray:
    """(2, NOISE_LEVEL_BINS) float64: the noise level function, per channel the median step of each
    brightness bin, at the bin's centre.

    The median is read from the histogram ``counts`` (:func:`step_histogram`), linearly in the log
    of the step inside its bin.  A bin with fewer than :data:`NOISE_LEVEL_MIN_COUNT` pixels takes the
    value interpolated between the nearest counted bins' (the nearest one's beyond the last); with
    no bin counted, 0.
    """
    counts = np.asarray(counts, np.int64)
    log_edges = np.log(step_edges().astype(np.float64))
    out = np.zeros((2, NOISE_LEVEL_BINS))
    centres = np.arange(NOISE_LEVEL_BINS, dtype=np.float64)
    for c in range(2):
        known, values = [], []
        for b in range(NOISE_LEVEL_BINS):
            row = counts[c, b]
            n = int(row.sum())
            if n < NOISE_LEVEL_MIN_COUNT:
                continue
            cumulative = np.cumsum(row)
            j = int(np.searchsorted(cumulative, n / 2.0))          # the first bin reaching half the pixels
            before = cumulative[j - 1] if j > 0 else 0
            frac = (n / 2.0 - before) / row[j]
            known.append(b)
            values.append(math.exp(log_edges[j] + frac * (log_edges[j + 1] - log_edges[j])))
        if known:
            out[c] = np.interp(centres, np.array(known, np.float64), np.array(values))
    return out


def level_axis() -> tuple[float, float]:
    """``(lo, width)``: the first brightness edge and the width of a brightness bin (float64), with
    which a pixel's luminance ``L`` reads the noise level function at ``(L - lo) / width - 0.5``
    bins from the first bin's centre."""
    edges = level_edges().astype(np.float64)
    return float(edges[0]), float((edges[-1] - edges[0]) / NOISE_LEVEL_BINS)


def level_floor(log_image, table) -> np.ndarray:
    """(T, H, W, 2) float64: the noise level function ``table`` (2, NOISE_LEVEL_BINS), its values at
    the brightness bins' centres, read at each pixel's :func:`frame_luminance`, linearly between
    centres and flat beyond the first and last."""
    lo, width = level_axis()
    u = (frame_luminance(log_image).astype(np.float64) - lo) / width - 0.5
    u = np.clip(np.nan_to_num(u, nan=0.0), 0.0, NOISE_LEVEL_BINS - 1.0)
    i0 = np.minimum(np.floor(u).astype(np.int64), NOISE_LEVEL_BINS - 1)
    i1 = np.minimum(i0 + 1, NOISE_LEVEL_BINS - 1)
    f = u - i0
    table = np.asarray(table, np.float64)
    return np.stack([table[c][i0] * (1.0 - f) + table[c][i1] * f for c in range(2)], axis=-1)


def cap_at_level(log_image, table, scale: float, floor) -> np.ndarray:
    """(T, H, W, 2) float64: ``floor`` capped at ``scale`` times :func:`level_floor` of ``table``."""
    return np.minimum(np.asarray(floor, np.float64), scale * level_floor(log_image, table))


def net_steps(dL, dC, floor, k: float, a, b):
    """``(dL, dC)`` of the pairs ``(a, b)`` net of the noise ``floor`` (T, H, W, 2) at ``k``
    (unchanged without a floor or with ``k = 0``): ``sqrt(max(d^2 - k^2 (f(a)^2 + f(b)^2) / 2, 0))``."""
    if floor is None or k <= 0:
        return dL, dC
    f = np.asarray(floor, np.float64)
    out = []
    for d, c in ((dL, 0), (dC, 1)):
        noise = k * k * (f[a + (c,)] ** 2 + f[b + (c,)] ** 2) / 2.0
        out.append(np.sqrt(np.maximum(np.asarray(d, np.float64) ** 2 - noise, 0.0)))
    return out[0], out[1]


def pixel_step_counts(log_image, tau: float, tau_chroma: float = 0.0, floor=None, k: float = 0.0) -> np.ndarray:
    """(T, H, W, 2) int64: per pixel ``x``, the sharp steps (channel 0) and the chromatic ones
    (channel 1) among its pairs ``(x, x + (0, 1))`` and ``(x, x + (1, 0))``.

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`).
    tau_chroma : 0: no step is chromatic.
    floor, k : the noise floor (:func:`net_steps`); ``None`` or 0: steps as read.
    """
    L, C = luminance_chroma(log_image)
    counts = np.zeros(L.shape + (2,), np.int64)
    for dy, dx in AXIS_NEIGHBOURS:
        a, b = pair_slices(L.shape, dy, dx)
        dL, dC = net_steps(np.abs(L[a] - L[b]), _chroma_change(C, a, b), floor, k, a, b)
        chromatic = dC > tau_chroma if tau_chroma > 0 else np.zeros(L[a].shape, bool)
        counts[a + (0,)] += chromatic | (dL > tau)
        counts[a + (1,)] += chromatic
    return counts


def step_counts(log_image, tau: float, tau_chroma: float = 0.0, floor=None, k: float = 0.0) -> np.ndarray:
    """(T*H, 2) int32: per row ``t * H + y``, the sharp steps (column 0) and the chromatic ones
    (column 1) among the pairs ``(x, x + (0, 1))`` and ``(x, x + (1, 0))`` of its pixels ``x``
    (:func:`pixel_step_counts` summed over the row).

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`).
    tau_chroma : 0: no step is chromatic.
    floor, k : the noise floor (:func:`net_steps`).
    """
    counts = pixel_step_counts(log_image, tau, tau_chroma, floor, k).sum(axis=2)
    return counts.reshape(-1, 2).astype(np.int32)


def pixel_counts(log_image, offset: float, tau: float, tau_chroma: float = 0.0, floor=None,
                 k: float = 0.0) -> np.ndarray:
    """(T, H, W, 2) int32: :func:`pixel_step_counts` of ``offset_log(log_image, offset)``, all in float64.

    log_image : (T, H, W, 3), ``log i`` (not offset).
    floor, k : the noise floor (:func:`net_steps`), of the offset log image's steps.
    """
    return pixel_step_counts(offset_log(log_image, offset), tau, tau_chroma, floor, k).astype(np.int32)


def window_sums(counts, radius: int) -> np.ndarray:
    """(T, H, W, 2) int64: the sums of ``counts`` (T, H, W, 2) over the (2 radius + 1)^2 window of
    each pixel of its frame, cut at the borders (from an integral image, exactly)."""
    counts = np.asarray(counts, np.int64)
    t, h, w, _ = counts.shape
    c = np.zeros((t, h + 1, w + 1, 2), np.int64)
    c[:, 1:, 1:] = counts.cumsum(1).cumsum(2)
    y0, y1 = np.clip(np.arange(h) - radius, 0, h), np.clip(np.arange(h) + radius + 1, 0, h)
    x0, x1 = np.clip(np.arange(w) - radius, 0, w), np.clip(np.arange(w) + radius + 1, 0, w)
    return c[:, y1][:, :, x1] - c[:, y0][:, :, x1] - c[:, y1][:, :, x0] + c[:, y0][:, :, x0]


def local_share(counts, radius: int, prior_steps: float) -> np.ndarray:
    """(T, H, W) float32: per pixel ``(chromatic + prior_steps * whole) / (sharp + prior_steps)``,
    ``sharp`` and ``chromatic`` the :func:`window_sums` of :func:`pixel_counts` ``counts`` and
    ``whole`` their :func:`share` over the video; the division in float64, then rounded."""
    counts = np.asarray(counts, np.int64)
    whole = share(counts.reshape(-1, 2))
    box = window_sums(counts, radius)
    return ((box[..., 1] + prior_steps * whole) / (box[..., 0] + prior_steps)).astype(np.float32)


def share_weight(counts, weight, radius: int, prior_steps: float) -> np.ndarray:
    """(T, H, W) float32: ``weight * (1 - s)^2`` with ``s`` the :func:`local_share`, in float32."""
    keep = (np.float32(1.0) - local_share(counts, radius, prior_steps)) ** 2
    return np.asarray(weight, np.float32) * keep


def share(counts) -> float:
    """The chromatic share ``sum counts[:, 1] / sum counts[:, 0]`` of :func:`step_counts`; 0 without sharp steps."""
    counts = np.asarray(counts, np.int64)
    sharp, chromatic = int(counts[:, 0].sum()), int(counts[:, 1].sum())
    return chromatic / sharp if sharp else 0.0


def evidence(log_image, tau: float, tau_chroma: float = 0.0, floor=None, k: float = 0.0) -> np.ndarray:
    """(T, H, W) float64 in [0, 1): the largest pair evidence over a pixel's 8 neighbours
    (0 for a pixel without any); ``log_image`` is ``I'``, ``tau_chroma = 0``: colour is not looked at;
    ``floor``, ``k``: the steps net of the noise floor (:func:`net_steps`)."""
    L, C = luminance_chroma(log_image)
    out = np.zeros(L.shape)
    for dy, dx in HALF_NEIGHBOURS:
        a, b = pair_slices(L.shape, dy, dx)
        dL, dC = net_steps(np.abs(L[a] - L[b]), _chroma_change(C, a, b), floor, k, a, b)
        ev = 1.0 - np.exp(-(dL / tau) ** 2)
        if tau_chroma > 0:
            ev *= np.exp(-(dC / tau_chroma) ** 2)
        np.maximum(out[a], ev, out=out[a])
        np.maximum(out[b], ev, out=out[b])
    return out


def step_gate(log_image, counts, weight, gate, gain: float, tau: float, tau_chroma: float = 0.0, floor=None,
              k: float = 0.0) -> np.ndarray:
    """``gate * (1 + gain (1 - share(counts))^2 weight evidence)`` (T, H, W), float64."""
    scaled = gain * (1.0 - share(counts)) ** 2
    return np.asarray(gate, np.float64) * (1.0 + scaled * np.asarray(weight, np.float64)
                                           * evidence(log_image, tau, tau_chroma, floor, k))


def moving(flow, n_frames: int, static_flow: float) -> np.ndarray:
    """(T, H, W) bool: the flow of a pair that starts or ends on the frame moves ``static_flow`` px or more."""
    flow = np.asarray(flow, np.float64)
    fast = np.sqrt((flow ** 2).sum(axis=-1)) >= static_flow
    out = np.zeros((n_frames, *flow.shape[1:3]), bool)
    out[:-1] |= fast
    out[1:] |= fast
    return out


def still_stability(log_image, flow, tau: float, static_flow: float) -> np.ndarray:
    """(T, H, W) float64: 1 where :func:`moving`, elsewhere Weiss's cue
    :func:`ivkernels.kernels.reference.maps.shading_gate` ``(log_image, flow, tau)``
    (a step whose contrast changes from frame to frame is light, not albedo)."""
    log_image = np.asarray(log_image, np.float64)
    return np.where(moving(flow, log_image.shape[0], static_flow), 1.0, ref_maps.shading_gate(log_image, flow, tau))


def stable_pairs(log_image, flow, tau: float, stability: float, floor: float, static_flow: float) -> np.ndarray:
    """(H, W, 2) float64: Weiss's stable-step evidence of the pairs ``(x, x + (0, 1))`` (channel 0)
    and ``(x, x + (1, 0))`` (channel 1), 0 for a pair leaving the image.

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`); ``L = mean_c I'``.
    flow : (T-1, H, W, 2); a pair holds still when neither pixel's flow in any frame pair
        is ``static_flow`` px or longer.
    The evidence of a still pair with median step ``m`` over the ``T`` frames (the mean of the
    middle two for even ``T``) and largest deviation from it ``D = max_t |s_t - m|``:
    ``(1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)``, 0 when ``|m| >= MAX_STABLE_STEP``
    or when it is under ``floor``.
    """
    moves = moving(flow, np.shape(log_image)[0], static_flow).any(axis=0)     # (H, W): in any pair
    out = np.zeros((*moves.shape, 2))
    for k, (a, b), m, ev in stable_step_parts(log_image, tau, stability):
        ev[(np.abs(m) >= MAX_STABLE_STEP) | (ev < floor) | moves[a[1:]] | moves[b[1:]]] = 0.0
        out[a[1], a[2], k] = ev
    return out


def moving_steps(log_image, flow, tau: float, spread: float, static_flow: float) -> np.ndarray:
    """(T, H, W) float64: Weiss's cue for the light's own edges, a factor on Eq. 9's local weight.

    For each horizontal or vertical pair that holds still (neither pixel's flow in any frame pair
    is ``static_flow`` px or longer), the step of the log luminance ``s_t = L(t, x + d) - L(t, x)``
    against its median ``m`` over the ``T`` frames (the mean of the middle two for even ``T``):
    ``exp(-((s_t - m) / w)^2)``, small in the frames where an edge of the light (a shadow's
    outline) crosses the pair.  The width ``w = sqrt(tau^2 + (spread * MAD)^2)`` grows with the
    pair's own spread, ``MAD`` the median over the frames of ``|s_t - m|`` (an outline crossing
    the pair in a few frames leaves it near 0; a relief lit from every side does not); ``spread``
    0 gives ``w = tau``.  A pixel's factor in frame ``t`` is the smallest over its (up to four)
    still pairs, 1 where it has none.

    log_image : (T, H, W, 3), ``I'`` (:func:`offset_log`); ``L = mean_c I'``.
    flow : (T-1, H, W, 2).
    """
    L, _ = luminance_chroma(log_image)
    moves = moving(flow, L.shape[0], static_flow).any(axis=0)                    # (H, W): in any pair
    out = np.ones(L.shape)
    for dy, dx in AXIS_NEIGHBOURS:
        a, b = pair_slices(L.shape, dy, dx)
        steps = L[b] - L[a]                                                      # (T, h', w')
        departure = steps - np.median(steps, axis=0)
        width = np.sqrt(tau ** 2 + (spread * np.median(np.abs(departure), axis=0)) ** 2)
        factor = np.exp(-(departure / width) ** 2)
        factor[:, moves[a[1:]] | moves[b[1:]]] = 1.0
        out[a] = np.minimum(out[a], factor)
        out[b] = np.minimum(out[b], factor)
    return out


def stable_step_parts(log_image, tau: float, stability: float):
    """Per axis ``k`` of :data:`AXIS_NEIGHBOURS`, ``(k, (a, b), m, ev)``: the index tuples of the
    pairs' pixels (:func:`pair_slices`), the median step ``m`` over the frames and the evidence
    ``(1 - exp(-(m / tau)^2)) exp(-(D / stability)^2)`` before the floor, the largest step and
    the flow rule of :func:`stable_pairs` (float64, (h', w') each)."""
    L, _ = luminance_chroma(log_image)
    for k, (dy, dx) in enumerate(AXIS_NEIGHBOURS):
        a, b = pair_slices(L.shape, dy, dx)
        steps = L[b] - L[a]                                                      # (T, h', w')
        m = np.median(steps, axis=0)
        spread = np.abs(steps - m).max(axis=0)
        yield k, (a, b), m, (1.0 - np.exp(-(m / tau) ** 2)) * np.exp(-(spread / stability) ** 2)


def least_stable_step(tau: float, floor: float) -> float:
    """The smallest median step whose :func:`stable_pairs` evidence can reach ``floor``, shaded
    down by a millionth for rounding: ``1 - exp(-(m / tau)^2) < floor`` for ``|m| < tau
    sqrt(-log(1 - floor))``, and the other factor is at most 1.  A pair none of whose steps
    reaches it gets 0 without its medians (the kernels skip them).  0 for ``floor = 0``."""
    if floor <= 0.0:
        return 0.0
    if floor >= 1.0:
        return math.inf
    return float(tau * math.sqrt(-math.log1p(-floor)) * (1.0 - 1e-6))
