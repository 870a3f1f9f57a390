"""Reading frames: video files, image folders and single images.

Everything inside ivkernels works on *linear* RGB in ``[0, 1]``, float32,
stacked as ``(T, H, W, 3)``; this module decodes sRGB (8- or 16-bit) on the
way in.

* :func:`read_frames` reads a video file (through imageio-ffmpeg, every
  decoded frame exactly once: ``-fps_mode passthrough``, so no frame is
  duplicated or dropped to fit a nominal frame rate) or a folder of images
  (png, jpg, tif, bmp; sorted naturally, so ``frame2.png`` comes before
  ``frame10.png``); :func:`read_image` reads one image.
* :func:`probe_frames` tells the size of a selection without decoding it.
* :func:`to_linear_float` turns user arrays (uint8 / uint16 sRGB or float
  linear) into float32 linear RGB, with clear errors; ``decompose`` calls it.
"""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np

from ivkernels.colour import srgb_int_to_linear
from ivkernels.validation import check_frames, check_memory, linear_frames

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")

__all__ = ["IMAGE_EXTENSIONS", "to_linear_float", "read_image", "read_frames", "list_image_files",
           "probe_frames"]


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


def _passthrough_option() -> list[str]:
    """The ffmpeg output option that passes every decoded frame through once,
    with no frame duplicated or dropped to fit a constant rate (``-fps_mode``
    since ffmpeg 5.1, ``-vsync`` before)."""
    m = re.search(r"(\d+)\.(\d+)", imageio_ffmpeg.get_ffmpeg_version())
    old = m is not None and (int(m.group(1)), int(m.group(2))) < (5, 1)
    return ["-vsync" if old else "-fps_mode", "passthrough"]


def _open_video(path: Path):
    """``(meta, generator of (H, W, 3) uint8 frames)`` of a video, through imageio-ffmpeg.

    The frames are those the decoder yields, each once, in order (the same
    frames as OpenCV's ``VideoCapture``): without passthrough timing ffmpeg
    duplicates frames to fill gaps in the timestamps at the header's rate.
    """
    gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24", output_params=_passthrough_option())
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


def _decode_error(path: Path) -> str | None:
    """The first error ffmpeg reports decoding the video stream of ``path``
    (a truncated or corrupt file), or ``None`` if it decodes cleanly."""
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-nostdin", "-v", "error", "-i", str(path),
           "-map", "0:v:0", "-f", "null", "-"]
    try:
        run = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, check=False)
    except OSError as err:
        return str(err)
    lines = [ln.strip() for ln in run.stderr.decode(errors="replace").splitlines() if ln.strip()]
    if lines:
        return re.sub(r"^\[[^]]*\]\s*", "", lines[0])
    return f"ffmpeg exited with status {run.returncode}" if run.returncode else None


def _announced_frames(meta: dict) -> int | None:
    """Frame count a video's header announces (duration x frame rate), or None if unknown."""
    duration, fps = meta.get("duration"), meta.get("fps")
    try:
        n = float(duration) * float(fps)
    except (TypeError, ValueError):
        return None
    return int(round(n)) if np.isfinite(n) and n > 0 else None


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
        _check_selection(f"folder {path}", len(files), start, stop)
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


def _check_end(path: Path, meta: dict, n_decoded: int, announced: int | None, start: int,
               stop: int | None) -> None:
    """After decoding a video to its end: refuse a damaged file, and a selection
    past the end, naming the frame count the file holds.

    A header's count (duration x frame rate) is only an estimate: a file that
    announces 682 frames at 50 fps may hold 341 at 25, and is complete.  A
    file is called damaged only when it ends short of its header and ffmpeg
    reports a decoding error.
    """
    if announced is not None and n_decoded < announced:
        problem = _decode_error(path)
        if problem is not None:
            raise ValueError(
                f"video file {path} ends after {n_decoded} frames but its header announces about "
                f"{announced} ({meta.get('duration')} s at {meta.get('fps')} fps), and ffmpeg reports "
                f"'{problem}'; the file looks truncated or damaged (pass --stop / stop= to read only "
                "the frames before the damage)")
    _check_selection(f"video file {path}", n_decoded, start, stop)


def _check_selection(what: str, count: int, start: int, stop: int | None) -> None:
    """Refuse a ``start`` or ``stop`` past the end of ``count`` frames, naming the count."""
    held = f"{count} frames (0 to {count - 1})" if count else "no frames"
    if stop is not None and stop > count:
        raise ValueError(f"stop {stop} (--stop) is past the end of {what}, which holds {held}; "
                         f"give a stop of at most {count} or leave it out")
    if start >= count:
        raise ValueError(f"start {start} (--start) is past the end of {what}, which holds {held}")


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
    selected, ``start`` or ``stop`` lies past the last frame (the message
    gives the count), a folder holds no images, images differ in size, a
    video ends short of the frame count its header announces and ffmpeg
    reports a decoding error (a truncated or damaged file; a header that
    merely over-counts is no error: the frames are those that decode), or
    the frames would not fit in the memory available (checked from
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
            _check_selection(f"folder {path}", len(files), start, stop)
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
            if stop is not None and i >= stop:
                ended = False
                break
            n_decoded = i + 1
            if i >= start and (i - start) % step == 0:
                frames.append(_resize(srgb_int_to_linear(rgb), scale))
    finally:
        decoded.close()
    if ended:
        _check_end(path, meta, n_decoded, announced, start, stop)
    if not frames:
        raise ValueError(f"no frames selected from {path} with start={start}, stop={stop}, step={step}")
    return np.ascontiguousarray(np.stack(frames).astype(np.float32, copy=False))


