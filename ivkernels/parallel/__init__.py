"""Many videos and long videos, in parallel: on a Ray cluster or in this process.

>>> import ivkernels as iv
>>> results = iv.decompose_many(["a.mp4", "b.mp4", frames])              # doctest: +SKIP
>>> long_video = iv.decompose_many([frames], chunk_frames=24)[0]          # doctest: +SKIP

Modules: :mod:`~ivkernels.parallel.many` (the public functions, the plan and
the checks), :mod:`~ivkernels.parallel.chunks` (cutting a long video and
stitching its chunks), :mod:`~ivkernels.parallel.engines` (this process, or
Ray), :mod:`~ivkernels.parallel.tasks` (what a task runs, per-process and
per-node set-up).  This package sits above :mod:`ivkernels.decompose`, which
never imports it.  See DESIGN.md section 7.
"""
from ivkernels.parallel.chunks import chunk_ranges, stitch
from ivkernels.parallel.many import ENGINES, VideoError, decompose_many, iter_decompose_many

__all__ = ["decompose_many", "iter_decompose_many", "VideoError", "ENGINES", "chunk_ranges", "stitch"]
