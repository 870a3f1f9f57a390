"""Writing files: PNG sequences, NPZ archives, H.264 videos.

Every writer goes through :func:`atomic_output`: the file is written under a
temporary name in the destination folder and renamed when complete, so an
interrupted write never leaves a file that looks finished.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np

from ivkernels.colour import linear_to_srgb

VIDEO_EXTENSIONS_WRITE = (".mp4", ".mkv", ".mov")

__all__ = ["VIDEO_EXTENSIONS_WRITE", "atomic_output", "write_png_sequence", "write_npz", "write_video",
           "current_umask"]


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

