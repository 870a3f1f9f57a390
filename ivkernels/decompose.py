"""Public entry point: :func:`decompose` a video into its intrinsic video.

Long videos are solved in overlapping windows of ``params.window`` frames;
the first ``params.overlap`` frames of each window after the first are the
previous window's last frames, held fixed, so albedo is carried forward and
memory is bounded by the window (:func:`iter_decompose` yields the windows one
by one; :func:`decompose` collects them).
"""
from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np
from tqdm.auto import tqdm

from ivkernels import validation as v
from ivkernels.backends import check_device, get_backend
from ivkernels.flow import FLOW_METHODS, estimate_flow
from ivkernels.kernels.memory import release_free_memory
from ivkernels.kernels.thread_count import check_threads, get_threads, iterate_with_threads
from ivkernels.kernels.thread_count import threads as launch_threads
from ivkernels.params import Params
from ivkernels.priors import load_albedo_prior
from ivkernels.solver.denoise import denoise_layers
from ivkernels.solver.guide import guide_shape, guide_solve, scaled_shape
from ivkernels.solver.motion_maps import motion_maps
from ivkernels.solver.pyramid import downsample, level_shapes, resize_flow
from ivkernels.solver.still_flow import (MOVING_CAMERA_FLOW, camera_holds_still, hold_still_surfaces,
                                         median_flow_length, still_surface_mask)
from ivkernels.solver.window_solver import SolveLog, solve_window

#: Flow method used when ``flow=None``.
DEFAULT_FLOW_METHOD = "classic_nl_fast"
#: Passes of flow and intrinsic video estimated together when the flow is
#: estimated (``flow=None`` or a method name); see :func:`decompose`.
#: Measured (perf/eval_joint.py and perf/eval_flow_passes.py, training seed 1,
#: 8 frames at 320x240): the second pass on the albedo lowers flow EPE, false
#: occlusions and LMSE on every synthetic kind; a third changes the flow by
#: under 0.07 px.
DEFAULT_FLOW_PASSES = 2
#: Frame pairs given to the flow method per call (bounds its working memory).
FLOW_PAIRS_PER_CALL = 7
#: Estimate the next window's first-pass flow, and this window's backward flow
#: (``Params.flow_round_trip_max``), on a second thread while this window is
#: solved, on a backend whose launches from two Python threads run at once
#: (``Backend.overlaps_python_threads``: Warp on the CPU); the results are the
#: same.
FLOW_AHEAD = True


@dataclass
class IntrinsicVideo:
    """The intrinsic video of ``T`` frames of size ``H x W``.

    Attributes
    ----------
    albedo : (T, H, W, 3) float32, linear RGB reflectance; its 99th
        percentile (over the first window's pixels and channels) is 1.
    shading : (T, H, W) float32, linear grey shading;
        ``albedo * shading[..., None]`` reconstructs the linear input, less
        the sensor noise taken out of both where the input is noisy
        (``Params.layer_denoise``).
    flow : (T-1, H, W, 2) float32 forward flow t -> t+1 in pixels (dx, dy),
        or ``None`` when solved with ``temporal=False`` and no flow given.
    occlusion : (T-1, H, W) float32, the paper's w_occ (Eq. 6): 1 = visible
        in t+1 (temporal terms on), 0 = occluded, leaves the image, or not
        trusted (:func:`ivkernels.solver.motion_maps.motion_maps`: the warp's
        reliability, chromaticity along the flow, an estimated flow's round
        trip).
    boundary : (T-1, H, W) float32, the paper's w_bnd: 1 = near a motion boundary.
    diagnostics : dict with ``energy`` (rows of window, level, outer
        iteration, L-BFGS iteration, energy), ``terms`` (each term's energy
        after each level), ``levels`` (per window and level: why each L-BFGS
        run stopped and ``converged``, i.e. stopped on its tolerance rather than
        its iteration budget), ``seconds`` (per stage), ``windows`` (frame ranges),
        ``independent_shadings`` (per window, the number its albedo priors
        were divided by; ``Params.independent_shading_gain``),
        ``noise_levels`` (per window, the median noise step of its frames in
        log units, ``None`` with ``Params.layer_denoise = 0``; at 0.01 or
        more its albedo and shading were smoothed,
        :mod:`ivkernels.solver.denoise`).
    """

    albedo: np.ndarray
    shading: np.ndarray
    flow: np.ndarray | None
    occlusion: np.ndarray | None
    boundary: np.ndarray | None
    diagnostics: dict = field(default_factory=dict)

    def reconstruct(self) -> np.ndarray:
        """Linear RGB frames ``albedo * shading`` (T, H, W, 3): the input, less the noise taken out."""
        return self.albedo * self.shading[..., None]


