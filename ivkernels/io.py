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
import os
import re
import tempfile
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

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
]


# ----------------------------------------------------------------------------
# sRGB transfer function (IEC 61966-2-1)
# ----------------------------------------------------------------------------

def _check_float(x, name: str) -> np.ndarray:
    x = np.asarray(x)
    if not np.issubdtype(x.dtype, np.floating):
        raise TypeError(
            f"{name}: expected a floating-point array with values in [0, 1], got dtype "
            f"{x.dtype}; for uint8/uint16 images use to_linear_float()"
        )
    return x


def srgb_to_linear(x) -> np.ndarray:
    """Decode sRGB-encoded values to linear light (IEC 61966-2-1).

    Parameters
    ----------
    x : array of any shape, floating point, sRGB-encoded values in ``[0, 1]``
        (values outside are clipped to ``[0, 1]`` first).

    Returns
    -------
    Linear values, same shape and float dtype as ``x``:
    ``x / 12.92`` for ``x <= 0.04045``, else ``((x + 0.055) / 1.055) ** 2.4``.
    """
    x = _check_float(x, "srgb_to_linear")
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(x.dtype, copy=False)


def linear_to_srgb(x) -> np.ndarray:
    """Encode linear values as sRGB (inverse of :func:`srgb_to_linear`).

    ``x`` (any shape, floating point) is clipped to ``[0, 1]``; returns
    ``12.92 x`` for ``x <= 0.0031308``, else ``1.055 x ** (1/2.4) - 0.055``,
    same shape and float dtype.
    """
    x = _check_float(x, "linear_to_srgb")
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1.0 / 2.4) - 0.055).astype(x.dtype, copy=False)


@lru_cache(maxsize=2)
def _decode_table(levels: int) -> np.ndarray:
    """float32 look-up table: integer sRGB code ``0 .. levels-1`` -> linear."""
    codes = np.arange(levels, dtype=np.float64) / (levels - 1)
    table = srgb_to_linear(codes).astype(np.float32)
    table.setflags(write=False)
    return table


def _srgb_int_to_linear(img: np.ndarray) -> np.ndarray:
    if img.dtype == np.uint8:
        return _decode_table(256)[img]
    if img.dtype == np.uint16:
        return _decode_table(65536)[img]
    raise TypeError(f"expected uint8 or uint16 sRGB values, got dtype {img.dtype}")


def to_linear_float(frames, name: str = "frames") -> np.ndarray:
    """Validate a user frame stack and return float32 linear RGB.

    Parameters
    ----------
    frames : array ``(T, H, W, 3)``
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
               non-finite or out-of-range floats.
    """
    if isinstance(frames, (list, tuple)):
        frames = np.stack([np.asarray(f) for f in frames]) if len(frames) else np.empty((0,))
    frames = np.asarray(frames)
    if frames.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        raise TypeError(
            f"{name}: unsupported dtype {frames.dtype}; expected uint8 or uint16 sRGB, "
            "or float32/float64 linear RGB in [0, 1]"
        )
    if frames.ndim != 4:
        hint = " (for a single image pass image[None])" if frames.ndim == 3 else ""
        raise ValueError(f"{name}: expected shape (T, H, W, 3), got {frames.shape}{hint}")
    if frames.shape[-1] != 3:
        raise ValueError(
            f"{name}: expected 3 colour channels (RGB) in the last axis, got shape {frames.shape}"
        )
    if min(frames.shape[:3]) == 0:
        raise ValueError(f"{name}: empty frame stack, shape {frames.shape}")
    if frames.dtype in (np.uint8, np.uint16):
        return np.ascontiguousarray(_srgb_int_to_linear(frames))
    if not np.all(np.isfinite(frames)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    lo, hi = float(frames.min()), float(frames.max())
    tol = 1e-6
    if lo < -tol or hi > 1.0 + tol:
        raise ValueError(
            f"{name}: float input must be linear RGB in [0, 1], got values in [{lo:.6g}, {hi:.6g}]"
            " (pass uint8/uint16 for sRGB-encoded images)"
        )
    out = np.clip(frames, 0.0, 1.0).astype(np.float32)
    return np.ascontiguousarray(out)


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
        return np.ascontiguousarray(_srgb_int_to_linear(img))
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


def _iter_video(path: Path):
    import imageio.v3 as iio

    try:
        yield from iio.imiter(str(path), plugin="FFMPEG")
    except (OSError, RuntimeError, ValueError) as err:
        lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
        detail = lines[0] if lines else type(err).__name__
        if len(lines) > 1:
            detail += f" ({lines[-1]})"
        raise ValueError(f"could not read video file {path}: {detail}") from err


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
    selected, a folder holds no images, or images differ in size.
    """
    _check_range(start, stop, step)
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number, got {scale}")
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file or folder: {path}")

    frames = []
    if path.is_dir():
        files = list_image_files(path)
        if not files:
            raise ValueError(f"folder {path} holds no images ({', '.join(IMAGE_EXTENSIONS)})")
        chosen = files[start:stop:step]
        first_shape = None
        for f in chosen:
            img = read_image(f)
            if first_shape is None:
                first_shape = (img.shape, f)
            elif img.shape != first_shape[0]:
                raise ValueError(
                    f"all images must share one size: {first_shape[1].name} is "
                    f"{first_shape[0][1]}x{first_shape[0][0]} but {f.name} is {img.shape[1]}x{img.shape[0]}"
                )
            frames.append(_resize(img, scale))
    elif path.suffix.lower() in IMAGE_EXTENSIONS:
        if start == 0:
            frames.append(_resize(read_image(path), scale))
    else:
        for i, rgb in enumerate(_iter_video(path)):
            if stop is not None and i >= stop:
                break
            if i >= start and (i - start) % step == 0:
                rgb = np.asarray(rgb)
                if rgb.ndim == 2:
                    rgb = np.repeat(rgb[:, :, None], 3, axis=2)
                frames.append(_resize(_srgb_int_to_linear(rgb[:, :, :3]), scale))
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
    import imageio_ffmpeg

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
