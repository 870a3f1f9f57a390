"""Command line: ``ivkernels decompose INPUT -o OUT``.

Writes into ``OUT``::

    albedo/NNNNN.png          albedo, sRGB 8-bit (for viewing)
    shading/NNNNN.png         shading, sRGB 8-bit grey (for viewing)
    albedo_linear/NNNNN.png   albedo, *linear* 16-bit RGB (for compositing; clipped to [0, 1])
    shading_linear/NNNNN.png  shading, *linear* 16-bit grey (for compositing; clipped to [0, 1])
    flow/NNNNN.png            forward flow t -> t+1, Baker et al. colour wheel
    occlusion/NNNNN.png       w_occ (white = visible in the next frame)
    boundary/NNNNN.png        w_bnd (white = near a motion boundary)
    intrinsics.npz            linear arrays albedo, shading, flow, occlusion, boundary
                              (float16 by default; --npz float32, or none)
    preview.mp4               input | albedo | shading | flow, side by side
    contact_sheet.png         a few frames of each, labelled

Before any work it prints a summary of the job (frames, size, windows, an
estimate of the time) and, while it runs, a progress bar in frames and
windows.  Everything is written into ``OUT.<pid>.partial`` and renamed to
``OUT`` only when complete, so a failed run never leaves output that looks
finished; the partial folder is removed on failure (a full disk included),
SIGINT, SIGTERM and SIGHUP, and one left by a killed run is removed by the
next.  OUT is claimed before any work, so a second run into the same OUT is
refused while the first runs.  OUT must not be, or hold, the input, a flow
folder or the current folder; an existing OUT is replaced only with
``--force``, and only if ivkernels wrote it (see
:class:`ivkernels.io.OutputFolder`).  Every foreseeable failure prints one
line and exits with status 2.
"""
from __future__ import annotations

import argparse
import errno
import math
import os
import sys
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
from tqdm.auto import tqdm

from ivkernels.backends import backend_names, check_device, start_warp
from ivkernels.decompose import (DEFAULT_FLOW_METHOD, DEFAULT_FLOW_PASSES, WindowResult, iter_decompose,
                                 window_ranges)
from ivkernels.flow import FLOW_METHODS
from ivkernels.flowio import read_flo
from ivkernels.io import (Interrupted, NpzWriter, OutputFolder, VideoWriter, probe_frames, read_frames,
                          write_png_sequence)
from ivkernels.kernels.thread_count import check_threads, default_threads
from ivkernels.parallel import iter_decompose_many
from ivkernels.params import Params
from ivkernels.solver.denoise import NOISE_TO_SMOOTH
from ivkernels.validation import check_memory, decompose_nbytes
from ivkernels.viz import albedo_to_srgb8, contact_sheet, flow_to_color, gray_to_rgb8, shading_to_srgb8

#: Seconds per pixel and solved frame of a default run (the flow estimated,
#: two passes), per backend, with both cores of a 2-core machine, and the
#: seconds of a run's start (imports, cached kernels); measured as written in
#: perf/RESULTS.md, "Command line: the time estimate, measured again".  A
#: frame is counted once per window that solves it (the frames windows share
#: are solved twice); the summary's estimate scales the cost by 2 / threads.
SECONDS_PER_PIXEL_FRAME = {"warp": 1.6e-5, "taichi": 5.5e-5, "numpy": 6.9e-4}
START_SECONDS = 3.0

