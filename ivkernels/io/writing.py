"""Writing files: PNG sequences, NPZ archives, H.264 videos.

Every writer goes through :func:`atomic_output`: the file is written under a
temporary name in the destination folder and renamed when complete, so an
interrupted write never leaves a file that looks finished.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
import zipfile
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np

from ivkernels.colour import linear_to_srgb

VIDEO_EXTENSIONS_WRITE = (".mp4", ".mkv", ".mov")

__all__ = ["VIDEO_EXTENSIONS_WRITE", "atomic_output", "write_png_sequence", "write_npz", "write_video",
           "VideoWriter", "NpzWriter", "current_umask"]


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


def _check_fps(fps) -> float:
    fps = float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise ValueError(f"write_video: fps must be positive, got {fps}")
    return fps


class VideoWriter:
    """An H.264 video written frame by frame, through imageio-ffmpeg.

    >>> with VideoWriter("preview.mp4", fps=10) as video:    # doctest: +SKIP
    ...     video.append(frame)            # (H, W, 3) or (H, W) uint8 sRGB

    Every frame must have the size of the first.  yuv420p needs an even
    width and height: an odd one is padded by repeating the last row or
    column (never cropped), so a read-back frame may be one pixel taller or
    wider.  :meth:`close` checks what the encoder wrote, by decoding it again:
    a file that is missing, empty or holds fewer frames than were sent
    (libx264 refusing a size, a full disk) raises :class:`OSError`.  The file
    is written under a temporary name and renamed when complete
    (:func:`atomic_output`).
    """

    def __init__(self, path, fps: float = 10):
        self.path = Path(path)
        if self.path.suffix.lower() not in VIDEO_EXTENSIONS_WRITE:
            raise ValueError(f"write_video: file name must end in one of {VIDEO_EXTENSIONS_WRITE}, "
                             f"got {self.path.name}")
        self.fps = _check_fps(fps)
        self.size: tuple[int, int] | None = None      # (H, W) of the frames given
        self.count = 0
        self._output = None
        self._tmp: Path | None = None
        self._writer = None

    def append(self, frame) -> None:
        """Add one ``(H, W, 3)`` or grey ``(H, W)`` uint8 sRGB frame."""
        frame = np.asarray(frame)
        if frame.dtype != np.uint8:
            raise TypeError(f"write_video: expected uint8 sRGB frames, got dtype {frame.dtype}")
        if frame.ndim == 2:
            frame = np.repeat(frame[..., None], 3, axis=-1)
        if frame.ndim != 3 or frame.shape[-1] != 3 or min(frame.shape[:2]) == 0:
            raise ValueError(f"write_video: expected (H, W, 3) or (H, W) frames, got shape {frame.shape}")
        h, w = frame.shape[:2]
        if self.size is None:
            self.size = (h, w)
            self._output = atomic_output(self.path)
            self._tmp = self._output.__enter__()
            self._writer = imageio_ffmpeg.write_frames(
                str(self._tmp), (w + w % 2, h + h % 2), fps=self.fps, codec="libx264",
                pix_fmt_out="yuv420p", quality=8, macro_block_size=1, ffmpeg_log_level="quiet")
            self._writer.send(None)
        elif (h, w) != self.size:
            raise ValueError(f"write_video: frame {self.count} is {w}x{h}, the first was "
                             f"{self.size[1]}x{self.size[0]}")
        frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
        self._writer.send(np.ascontiguousarray(frame))
        self.count += 1

    def close(self) -> Path:
        """Finish the video, check it, and rename it into place."""
        if self._writer is None:
            raise ValueError("write_video: no frames were given")
        writer, output, self._writer = self._writer, self._output, None
        try:
            writer.close()
            self._check_written()
        except BaseException as err:
            output.__exit__(type(err), err, err.__traceback__)
            raise
        output.__exit__(None, None, None)
        return self.path

    def _check_written(self) -> None:
        tmp = self._tmp
        size = tmp.stat().st_size if tmp.exists() else 0
        frames = 0
        if size:
            try:
                frames = imageio_ffmpeg.count_frames_and_secs(str(tmp))[0]
            except (OSError, RuntimeError, ValueError):
                frames = 0
        if frames != self.count:
            h, w = self.size
            raise OSError(f"the video encoder failed writing {self.path.name} ({self.count} frames of "
                          f"{w}x{h}; the file holds {size} bytes and {frames} frames): check the free "
                          "space where it is written")

    def abort(self) -> None:
        """Stop without a file (after an error elsewhere)."""
        if self._writer is not None:
            writer, output, self._writer = self._writer, self._output, None
            try:
                writer.close()
            finally:
                output.__exit__(RuntimeError, RuntimeError("aborted"), None)

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if exc_type is None:
            self.close()
        else:
            self.abort()
        return False


def write_video(path, frames_srgb_uint8, fps: float = 10) -> Path:
    """Write sRGB uint8 frames to an H.264 video (``.mp4``, ``.mkv`` or ``.mov``).

    Parameters
    ----------
    frames_srgb_uint8 : ``(T, H, W, 3)`` or grey ``(T, H, W)`` uint8,
        already sRGB-encoded (display values).
    fps : frames per second, > 0.

    Odd widths/heights are made even (yuv420p needs it) by repeating the last
    column/row, so a read-back frame may be one pixel wider/taller; the file
    is checked after writing (:class:`VideoWriter`).
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
    with VideoWriter(path, fps) as video:
        for f in frames:
            video.append(f)
    return Path(path)