@dataclass
class WindowResult:
    """One solved window: frames ``[start, stop)`` of the video, of which the
    first ``n_carried`` repeat the previous window's output."""

    start: int
    stop: int
    n_carried: int
    albedo: np.ndarray       # (stop-start, H, W, 3) linear
    shading: np.ndarray      # (stop-start, H, W) linear
    flow: np.ndarray | None  # (stop-start-1, H, W, 2)
    occlusion: np.ndarray | None
    boundary: np.ndarray | None
    noise_levels: tuple = ()  # the median noise step of each window solved (solver.denoise), None if not read


def window_ranges(n_frames: int, window: int, overlap: int) -> list[tuple[int, int, int]]:
    """``(start, stop, n_carried)`` of each window covering ``n_frames`` frames.

    Windows have ``window`` frames (fewer only if the video is shorter) and
    share ``overlap`` frames with the previous one (at least 1 whenever there
    is a previous window, so the temporal terms link every pair of frames);
    the last window is moved back to stay full, sharing more frames instead.
    """
    if n_frames <= window:
        return [(0, n_frames, 0)]
    overlap = max(1, overlap)
    out = [(0, window, 0)]
    while out[-1][1] < n_frames:
        prev_stop = out[-1][1]
        start = min(prev_stop - overlap, n_frames - window)
        out.append((start, start + window, prev_stop - start))
    return out


def _resolved_threads(threads) -> int:
    """``threads`` checked, or the calling thread's launch thread count when ``None``."""
    return get_threads() if threads is None else check_threads(threads)


def _as_flow(flow, n_frames: int, height: int, width: int) -> np.ndarray:
    """A user flow (T-1, H, W, 2) as float32, checked by :func:`ivkernels.validation.check_flow`."""
    return v.check_flow(flow, n_frames, height, width)


def iter_decompose(frames, flow=None, temporal: bool = True, backend: str = "warp",
                   device: str = "cpu", params: Params | None = None,
                   progress: bool = False, threads: int | None = None,
                   flow_passes: int = DEFAULT_FLOW_PASSES) -> Iterator[WindowResult]:
    """Decompose window by window; see :func:`decompose` for the arguments.

    Yields :class:`WindowResult` objects in order; memory stays bounded by one
    window whatever the length of the video (the command line writes each
    window to disk as it arrives).  Use :func:`decompose` for diagnostics.
    Every argument is checked when this function is called, before it
    returns the iterator: bad input raises here, not at the first ``next()``.
    The thread count applies while a window is being solved, not between
    windows (the caller's own launches keep theirs).
    """
    job = _Decomposer(frames, flow, temporal, backend, device, params, progress, threads,
                      keep_outputs=False, flow_passes=flow_passes)
    return iterate_with_threads(job.threads, job.windows())


