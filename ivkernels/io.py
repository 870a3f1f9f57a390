"""Reading and writing frames: video files, image folders, PNG sequences, NPZ.

Everything inside ivkernels works on *linear* RGB in ``[0, 1]``, float32,
stacked as ``(T, H, W, 3)``.  This module is the border: it decodes sRGB
(8- or 16-bit) on the way in and encodes it on the way out.

* :func:`read_frames` / :func:`read_image` read a video file (through
  imageio's ffmpeg plugin) or a folder of images (png, jpg, tif, bmp; sorted
  naturally, so ``frame2.png`` comes before ``frame10.png``).
* :func:`to_linear_float` turns user arrays (uint8 / uint16 sRGB or float
  linear) into float32 linear RGB, with clear errors; ``decompose`` calls it.
* :func:`write_png_sequence`, :func:`write_npz`, :func:`write_video` write
  to a temporary name in the destination folder and rename it when complete,
  so an interrupted write never leaves a file that looks finished.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import socket
import tempfile
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np

from ivkernels._version import __version__
from ivkernels.colour import linear_to_srgb, srgb_decode_table, srgb_int_to_linear, srgb_to_linear
from ivkernels.validation import check_frames, check_memory, linear_frames

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")
VIDEO_EXTENSIONS_WRITE = (".mp4", ".mkv", ".mov")

__all__ = [
    "IMAGE_EXTENSIONS",
    "srgb_to_linear",
    "linear_to_srgb",
    "to_linear_float",
    "read_image",
    "read_frames",
    "list_image_files",
    "write_png_sequence",
    "write_npz",
    "write_video",
    "atomic_output",
    "probe_frames",
    "srgb_decode_table",
    "current_umask",
    "OutputFolder",
    "OUTPUT_MARKER",
]


def to_linear_float(frames, name: str = "frames") -> np.ndarray:
    """Validate a user frame stack and return float32 linear RGB.

    The rules are those of :mod:`ivkernels.validation`, shared with
    :func:`ivkernels.decompose` and :func:`ivkernels.estimate_flow`.

    Parameters
    ----------
    frames : array ``(T, H, W, 3)``, or a list of ``(H, W, 3)`` frames
        * ``uint8``  : sRGB-encoded, 0..255;
        * ``uint16`` : sRGB-encoded, 0..65535;
        * ``float32`` / ``float64`` : already *linear* RGB in ``[0, 1]``
          (values within 1e-6 outside the range are clipped, anything further
          out is an error; NaN / inf are errors).
    name : used in error messages.

    Returns
    -------
    ``(T, H, W, 3)`` float32, C-contiguous, linear RGB in ``[0, 1]``.

    Raises
    ------
    TypeError  for other dtypes (bool, signed ints, float16, object, ...).
    ValueError for a wrong number of dimensions or channels, empty stacks,
               frames of different sizes in a list, non-finite or
               out-of-range floats.
    """
    return linear_frames(check_frames(frames, name, single_frame=False))


# ----------------------------------------------------------------------------
# Reading
# ----------------------------------------------------------------------------

def _natural_key(name: str):
    parts = re.split(r"(\d+)", name.lower())
    return [int(p) if i % 2 else p for i, p in enumerate(parts)]


def list_image_files(folder) -> list[Path]:
    """Image files (:data:`IMAGE_EXTENSIONS`, any case) in ``folder``, sorted
    naturally (``f2`` < ``f10``).  Hidden files are ignored."""
    folder = Path(folder)
    if not folder.is_dir():
        raise NotADirectoryError(f"not a folder: {folder}")
    files = [p for p in folder.iterdir()
             if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS and not p.name.startswith(".")]
    return sorted(files, key=lambda p: _natural_key(p.name))


def _decode_to_linear_rgb(img: np.ndarray, source: str) -> np.ndarray:
    """OpenCV-decoded image (grey, BGR or BGRA; uint8/uint16/float) -> float32 linear RGB."""
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3 or img.shape[2] not in (1, 3, 4):
        raise ValueError(f"{source}: unsupported image layout {img.shape}")
    c = img.shape[2]
    if c == 1:
        img = np.repeat(img, 3, axis=2)
    elif c == 3:
        img = img[:, :, ::-1]           # BGR -> RGB
    else:
        img = img[:, :, 2::-1]          # BGRA -> RGB, alpha dropped
    if img.dtype in (np.uint8, np.uint16):
        return np.ascontiguousarray(srgb_int_to_linear(img))
    if img.dtype in (np.float32, np.float64):
        # Floating-point files (e.g. 32-bit TIFF) are taken as linear values.
        return to_linear_float(img[None], name=source)[0]
    raise TypeError(f"{source}: unsupported pixel type {img.dtype}; expected 8- or 16-bit")


def read_image(path) -> np.ndarray:
    """Read one image file as float32 linear RGB ``(H, W, 3)`` in ``[0, 1]``.

    8- and 16-bit files are taken as sRGB-encoded; grey is replicated to RGB;
    an alpha channel is dropped; 32-bit float TIFFs are taken as linear.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such image file: {path}")
    data = np.fromfile(str(path), dtype=np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if img is None:
        raise ValueError(f"could not decode image file {path}")
    return _decode_to_linear_rgb(img, str(path))


def _check_range(start, stop, step):
    for name, v in (("start", start), ("step", step)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool):
            raise TypeError(f"{name} must be an int, got {v!r}")
    if stop is not None and (not isinstance(stop, (int, np.integer)) or isinstance(stop, bool)):
        raise TypeError(f"stop must be an int or None, got {stop!r}")
    if start < 0:
        raise ValueError(f"start must be >= 0, got {start}")
    if step < 1:
        raise ValueError(f"step must be >= 1, got {step}")
    if stop is not None and stop <= start:
        raise ValueError(f"stop ({stop}) must be greater than start ({start})")


def _resize(frame: np.ndarray, scale: float) -> np.ndarray:
    if scale == 1.0:
        return frame
    h, w = frame.shape[:2]
    size = (max(1, int(round(w * scale))), max(1, int(round(h * scale))))
    interp = cv2.INTER_AREA if scale < 1.0 else cv2.INTER_LINEAR
    return cv2.resize(frame, size, interpolation=interp)


def _video_error(path: Path, err: BaseException) -> ValueError:
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip() and not ln.startswith("=")]
    detail = lines[0] if lines else type(err).__name__
    if len(lines) > 1:
        detail += f" ({lines[-1]})"
    return ValueError(f"could not read video file {path}: {detail}")


