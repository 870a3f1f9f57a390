"""Reading and writing frames: video files, image folders, PNG sequences, NPZ.

Everything inside ivkernels works on *linear* RGB in ``[0, 1]``, float32,
stacked as ``(T, H, W, 3)``.  This package is the border, one concern a module:

* :mod:`.reading`: :func:`read_frames`, :func:`read_image`,
  :func:`probe_frames`, :func:`to_linear_float` (sRGB decoded on the way in);
* :mod:`.writing`: :func:`write_png_sequence` (8-bit sRGB or 16-bit linear),
  :func:`write_npz`, :func:`write_video` and :class:`VideoWriter` (checked after
  writing), :class:`NpzWriter` (streamed, no memory map), each through
  :func:`atomic_output`;
* :mod:`.output_folder`: :class:`OutputFolder`, the command line's output,
  claimed before work and renamed into place when complete.

The sRGB maths lives in :mod:`ivkernels.colour`; its names are re-exported
here for existing callers.
"""
from __future__ import annotations

from ivkernels.colour import linear_to_srgb, srgb_decode_table, srgb_to_linear
from ivkernels.io.output_folder import OUTPUT_MARKER, Interrupted, OutputFolder, glob_escape
from ivkernels.io.reading import (IMAGE_EXTENSIONS, list_image_files, probe_frames, read_frames,
                                  read_image, to_linear_float)
from ivkernels.io.writing import (VIDEO_EXTENSIONS_WRITE, NpzWriter, VideoWriter, atomic_output, current_umask,
                                  write_npz, write_png_sequence, write_video)

__all__ = [
    "IMAGE_EXTENSIONS",
    "VIDEO_EXTENSIONS_WRITE",
    "srgb_to_linear",
    "linear_to_srgb",
    "srgb_decode_table",
    "to_linear_float",
    "read_image",
    "read_frames",
    "list_image_files",
    "probe_frames",
    "write_png_sequence",
    "write_npz",
    "write_video",
    "VideoWriter",
    "NpzWriter",
    "atomic_output",
    "current_umask",
    "OutputFolder",
    "OUTPUT_MARKER",
    "Interrupted",
    "glob_escape",
]
