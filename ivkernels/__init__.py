"""ivkernels: intrinsic video (albedo, shading, flow, occlusion, motion
boundaries) with data-parallel Warp kernels and a Taichi mirror.

>>> import ivkernels as iv
>>> video = iv.decompose(frames)                 # doctest: +SKIP
>>> video.albedo, video.shading, video.flow, video.occlusion, video.boundary  # doctest: +SKIP

Method: N. Kong, P. V. Gehler, M. J. Black, "Intrinsic Video", ECCV 2014.
"""
import importlib

from ivkernels import backends, flow, flowio, io, viz
from ivkernels._version import __version__
from ivkernels.decompose import DEFAULT_FLOW_METHOD, IntrinsicVideo, decompose, iter_decompose
from ivkernels.flow import estimate_flow
from ivkernels.params import Params
from ivkernels.parallel import VideoError, decompose_many, iter_decompose_many


#: The research harness (renderer, metrics, baselines, datasets) lives in
#: :mod:`ivkernels.evaluation`; these names reach it from the top, loaded on
#: first use (``ivkernels.synthetic.render_sequence(...)``).
_EVALUATION = ("synthetic", "metrics", "baselines", "datasets")


def __getattr__(name):
    if name in _EVALUATION:
        return importlib.import_module(f"ivkernels.evaluation.{name}")
    raise AttributeError(f"module 'ivkernels' has no attribute {name!r}")


__all__ = ["decompose", "iter_decompose", "decompose_many", "iter_decompose_many", "VideoError",
           "IntrinsicVideo", "Params", "estimate_flow",
           "DEFAULT_FLOW_METHOD", "__version__"]
