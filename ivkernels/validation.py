"""One place for the checks on what users hand to ivkernels.

:func:`ivkernels.decompose`, :func:`ivkernels.iter_decompose`,
:func:`ivkernels.estimate_flow`, :func:`ivkernels.io.to_linear_float` and the
command line all validate through this module, so one input gets one answer
everywhere:

* **frames** (:func:`check_frames`, then :func:`linear_frames`):
  ``uint8`` / ``uint16`` are sRGB-encoded; ``float32`` / ``float64`` are
  already *linear* RGB in ``[0, 1]`` (values within ``1e-6`` outside are
  clipped; anything further out, NaN and inf are refused: float frames in
  0..255 are refused, never clipped or rescaled).  Other dtypes are refused.
  A stack ``(T, H, W, 3)``, a single frame ``(H, W, 3)`` (taken as T = 1
  where the caller allows it), or a list of ``(H, W, 3)`` frames of one size
  and dtype (a frame that differs is named).
* **flow** (:func:`check_flow`): float, ``(T-1, H, W, 2)``, finite, and
  at most :data:`MAX_FLOW` pixels in each component once in float32.
* **memory** (:func:`check_memory`): the bytes a call will hold are estimated
  from the shapes alone and compared with the memory available *before*
  anything is allocated.
* **settings** (:func:`check_fields`): the fields of a dataclass such as
  :class:`ivkernels.Params` against per-field :class:`Range` rules: integers
  must be integers, every number finite and inside its range.

Shapes are checked before values, and values are checked one frame at a time,
so a refused input never costs more than one frame of scratch memory.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
import os
from dataclasses import dataclass
from typing import Any, NamedTuple, Sequence

import numpy as np

from ivkernels.colour import srgb_decode_table

#: Float frames may lie this far outside [0, 1] (rounding) and are clipped.
FLOAT_TOLERANCE = 1e-6
#: Largest flow component accepted, in pixels.  Far beyond any image, while
#: float32 still resolves 1/16 pixel there; Middlebury's "unknown" marker
#: (1e9) and values that overflow float32 are refused.
MAX_FLOW = 1e6
#: Smallest frame side :func:`ivkernels.decompose` accepts (and the smallest
#: coarsest pyramid level): the 5x5 albedo and 3x3 shading neighbourhoods and
#: the flow's 5x5 median need a few pixels of interior.
MIN_FRAME_SIZE = 8
#: Most pyramid levels a decomposition may have.
MAX_PYRAMID_LEVELS = 64
#: Working memory of one solved window, bytes per pixel per frame of the
#: window (input, log image, weights, the unknowns and their gradients, the
#: L-BFGS history, the pyramid, the flow and the maps).  Measured peak of a
#: whole decompose() of 8 frames with DIS flow: about 500 at 320x240 and at
#: 640x480; a margin on top.
SOLVER_BYTES_PER_PIXEL = 640
#: Working memory of the flow, bytes per pixel per frame given to one call.
FLOW_BYTES_PER_PIXEL = 512
FRAME_DTYPES = (np.uint8, np.uint16, np.float32, np.float64)


class NotEnoughMemoryError(MemoryError, ValueError):
    """A call would need more memory than the machine has available."""


# ----------------------------------------------------------------------------
# frames
# ----------------------------------------------------------------------------

class Frames(NamedTuple):
    """Frames whose shape and dtype passed :func:`check_frames` (values not yet read)."""

    source: Any                 # ndarray (T, H, W, 3), or a list of (H, W, 3) ndarrays
    shape: tuple                # (T, H, W)
    dtype: np.dtype
    name: str

    @property
    def linear_nbytes(self) -> int:
        """Bytes of the float32 linear copy :func:`linear_frames` returns."""
        T, H, W = self.shape
        return T * H * W * 3 * 4


def _dtype_error(name: str, dtype) -> TypeError:
    return TypeError(f"{name}: unsupported dtype {dtype}; expected uint8 or uint16 sRGB, "
                     "or float32/float64 linear RGB in [0, 1]")


def _shape_text(shape) -> str:
    return "x".join(str(n) for n in shape)


def check_frames(frames, name: str = "frames", *, min_frames: int = 1, min_size: int = 1,
                 single_frame: bool = True, what: str | None = None) -> Frames:
    """Check the type, dtype and shape of user frames without reading their values.

    Parameters
    ----------
    frames : ``(T, H, W, 3)`` array, a single ``(H, W, 3)`` frame (when
        ``single_frame``), or a list / tuple of ``(H, W, 3)`` frames.
    name : what the messages call the argument.
    min_frames : fewest frames accepted.
    min_size : smallest height and width accepted.
    single_frame : take an ``(H, W, 3)`` array as one frame.
    what : the operation, for the "needs at least N frames" message.

    Returns
    -------
    :class:`Frames`; pass it to :func:`linear_frames`.

    Raises
    ------
    TypeError for a non-array argument or an unsupported dtype; ValueError for
    a wrong shape, frames of different sizes or dtypes in a list, too few or
    too small frames.
    """
    if isinstance(frames, (str, bytes, os.PathLike)) or frames is None or isinstance(frames, dict):
        raise TypeError(f"{name} must be a numpy array (T, H, W, 3), got {type(frames).__name__}"
                        + ("; read files with ivkernels.io.read_frames" if isinstance(
                            frames, (str, os.PathLike)) else ""))
    if isinstance(frames, (list, tuple)):
        source = _check_frame_list(frames, name)
        T = len(source)
        H, W = source[0].shape[:2]
        dtype = source[0].dtype
    else:
        if not isinstance(frames, np.ndarray):
            if not hasattr(frames, "__array__"):
                raise TypeError(f"{name} must be a numpy array (T, H, W, 3), got {type(frames).__name__}")
            frames = np.asarray(frames)
        if frames.dtype.type not in FRAME_DTYPES:
            raise _dtype_error(name, frames.dtype)
        if frames.ndim == 3 and frames.shape[-1] == 3 and single_frame:
            frames = frames[None]
        if frames.ndim != 4:
            hint = (" (for a single image pass image[None])"
                    if frames.ndim == 3 and frames.shape[-1] == 3 else "")
            raise ValueError(f"{name}: expected shape (T, H, W, 3), got {frames.shape}{hint}")
        if frames.shape[-1] != 3:
            raise ValueError(f"{name}: expected 3 colour channels (RGB) in the last axis, shape "
                             f"(T, H, W, 3), got shape {frames.shape}")
        source = frames
        T, H, W = frames.shape[:3]
        dtype = frames.dtype
    if min(T, H, W) == 0:
        raise ValueError(f"{name}: empty frame stack, shape {(T, H, W, 3)}")
    if T < min_frames:
        raise ValueError(f"{name}: {what or 'this'} needs at least {min_frames} frames, shape "
                         f"(T, H, W, 3) with T >= {min_frames}; got T = {T}")
    if min(H, W) < min_size:
        raise ValueError(f"{name}: frames must be at least {min_size}x{min_size} pixels, got {H}x{W}")
    return Frames(source, (T, H, W), np.dtype(dtype), name)


def _check_frame_list(frames: Sequence, name: str) -> list:
    if not frames:
        raise ValueError(f"{name}: empty list of frames")
    out = []
    for t, f in enumerate(frames):
        if isinstance(f, (str, bytes, os.PathLike)) or not (isinstance(f, np.ndarray)
                                                           or hasattr(f, "__array__")
                                                           or isinstance(f, (list, tuple))):
            raise TypeError(f"{name}[{t}] must be an (H, W, 3) array, got {type(f).__name__}")
        f = np.asarray(f)
        if f.dtype.type not in FRAME_DTYPES:
            raise _dtype_error(f"{name}[{t}]", f.dtype)
        if f.ndim != 3 or f.shape[-1] != 3:
            raise ValueError(f"{name}[{t}]: expected an (H, W, 3) frame, got shape {f.shape}")
        if out:
            if f.shape != out[0].shape:
                raise ValueError(f"{name}[{t}] is {_shape_text(f.shape)} but {name}[0] is "
                                 f"{_shape_text(out[0].shape)}; all frames must share one size")
            if f.dtype != out[0].dtype:
                raise ValueError(f"{name}[{t}] has dtype {f.dtype} but {name}[0] has "
                                 f"{out[0].dtype}; all frames must share one dtype")
        out.append(f)
    return out


def linear_frames(frames: Frames) -> np.ndarray:
    """Float32 linear RGB ``(T, H, W, 3)``, C-contiguous, of checked frames.

    Integer frames are sRGB-decoded; float frames are checked one frame at a
    time (finite, inside ``[0, 1]`` up to :data:`FLOAT_TOLERANCE`) and copied.
    """
    T, H, W = frames.shape
    check_memory(frames.linear_nbytes, f"{frames.name}: {T} frames of {W}x{H} in float32")
    out = np.empty((T, H, W, 3), np.float32)
    integer = frames.dtype.kind == "u"
    table = srgb_decode_table(256 if frames.dtype == np.uint8 else 65536) if integer else None
    for t in range(T):
        f = np.asarray(frames.source[t])
        if integer:
            np.take(table, f, out=out[t])
            continue
        label = frames.name if T == 1 else f"{frames.name}[{t}]"
        if not np.isfinite(f).all():
            raise ValueError(f"{label}: contains NaN or infinite values")
        lo, hi = float(f.min()), float(f.max())
        if lo < -FLOAT_TOLERANCE or hi > 1.0 + FLOAT_TOLERANCE:
            hint = (" (values up to 255 look like 8-bit sRGB: pass them as uint8)"
                    if 1.0 < hi <= 255.0 and lo >= -FLOAT_TOLERANCE else
                    " (pass uint8/uint16 for sRGB-encoded images)")
            raise ValueError(f"{label}: float input must be linear RGB in [0, 1], got values in "
                             f"[{lo:.6g}, {hi:.6g}]{hint}")
        np.clip(f, 0.0, 1.0, out=out[t], casting="unsafe")
    return out


# ----------------------------------------------------------------------------
# flow
# ----------------------------------------------------------------------------

def check_flow(flow, n_frames: int, height: int, width: int, name: str = "flow") -> np.ndarray:
    """Validate a forward flow ``(T-1, H, W, 2)``; returns it as float32, C-contiguous.

    Any float dtype is accepted; components must be finite and at most
    :data:`MAX_FLOW` pixels in magnitude (checked before the cast, so float64
    values that would overflow float32 are refused, not turned into inf).
    """
    if isinstance(flow, (str, bytes)) or flow is None:
        raise TypeError(f"{name} must be a float array (T-1, H, W, 2), got {type(flow).__name__}")
    flow = np.asarray(flow)
    expected = (n_frames - 1, height, width, 2)
    if flow.shape != expected:
        raise ValueError(f"{name} must have shape (T-1, H, W, 2) = {expected}, got {flow.shape}")
    if not np.issubdtype(flow.dtype, np.floating):
        raise TypeError(f"{name} must be a float array, got dtype {flow.dtype}")
    out = np.empty(expected, np.float32)
    for t in range(expected[0]):
        f = flow[t]
        if not np.isfinite(f).all():
            raise ValueError(f"{name}[{t}] contains NaN or infinite values")
        peak = float(np.abs(f).max())
        if peak > MAX_FLOW:
            raise ValueError(f"{name}[{t}] has a component of {peak:.3g} pixels; flow must stay within "
                             f"+-{MAX_FLOW:.0e} pixels (Middlebury marks unknown flow with 1e9: "
                             "fill those pixels first)")
        out[t] = f
    return out


# ----------------------------------------------------------------------------
# backend and device
# ----------------------------------------------------------------------------

# ----------------------------------------------------------------------------
# memory
# ----------------------------------------------------------------------------

def available_memory() -> int:
    """Bytes of memory available to this process now (``MemAvailable``, else physical memory)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return 1 << 62


