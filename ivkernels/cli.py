"""Command line: ``ivkernels decompose INPUT -o OUT``.

Writes into ``OUT``::

    albedo/NNNNN.png      albedo, sRGB 8-bit
    shading/NNNNN.png     shading, sRGB 8-bit grey
    flow/NNNNN.png        forward flow, Baker et al. colour wheel
    occlusion/NNNNN.png   w_occ (white = visible in the next frame)
    boundary/NNNNN.png    w_bnd (white = near a motion boundary)
    intrinsics.npz        linear float32 arrays albedo, shading, flow, occlusion, boundary
    preview.mp4           input | albedo | shading | flow, side by side
    contact_sheet.png     a few frames of each, labelled

Everything is written into ``OUT.<pid>.partial`` and renamed to ``OUT`` only
when complete, so a failed run never leaves output that looks finished; the
partial folder is removed on failure, SIGINT, SIGTERM and SIGHUP, and one left
by a killed run is removed by the next.  OUT must not be, or hold, the input,
a flow folder or the current folder; an existing OUT is replaced only with
``--force``, and only if ivkernels wrote it (see :class:`ivkernels.io.OutputFolder`).
Every foreseeable failure prints one line and exits with status 2.
"""
from __future__ import annotations

import argparse
import math
import sys
import zipfile
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
from numpy.lib.format import open_memmap

from ivkernels.backends import backend_names, check_device
from ivkernels.decompose import DEFAULT_FLOW_PASSES, iter_decompose
from ivkernels.flow import FLOW_METHODS
from ivkernels.flowio import read_flo
from ivkernels.io import Interrupted, OutputFolder, probe_frames, read_frames, write_png_sequence
from ivkernels.kernels.thread_count import check_threads, default_threads
from ivkernels.params import Params
from ivkernels.validation import check_memory, decompose_nbytes
from ivkernels.viz import albedo_to_srgb8, contact_sheet, flow_to_color, gray_to_rgb8, shading_to_srgb8


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line (the usage itself is under ``--help``), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="ivkernels", description="Intrinsic video: albedo, shading, flow, occlusion and "
        "motion boundaries of a video (Kong, Gehler & Black, ECCV 2014).")
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("decompose", help="decompose a video file or a folder of images")
    d.add_argument("input", help="video file (mp4, avi, ...) or folder of images (png, jpg, tif)")
    d.add_argument("-o", "--out", required=True,
                   help="output folder (must not exist; --force replaces one ivkernels wrote)")
    d.add_argument("--backend", default="warp", choices=backend_names(),
                   help="kernel backend (numpy: the slow exact references, for checking)")
    d.add_argument("--device", default="cpu", help="'cpu' or 'cuda' (warp only)")
    d.add_argument("--threads", type=int, default=None,
                   help="CPU threads the kernels run on (default: IVKERNELS_THREADS if set, else "
                        "every core this process may use)")
    d.add_argument("--flow", default=None,
                   help="flow method (classic_nl_fast, classic_nl, dis, farneback) or a folder of "
                        ".flo files, one per consecutive pair")
    d.add_argument("--flow-passes", type=int, default=None,
                   help="passes of flow and intrinsic video estimated together when the flow is "
                        "estimated (default 2; 1: flow on the input only)")
    d.add_argument("--no-temporal", action="store_true",
                   help="drop the temporal terms and motion weights (the 'IV w/o flow' ablation)")
    d.add_argument("--start", type=int, default=0, help="first frame index")
    d.add_argument("--stop", type=int, default=None, help="stop before this frame index")
    d.add_argument("--step", type=int, default=1, help="take every STEP-th frame")
    d.add_argument("--scale", type=float, default=1.0, help="resize frames by this factor first")
    d.add_argument("--window", type=int, default=None, help="frames per solved window")
    d.add_argument("--fps", type=float, default=10.0, help="frame rate of preview.mp4")
    d.add_argument("--force", action="store_true",
                   help="replace OUT if it exists and ivkernels wrote it (never the input or the "
                        "current folder, nor a folder holding other files)")
    d.add_argument("--quiet", action="store_true", help="no progress bars")
    return parser


def _read_flo_folder(folder: Path, n_pairs: int, start: int, step: int) -> np.ndarray:
    files = sorted(folder.glob("*.flo"))
    files = files[start:start + n_pairs]
    if len(files) != n_pairs:
        raise ValueError(f"{folder} holds {len(files)} .flo files from frame {start}; "
                         f"{n_pairs} are needed (one per consecutive pair)")
    return np.stack([read_flo(f) for f in files])


class _NpzWriter:
    """Builds ``intrinsics.npz`` window by window through memory-mapped .npy files."""

    def __init__(self, folder: Path, shapes: dict):
        self.folder = folder
        self.arrays = {name: open_memmap(folder / f"{name}.npy", mode="w+", dtype=np.float32,
                                         shape=shape) for name, shape in shapes.items()}

    def close(self, path: Path) -> None:
        for array in self.arrays.values():
            array.flush()
        with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED, allowZip64=True) as z:
            for name in self.arrays:
                z.write(self.folder / f"{name}.npy", arcname=f"{name}.npy")
        self.arrays.clear()
        for npy in self.folder.glob("*.npy"):
            npy.unlink()