def _open_video(path: Path):
    """``(meta, generator of (H, W, 3) uint8 frames)`` of a video, through imageio-ffmpeg."""
    gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    try:
        meta = next(gen)
    except (OSError, RuntimeError, ValueError, StopIteration) as err:
        gen.close()
        raise _video_error(path, err) from err
    w, h = meta["size"]

    def frames():
        try:
            for buf in gen:
                yield np.frombuffer(buf, np.uint8).reshape(h, w, 3)
        except (OSError, RuntimeError, ValueError) as err:
            raise _video_error(path, err) from err
        finally:
            gen.close()

    return meta, frames()


def _announced_frames(meta: dict) -> int | None:
    """Frame count a video's header announces (duration x frame rate), or None if unknown."""
    duration, fps = meta.get("duration"), meta.get("fps")
    try:
        n = float(duration) * float(fps)
    except (TypeError, ValueError):
        return None
    return int(round(n)) if np.isfinite(n) and n > 0 else None


def _truncation_tolerance(announced: int) -> int:
    """Frames a complete video may fall short of its header's count (rounding of the
    duration, a variable frame rate)."""
    return max(2, int(np.ceil(0.05 * announced)))


def _scaled_size(h: int, w: int, scale: float) -> tuple[int, int]:
    if scale == 1.0:
        return h, w
    return max(1, int(round(h * scale))), max(1, int(round(w * scale)))


def _check_scale(scale) -> float:
    if isinstance(scale, bool) or not isinstance(scale, (int, float, np.integer, np.floating)):
        raise TypeError(f"scale must be a positive number, got {scale!r}")
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number, got {scale}")
    return scale


