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
2. chain: chunk ``c`` is corrected after chunk ``c-1``, so every chunk ends
   on chunk 0's scale;
3. blend the shared frames linearly in time, in log (a geometric blend, so
   the blended albedo times the blended shading still reconstructs the
   input as well as either chunk does): weight ``j / (overlap + 1)`` for
   chunk ``c`` on its ``j``-th shared frame (``j = 1 .. overlap``).

The albedo and shading offsets are fitted separately; both chunks
reconstruct the same frames, so their sum is close to zero, and its size
(``diagnostics["seams"]``) says how well the two solves agree.  Flow,
occlusion and motion-boundary maps are not blended: each shared frame pair
takes them from the chunk whose blend weight is larger there.
"""
from __future__ import annotations

import numpy as np

from ivkernels.decompose import IntrinsicVideo
from ivkernels.params import Params

#: Smallest albedo or shading value taken into the log fits (both are > 0).
_LOG_FLOOR = 1e-6
#: A chunk's windows hold up to this many times ``Params.window`` frames (:func:`chunk_params`).
CHUNK_WINDOW_FACTOR = 2


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
    offset per channel and log shading offset), and ``chunk_diagnostics``
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
