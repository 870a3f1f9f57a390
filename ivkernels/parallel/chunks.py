"""Long videos in parallel chunks: where to cut, and how to stitch the pieces.

A long video is cut into chunks of at most ``chunk_frames`` frames of its own;
each chunk after the first also solves the ``overlap`` frames before it, so
neighbouring chunks share ``overlap`` frames.  Chunks are solved
independently (in parallel); inside a chunk the windows stay sequential and
carry the albedo forward as in :func:`ivkernels.decompose`.

A chunk is solved in windows of up to :data:`CHUNK_WINDOW_FACTOR` times
``Params.window`` frames (:func:`chunk_params`): one window for a chunk of up
to 16 frames at the defaults, where the sequential solve would use two.  The
sequential solve's later windows start from carried, better converged frames
(and, under a moving lamp, from the lamp positions seen so far); a chunk
starts over with a cold first window, and two windows of 8 frames leave its
albedo further from the minimum than the sequential solve's on the same
frames.  One window over all of a chunk's frames reads every frame (every
lamp position) at once and costs no more (14 frames in one window are fewer
frame-iterations than two windows of 8 sharing 2): on 36-frame training
sequences in 12-frame chunks it brought the chunked albedo LMSE of a static
scene under a moving lamp from 1.02-1.24x the sequential solve's to
0.90-1.07x over four seeds (perf/RESULTS.md, "Chunks solved as one window").
The factor bounds a window's working memory at twice the sequential solve's.

A chunk solved on its own has its own global gain: the product ``A * S``
is fixed by the data term (Eq. 3) but the split is fixed only up to a
scale by the priors and by the output normalisation (albedo's 99th
percentile = 1 on the chunk's first window, DESIGN sec. 2).  Stitching puts
every chunk on the first chunk's scale:

1. fit, on the shared frames, chunk ``c``'s log albedo to chunk ``c-1``'s
   (already corrected) log albedo with one offset per channel (gain and
   colour balance), and its log shading with one offset: each offset is the
   median over the shared pixels of the log ratio, robust to the pixels
   where the two solves differ;
2. carry what one gain leaves (:func:`residual_field`): where the two
   solves split the shared frames differently region by region (a wall too
   dark in one, the floor in the other), the rest of the log-albedo
   difference on the last shared frame, blurred to its large scale
   (Gaussian, :data:`FIELD_SIGMA` of the frame's shorter side), is added to
   chunk ``c``'s log albedo and taken from its log shading (the product is
   unchanged), on its shared frames and, carried along the chunk's own flow
   frame by frame (:func:`carry_field`), on the frames after them.  So a
   surface the previous chunk saw keeps its albedo while the camera moves
   on; what enters the view takes the correction of the view's edge.  On
   36-frame training videos in 12-frame chunks this brought the change of
   the tracked surface points' albedo first to last from 0.02-2.6% to
   0.04-0.49% (seven videos, lamp and moving camera) at the same LMSE, and
   the flicker at the seams down by 7-36% (perf/RESULTS.md, "The chunks'
   residual field").  Chunks without a flow (``temporal=False``) get no
   field;
3. chain: chunk ``c`` is corrected after chunk ``c-1``, so every chunk ends
   on chunk 0's scale;
4. blend the shared frames linearly in time, in log (a geometric blend, so
   the blended albedo times the blended shading still reconstructs the
   input as well as either chunk does): weight ``j / (overlap + 1)`` for
   chunk ``c`` on its ``j``-th shared frame (``j = 1 .. overlap``).

The albedo and shading offsets are fitted separately; both chunks
reconstruct the same frames, so their sum is close to zero, and its size
(``diagnostics["seams"]``) says how well the two solves agree; so does the
residual field's root mean square (``field_rms``, log units).  Flow,
occlusion and motion-boundary maps are not blended: each shared frame pair
takes them from the chunk whose blend weight is larger there.
"""
from __future__ import annotations

import cv2
import numpy as np

from ivkernels.colour import REC709_LUMINANCE
from ivkernels.decompose import IntrinsicVideo
from ivkernels.params import Params

#: Smallest albedo or shading value taken into the log fits (both are > 0).
_LOG_FLOOR = 1e-6
#: A chunk's windows hold up to this many times ``Params.window`` frames (:func:`chunk_params`).
CHUNK_WINDOW_FACTOR = 2
#: Gaussian sigma of the residual field's blur, as a fraction of the frame's shorter side
#: (:func:`residual_field`); chosen on training videos (perf/RESULTS.md, "The chunks' residual field").
FIELD_SIGMA = 0.1
#: Rec. 709 luminance weights: the residual field is the log albedo's difference in luminance.
_REC709 = np.array(REC709_LUMINANCE, np.float32)


