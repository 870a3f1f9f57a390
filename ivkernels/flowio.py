"""Middlebury ``.flo`` optical-flow files.

Layout (little-endian): the 4 bytes ``b"PIEH"`` (the float32 202021.25, a
sanity tag), int32 width, int32 height, then ``height * width * 2`` float32
values, row-major, ``(u, v)`` interleaved per pixel.  ``u`` is the motion
along x (columns), ``v`` along y (rows), in pixels, from the first frame to
the second (Baker et al., IJCV 2011).  Components with magnitude above
:data:`UNKNOWN_FLOW_THRESHOLD` (1e9) mark unknown flow: they are read and
written as given; :func:`valid_flow_mask` tells the known pixels.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ivkernels.io import atomic_output

TAG_FLOAT = 202021.25
TAG_BYTES = b"PIEH"
UNKNOWN_FLOW_THRESHOLD = 1e9
_MAX_SIDE = 1 << 16

__all__ = ["read_flo", "write_flo", "valid_flow_mask", "UNKNOWN_FLOW_THRESHOLD"]


def valid_flow_mask(flow) -> np.ndarray:
    """Boolean ``(..., H, W)``: True where the flow ``(..., H, W, 2)`` is known.

    A pixel is unknown when either component is NaN/inf or has magnitude
    above :data:`UNKNOWN_FLOW_THRESHOLD` (the Middlebury convention).
    """
    flow = np.asarray(flow)
    if flow.ndim < 3 or flow.shape[-1] != 2:
        raise ValueError(f"flow: expected shape (..., H, W, 2), got {flow.shape}")
    if not np.issubdtype(flow.dtype, np.number) or np.issubdtype(flow.dtype, np.complexfloating):
        raise TypeError(f"flow: expected a real numeric array, got dtype {flow.dtype}")
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(flow) & (np.abs(flow) <= UNKNOWN_FLOW_THRESHOLD)
    return np.all(ok, axis=-1)


def read_flo(path) -> np.ndarray:
    """Read a Middlebury ``.flo`` file as float32 ``(H, W, 2)`` (u, v) in pixels.

    Raises FileNotFoundError for a missing file and ValueError for a wrong
    tag, implausible size, or a file shorter/longer than its header says.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such .flo file: {path}")
    data = path.read_bytes()
    if len(data) < 12:
        raise ValueError(f"{path}: truncated .flo file ({len(data)} bytes, header needs 12)")
    if data[:4] != TAG_BYTES:
        tag = np.frombuffer(data[:4], dtype="<f4")[0]
        raise ValueError(
            f"{path}: not a Middlebury .flo file (tag {data[:4]!r} = {tag!r}, expected "
            f"{TAG_BYTES!r} = {TAG_FLOAT})"
        )
    width, height = (int(v) for v in np.frombuffer(data[4:12], dtype="<i4"))
    if not (0 < width <= _MAX_SIDE and 0 < height <= _MAX_SIDE):
        raise ValueError(f"{path}: implausible size in header: width={width}, height={height}")
    expected = 12 + 8 * width * height
    if len(data) != expected:
        state = "truncated" if len(data) < expected else "has trailing bytes"
        raise ValueError(
            f"{path}: {state}: header says {width}x{height} ({expected} bytes), file has {len(data)} bytes"
        )
    flow = np.frombuffer(data, dtype="<f4", offset=12).reshape(height, width, 2)
    return flow.astype(np.float32)  # native byte order, writable copy


def write_flo(path, flow) -> Path:
    """Write ``flow`` ``(H, W, 2)`` (u, v in pixels) as a Middlebury ``.flo``.

    Values are stored as float32 as given (unknown-flow markers included).
    The file is written under a temporary name and renamed when complete.
    """
    flow = np.asarray(flow)
    if flow.ndim != 3 or flow.shape[-1] != 2:
        raise ValueError(f"write_flo: expected flow of shape (H, W, 2), got {flow.shape}")
    if not np.issubdtype(flow.dtype, np.number) or np.issubdtype(flow.dtype, np.complexfloating):
        raise TypeError(f"write_flo: expected a real numeric array, got dtype {flow.dtype}")
    height, width = flow.shape[:2]
    if not (0 < width <= _MAX_SIDE and 0 < height <= _MAX_SIDE):
        raise ValueError(f"write_flo: unsupported size {width}x{height}")
    header = TAG_BYTES + np.array([width, height], dtype="<i4").tobytes()
    body = np.ascontiguousarray(flow, dtype="<f4").tobytes()
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_bytes(header + body)
    return path