class _Decomposer:
    """Host-side schedule of a decomposition: flow, maps, then the window solves."""

    def __init__(self, frames, flow, temporal, backend, device, params, progress, threads, *,
                 keep_outputs: bool = True, flow_passes: int = 1):
        # cheap checks first, then shapes, then memory, and only then values and allocations
        if params is None:
            params = Params()
        if not isinstance(params, Params):
            raise TypeError(f"params must be an ivkernels.Params, got {type(params).__name__}")
        if not isinstance(temporal, (bool, np.bool_)):
            raise TypeError(f"temporal must be True or False, got {temporal!r}")
        check_device(backend, device)
        threads = _resolved_threads(threads)
        if isinstance(flow_passes, (bool, np.bool_)) or not isinstance(flow_passes, (int, np.integer)) \
                or flow_passes < 1:
            raise ValueError(f"flow_passes must be an int >= 1, got {flow_passes!r}")
        if isinstance(flow, str):
            if flow not in FLOW_METHODS:
                raise ValueError(f"unknown flow method {flow!r}; expected one of {FLOW_METHODS}")
        checked = v.check_frames(frames, min_size=v.MIN_FRAME_SIZE, what="decompose")
        T, H, W = checked.shape
        levels = v.pyramid_levels(H, W, params.pyramid_scale, params.pyramid_min_size)
        if levels > v.MAX_PYRAMID_LEVELS:
            raise ValueError(f"Params.pyramid_scale={params.pyramid_scale} and pyramid_min_size="
                             f"{params.pyramid_min_size} give more than {v.MAX_PYRAMID_LEVELS} pyramid "
                             f"levels on {W}x{H} frames; use a smaller pyramid_scale or a larger "
                             "pyramid_min_size")
        v.check_memory(v.decompose_nbytes(T, H, W, int(params.window), keep_outputs=keep_outputs),
                       f"decomposing {T} frames of {W}x{H}",
                       hint="use fewer or smaller frames, or iter_decompose and a smaller "
                            "Params.window")
        given_flow = None
        if flow is not None and not isinstance(flow, str):
            given_flow = _as_flow(flow, T, H, W)

        self.frames = v.linear_frames(checked)
        self.params = params
        self.temporal = bool(temporal)
        self.be = get_backend(backend, device)
        self.threads = threads
        self.be.use_threads(threads)
        self.prior = load_albedo_prior()
        self.progress = progress
        self.log = SolveLog()
        self.flow_method = None
        self.flow_passes = int(flow_passes)
        self.flow = given_flow
        if isinstance(flow, str):
            self.flow_method = flow
        elif flow is None:
            self.flow_method = DEFAULT_FLOW_METHOD if self.temporal else None
        self.scale = None

    def _flow_for(self, start: int, stop: int, cached: dict, stage: str = "flow") -> np.ndarray | None:
        if self.flow is not None:
            return self.flow[start:stop - 1]
        if self.flow_method is None or stop - start < 2:
            return None
        return self._cached_pairs(start, stop, cached, stage, f"flow ({self.flow_method})",
                                  lambda first, last: self._first_pass_flow(self.frames[first:last + 2]))

    def _cached_pairs(self, start: int, stop: int, cached: dict, stage: str, desc: str | None,
                      estimate) -> np.ndarray:
        """The flows of pairs ``start..stop-2`` (stop-start-1, H, W, 2) from ``cached`` (pair ->
        flow), the missing ones estimated by ``estimate(first, last)`` (the flows of pairs
        first..last) and cached; pairs before ``start`` are dropped from the cache.  Seconds
        are logged as ``stage``; ``desc`` names the progress bar (None: no bar)."""
        missing = [t for t in range(start, stop - 1) if t not in cached]
        if missing:
            t0 = time.perf_counter()
            # Several pairs per call: the flow kernels then run over longer row
            # ranges, with fewer launches per pair, while the progress bar still
            # moves a few times per window.
            batches = [missing[i:i + FLOW_PAIRS_PER_CALL]
                       for i in range(0, len(missing), FLOW_PAIRS_PER_CALL)]
            with tqdm(total=len(missing), desc=desc, unit="pair",
                      disable=not self.progress or desc is None, leave=False) as bar:
                for batch in batches:
                    first, last = batch[0], batch[-1]
                    flows = estimate(first, last)
                    for t in batch:
                        cached[t] = flows[t - first]
                    bar.update(len(batch))
            self.log.add_time(stage, time.perf_counter() - t0)
        for t in [t for t in cached if t < start]:
            del cached[t]
        return np.stack([cached[t] for t in range(start, stop - 1)])

    def _in_background(self, method, *args, **kwargs):
        """``method(*args, **kwargs)`` with this job's launch threads, for a second Python
        thread whose flow estimates overlap the solve's launches."""
        with launch_threads(self.threads):
            return method(*args, **kwargs)

    @property
    def checks_round_trip(self) -> bool:
        """Whether ``w_occ`` gets the forward-backward check (an estimated flow,
        ``Params.flow_round_trip_max`` > 0): a given flow is taken as it is."""
        return self.flow is None and self.flow_method is not None and self.params.flow_round_trip_max > 0.0

    def _back_flow_for(self, start: int, stop: int, cached: dict, stage: str = "back flow") -> np.ndarray | None:
        """The backward flow of frames ``start..stop-1``, (stop-start-1, H, W, 2): entry ``t``
        maps frame ``start+t+1`` to frame ``start+t``, estimated from the input frames at
        ``Params.flow_round_trip_scale`` times their size (:func:`scaled_shape`); None where
        the check is off.
        ``cached`` (pair -> flow) keeps the pairs a later window shares."""
        if not self.checks_round_trip or stop - start < 2:
            return None
        shape = scaled_shape(*self.frames.shape[1:3], self.params.flow_round_trip_scale)

        def backward(first: int, last: int) -> np.ndarray:
            # frames last+1, last, ..., first: their forward flow is the backward flow, last pair first
            return self._flow_at(self.frames[first:last + 2][::-1].copy(), shape)[::-1]

        return self._cached_pairs(start, stop, cached, stage, None, backward)

    def _still_surfaces(self, frames_be, flow_np: np.ndarray | None) -> np.ndarray | None:
        """(H, W) bool: the pixels of a window whose frames ``frames_be`` show the same
        surface (:func:`still_surface_mask`), where the flow is estimated,
        ``Params.flow_still_surface_tau`` > 0 and the window's first-pass flow
        ``flow_np`` says the camera holds still (:func:`camera_holds_still`); else None.
        The mask is computed only where the median flow is under ``MOVING_CAMERA_FLOW``."""
        p = self.params
        if self.flow is not None or flow_np is None or not len(flow_np) or p.flow_still_surface_tau <= 0 \
                or median_flow_length(flow_np) >= MOVING_CAMERA_FLOW:
            return None
        t0 = time.perf_counter()
        still = still_surface_mask(self.be, frames_be, p)
        self.log.add_time("maps", time.perf_counter() - t0)
        return still if camera_holds_still(flow_np, still) else None

    def _first_pass_flow(self, frames: np.ndarray) -> np.ndarray:
        """The flow of the first pass on ``frames`` (T, H, W, 3), at full size.

        When later passes re-estimate it (:attr:`joint`) and
        ``Params.first_flow_at_guide_size`` is set, it only feeds the guide
        solve, which works at the guide's size: it is estimated on the
        frames resized to that size, and its up-sampled vectors are returned.
        """
        H, W = frames.shape[1:3]
        shape = guide_shape(H, W, self.params) if self.joint and self.params.first_flow_at_guide_size \
            else (H, W)
        return self._flow_at(frames, shape)

    def _refine_shape(self, H: int, W: int) -> tuple[int, int]:
        """The size the flow passes after the first run at for frames of (H, W): the
        guide's when its shorter side is at least ``Params.flow_refine_guide_min_side``
        (> 0), else (H, W)."""
        least = int(self.params.flow_refine_guide_min_side)
        shape = guide_shape(H, W, self.params)
        return shape if least > 0 and min(shape) >= least else (H, W)

    def _flow_at(self, frames: np.ndarray, shape: tuple[int, int], init: np.ndarray | None = None,
                 **options) -> np.ndarray:
        """Flow of ``frames`` (T, H, W, 3) estimated at ``shape`` (h, w): the frames (and
        ``init``, (T-1, H, W, 2), when given) resized to it, the vectors up-sampled back
        to (T-1, H, W, 2); ``options`` go to :func:`estimate_flow`."""
        be, (H, W) = self.be, frames.shape[1:3]
        if tuple(shape) != (H, W):
            frames = np.array(be.numpy(downsample(be, be.asarray(frames), shape)), copy=True)
            if init is not None:
                init = np.array(be.numpy(resize_flow(be, be.asarray(init), shape)), copy=True)
        if init is not None:
            options["init"] = init
        flow = estimate_flow(frames, method=self.flow_method, backend=be.name, device=be.device, **options)
        if tuple(shape) != (H, W):
            flow = np.array(be.numpy(resize_flow(be, be.asarray(flow), (H, W))), copy=True)
        return flow

    @property
    def joint(self) -> bool:
        """Whether the flow is re-estimated on the albedo (estimated flow, temporal terms on)."""
        return self.flow is None and self.flow_method is not None and self.flow_passes > 1

    def _joint_flow(self, frames_be, flow_np: np.ndarray, shared: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Passes 2..N of flow and intrinsic video together, for one window.

        Each pass re-estimates the window's flow on the albedo of a guide
        solve (:func:`ivkernels.solver.guide.guide_solve`), which obeys
        brightness constancy where the input does not (paper Sec. 5.1, 6);
        Classic+NL starts from the previous pass's flow, with
        ``Params.flow_refine_warps`` warping steps per level, at the guide's
        size from ``Params.flow_refine_guide_min_side`` up (:meth:`_refine_shape`).  The first
        ``shared`` pairs are the previous window's last flow (the pairs of the
        frames both windows hold): kept, not re-estimated.  Returns the last
        flow and the last guide's log shading (at the guide's size).
        """
        classic = self.flow_method.startswith("classic_nl")
        guide_shading = None
        for _ in range(self.flow_passes - 1):
            albedo, guide_shading = guide_solve(self.be, frames_be, flow_np, self.params, self.prior,
                                                log=self.log)
            t0 = time.perf_counter()
            extra = {"init": flow_np[shared:], "warps": int(self.params.flow_refine_warps)} if classic else {}
            new = self._flow_at(albedo[shared:], self._refine_shape(*albedo.shape[1:3]), **extra)
            flow_np = np.concatenate([flow_np[:shared], new]) if shared else new
            self.log.add_time("flow", time.perf_counter() - t0)
        return flow_np, guide_shading

    def windows(self) -> Iterator[WindowResult]:
        be, p = self.be, self.params
        T, H, W, _ = self.frames.shape
        ranges = window_ranges(T, int(p.window), int(p.overlap))
        n_levels = len(level_shapes(H, W, p.pyramid_scale, p.pyramid_min_size))
        bar = None
        if self.progress:
            bar = tqdm(total=len(ranges) * n_levels, desc="solve (window x level)", unit="level")
        cached_flow: dict = {}
        cached_back: dict = {}      # pair -> backward flow of the forward-backward check
        last_flow: dict = {}        # pair -> the previous window's last-pass flow
        carried = None
        ahead = pool = None
        if FLOW_AHEAD and (len(ranges) > 1 or self.checks_round_trip) and self.flow is None \
                and self.flow_method is not None and be.overlaps_python_threads:
            pool = ThreadPoolExecutor(1, thread_name_prefix="ivkernels-flow-ahead")
        try:
            for index, (start, stop, n_carried) in enumerate(ranges):
                frames_np = self.frames[start:stop]
                if ahead is not None:
                    ahead.result()          # the cache holds this window's first-pass flow now
                flow_np = self._flow_for(start, stop, cached_flow)
                frames_be = be.asarray(frames_np)
                still = self._still_surfaces(frames_be, flow_np)
                # Short vectors are held in the final flow only: a later pass starts from this
                # one, and a moving object whose first flow is patchy would lose its motion.
                flow_np = hold_still_surfaces(flow_np, still, 0.0 if self.joint else p.flow_still_small)
                back = None         # this window's backward flow, estimated while its guide is solved
                if pool is not None and self.checks_round_trip:
                    back = pool.submit(self._in_background, self._back_flow_for, start, stop, cached_back,
                                       stage="back flow, overlapped")
                if pool is not None and index + 1 < len(ranges):
                    ahead = pool.submit(self._in_background, self._flow_for, *ranges[index + 1][:2], cached_flow,
                                        stage="flow ahead")
                occ_np = bnd_np = None
                guide_shading = None
                if flow_np is not None and self.joint:
                    shared = 0
                    while shared < len(flow_np) - 1 and start + shared in last_flow:
                        flow_np[shared] = last_flow[start + shared]
                        shared += 1
                    flow_np, guide_shading = self._joint_flow(frames_be, flow_np, shared)
                    if still is not None:       # the shared pairs were held by the window before
                        held = hold_still_surfaces(flow_np[shared:], still, p.flow_still_small)
                        flow_np = np.concatenate([flow_np[:shared], held])
                    last_flow = {start + k: f for k, f in enumerate(flow_np)}
                elif self.flow is not None and self.temporal and p.start_from_guide \
                        and flow_np is not None and len(flow_np):
                    # A given flow is final: one guide solve with it, the last solve's start.
                    _, guide_shading = guide_solve(be, frames_be, flow_np, p, self.prior, log=self.log)
                back_np = back.result() if back is not None else self._back_flow_for(start, stop, cached_back)
                back_np = hold_still_surfaces(back_np, still, p.flow_still_small)
                t0 = time.perf_counter()
                flow_be = occ_be = bnd_be = None
                if flow_np is not None:
                    flow_be = be.asarray(flow_np)
                    occ_be, bnd_be = motion_maps(be, frames_be, flow_be, p,
                                                 back_flow=None if back_np is None else be.asarray(back_np))
                    occ_np = np.array(be.numpy(occ_be), copy=True)
                    bnd_np = np.array(be.numpy(bnd_be), copy=True)
                self.log.add_time("maps", time.perf_counter() - t0)
                use_flow = self.temporal and flow_be is not None
                A, S = solve_window(
                    be, frames_be, flow_be if use_flow else None, occ_be if use_flow else None,
                    bnd_be if use_flow else None, p, self.prior,
                    carried=None if carried is None else
                    (carried[0][-n_carried:], carried[1][-n_carried:]) if n_carried else None,
                    window_index=index, log=self.log,
                    progress=None if bar is None else bar.update,
                    start_shading=guide_shading if use_flow and p.start_from_guide else None)
                carried = (A, S)
                t0 = time.perf_counter()
                A, S, noise = denoise_layers(be, frames_be, flow_be, A, S, p)
                self.log.noise_levels.append(noise)
                self.log.add_time("denoise", time.perf_counter() - t0)
                albedo, shading = np.exp(A), np.exp(S)
                if self.scale is None:
                    # Scale ambiguity of A + S: albedo's 99th percentile = 1 (DESIGN sec. 2).
                    self.scale = float(np.percentile(albedo, 99.0)) or 1.0
                albedo /= self.scale
                shading *= self.scale
                yield WindowResult(start, stop, n_carried, albedo.astype(np.float32),
                                   shading.astype(np.float32), flow_np, occ_np, bnd_np, (noise,))
        finally:
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
            if bar is not None:
                bar.close()


def decompose(frames, flow=None, temporal: bool = True, backend: str = "warp",
              device: str = "cpu", params: Params | None = None,
              progress: bool = False, flow_passes: int = DEFAULT_FLOW_PASSES,
              threads: int | None = None) -> IntrinsicVideo:
    """Decompose a video into albedo, shading, flow, occlusion and boundaries.

    Minimises Eq. 2 of Kong, Gehler & Black (ECCV 2014) coarse to fine over
    windows of frames.

    Parameters
    ----------
    frames : (T, H, W, 3) array: uint8 or uint16 sRGB, or float linear RGB in
        [0, 1].  A single frame (H, W, 3) is treated as T = 1.
    flow : ``None`` (estimate with :data:`DEFAULT_FLOW_METHOD`), the name of
        a method of :func:`ivkernels.estimate_flow`, or a (T-1, H, W, 2)
        float array of forward flow in pixels (e.g. ground truth).  An
        estimated flow is also estimated backwards, at a quarter of the size,
        and the temporal terms leave out the pixels where the two miss each
        other (``Params.flow_round_trip_max``); where a window's camera holds
        still, both are zero at the pixels whose frames show the same surface
        (``Params.flow_still_surface_tau``: a moving shadow does not drag the
        flow of the floor it crosses) and wherever the final flow is shorter
        than ``Params.flow_still_small`` (a moving light's pull on a static
        scene).  A given flow is taken as it is.
    temporal : ``False`` drops the temporal terms and the motion weights (the
        paper's "IV w/o flow" ablation); no flow is estimated then.
    backend : ``"warp"`` (default) or ``"taichi"``.
    device : ``"cpu"`` or ``"cuda"`` (Warp only).
    params : :class:`ivkernels.Params`; defaults are the paper's weights where
        they measured well and weights chosen on training sequences elsewhere
        (each documented in ``Params``).
    progress : show a progress bar per stage.
    flow_passes : passes of flow and intrinsic video estimated together,
        per window, when the flow is estimated (``flow=None`` or a method
        name; ignored for a given flow array and with ``temporal=False``).
        Pass 1 estimates the flow on the input; each later pass solves the
        window at ``Params.flow_guide_scale`` of its size, re-estimates the
        flow on that solve's albedo, which obeys brightness constancy where
        the input does not (paper Sec. 5.1 and 6), starting from the previous
        flow, and the last solve uses the final flow
        (:func:`ivkernels.solver.guide.guide_albedo`).  Default 2, measured on
        training seed 1 (perf/RESULTS.md, "Flow and intrinsic video
        together"): the second pass lowers flow EPE on a static scene under
        a moving light from 0.168 to 0.053 px, under rotating shadows from
        0.527 to 0.186 px, and LMSE on every kind, for about 1.4x the time
        of one pass; 1 estimates the flow on the input only.
    threads : CPU threads the kernels run on (an integer >= 1).  ``None``
        (default): the environment variable ``IVKERNELS_THREADS`` if set, else
        every core this process may use (see :mod:`ivkernels.kernels.launch`).
        Warp splits each launch into up to this many row bands; Taichi is
        (re-)initialised with this count (a different count than Taichi's
        current one re-initialises it, see :func:`ivkernels.kernels.taichi.init`).

    Returns
    -------
    IntrinsicVideo

    Raises
    ------
    TypeError, ValueError
        for bad arguments, checked before any work by
        :mod:`ivkernels.validation` (the rules :func:`iter_decompose`,
        :func:`ivkernels.estimate_flow` and the command line share): frames of
        an unsupported dtype or shape, float frames outside [0, 1] or not
        finite, frames of different sizes in a list (the frame is named), a
        flow of the wrong shape, not finite or beyond
        :data:`ivkernels.validation.MAX_FLOW` pixels, an unknown backend, a
        malformed device, a CUDA device that is not present, or ``threads``
        (or ``IVKERNELS_THREADS``) that is not an integer >= 1.
    ivkernels.validation.NotEnoughMemoryError
        (a MemoryError and a ValueError) when the estimated memory of the
        call exceeds the memory available, before anything is allocated.

    Examples
    --------
    >>> import ivkernels as iv
    >>> seq = iv.synthetic.render_sequence("static_moving_light", n_frames=3, size=(48, 64))
    >>> video = iv.decompose(seq.frames, flow=seq.flow)          # doctest: +SKIP
    >>> video.albedo.shape, video.shading.shape
    ((3, 48, 64, 3), (3, 48, 64))
    """
    n_threads = _resolved_threads(threads)
    with launch_threads(n_threads):
        video = _collect(_Decomposer(frames, flow, temporal, backend, device, params, progress,
                                     n_threads, flow_passes=flow_passes))
    release_free_memory()       # the call's arrays are freed: their heap pages go back (kernels/memory.py)
    return video


def _flow_label(job: _Decomposer) -> str | None:
    """How the flow of ``job`` was made, for ``diagnostics["flow_method"]``."""
    if job.flow is not None:
        return "given"
    if job.joint:
        return f"{job.flow_method}, {job.flow_passes} passes with the intrinsic video"
    return job.flow_method


def _collect(job: _Decomposer) -> IntrinsicVideo:
    """Run every window of ``job`` and assemble the :class:`IntrinsicVideo`."""
    T, H, W, _ = job.frames.shape
    albedo = np.empty((T, H, W, 3), np.float32)
    shading = np.empty((T, H, W), np.float32)
    flow_out = occ_out = bnd_out = None
    windows = []
    for res in job.windows():
        albedo[res.start:res.stop] = res.albedo
        shading[res.start:res.stop] = res.shading
        if res.flow is not None:
            if flow_out is None:
                flow_out = np.zeros((T - 1, H, W, 2), np.float32)
                occ_out = np.zeros((T - 1, H, W), np.float32)
                bnd_out = np.zeros((T - 1, H, W), np.float32)
            flow_out[res.start:res.stop - 1] = res.flow
            occ_out[res.start:res.stop - 1] = res.occlusion
            bnd_out[res.start:res.stop - 1] = res.boundary
        windows.append((res.start, res.stop))
    diagnostics = {"energy": job.log.energy, "terms": job.log.terms, "levels": job.log.levels,
                   "seconds": dict(job.log.seconds), "windows": windows,
                   "independent_shadings": [n for _, n in job.log.shadings],
                   "noise_levels": list(job.log.noise_levels),
                   "flow_method": _flow_label(job),
                   "albedo_scale": job.scale}
    return IntrinsicVideo(albedo, shading, flow_out, occ_out, bnd_out, diagnostics)