def probe_frames(path, start: int = 0, stop: int | None = None, step: int = 1,
                 scale: float = 1.0) -> tuple[int, int, int]:
    """``(T, H, W)`` that :func:`read_frames` with these arguments would return,
    read from a video's header or a folder's file list and first image, without
    decoding the frames.  For a video, ``T`` is the header's estimate.
    """
    _check_range(start, stop, step)
    scale = _check_scale(scale)
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file or folder: {path}")
    if path.is_dir():
        files = list_image_files(path)
        if not files:
            raise ValueError(f"folder {path} holds no images ({', '.join(IMAGE_EXTENSIONS)})")
        chosen = files[start:stop:step]
        if not chosen:
            raise ValueError(f"no frames selected from {path} with start={start}, stop={stop}, "
                             f"step={step} ({len(files)} images)")
        h, w = _image_size(chosen[0])
        return (len(chosen), *_scaled_size(h, w, scale))
    if path.suffix.lower() in IMAGE_EXTENSIONS:
        h, w = _image_size(path)
        return (1 if start == 0 else 0, *_scaled_size(h, w, scale))
    meta, frames = _open_video(path)
    frames.close()
    w, h = meta["size"]
    announced = _announced_frames(meta)
    n = len(range(start, announced if stop is None else min(stop, announced), step)) \
        if announced is not None else 1
    return (n, *_scaled_size(h, w, scale))


def _image_size(path: Path) -> tuple[int, int]:
    return read_image(path).shape[:2]


def read_frames(path, start: int = 0, stop: int | None = None, step: int = 1,
                scale: float = 1.0) -> np.ndarray:
    """Read frames ``start, start+step, ... < stop`` of a video, image folder or image.

    Parameters
    ----------
    path : video file (anything ffmpeg reads), a folder of images
        (:data:`IMAGE_EXTENSIONS`, sorted naturally), or a single image
        (returned as one frame).
    start, stop, step : frame selection, as in ``range(start, stop, step)``;
        ``stop=None`` reads to the end.
    scale : resize factor applied to every frame (in linear light; area
        averaging when shrinking, bilinear when enlarging); the new size is
        ``round(W * scale) x round(H * scale)``.

    Returns
    -------
    ``(T, H, W, 3)`` float32 linear RGB in ``[0, 1]`` (8/16-bit sources
    are sRGB-decoded with :func:`srgb_to_linear`).

    Raises
    ------
    FileNotFoundError if ``path`` does not exist; ValueError if no frame is
    selected, a folder holds no images, images differ in size, a video ends
    well before the frame count its header announces (a truncated or damaged
    file), or the frames would not fit in the memory available (checked from
    the file list or the video header before decoding; the message gives the
    size).
    """

    _check_range(start, stop, step)
    scale = _check_scale(scale)
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file or folder: {path}")

    if path.is_dir() or path.suffix.lower() in IMAGE_EXTENSIONS:
        if path.is_dir():
            files = list_image_files(path)
            if not files:
                raise ValueError(f"folder {path} holds no images ({', '.join(IMAGE_EXTENSIONS)})")
            chosen = files[start:stop:step]
        else:
            chosen = [path] if start == 0 else []
        if not chosen:
            raise ValueError(f"no frames selected from {path} with start={start}, stop={stop}, step={step}")
        out = None
        first = None
        for t, f in enumerate(chosen):
            img = read_image(f)
            if first is None:
                first = (img.shape, f)
                h, w = _scaled_size(*img.shape[:2], scale)
                check_memory(len(chosen) * h * w * 3 * 4,
                             f"reading {len(chosen)} frames of {w}x{h} from {path}")
                out = np.empty((len(chosen), h, w, 3), np.float32)
            elif img.shape != first[0]:
                raise ValueError(
                    f"all images must share one size: {first[1].name} is "
                    f"{first[0][1]}x{first[0][0]} but {f.name} is {img.shape[1]}x{img.shape[0]}"
                )
            out[t] = _resize(img, scale)
        return out

    meta, decoded = _open_video(path)
    announced = _announced_frames(meta)
    w, h = meta["size"]
    hs, ws = _scaled_size(h, w, scale)
    if announced is not None:
        wanted = len(range(start, announced if stop is None else min(stop, announced), step))
        # the frames are collected, then stacked: twice their size at the peak
        check_memory(2 * wanted * hs * ws * 3 * 4,
                     f"reading about {wanted} frames of {ws}x{hs} from {path}")
    frames = []
    n_decoded = 0
    ended = True
    try:
        for i, rgb in enumerate(decoded):
            n_decoded = i + 1
            if stop is not None and i >= stop:
                ended = False
                break
            if i >= start and (i - start) % step == 0:
                frames.append(_resize(srgb_int_to_linear(rgb), scale))
    finally:
        decoded.close()
    if ended and announced is not None and n_decoded < announced - _truncation_tolerance(announced) \
            and (stop is None or n_decoded < stop):
        raise ValueError(
            f"video file {path} ends after {n_decoded} frames but its header announces about "
            f"{announced} ({meta.get('duration')} s at {meta.get('fps')} fps); the file looks "
            "truncated or damaged (pass --stop / stop= to read only the frames before the damage)")
    if not frames:
        raise ValueError(f"no frames selected from {path} with start={start}, stop={stop}, step={step}")
    return np.ascontiguousarray(np.stack(frames).astype(np.float32, copy=False))