class NpzWriter:
    """An uncompressed ``.npz`` built frame range by frame range, without memory maps.

    Each array is streamed into its own ``.npy`` file next to the archive
    with ordinary writes, in order (a full disk raises :class:`OSError` at
    the write, where a memory map would end the process with SIGBUS), then
    the files are stored into the archive and removed.

    Parameters
    ----------
    folder : where the ``.npy`` files are written.
    shapes : name -> full shape of each array; rows (the first axis) are
        appended with :meth:`append` in order.
    dtype : stored dtype (float16 halves the size of float32; linear values
        keep 3 significant digits).
    """

    def __init__(self, folder, shapes: dict, dtype=np.float32):
        self.folder = Path(folder)
        self.dtype = np.dtype(dtype)
        self.shapes = {name: tuple(int(n) for n in shape) for name, shape in shapes.items()}
        self.rows = dict.fromkeys(self.shapes, 0)
        self._files = {}
        for name, shape in self.shapes.items():
            fh = open(self.folder / f"{name}.npy", "wb")
            self._files[name] = fh
            np.lib.format.write_array_header_1_0(fh, {"descr": np.lib.format.dtype_to_descr(self.dtype),
                                                      "fortran_order": False, "shape": shape})

    def append(self, name: str, rows) -> None:
        """Append ``rows`` (``(n, *shape[1:])``) to array ``name``."""
        rows = np.ascontiguousarray(rows, dtype=self.dtype)
        shape = self.shapes[name]
        if rows.shape[1:] != shape[1:] or self.rows[name] + rows.shape[0] > shape[0]:
            raise ValueError(f"NpzWriter: {name} rows of shape {rows.shape} do not fit {shape} "
                             f"after {self.rows[name]} rows")
        self._files[name].write(rows.tobytes())
        self.rows[name] += rows.shape[0]

    def close(self, path) -> Path:
        """Store every array into ``path`` (through :func:`atomic_output`)."""
        missing = [f"{n} ({self.rows[n]} of {s[0]} rows)" for n, s in self.shapes.items()
                   if self.rows[n] != s[0]]
        if missing:
            raise ValueError(f"NpzWriter: incomplete arrays: {', '.join(missing)}")
        for fh in self._files.values():
            fh.close()
        with atomic_output(path) as tmp:
            with zipfile.ZipFile(tmp, "w", zipfile.ZIP_STORED, allowZip64=True) as z:
                for name in self.shapes:
                    z.write(self.folder / f"{name}.npy", arcname=f"{name}.npy")
        self.discard()
        return Path(path)

    def discard(self) -> None:
        """Close and remove the ``.npy`` files."""
        for name, fh in self._files.items():
            fh.close()
            with contextlib.suppress(OSError):
                (self.folder / f"{name}.npy").unlink()
        self._files.clear()


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

