"""Many videos and long videos: :func:`decompose_many` and :func:`iter_decompose_many`.

The plan: every video is one task, or, with ``chunk_frames``, one task per
chunk (:mod:`ivkernels.parallel.chunks`; a chunk's task solves it in longer
windows than ``Params.window``, :func:`~ivkernels.parallel.chunks.chunk_params`);
the tasks run on an engine (:mod:`ivkernels.parallel.engines`: this process,
or a Ray cluster), and a chunked video is stitched once all its chunks are
back.  Every input is checked in this process before any task starts, so a
bad one fails early and alone; paths are read here, one video at a time as
tasks are submitted, so the workers need neither the files nor a shared file
system, and at most :meth:`capacity` tasks' frames wait in the object store.
"""
from __future__ import annotations

import inspect
import os
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Sequence

import numpy as np
from tqdm.auto import tqdm

from ivkernels import validation as v
from ivkernels.backends import check_device
from ivkernels.decompose import IntrinsicVideo, decompose
from ivkernels.flow import FLOW_METHODS
from ivkernels.io import probe_frames, read_frames
from ivkernels.kernels.thread_count import check_threads
from ivkernels.params import Params
from ivkernels.parallel.chunks import chunk_params, chunk_ranges, stitch
from ivkernels.parallel.engines import LocalEngine, RayEngine, import_ray

#: Engines :func:`decompose_many` runs on.
ENGINES = ("ray", "local")
#: What :func:`decompose_many` does with a video that fails (``errors=``).
ERROR_MODES = ("raise", "return")
#: Keyword arguments of :func:`ivkernels.decompose` passed through (all but
#: the frames, the flow, which may differ per video, and the progress bars).
DECOMPOSE_OPTIONS = tuple(name for name in inspect.signature(decompose).parameters
                          if name not in ("frames", "flow", "progress"))


class VideoError(Exception):
    """A video of :func:`decompose_many` that failed: its index, its source, and why.

    ``str(err)`` is one line, ``"videos[i] (source): reason"``; the exception
    the task raised is ``err.__cause__`` (and ``err.cause``).
    """

    def __init__(self, index: int, source: str, cause: BaseException):
        reason = " ".join(str(cause).split()) or type(cause).__name__
        super().__init__(f"videos[{index}] ({source}): {reason}")
        self.index, self.source, self.cause = index, source, cause
        self.__cause__ = cause


@dataclass
class _Video:
    """One input and the state of its tasks."""

    index: int
    source: object                     # an array, or a Path read when submitted
    flow: object                       # None, a method name, or a (T-1, H, W, 2) array
    n_frames: int                      # from the array, or the file's header
    ranges: list = field(default_factory=list)
    done: dict = field(default_factory=dict)

    @property
    def label(self) -> str:
        if isinstance(self.source, Path):
            return str(self.source)
        return f"array {tuple(np.shape(self.source))} {getattr(self.source, 'dtype', '')}".strip()


def _check_options(kwargs: dict, engine: str, errors: str, chunk_frames, chunk_overlap,
                   max_retries) -> tuple[dict, int]:
    """The decompose options as a dict, checked once for every video; returns ``(options, overlap)``."""
    unknown = sorted(set(kwargs) - set(DECOMPOSE_OPTIONS))
    if unknown:
        raise TypeError(f"decompose_many got unexpected keyword argument(s) {', '.join(unknown)}; "
                        f"it passes on {', '.join(DECOMPOSE_OPTIONS)} (and flow)")
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    if engine == "ray":
        import_ray()                   # ImportError with the install line, before any work
    if errors not in ERROR_MODES:
        raise ValueError(f"errors must be one of {ERROR_MODES}, got {errors!r}")
    params = kwargs.get("params") or Params()
    if not isinstance(params, Params):
        raise TypeError(f"params must be an ivkernels.Params, got {type(params).__name__}")
    temporal = kwargs.get("temporal", True)
    if not isinstance(temporal, (bool, np.bool_)):
        raise TypeError(f"temporal must be True or False, got {temporal!r}")
    check_device(kwargs.get("backend", "warp"), kwargs.get("device", "cpu"))
    if kwargs.get("threads") is not None:
        check_threads(kwargs["threads"])
    passes = kwargs.get("flow_passes", 1)
    if isinstance(passes, (bool, np.bool_)) or not isinstance(passes, (int, np.integer)) or passes < 1:
        raise ValueError(f"flow_passes must be an int >= 1, got {passes!r}")
    if chunk_frames is not None:
        _check_int(chunk_frames, "chunk_frames", 2)
    overlap = int(params.overlap) if chunk_overlap is None else _check_int(chunk_overlap, "chunk_overlap", 1)
    overlap = max(1, overlap)
    if chunk_frames is not None and overlap >= chunk_frames:
        raise ValueError(f"chunk_overlap ({overlap}) must be smaller than chunk_frames ({chunk_frames})")
    _check_int(max_retries, "max_retries", 0)
    return dict(kwargs, params=params), overlap