# ----------------------------------------------------------------------------
# Writing (always through a temporary name, renamed when complete)
# ----------------------------------------------------------------------------

@contextlib.contextmanager
def atomic_output(path):
    """Context manager yielding a temporary path next to ``path`` (same suffix).

    Write the file to the yielded path; on normal exit it is renamed onto
    ``path`` (atomic on one file system); on an exception it is removed, and
    ``path`` is left untouched.  Parent folders are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".part{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~current_umask())     # mkstemp makes 0600; give the usual mode
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def _write_bytes(path: Path, data: bytes) -> None:
    with atomic_output(path) as tmp:
        tmp.write_bytes(data)


def write_png_sequence(folder, frames, prefix: str = "frame", *, bits: int = 8,
                       srgb: bool | None = None, start_index: int = 0) -> list[Path]:
    """Write a frame stack as ``folder/{prefix}_{t:05d}.png``.

    ``t`` runs from ``start_index`` to ``start_index + T - 1`` (so a long
    video can be written window by window into one folder).

    Parameters
    ----------
    frames :
        * float ``(T, H, W, 3)`` linear RGB: clipped to ``[0, 1]``,
          sRGB-encoded (unless ``srgb=False``) and quantised to ``bits``;
        * float ``(T, H, W)`` grey maps in ``[0, 1]`` (occlusion, boundary,
          ...): written as they are (unless ``srgb=True``);
        * uint8 / uint16 ``(T, H, W[, 3])``: written unchanged (``bits`` and
          ``srgb`` do not apply).
    bits : 8 or 16, bit depth of float input.
    srgb : encode float input with :func:`linear_to_srgb`; default ``True``
        for colour, ``False`` for grey.
    start_index : number of the first file, >= 0.

    Returns
    -------
    The written paths, in frame order.
    """
    frames = np.asarray(frames)
    if bits not in (8, 16):
        raise ValueError(f"bits must be 8 or 16, got {bits}")
    if not isinstance(prefix, str) or not prefix or os.sep in prefix or "/" in prefix:
        raise ValueError(f"prefix must be a non-empty file-name prefix without separators, got {prefix!r}")
    if not isinstance(start_index, (int, np.integer)) or isinstance(start_index, bool) or start_index < 0:
        raise ValueError(f"start_index must be an int >= 0, got {start_index!r}")
    if frames.ndim == 4 and frames.shape[-1] == 1:
        frames = frames[..., 0]
    if not (frames.ndim == 3 or (frames.ndim == 4 and frames.shape[-1] == 3)):
        raise ValueError(f"frames: expected (T, H, W, 3) colour or (T, H, W) grey, got shape {frames.shape}")
    if min(frames.shape[:3]) == 0:
        raise ValueError(f"frames: empty stack, shape {frames.shape}")
    if np.issubdtype(frames.dtype, np.floating):
        if not np.all(np.isfinite(frames)):
            raise ValueError("frames: contains NaN or infinite values")
        colour = frames.ndim == 4
        encode = colour if srgb is None else bool(srgb)
        values = np.clip(frames, 0.0, 1.0)
        if encode:
            values = linear_to_srgb(values)
        maxval = 255 if bits == 8 else 65535
        frames = np.round(values * maxval).astype(np.uint8 if bits == 8 else np.uint16)
    elif frames.dtype == np.bool_:
        frames = frames.astype(np.uint8) * 255
    elif frames.dtype not in (np.uint8, np.uint16):
        raise TypeError(f"frames: unsupported dtype {frames.dtype}; expected float, uint8 or uint16")

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for t, img in enumerate(frames):
        if img.ndim == 3:
            img = img[:, :, ::-1]  # RGB -> BGR for OpenCV
        ok, buf = cv2.imencode(".png", np.ascontiguousarray(img))
        if not ok:
            raise RuntimeError(f"PNG encoding failed for frame {t}")
        p = folder / f"{prefix}_{start_index + t:05d}.png"
        _write_bytes(p, buf.tobytes())
        paths.append(p)
    return paths


def write_npz(path, **arrays) -> Path:
    """Write named arrays to a compressed ``.npz`` file at exactly ``path``.

    Each value is converted with ``np.asarray``; object arrays are refused
    (they would need pickling to read back).
    """
    if not arrays:
        raise ValueError("write_npz: give at least one array as a keyword argument")
    converted = {}
    for key, value in arrays.items():
        a = np.asarray(value)
        if a.dtype == object:
            raise TypeError(f"write_npz: array {key!r} has dtype object; give numeric arrays")
        converted[key] = a
    path = Path(path)
    with atomic_output(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **converted)
    return path


def write_video(path, frames_srgb_uint8, fps: float = 10) -> Path:
    """Write sRGB uint8 frames to an H.264 video (``.mp4``, ``.mkv`` or ``.mov``).

    Parameters
    ----------
    frames_srgb_uint8 : ``(T, H, W, 3)`` or grey ``(T, H, W)`` uint8,
        already sRGB-encoded (display values).
    fps : frames per second, > 0.

    Odd widths/heights are made even (yuv420p needs it) by repeating the last
    column/row, so a read-back frame may be one pixel wider/taller.
    """
    frames = np.asarray(frames_srgb_uint8)
    if frames.dtype != np.uint8:
        raise TypeError(f"write_video: expected uint8 sRGB frames, got dtype {frames.dtype}")
    if frames.ndim == 3:
        frames = np.repeat(frames[..., None], 3, axis=-1)
    if frames.ndim != 4 or frames.shape[-1] != 3:
        raise ValueError(f"write_video: expected (T, H, W, 3) or (T, H, W), got shape {frames.shape}")
    if min(frames.shape[:3]) == 0:
        raise ValueError(f"write_video: empty stack, shape {frames.shape}")
    fps = float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise ValueError(f"write_video: fps must be positive, got {fps}")
    path = Path(path)
    if path.suffix.lower() not in VIDEO_EXTENSIONS_WRITE:
        raise ValueError(f"write_video: file name must end in one of {VIDEO_EXTENSIONS_WRITE}, got {path.name}")
    t, h, w, _ = frames.shape
    frames = np.pad(frames, ((0, 0), (0, h % 2), (0, w % 2), (0, 0)), mode="edge")
    size = (frames.shape[2], frames.shape[1])
    with atomic_output(path) as tmp:
        writer = imageio_ffmpeg.write_frames(
            str(tmp), size, fps=fps, codec="libx264", pix_fmt_out="yuv420p",
            quality=8, macro_block_size=1, ffmpeg_log_level="error",
        )
        writer.send(None)
        try:
            for f in frames:
                writer.send(np.ascontiguousarray(f))
        finally:
            writer.close()
    return path


def current_umask() -> int:
    """The process's file-mode creation mask (read without changing it where Linux allows)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# ----------------------------------------------------------------------------
