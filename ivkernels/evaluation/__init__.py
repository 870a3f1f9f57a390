"""The research harness, a wing above the library: what measures ivkernels.

* :mod:`~ivkernels.evaluation.synthetic`  Lambertian video renderer with exact
  albedo, shading, flow and visibility;
* :mod:`~ivkernels.evaluation.datasets`   the MIT-Berkeley objects and the
  Middlebury flow pairs, read as videos;
* :mod:`~ivkernels.evaluation.metrics`    LMSE, flow end-point error, flicker;
* :mod:`~ivkernels.evaluation.baselines`  per-frame Retinex and the Weiss
  temporal median, the methods intrinsic video is compared with;
* :mod:`~ivkernels.evaluation.joint`      whole-video alternation of flow and
  decomposition, used to measure the flow passes.

It imports the public API; nothing in the library imports it.
``ivkernels.synthetic``, ``ivkernels.metrics``, ``ivkernels.baselines`` and
``ivkernels.datasets`` are these modules.
"""