def chunk_ranges(n_frames: int, chunk_frames: int | None, overlap: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of the frames each chunk solves.

    The video's ``n_frames`` frames are split into ``ceil(n_frames /
    chunk_frames)`` runs of equal length (up to one frame), so no chunk owns
    more than ``chunk_frames`` frames; each chunk after the first starts
    ``overlap`` frames before its own, the frames it shares with the chunk
    before.  ``chunk_frames=None`` (or one chunk) gives the whole video.

    >>> chunk_ranges(36, 12, 2)
    [(0, 12), (10, 24), (22, 36)]
    """
    if chunk_frames is None:
        return [(0, n_frames)]
    n_chunks = max(1, -(-n_frames // chunk_frames))
    bounds = [round(i * n_frames / n_chunks) for i in range(n_chunks + 1)]
    return [(max(0, a - overlap) if i else a, b)
            for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:]))]


def chunk_window(n_frames: int, window: int, overlap: int) -> int:
    """Frames per window for a chunk of ``n_frames`` frames (see the module docstring).

    The fewest windows of at most ``CHUNK_WINDOW_FACTOR * window`` frames that
    cover the chunk, sharing ``max(1, overlap)`` frames as
    :func:`ivkernels.decompose.window_ranges` lays them out, made as long as
    that many windows need (so they come out of about equal length); never shorter
    than ``window``.  A chunk of at most ``CHUNK_WINDOW_FACTOR * window``
    frames is one window.

    >>> chunk_window(12, 8, 2), chunk_window(14, 8, 2), chunk_window(26, 8, 2), chunk_window(40, 8, 2)
    (12, 14, 14, 15)
    """
    if n_frames <= window:
        return window
    longest = CHUNK_WINDOW_FACTOR * window
    overlap = max(1, overlap)
    n_windows = -(-(n_frames - overlap) // (longest - overlap))
    return max(window, -(-(n_frames + (n_windows - 1) * overlap) // n_windows))


def chunk_params(params: Params, n_frames: int) -> Params:
    """``params`` for a chunk of ``n_frames`` frames: ``window`` set by :func:`chunk_window`,
    every other field as given (the same object when the window does not change)."""
    window = chunk_window(n_frames, int(params.window), int(params.overlap))
    return params if window == params.window else params.replace(window=window)


def _log(x: np.ndarray) -> np.ndarray:
    return np.log(np.maximum(x, _LOG_FLOOR))


def fit_offsets(prev_albedo, prev_shading, albedo, shading) -> tuple[np.ndarray, float]:
    """Log offsets that put ``(albedo, shading)`` on the scale of ``(prev_albedo, prev_shading)``.

    Parameters
    ----------
    prev_albedo, albedo : (K, H, W, 3) linear albedo of the shared frames.
    prev_shading, shading : (K, H, W) linear shading of the same frames.

    Returns
    -------
    ``(a, s)``: ``a`` (3,) float64, the per-channel log albedo offset (global
    gain and colour balance), and ``s`` the log shading offset, each the
    median over the shared pixels of the log ratio; ``albedo * exp(a)`` and
    ``shading * exp(s)`` match the previous chunk.
    """
    a = np.median((_log(prev_albedo) - _log(albedo)).reshape(-1, 3), axis=0)
    s = float(np.median(_log(prev_shading) - _log(shading)))
    return a.astype(np.float64), s


def residual_field(prev_log_albedo: np.ndarray, log_albedo: np.ndarray) -> np.ndarray:
    """What one gain leaves of a seam, at large scale.

    Parameters
    ----------
    prev_log_albedo, log_albedo : (H, W, 3) log albedo of the same frame, the
        previous chunk's (stitched) and this chunk's (its offsets applied).

    Returns
    -------
    (H, W) float32, log units: the difference of the two in luminance
    (Rec. 709 weights on the log channels), blurred with a Gaussian of
    :data:`FIELD_SIGMA` times the frame's shorter side.
    """
    diff = ((prev_log_albedo - log_albedo) @ _REC709).astype(np.float32)
    sigma = FIELD_SIGMA * min(diff.shape)
    return cv2.GaussianBlur(diff, (0, 0), sigma) if sigma > 0 else diff


def carry_field(field: np.ndarray, flow: np.ndarray) -> np.ndarray:
    """``field`` (H, W) of frame ``t`` moved to frame ``t + 1`` along the forward ``flow``
    (H, W, 2) of that pair: ``out(y) = field(y - u(y))`` (bilinear; the flow read at the
    target, which for a field this smooth is the source's to first order), the view's
    edge value where ``y - u(y)`` leaves the frame."""
    h, w = field.shape
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    return cv2.remap(field, gx - flow[..., 0], gy - flow[..., 1], cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)


def stitch(chunks: list[IntrinsicVideo], ranges: list[tuple[int, int]]) -> IntrinsicVideo:
    """One :class:`IntrinsicVideo` from chunk solutions (see the module docstring).

    Parameters
    ----------
    chunks : the solution of each chunk, in order; chunk ``c`` covers frames
        ``ranges[c]`` of the video.
    ranges : ``(start, stop)`` per chunk, from :func:`chunk_ranges`.

    Returns
    -------
    IntrinsicVideo of all frames; ``diagnostics`` holds ``chunks`` (the
    ranges), ``seams`` (per seam: the shared frames, the fitted log albedo
    offset per channel and log shading offset, and, with a flow, the
    residual field's root mean square ``field_rms``), and ``chunk_diagnostics``
    (each chunk's own diagnostics).  A single chunk is returned unchanged.
    """
    if len(chunks) != len(ranges) or not chunks:
        raise ValueError(f"stitch needs one solution per chunk, got {len(chunks)} for {len(ranges)} ranges")
    if len(chunks) == 1:
        return chunks[0]
    T = ranges[-1][1]
    first = chunks[0]
    H, W = first.albedo.shape[1:3]
    log_a = np.empty((T, H, W, 3), np.float32)
    log_s = np.empty((T, H, W), np.float32)
    has_flow = all(c.flow is not None for c in chunks)
    flow = np.empty((T - 1, H, W, 2), np.float32) if has_flow else None
    occ = np.empty((T - 1, H, W), np.float32) if has_flow else None
    bnd = np.empty((T - 1, H, W), np.float32) if has_flow else None
    seams = []
    prev_stop = 0
    for c, (chunk, (start, stop)) in enumerate(zip(chunks, ranges)):
        if chunk.albedo.shape[0] != stop - start:
            raise ValueError(f"chunk {c} holds {chunk.albedo.shape[0]} frames, its range "
                             f"{(start, stop)} {stop - start}")
        ca, cs = chunk.albedo, chunk.shading
        shared = prev_stop - start           # frames shared with the previous chunk
        if c == 0:
            a_off, s_off = np.zeros(3), 0.0
        else:
            # the previous chunk's frames [start, prev_stop) are already corrected in log_a / log_s
            a_off, s_off = fit_offsets(np.exp(log_a[start:prev_stop]), np.exp(log_s[start:prev_stop]),
                                       ca[:shared], cs[:shared])
            seams.append({"frames": (start, prev_stop), "albedo_log_offset": a_off.tolist(),
                          "shading_log_offset": s_off})
        la = _log(ca) + a_off.astype(np.float32)
        ls = _log(cs) + np.float32(s_off)
        if c > 0 and shared > 0 and chunk.flow is not None:
            field = residual_field(log_a[prev_stop - 1], la[shared - 1])
            seams[-1]["field_rms"] = float(np.sqrt(np.mean(np.square(field, dtype=np.float64))))
            for k in range(la.shape[0]):
                la[k] += field[..., None]
                ls[k] -= field
                if k >= shared - 1 and k + 1 < la.shape[0]:
                    field = carry_field(field, chunk.flow[k])
        if shared > 0:
            w = (np.arange(1, shared + 1, dtype=np.float32) / (shared + 1))
            log_a[start:prev_stop] = (1 - w[:, None, None, None]) * log_a[start:prev_stop] \
                + w[:, None, None, None] * la[:shared]
            log_s[start:prev_stop] = (1 - w[:, None, None]) * log_s[start:prev_stop] + w[:, None, None] * ls[:shared]
        log_a[prev_stop:stop] = la[shared:]
        log_s[prev_stop:stop] = ls[shared:]
        if has_flow:
            # pair t (frames t, t+1) comes from this chunk from the first shared frame where
            # this chunk's blend weight passes 1/2 (all pairs when nothing is shared)
            take = start + shared // 2 if shared else start
            n = stop - 1 - take
            flow[take:stop - 1] = chunk.flow[take - start:take - start + n]
            occ[take:stop - 1] = chunk.occlusion[take - start:take - start + n]
            bnd[take:stop - 1] = chunk.boundary[take - start:take - start + n]
        prev_stop = stop
    diagnostics = {"chunks": [tuple(r) for r in ranges], "seams": seams,
                   "chunk_diagnostics": [c.diagnostics for c in chunks]}
    return IntrinsicVideo(np.exp(log_a), np.exp(log_s), flow, occ, bnd, diagnostics)