def format_bytes(n: float) -> str:
    """``n`` bytes as a short text (``"1.5 GiB"``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n:.1f} PiB"


def check_memory(nbytes: int, what: str, hint: str = "use fewer or smaller frames") -> None:
    """Raise :class:`NotEnoughMemoryError` if ``nbytes`` exceed the memory available."""
    available = available_memory()
    if nbytes > available:
        raise NotEnoughMemoryError(f"{what} needs about {format_bytes(nbytes)} of memory "
                                   f"({nbytes} bytes) but {format_bytes(available)} is available; "
                                   f"{hint}")


def decompose_nbytes(n_frames: int, height: int, width: int, window: int, *,
                     keep_outputs: bool) -> int:
    """Estimated peak bytes of a decomposition of ``n_frames`` frames of ``height x width``.

    The linear input, the working set of one window
    (:data:`SOLVER_BYTES_PER_PIXEL` per pixel and frame), and with
    ``keep_outputs`` the collected albedo, shading, flow and maps
    (8 float32 per pixel and frame).
    """
    pixels = height * width
    total = n_frames * pixels * 3 * 4
    total += min(n_frames, window) * pixels * SOLVER_BYTES_PER_PIXEL
    if keep_outputs:
        total += n_frames * pixels * 8 * 4
    return total


def flow_nbytes(n_frames: int, height: int, width: int) -> int:
    """Estimated peak bytes of :func:`ivkernels.estimate_flow` on ``n_frames`` frames."""
    return n_frames * height * width * (3 + 2) * 4 + n_frames * height * width * FLOW_BYTES_PER_PIXEL


def pyramid_levels(height: int, width: int, scale: float, min_size: int) -> int:
    """Levels of the coarse-to-fine pyramid (as :func:`ivkernels.solver.pyramid.level_shapes`),
    counted without building the list; stops counting past :data:`MAX_PYRAMID_LEVELS`."""
    n = 1
    while n <= MAX_PYRAMID_LEVELS:
        h = int(round(height * scale ** n))
        w = int(round(width * scale ** n))
        if min(h, w) < min_size:
            break
        n += 1
    return n


# ----------------------------------------------------------------------------
# settings
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Range:
    """The valid values of one numeric setting.

    ``kind`` is ``int`` (an integer is required; floats such as 2.5 or 2.0
    are refused) or ``float`` (any real number, stored as float; it must be
    finite).  ``low`` / ``high`` bound it (``None``: unbounded), inclusive
    unless ``low_open`` / ``high_open``.  ``why`` is added to the message.
    """

    kind: type = float
    low: float | None = 0.0
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    why: str = ""

    def describe(self) -> str:
        if self.low is not None and self.high is not None:
            return (f"in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                    f"{')' if self.high_open else ']'}")
        if self.low is not None:
            return f"{'>' if self.low_open else '>='} {self.low:g}"
        if self.high is not None:
            return f"{'<' if self.high_open else '<='} {self.high:g}"
        return "finite"

    def contains(self, v) -> bool:
        if self.low is not None and (v <= self.low if self.low_open else v < self.low):
            return False
        if self.high is not None and (v >= self.high if self.high_open else v > self.high):
            return False
        return True


_KIND_BY_ANNOTATION = {"int": int, "float": float, "bool": bool, "str": str}


def _annotation_kind(f: dataclasses.Field):
    t = f.type
    if isinstance(t, str):
        return _KIND_BY_ANNOTATION.get(t.strip())
    return t if t in (int, float, bool, str) else None


def check_fields(obj, rules: dict, owner: str | None = None) -> None:
    """Validate (and normalise) every field of the frozen dataclass ``obj``.

    A field named in ``rules`` follows its :class:`Range`; any other ``int``
    or ``float`` field must be finite and >= 0; ``bool`` and ``str`` fields
    must have that type.  Integers are stored as ``int``, reals as ``float``
    (numpy scalars included).  Raises TypeError for a wrong type, ValueError
    for a value out of range, naming ``owner.field``.
    """
    owner = owner or type(obj).__name__
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        label = f"{owner}.{f.name}"
        rule = rules.get(f.name)
        kind = rule.kind if rule is not None else _annotation_kind(f)
        if kind is bool:
            if not isinstance(v, (bool, np.bool_)):
                raise TypeError(f"{label} must be True or False, got {v!r}")
            object.__setattr__(obj, f.name, bool(v))
            continue
        if kind is str:
            if not isinstance(v, str):
                raise TypeError(f"{label} must be a string, got {v!r}")
            continue
        if kind not in (int, float):
            continue
        rule = rule or Range(kind)
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
            raise TypeError(f"{label} must be {'an integer' if kind is int else 'a number'}, got {v!r}")
        if kind is int:
            if not isinstance(v, numbers.Integral):
                raise TypeError(f"{label} must be an integer, got {v!r}")
            v = int(v)
        else:
            v = float(v)
            if not math.isfinite(v):
                raise ValueError(f"{label} must be a finite number, got {v!r}")
        if not rule.contains(v):
            why = f" ({rule.why})" if rule.why else ""
            raise ValueError(f"{label} must be {rule.describe()}, got {v!r}{why}")
        object.__setattr__(obj, f.name, v)