def _check_int(value, name: str, least: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


def _per_video_flows(flow, n_videos: int) -> list:
    """``flow`` as one entry per video: ``None`` or a method name for all, or a list of them."""
    if flow is None or isinstance(flow, str):
        if isinstance(flow, str):
            if flow not in FLOW_METHODS:
                raise ValueError(f"unknown flow method {flow!r}; expected one of {FLOW_METHODS}")
        return [flow] * n_videos
    if isinstance(flow, np.ndarray) or not isinstance(flow, (list, tuple)):
        raise TypeError("flow for decompose_many must be None, a flow method name, or a list with "
                        f"one entry (None, a method name or a (T-1, H, W, 2) array) per video; got "
                        f"{type(flow).__name__}")
    if len(flow) != n_videos:
        raise ValueError(f"flow lists {len(flow)} entries for {n_videos} videos; give one per video")
    return list(flow)


def _check_frames(frames, name: str) -> v.Frames:
    """Shape, dtype and (for float frames) values of one video, without a converted copy."""
    checked = v.check_frames(frames, name=name, min_size=v.MIN_FRAME_SIZE, what="decompose")
    if checked.dtype.kind == "f":
        for t in range(checked.shape[0]):
            f = np.asarray(checked.source[t])
            if not np.isfinite(f).all():
                raise ValueError(f"{name}[{t}] contains NaN or infinite values")
            lo, hi = float(f.min()), float(f.max())
            if lo < -v.FLOAT_TOLERANCE or hi > 1 + v.FLOAT_TOLERANCE:
                raise ValueError(f"{name}[{t}]: float frames are linear RGB in [0, 1], got values in "
                                 f"[{lo:.4g}, {hi:.4g}]")
    return checked


def _check_shape(T: int, H: int, W: int, params: Params, name: str) -> None:
    if min(H, W) < v.MIN_FRAME_SIZE:
        raise ValueError(f"{name}: frames must be at least {v.MIN_FRAME_SIZE}x{v.MIN_FRAME_SIZE} "
                         f"pixels, got {H}x{W}")
    if v.pyramid_levels(H, W, params.pyramid_scale, params.pyramid_min_size) > v.MAX_PYRAMID_LEVELS:
        raise ValueError(f"{name}: Params.pyramid_scale={params.pyramid_scale} gives more than "
                         f"{v.MAX_PYRAMID_LEVELS} pyramid levels on {W}x{H} frames")


def _prepare(index: int, video, flow, params: Params, probe: Callable) -> _Video:
    """Check one input up front; raises the reason it cannot be decomposed."""
    name = f"videos[{index}]"
    if isinstance(video, (str, os.PathLike)):
        path = Path(video)
        if not path.exists():
            raise FileNotFoundError(f"{path} does not exist; expected a video file or a folder of images")
        T, H, W = probe(path)
        if T < 1:
            raise ValueError(f"{path}: no frames selected")
        _check_shape(T, H, W, params, name)
        source = path
    else:
        checked = _check_frames(video, name)
        T, H, W = checked.shape
        _check_shape(T, H, W, params, name)
        source = np.asarray(checked.source) if not isinstance(checked.source, list) \
            else np.stack(checked.source)
        if source.ndim == 3:
            source = source[None]
    if flow is not None and not isinstance(flow, str):
        if isinstance(source, Path):
            flow = np.asarray(flow)            # checked against the frames once they are read
        else:
            flow = v.check_flow(flow, T, H, W, name=f"flow[{index}]")
    elif isinstance(flow, str):
        if flow not in FLOW_METHODS:
            raise ValueError(f"unknown flow method {flow!r}; expected one of {FLOW_METHODS}")
    return _Video(index, source, flow, T)


def _load(video: _Video, reader: Callable) -> tuple[np.ndarray, object]:
    """The frames and flow of ``video``, read now if it is a path."""
    if not isinstance(video.source, Path):
        return video.source, video.flow
    frames = _check_frames(reader(video.source), f"videos[{video.index}]")
    T, H, W = frames.shape
    flow = video.flow
    if flow is not None and not isinstance(flow, str):
        flow = v.check_flow(flow, T, H, W, name=f"flow[{video.index}]")
    video.n_frames = T
    return np.asarray(frames.source), flow


def iter_decompose_many(videos: Sequence, *, engine: str = "ray", address: str | None = None,
                        chunk_frames: int | None = None, chunk_overlap: int | None = None,
                        errors: str = "raise", max_retries: int = 3, progress: bool = False,
                        reader: Callable | None = None, probe: Callable | None = None,
                        flow=None, **kwargs) -> Iterator[tuple[int, IntrinsicVideo | VideoError]]:
    """Decompose many videos; yields ``(index, result)`` as each video is finished.

    The arguments are those of :func:`decompose_many`, plus:

    reader : function ``path -> frames`` used for the inputs that are paths
        (default :func:`ivkernels.io.read_frames`); the command line passes
        one that applies its frame selection.
    probe : function ``path -> (T, H, W)`` that checks a path up front
        without decoding it (default :func:`ivkernels.io.probe_frames`).

    Every argument and every input is checked when this function is called,
    before it returns the iterator (and before a cluster is started or
    joined): with ``errors="raise"`` a bad input raises here.  Results come
    in the order the videos finish, each as soon as it (all of its chunks)
    is done.  With ``errors="return"`` a failed video yields a
    :class:`VideoError` in its place (bad inputs first); with
    ``errors="raise"`` the first failure raises it and the remaining tasks
    are cancelled.  Closing the iterator cancels the tasks still running.
    """
    options, overlap = _check_options(kwargs, engine, errors, chunk_frames, chunk_overlap, max_retries)
    if isinstance(videos, np.ndarray) or isinstance(videos, (str, os.PathLike)):
        raise TypeError("videos must be a list of videos (arrays or paths); for one video "
                        "pass [video]")
    videos = list(videos)
    flows = _per_video_flows(flow, len(videos))
    reader = reader or read_frames
    probe = probe or probe_frames

    # every input checked before any work: a bad one fails early and alone
    ready: deque = deque()
    failed: list = []
    for i, (video, video_flow) in enumerate(zip(videos, flows)):
        try:
            ready.append(_prepare(i, video, video_flow, options["params"], probe))
        except (ValueError, TypeError, OSError, MemoryError) as err:
            label = str(video) if isinstance(video, (str, os.PathLike)) else f"array {type(video).__name__}"
            failure = VideoError(i, label, err)
            if errors == "raise":
                raise failure from err
            failed.append((i, failure))
    return _run(failed, ready, options, overlap, engine, address, chunk_frames, errors, max_retries,
                progress, reader, flows)


def _run(failed: list, ready: deque, options: dict, overlap: int, engine_name: str, address,
         chunk_frames, errors: str, max_retries: int, progress: bool, reader: Callable, flows: list):
    """Submit, collect and stitch (see :func:`iter_decompose_many`)."""
    yield from failed
    if not ready:
        return

    warm_flow = next((f for f in flows if f is not None), None)
    engine = RayEngine(options, address=address, max_retries=max_retries, warm_up_flow=warm_flow) \
        if engine_name == "ray" else LocalEngine(options)
    n_tasks = sum(len(chunk_ranges(video.n_frames, chunk_frames, overlap)) for video in ready)
    bar = tqdm(total=n_tasks, desc=f"decompose_many ({engine.name})", unit="task", disable=not progress)
    active: dict = {}
    try:
        engine.expect(n_tasks)
        while ready or engine.in_flight():
            while ready and engine.in_flight() < engine.capacity():
                video = ready.popleft()
                estimated = len(chunk_ranges(video.n_frames, chunk_frames, overlap))
                try:
                    frames, flow = _load(video, reader)
                except (ValueError, TypeError, OSError, MemoryError) as err:
                    bar.total -= estimated
                    bar.refresh()
                    failure = VideoError(video.index, video.label, err)
                    if errors == "raise":
                        raise failure from err
                    yield video.index, failure
                    continue
                video.ranges = chunk_ranges(frames.shape[0], chunk_frames, overlap)
                bar.total += len(video.ranges) - estimated
                active[video.index] = video
                for c, (start, stop) in enumerate(video.ranges):
                    chunk_flow = flow[start:stop - 1] if flow is not None and not isinstance(flow, str) \
                        else flow
                    # a video cut into chunks: each solved in longer windows (chunks.chunk_params);
                    # a whole video keeps the caller's params, so it gets decompose()'s result
                    params = chunk_params(options["params"], stop - start) if len(video.ranges) > 1 \
                        else None
                    engine.submit((video.index, c), np.ascontiguousarray(frames[start:stop]), chunk_flow,
                                  params=params)
                del frames, flow
            if not engine.in_flight():
                continue
            (index, c), result = engine.next_done()
            bar.update(1)
            video = active.get(index)
            if video is None:                  # an earlier chunk of this video failed
                continue
            if isinstance(result, BaseException):
                del active[index]
                failure = VideoError(index, video.label, result)
                if errors == "raise":
                    raise failure from result
                yield index, failure
                continue
            video.done[c] = result
            if len(video.done) == len(video.ranges):
                del active[index]
                chunks = [video.done[k] for k in range(len(video.ranges))]
                video.done = {}
                yield index, stitch(chunks, video.ranges)
    finally:
        bar.close()
        engine.cancel()
        engine.close()


def decompose_many(videos: Sequence, *, engine: str = "ray", address: str | None = None,
                   chunk_frames: int | None = None, chunk_overlap: int | None = None,
                   errors: str = "raise", max_retries: int = 3, progress: bool = False,
                   flow=None, **kwargs) -> list:
    """Decompose many videos (and long ones in parallel chunks) on a Ray cluster or in this process.

    Each video is one task, or, with ``chunk_frames``, one task per chunk;
    a task holds one CPU and runs :func:`ivkernels.decompose` with the
    kernels on one thread, so a machine with N cores solves N tasks at
    once (whole videos give exactly the result of :func:`ivkernels.decompose`).
    A call with fewer tasks than twice the CPUs shares them so that none
    idles while the last tasks finish
    (:func:`ivkernels.parallel.engines.task_cpus`): more tasks than CPUs all
    run at once, fewer get several CPUs each and as many kernel threads.

    Parameters
    ----------
    videos : list of videos, each a (T, H, W, 3) array as
        :func:`ivkernels.decompose` takes it, or a path (a video file or a
        folder of images, read here with :func:`ivkernels.io.read_frames` just
        before its tasks are submitted).
    engine : ``"ray"`` (default) runs the tasks on a Ray cluster (needs
        ``pip install 'ivkernels[ray]'``); ``"local"`` runs the same tasks
        one after another in this process, with ``threads`` as given.
    address : Ray cluster to join (``"auto"``, ``"host:port"``,
        ``"ray://host:port"``).  ``None``: the Ray connection this process
        already has, else ``RAY_ADDRESS``, else a local cluster started for
        this call (all of this machine's cores) and shut down at its end.
        Each node of a joined cluster needs ivkernels installed; the files
        need not be there (paths are read in this process).
    chunk_frames : cut each video into chunks of at most this many frames
        of their own (``ceil(T / chunk_frames)`` chunks of equal length),
        solved in parallel, each in windows of up to twice
        ``Params.window`` frames (one window for a chunk of up to 16
        frames at the defaults), and stitched
        (:mod:`ivkernels.parallel.chunks`); ``None`` (default): one task
        per video.
    chunk_overlap : frames each chunk shares with the one before (>= 1);
        default ``Params.overlap``, the frames consecutive windows share
        in the sequential solve (perf/RESULTS.md, "Many videos and long
        videos on Ray", measures the seam's cost).
    errors : ``"raise"`` (default): the first video that fails raises
        :class:`VideoError` (a bad input before any work starts) and the
        other tasks are cancelled.  ``"return"``: a failed video's place in
        the list holds its :class:`VideoError`; the others finish.
    max_retries : times a Ray task whose worker died is run again.
    progress : a progress bar over the tasks (videos and chunks).
    flow : ``None`` or a flow method name for every video, or a list with
        one entry per video (``None``, a method name, or a (T-1, H, W, 2)
        array).
    **kwargs : the other arguments of :func:`ivkernels.decompose`
        (``temporal``, ``backend``, ``device``, ``params``, ``flow_passes``,
        ``threads``; on Ray ``threads`` is the CPUs a task holds, at
        least 1).

    Returns
    -------
    list with one :class:`ivkernels.IntrinsicVideo` per video, in order
    (or a :class:`VideoError` for a failed one with ``errors="return"``).

    Raises
    ------
    TypeError, ValueError : bad arguments shared by all videos, before any work.
    VideoError : with ``errors="raise"``, the first video that failed.
    ImportError : ``engine="ray"`` without Ray installed.

    Examples
    --------
    >>> import ivkernels as iv
    >>> videos = iv.decompose_many(["a.mp4", "b.mp4"])                    # doctest: +SKIP
    >>> long = iv.decompose_many([frames], chunk_frames=24)[0]            # doctest: +SKIP
    """
    if not isinstance(videos, (np.ndarray, str, os.PathLike)):
        videos = list(videos)
    results: list = [None] * len(videos)
    for index, result in iter_decompose_many(videos, engine=engine, address=address,
                                             chunk_frames=chunk_frames, chunk_overlap=chunk_overlap,
                                             errors=errors, max_retries=max_retries,
                                             progress=progress, flow=flow, **kwargs):
        results[index] = result
    return results