# Output folders: written under a temporary name, never replacing what the user owns
# ----------------------------------------------------------------------------

#: File that marks a folder as written by ivkernels (``--force`` replaces only these).
OUTPUT_MARKER = ".ivkernels-output"
_PARTIAL = re.compile(r"^(?P<name>.+)\.(?P<pid>\d+)(?:\.old)?\.partial$")


class Interrupted(BaseException):
    """Raised in the main thread when the process receives SIGTERM or SIGHUP while an
    :class:`OutputFolder` is open (SIGINT raises :class:`KeyboardInterrupt`)."""

    def __init__(self, signum: int):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # it exists, under another user
        return True
    except (OverflowError, OSError):
        return False
    return True


def _is_within(path: Path, folder: Path) -> bool:
    """``path`` is ``folder`` or lies inside it (both resolved)."""
    return path == folder or folder in path.parents


class OutputFolder:
    """The one writer of a command-line output folder.

    >>> target = OutputFolder("out", force=False, protect={"input": "frames/"})   # doctest: +SKIP
    >>> target.check()                 # before any work: refuses what must not be replaced
    >>> with target as tmp:            # ``out.<pid>.partial``, marked, removed on failure
    ...     write_everything(tmp)
    ...     target.commit()            # renamed to ``out``

    Rules:

    * ``out`` must not be, or hold, any path in ``protect`` (the input, a flow
      folder) nor the current folder, resolved through symbolic links;
    * ``out`` must not be a file or a symbolic link;
    * an existing ``out`` is replaced only with ``force``, and only if it is
      empty, or holds the :data:`OUTPUT_MARKER` ivkernels writes and nothing
      but the names in ``contents``;
    * the partial folder ``<out>.<pid>.partial`` (the pid of the writing
      process) carries the marker from the start; it is removed on any
      exception, on SIGINT and, while the folder is open, on SIGTERM and
      SIGHUP (raised as :class:`Interrupted`); one left by a process that no
      longer runs (killed with SIGKILL, power lost) is removed by the next
      :meth:`check` and named in :attr:`notes`;
    * folders and files get the modes the umask gives (0755 / 0644 under the
      usual 0022), not the 0700 / 0600 of temporary files.
    """

    def __init__(self, out, *, force: bool = False, protect: dict | None = None,
                 contents: tuple = ()):
        self.out = Path(out)
        self.force = bool(force)
        self.protect = {k: Path(v) for k, v in (protect or {}).items() if v is not None}
        self.contents = frozenset(contents) | {OUTPUT_MARKER}
        self.notes: list[str] = []
        self.partial: Path | None = None
        self._old_handlers: dict = {}
        self._committed = False

    # -- checks ----------------------------------------------------------------
    def check(self) -> None:
        """Refuse an output that must not be written (ValueError), and remove
        stale partial folders of this output left by processes that are gone."""
        out = self.out
        if str(out) in ("", "."):
            raise ValueError("output folder must be named (not '.')")
        target = out.resolve()
        guarded = dict(self.protect)
        guarded["current folder"] = Path.cwd()
        for what, path in guarded.items():
            if _is_within(path.resolve(), target):
                same = path.resolve() == target
                raise ValueError(f"output {out} {'is' if same else 'holds'} the {what} {path}; "
                                 "choose another output folder")
        if out.is_symlink():
            raise ValueError(f"output {out} is a symbolic link; give the folder itself")
        if not target.parent.is_dir():
            raise ValueError(f"the folder that would hold output {out}, {out.parent}, does not exist")
        if out.exists():
            if not out.is_dir():
                raise ValueError(f"output {out} exists and is not a folder; choose another name")
            if not self.force:
                raise ValueError(f"output {out} already exists; choose another folder or pass --force "
                                 "(which replaces only a folder written by ivkernels)")
            self._check_replaceable(out)
        self._clean_stale()

    def _check_replaceable(self, folder: Path) -> None:
        names = sorted(p.name for p in folder.iterdir())
        if not names:
            return
        if OUTPUT_MARKER not in names:
            raise ValueError(f"output {folder} exists and was not written by ivkernels (it has no "
                             f"{OUTPUT_MARKER} file); --force replaces only ivkernels output, so "
                             "choose another folder or remove it yourself")
        foreign = [n for n in names if n not in self.contents]
        if foreign:
            raise ValueError(f"output {folder} holds {foreign[0]!r}"
                             f"{f' and {len(foreign) - 1} more' if len(foreign) > 1 else ''}, which "
                             "ivkernels did not write; --force will not delete it, so move it or "
                             "choose another folder")

    def _clean_stale(self) -> None:
        for p in sorted(self.out.resolve().parent.glob(f"{glob_escape(self.out.name)}.*.partial")):
            m = _PARTIAL.match(p.name)
            if not m or m.group("name") != self.out.name or not p.is_dir() or p.is_symlink():
                continue
            if not (p / OUTPUT_MARKER).is_file():
                self.notes.append(f"{p} was not written by this version of ivkernels; "
                                  "left in place, remove it by hand")
                continue
            pid = int(m.group("pid"))
            host = _read_marker(p).get("host", socket.gethostname())
            if host != socket.gethostname():
                self.notes.append(f"{p} is being or was written on host {host}; left in place, "
                                  "remove it by hand if no run is active there")
                continue
            if _pid_alive(pid):
                if pid == os.getpid():
                    continue
                raise ValueError(f"another ivkernels run (pid {pid}) is writing {self.out} "
                                 f"(into {p}); wait for it or stop it first")
            shutil.rmtree(p, ignore_errors=True)
            self.notes.append(f"removed {p}, the partial output of an earlier run "
                              f"(pid {pid}) that did not finish")

    # -- writing ---------------------------------------------------------------
    def __enter__(self) -> Path:
        if self.partial is not None:
            raise RuntimeError("OutputFolder is already open")
        self._install_handlers()
        try:
            self.partial = self.out.resolve().parent / f"{self.out.name}.{os.getpid()}.partial"
            if self.partial.exists():
                shutil.rmtree(self.partial)
            os.mkdir(self.partial)        # mode 0777 & ~umask
            _write_marker(self.partial)
        except BaseException:
            self._cleanup()
            raise
        return self.partial

    def commit(self) -> Path:
        """Move the partial folder to the output name (replacing a checked old output)."""
        out = self.out
        old = None
        if out.exists() or out.is_symlink():
            # checked again: the folder may have changed since check()
            if out.is_symlink() or not out.is_dir():
                raise ValueError(f"output {out} changed while writing and is no longer a folder")
            self._check_replaceable(out)
            old = out.resolve().parent / f"{out.name}.{os.getpid()}.old.partial"
            os.replace(out, old)
        try:
            os.replace(self.partial, out)
        except BaseException:
            if old is not None:
                os.replace(old, out)
            raise
        self._committed = True
        self.partial = None
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return out

    def __exit__(self, exc_type, exc, tb) -> bool:
        self._cleanup()
        return False

    def _cleanup(self) -> None:
        # a second signal must not interrupt the removal
        for signum in self._old_handlers:
            with contextlib.suppress(ValueError, OSError):
                signal.signal(signum, signal.SIG_IGN)
        try:
            if self.partial is not None:
                shutil.rmtree(self.partial, ignore_errors=True)
                self.partial = None
        finally:
            self._restore_handlers()

    def _install_handlers(self) -> None:
        def handler(signum, frame):
            raise Interrupted(signum)

        for signum in (signal.SIGTERM, getattr(signal, "SIGHUP", None)):
            if signum is None:
                continue
            try:
                self._old_handlers[signum] = signal.signal(signum, handler)
            except ValueError:          # not the main thread: signals stay as they were
                break

    def _restore_handlers(self) -> None:
        for signum, old in self._old_handlers.items():
            with contextlib.suppress(ValueError, OSError, TypeError):
                signal.signal(signum, old if old is not None else signal.SIG_DFL)
        self._old_handlers.clear()


def glob_escape(name: str) -> str:
    """``name`` with the glob metacharacters ``* ? [`` escaped."""
    return re.sub(r"([*?\[])", r"[\1]", name)


def _write_marker(folder: Path) -> None:
    info = {"written_by": "ivkernels", "version": __version__, "pid": os.getpid(),
            "host": socket.gethostname()}
    (folder / OUTPUT_MARKER).write_text(json.dumps(info) + "\n")


def _read_marker(folder: Path) -> dict:
    try:
        info = json.loads((folder / OUTPUT_MARKER).read_text())
        return info if isinstance(info, dict) else {}
    except (OSError, ValueError):
        return {}