#: ``--npz`` choices: the dtype of ``intrinsics.npz``, or no file.
NPZ_CHOICES = ("float16", "float32", "none")


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line (the usage itself is under ``--help``), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` shows each option's default; options whose default is
    worked out at run time (``None``) say it in their own words, switches
    (``False``) need none."""

    def _get_help_string(self, action):
        if action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="ivkernels", description="Intrinsic video: albedo, shading, flow, occlusion and "
        "motion boundaries of a video (Kong, Gehler & Black, ECCV 2014).")
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("decompose", help="decompose a video file or a folder of images",
                       formatter_class=_HelpFormatter)
    d.add_argument("input", nargs="+", help="video file (mp4, avi, ...) or folder of images (png, jpg, "
                   "tif); with several inputs, or --engine, each is written to OUT/<input name>/")
    d.add_argument("-o", "--out", required=True,
                   help="output folder (must not exist; --force replaces one ivkernels wrote)")
    d.add_argument("--backend", default="warp", choices=backend_names(),
                   help="kernel backend (numpy: the slow exact references, for checking)")
    d.add_argument("--device", default="cpu", help="'cpu' or 'cuda' (warp only)")
    d.add_argument("--threads", type=int, default=None,
                   help="CPU threads the kernels run on (default: IVKERNELS_THREADS if set, else "
                        "every core this process may use)")
    d.add_argument("--flow", default=None,
                   help=f"flow method ({', '.join(FLOW_METHODS)}) or a folder of .flo files, one per "
                        f"consecutive pair (default: {DEFAULT_FLOW_METHOD}; none with --no-temporal)")
    d.add_argument("--flow-passes", type=int, default=DEFAULT_FLOW_PASSES,
                   help="passes of flow and intrinsic video estimated together when the flow is "
                        "estimated (1: flow on the input only)")
    d.add_argument("--no-temporal", action="store_true",
                   help="drop the temporal terms and motion weights (the 'IV w/o flow' ablation)")
    d.add_argument("--start", type=int, default=0, help="first frame index")
    d.add_argument("--stop", type=int, default=None,
                   help="stop before this frame index (default: the end)")
    d.add_argument("--step", type=int, default=1, help="take every STEP-th frame")
    d.add_argument("--scale", type=float, default=1.0, help="resize frames by this factor first")
    d.add_argument("--window", type=int, default=None,
                   help=f"frames per solved window (default: {Params().window}, sharing "
                        f"{Params().overlap} with the previous one)")
    d.add_argument("--denoise", type=float, default=None, metavar="K",
                   help=f"smooth the albedo and shading of a noisy video at K times its noise's step "
                        f"(default: {Params().layer_denoise:g}; 0 keeps albedo * shading = input exactly)")
    d.add_argument("--fps", type=float, default=10.0, help="frame rate of preview.mp4")
    d.add_argument("--force", action="store_true",
                   help="replace OUT if it exists and ivkernels wrote it (never the input or the "
                        "current folder, nor a folder holding other files)")
    d.add_argument("--npz", default="float16", choices=NPZ_CHOICES,
                   help="intrinsics.npz: its float type, or none to write no npz")
    d.add_argument("--quiet", action="store_true", help="no job summary and no progress bar")
    d.add_argument("--engine", choices=("ray", "local"), default=None,
                   help="run the inputs (and chunks) as parallel tasks on a Ray cluster, or one after "
                        "another in this process (default for several inputs: local)")
    d.add_argument("--address", default=None, metavar="ADDR",
                   help="Ray cluster to join (with --engine ray; default: RAY_ADDRESS, else a local "
                        "cluster for this run)")
    d.add_argument("--chunk-frames", type=int, default=None, metavar="N",
                   help="solve each input in parallel chunks of at most N frames, stitched")
    return parser


def _read_flo_folder(folder: Path, n_pairs: int, start: int, step: int) -> np.ndarray:
    files = sorted(folder.glob("*.flo"))
    files = files[start:start + n_pairs]
    if len(files) != n_pairs:
        raise ValueError(f"{folder} holds {len(files)} .flo files from frame {start}; "
                         f"{n_pairs} are needed (one per consecutive pair)")
    return np.stack([read_flo(f) for f in files])


#: Everything :func:`run_decompose` writes into OUT (besides the marker file).
OUTPUT_CONTENTS = ("albedo", "shading", "albedo_linear", "shading_linear", "flow", "occlusion", "boundary",
                   "intrinsics.npz", "preview.mp4", "contact_sheet.png")


def _check_arguments(args):
    """Everything that can be checked from the command line alone, before any work.

    Returns ``(params, flow_folder)``.
    """
    src = Path(args.input)
    if not src.exists():
        raise ValueError(f"input {src} does not exist; expected a video file or a folder of images")
    if not math.isfinite(args.fps) or not 0 < args.fps <= 1000:
        raise ValueError(f"--fps must be a frame rate in (0, 1000], got {args.fps}")
    if not math.isfinite(args.scale) or not 0 < args.scale <= 16:
        raise ValueError(f"--scale must be a factor in (0, 16], got {args.scale}")
    if args.start < 0:
        raise ValueError(f"--start must be >= 0, got {args.start}")
    if args.step < 1:
        raise ValueError(f"--step must be >= 1, got {args.step}")
    if args.stop is not None and args.stop <= args.start:
        raise ValueError(f"--stop ({args.stop}) must be greater than --start ({args.start})")
    params = Params()
    if args.window is not None:
        if args.window < 2:
            raise ValueError(f"--window must be at least 2 frames, got {args.window}")
        params = params.replace(window=args.window, overlap=min(params.overlap, args.window - 1))
    if args.denoise is not None:
        if not (math.isfinite(args.denoise) and 0 <= args.denoise <= 20):
            raise ValueError(f"--denoise must be a multiple of the noise's step in [0, 20], got {args.denoise}")
        params = params.replace(layer_denoise=args.denoise)
    check_device(args.backend, args.device)
    if args.threads is not None:
        check_threads(args.threads, name="--threads")
    else:
        default_threads()           # refuses a malformed IVKERNELS_THREADS before any work
    flow_folder = None
    if args.flow is not None and args.flow not in FLOW_METHODS:
        if not Path(args.flow).is_dir():
            raise ValueError(f"unknown flow method {args.flow!r} (and no such folder); --flow must be "
                             f"one of {', '.join(FLOW_METHODS)} or a folder of .flo files")
        flow_folder = Path(args.flow)
        if args.step != 1:
            raise ValueError("--flow with a folder of .flo files needs --step 1")
    return params, flow_folder


def _estimate_seconds(backend: str, solved_frames: int, height: int, width: int, threads: int) -> float | None:
    """The time a run should take: ``solved_frames`` is the sum of the windows' lengths."""
    per = SECONDS_PER_PIXEL_FRAME.get(backend)
    if per is None:
        return None
    return START_SECONDS + per * solved_frames * height * width * 2.0 / max(1, threads)


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{max(1, round(seconds))} s"
    if seconds < 5400:
        return f"{round(seconds / 60)} min"
    return f"{seconds / 3600:.1f} h"


def _summary(args, src: Path, T: int, H: int, W: int, params: Params, flow_label: str | None,
             threads: int) -> str:
    """The job, in a few lines, before any work."""
    ranges = window_ranges(T, int(params.window), int(params.overlap))
    estimate = _estimate_seconds(args.backend, sum(stop - start for start, stop, _ in ranges), H, W, threads)
    lines = [
        f"ivkernels: {T} frame{'s' if T != 1 else ''} of {W}x{H} from {src} (frames {args.start} to "
        f"{args.start + (T - 1) * args.step}{f', every {args.step}' if args.step > 1 else ''})",
        f"  {len(ranges)} window{'s' if len(ranges) != 1 else ''} of up to {params.window} frames"
        f"{f', {params.overlap} shared' if len(ranges) > 1 else ''}; flow: {flow_label or 'none'}; "
        f"backend {args.backend} on {args.device}, {threads} thread{'s' if threads != 1 else ''}",
    ]
    if estimate is not None:
        per = SECONDS_PER_PIXEL_FRAME[args.backend]
        lines.append(f"  estimated time: about {_duration(estimate)} ({per * 1e6:.0f} us per pixel and "
                     f"frame, measured with 2 threads on a 2-core machine; scaled by 2/{threads})")
    return "\n".join(lines)


class _PanelQueue:
    """Frames of preview.mp4 and the contact sheet, each with its flow panel.

    Frame ``t``'s flow panel is pair ``t -> t+1``; the last new frame of a
    window has its pair in the next window, so it waits for it.  The last
    frame of the video has no pair of its own and shows pair ``T-2``.
    """

    def __init__(self, n_frames: int, video: VideoWriter, sheet_frames: set, with_flow: bool):
        self.n_frames = n_frames
        self.video = video
        self.sheet_frames = sheet_frames
        self.with_flow = with_flow
        self.pending: list = []               # (t, [input, albedo, shading]) in frame order
        self.flow: dict[int, np.ndarray] = {}  # pair index -> flow image
        self.sheet = {"input": [], "albedo": [], "shading": [], "flow": []}

    def add_frames(self, first: int, input8, albedo8, shading8) -> None:
        for i in range(albedo8.shape[0]):
            self.pending.append((first + i, [input8[i], albedo8[i], shading8[i]]))

    def add_flow(self, first_pair: int, flow8) -> None:
        for i in range(flow8.shape[0]):
            self.flow[first_pair + i] = flow8[i]

    def flush(self) -> None:
        """Write every pending frame whose flow panel is known, in order."""
        while self.pending:
            t, panels = self.pending[0]
            if self.with_flow:
                pair = t if t < self.n_frames - 1 else t - 1
                if pair not in self.flow:
                    return
                panels = panels + [self.flow[pair]]
            self.pending.pop(0)
            self.video.append(np.concatenate(panels, axis=1))
            if t in self.sheet_frames:
                for name, image in zip(self.sheet, panels):
                    self.sheet[name].append(image)
            for old in [k for k in self.flow if k < t - 1]:
                del self.flow[old]

    def sheet_rows(self) -> list:
        return [(name, np.stack(images)) for name, images in self.sheet.items() if images]


def _write_outputs(tmp: Path, frames: np.ndarray, windows, args, with_flow: bool, bar, n_windows: int) -> list:
    """Write every output of a run into the partial folder ``tmp``, window by window; returns the
    windows' median noise steps (``WindowResult.noise_levels``)."""
    T, H, W, _ = frames.shape
    npz = None
    if args.npz != "none":
        shapes = {"albedo": (T, H, W, 3), "shading": (T, H, W)}
        if with_flow:
            shapes.update(flow=(T - 1, H, W, 2), occlusion=(T - 1, H, W), boundary=(T - 1, H, W))
        npz = NpzWriter(tmp, shapes, dtype=np.dtype(args.npz))
    sheet_frames = set(np.linspace(0, T - 1, min(T, 4)).round().astype(int).tolist())
    video = VideoWriter(tmp / "preview.mp4", fps=args.fps)
    try:
        queue = _PanelQueue(T, video, sheet_frames, with_flow)
        flow_max = None
        noise_levels = []
        for index, res in enumerate(windows):
            noise_levels.extend(res.noise_levels)
            new = slice(res.n_carried, res.stop - res.start)       # frames not written yet
            first = res.start + res.n_carried
            albedo8 = albedo_to_srgb8(res.albedo[new])
            shading8 = shading_to_srgb8(res.shading[new])
            write_png_sequence(tmp / "albedo", albedo8, start_index=first)
            write_png_sequence(tmp / "shading", shading8, start_index=first)
            write_png_sequence(tmp / "albedo_linear", res.albedo[new], bits=16, srgb=False, start_index=first)
            write_png_sequence(tmp / "shading_linear", res.shading[new], bits=16, srgb=False,
                               start_index=first)
            if npz is not None:
                npz.append("albedo", res.albedo[new])
                npz.append("shading", res.shading[new])
            if with_flow and res.flow is not None:
                pairs = slice(max(res.n_carried - 1, 0), res.stop - res.start - 1)
                first_pair = res.start + pairs.start
                if flow_max is None:
                    flow_max = float(np.linalg.norm(res.flow, axis=-1).max()) or 1.0
                flow8 = flow_to_color(res.flow[pairs], max_magnitude=flow_max)
                write_png_sequence(tmp / "flow", flow8, start_index=first_pair)
                write_png_sequence(tmp / "occlusion", gray_to_rgb8(res.occlusion[pairs]), start_index=first_pair)
                write_png_sequence(tmp / "boundary", gray_to_rgb8(res.boundary[pairs]), start_index=first_pair)
                if npz is not None:
                    npz.append("flow", res.flow[pairs])
                    npz.append("occlusion", res.occlusion[pairs])
                    npz.append("boundary", res.boundary[pairs])
                queue.add_flow(first_pair, flow8)
            queue.add_frames(first, albedo_to_srgb8(frames[first:res.stop]), albedo8, shading8)
            queue.flush()
            if bar is not None:
                bar.update(res.stop - first)
                bar.set_postfix_str(f"window {index + 1}/{n_windows}")
        if queue.pending:
            raise RuntimeError(f"frames {queue.pending[0][0]}.. have no flow panel")
        video.close()
        if npz is not None:
            npz.close(tmp / "intrinsics.npz")
            npz = None
        imageio.imwrite(tmp / "contact_sheet.png", contact_sheet(queue.sheet_rows()))
        return noise_levels
    except BaseException:
        video.abort()
        if npz is not None:
            npz.discard()
        raise


def run_decompose(args, windows=None) -> Path:
    """``ivkernels decompose``: check everything, claim OUT, then write it
    through an :class:`ivkernels.io.OutputFolder`.  ``windows``: the input's
    solved windows when they were solved elsewhere (:func:`run_decompose_many`);
    ``None`` solves them here."""
    params, flow_folder = _check_arguments(args)
    src = Path(args.input)
    target = OutputFolder(args.out, force=args.force, protect={"input": src, "flow folder": flow_folder},
                          contents=OUTPUT_CONTENTS)
    target.check()                     # claims OUT: a second run into it is refused from here on
    try:
        for note in target.notes:      # e.g. a stale partial folder removed
            print(f"ivkernels: {note}", file=sys.stderr)
        T, H, W = probe_frames(src, start=args.start, stop=args.stop, step=args.step, scale=args.scale)
        check_memory(T * H * W * 3 * 4 + decompose_nbytes(T, H, W, params.window, keep_outputs=False),
                     f"decomposing {T} frames of {W}x{H}",
                     hint="select fewer frames (--start/--stop/--step), shrink them (--scale) or "
                          "solve shorter windows (--window)")
        frames = read_frames(src, start=args.start, stop=args.stop, step=args.step, scale=args.scale)
        T, H, W, _ = frames.shape
        flow = args.flow
        if flow_folder is not None:
            flow = _read_flo_folder(flow_folder, T - 1, args.start, args.step)
        if args.backend == "warp":
            start_warp()
        # validates frames, flow, params, backend and device now, before the output is opened
        if windows is None:
            windows = iter_decompose(frames, flow=flow, temporal=not args.no_temporal, backend=args.backend,
                                     device=args.device, params=params, progress=False, threads=args.threads,
                                     flow_passes=DEFAULT_FLOW_PASSES if args.flow_passes is None
                                     else args.flow_passes)
        with_flow = T > 1 and not (args.no_temporal and flow is None)
        threads = args.threads if args.threads is not None else default_threads()
        if not args.quiet:
            label = None
            if with_flow:
                label = (f"from {flow_folder}" if flow_folder is not None
                         else f"{flow or DEFAULT_FLOW_METHOD}, {args.flow_passes} pass"
                              f"{'es' if args.flow_passes != 1 else ''}")
            print(_summary(args, src, T, H, W, params, label, threads), file=sys.stderr)
        with target as tmp:
            n_windows = len(window_ranges(T, int(params.window), int(params.overlap)))
            with tqdm(total=T, unit="frame", desc="decompose", disable=args.quiet, file=sys.stderr) as bar:
                noise_levels = _write_outputs(tmp, frames, windows, args, with_flow, bar, n_windows)
            note = _noise_note(noise_levels)
            if note and not args.quiet:
                print(f"ivkernels: {note}", file=sys.stderr)
            return target.commit()
    finally:
        target.release()


def _noise_note(noise_levels) -> str | None:
    """What the user is told when the noise was taken out of some windows' layers, else ``None``."""
    smoothed = [n for n in noise_levels if n is not None and n >= NOISE_TO_SMOOTH]
    if not smoothed:
        return None
    return (f"the input is noisy (median noise step {max(smoothed):.3f} in log units): the noise was taken "
            f"out of the albedo and shading of {len(smoothed)} of {len(noise_levels)} window"
            f"{'s' if len(noise_levels) != 1 else ''}, so albedo * shading is the input less that noise "
            f"(--denoise 0 keeps it)")


def run_decompose_many(args) -> int:
    """``ivkernels decompose A B ... -o OUT [--engine ray|local] [--chunk-frames N]``.

    Every input is checked first; the inputs (and their chunks) are then
    solved as tasks of :func:`ivkernels.iter_decompose_many` and each is
    written to ``OUT/<input name>/`` (the file name without its suffix, or
    the folder's name) through its own :class:`ivkernels.io.OutputFolder` as
    soon as it is done.  An input that fails is reported on one line and the
    others finish.  Returns 0 when every input was written, 1 when some
    failed; arguments that concern every input raise as in :func:`run_decompose`.
    """
    sources = [Path(name) for name in args.input]
    names = [src.stem if src.is_file() else src.resolve().name for src in sources]
    seen: dict = {}
    for src, name in zip(sources, names):
        if name in seen:
            raise ValueError(f"inputs {seen[name]} and {src} would both be written to "
                             f"{Path(args.out) / name}; rename one")
        seen[name] = src
    failed: dict = {}
    for src in sources:
        if not src.exists():
            failed[src] = f"{src} does not exist; expected a video file or a folder of images"
    present = [src for src in sources if src not in failed]
    if present:            # the arguments shared by every input, checked once
        params, flow_folder = _check_arguments(argparse.Namespace(**dict(vars(args), input=str(present[0]))))
        if flow_folder is not None:
            raise ValueError("--flow with a folder of .flo files takes a single input")
        if args.chunk_frames is not None and args.chunk_frames < 2:
            raise ValueError(f"--chunk-frames must be at least 2 frames, got {args.chunk_frames}")
        Path(args.out).mkdir(exist_ok=True)
    sub_args: dict = {}
    for src, name in zip(sources, names):
        if src in failed:
            continue
        # each output is written quietly: the progress bar is the one over the tasks
        sub_args[src] = argparse.Namespace(**dict(vars(args), input=str(src), out=str(Path(args.out) / name),
                                                  quiet=True))
        target = OutputFolder(sub_args[src].out, force=args.force, contents=OUTPUT_CONTENTS,
                              protect={f"input {other}": other for other in sources})
        try:
            target.check()             # refused early; claimed again when written
        except ValueError as err:
            failed[src] = _one_line(err)
        finally:
            target.release()
    for src, why in failed.items():
        print(f"ivkernels: error: {src}: {why}", file=sys.stderr)
    todo = [src for src in sources if src not in failed]
    if not todo:
        return 1

    selection = dict(start=args.start, stop=args.stop, step=args.step, scale=args.scale)
    try:
        results = iter_decompose_many(
            todo, engine=args.engine or "local", address=args.address, chunk_frames=args.chunk_frames,
            errors="return", progress=not args.quiet, reader=lambda p: read_frames(p, **selection),
            probe=lambda p: probe_frames(p, **selection), flow=args.flow,
            temporal=not args.no_temporal, backend=args.backend, device=args.device, params=params,
            threads=args.threads,
            flow_passes=DEFAULT_FLOW_PASSES if args.flow_passes is None else args.flow_passes)
    except ImportError as err:
        raise ValueError(_one_line(err)) from err
    for index, video in results:
        src = todo[index]
        if isinstance(video, BaseException):
            failed[src] = _one_line(video.cause)
        else:
            solved = [WindowResult(0, video.albedo.shape[0], 0, video.albedo, video.shading, video.flow,
                                   video.occlusion, video.boundary,
                                   tuple(video.diagnostics.get("noise_levels", ())))]
            try:
                print(f"wrote {run_decompose(sub_args[src], windows=solved)}")
            except (ValueError, TypeError, OSError, MemoryError) as err:
                failed[src] = _one_line(err)
        if src in failed:
            print(f"ivkernels: error: {src}: {failed[src]}", file=sys.stderr)
    if failed:
        print(f"ivkernels: {len(failed)} of {len(sources)} inputs failed; the others were written",
              file=sys.stderr)
    return 1 if failed else 0


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


def _write_error(err: OSError) -> str:
    """An operating-system error in one line, a full disk said plainly."""
    if err.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
        where = f" writing {err.filename}" if err.filename else ""
        return (f"no space left on the device{where} ({os.strerror(err.errno)}); the partial output "
                "was removed: free some space or choose another -o")
    return _one_line(err)


def main(argv=None) -> int:
    """Run the command line; returns the exit status.

    0 on success; 2 with a one-line message for every foreseeable failure (bad
    arguments or input, an output that must not be replaced or that another
    run is writing, no CUDA device, not enough memory, a file that cannot be
    read or written, a full disk: the partial output is removed); with several
    inputs (or ``--engine``), 1 when some inputs failed (each reported on its
    own line) and the others were written; 130 on SIGINT
    and 128 + N on signal N (SIGTERM, SIGHUP), with the partial output removed.
    """
    args = _parser().parse_args(argv)
    try:
        if args.command == "decompose":
            if len(args.input) > 1 or args.engine or args.address or args.chunk_frames:
                return run_decompose_many(args)
            args.input = args.input[0]
            out = run_decompose(args)
            print(f"wrote {out}")
    except Interrupted as err:
        print(f"ivkernels: {err}; partial output removed", file=sys.stderr)
        return 128 + err.signum
    except KeyboardInterrupt:
        print("ivkernels: interrupted; partial output removed", file=sys.stderr)
        return 130
    except OSError as err:
        print(f"ivkernels: error: {_write_error(err)}", file=sys.stderr)
        return 2
    except (ValueError, TypeError, MemoryError) as err:
        print(f"ivkernels: error: {_one_line(err)}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