#: Everything :func:`run_decompose` writes into OUT (besides the marker file).
OUTPUT_CONTENTS = ("albedo", "shading", "flow", "occlusion", "boundary", "intrinsics.npz",
                   "preview.mp4", "contact_sheet.png")


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


def run_decompose(args) -> Path:
    """``ivkernels decompose``: check everything, then write OUT through an
    :class:`ivkernels.io.OutputFolder`."""
    params, flow_folder = _check_arguments(args)
    src = Path(args.input)
    target = OutputFolder(args.out, force=args.force, protect={"input": src, "flow folder": flow_folder},
                          contents=OUTPUT_CONTENTS)
    target.check()
    for note in target.notes:          # e.g. a stale partial folder removed
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
    # validates frames, flow, params, backend and device now, before the output is opened
    windows = iter_decompose(frames, flow=flow, temporal=not args.no_temporal, backend=args.backend,
                             device=args.device, params=params, progress=not args.quiet,
                             threads=args.threads,
                             flow_passes=DEFAULT_FLOW_PASSES if args.flow_passes is None else args.flow_passes)

    with target as tmp:
        shapes = {"albedo": (T, H, W, 3), "shading": (T, H, W)}
        if T > 1 and not (args.no_temporal and flow is None):
            shapes.update(flow=(T - 1, H, W, 2), occlusion=(T - 1, H, W), boundary=(T - 1, H, W))
        npz = _NpzWriter(tmp, shapes)
        preview = imageio.get_writer(tmp / "preview.mp4", fps=args.fps, macro_block_size=1,
                                     ffmpeg_log_level="error")
        sheet_rows = {"input": [], "albedo": [], "shading": [], "flow": []}
        sheet_frames = set(np.linspace(0, T - 1, min(T, 4)).round().astype(int).tolist())
        flow_max = None
        for res in windows:
            new = slice(res.n_carried, res.stop - res.start)       # frames not written yet
            first = res.start + res.n_carried
            albedo8 = albedo_to_srgb8(res.albedo[new])
            shading8 = shading_to_srgb8(res.shading[new])
            write_png_sequence(tmp / "albedo", albedo8, start_index=first)
            write_png_sequence(tmp / "shading", shading8, start_index=first)
            npz.arrays["albedo"][res.start + res.n_carried:res.stop] = res.albedo[new]
            npz.arrays["shading"][res.start + res.n_carried:res.stop] = res.shading[new]
            flow8 = None
            if res.flow is not None and "flow" in npz.arrays:
                pairs = slice(max(res.n_carried - 1, 0), res.stop - res.start - 1)
                first_pair = res.start + pairs.start
                if flow_max is None:
                    flow_max = float(np.linalg.norm(res.flow, axis=-1).max()) or 1.0
                flow8 = flow_to_color(res.flow[pairs], max_magnitude=flow_max)
                write_png_sequence(tmp / "flow", flow8, start_index=first_pair)
                write_png_sequence(tmp / "occlusion", gray_to_rgb8(res.occlusion[pairs]),
                                   start_index=first_pair)
                write_png_sequence(tmp / "boundary", gray_to_rgb8(res.boundary[pairs]),
                                   start_index=first_pair)
                stop_pair = first_pair + flow8.shape[0]
                npz.arrays["flow"][first_pair:stop_pair] = res.flow[pairs]
                npz.arrays["occlusion"][first_pair:stop_pair] = res.occlusion[pairs]
                npz.arrays["boundary"][first_pair:stop_pair] = res.boundary[pairs]
            input8 = albedo_to_srgb8(frames[first:res.stop])
            for i in range(albedo8.shape[0]):
                t = first + i
                panels = [input8[i], albedo8[i], shading8[i]]
                if flow8 is not None:
                    j = t - (res.start + max(res.n_carried - 1, 0))
                    panels.append(flow8[j] if 0 <= j < flow8.shape[0] else np.zeros_like(input8[i]))
                preview.append_data(np.concatenate(panels, axis=1))
                if t in sheet_frames:
                    sheet_rows["input"].append(input8[i])
                    sheet_rows["albedo"].append(albedo8[i])
                    sheet_rows["shading"].append(shading8[i])
                    if flow8 is not None:
                        sheet_rows["flow"].append(panels[3])
        preview.close()
        npz.close(tmp / "intrinsics.npz")
        rows = [(name, np.stack(images)) for name, images in sheet_rows.items() if images]
        imageio.imwrite(tmp / "contact_sheet.png", contact_sheet(rows))
        return target.commit()


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


def main(argv=None) -> int:
    """Run the command line; returns the exit status.

    0 on success; 2 with a one-line message for every foreseeable failure (bad
    arguments or input, an output that must not be replaced, no CUDA device,
    not enough memory, a file that cannot be read or written); 130 on SIGINT
    and 128 + N on signal N (SIGTERM, SIGHUP), with the partial output removed.
    """
    args = _parser().parse_args(argv)
    try:
        if args.command == "decompose":
            out = run_decompose(args)
            print(f"wrote {out}")
    except Interrupted as err:
        print(f"ivkernels: {err}; partial output removed", file=sys.stderr)
        return 128 + err.signum
    except KeyboardInterrupt:
        print("ivkernels: interrupted; partial output removed", file=sys.stderr)
        return 130
    except (ValueError, TypeError, OSError, MemoryError) as err:
        print(f"ivkernels: error: {_one_line(err)}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
