"""ivkernels: intrinsic video (albedo, shading, flow, occlusion, motion
boundaries) with data-parallel Warp kernels and a Taichi mirror.

>>> import ivkernels as iv
>>> video = iv.decompose(frames)                 # doctest: +SKIP
>>> video.albedo, video.shading, video.flow, video.occlusion, video.boundary  # doctest: +SKIP

Method: N. Kong, P. V. Gehler, M. J. Black, "Intrinsic Video", ECCV 2014.
"""
from ivkernels.decompose import DEFAULT_FLOW_METHOD, IntrinsicVideo, decompose, iter_decompose
from ivkernels.params import Params

__version__ = "0.1.0"


def __getattr__(name):
    # Submodules with heavier imports load on first use.
    import importlib

    if name in ("synthetic", "metrics", "baselines", "io", "flowio", "viz", "flow", "backends"):
        return importlib.import_module(f"ivkernels.{name}")
    if name == "estimate_flow":
        from ivkernels.flow import estimate_flow

        return estimate_flow
    raise AttributeError(f"module 'ivkernels' has no attribute {name!r}")


__all__ = ["decompose", "iter_decompose", "IntrinsicVideo", "Params", "estimate_flow",
           "DEFAULT_FLOW_METHOD", "__version__"]
