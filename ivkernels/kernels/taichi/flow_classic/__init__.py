"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic` (same names, same
signatures, NumPy arrays passed as ``ti.types.ndarray()``).

See the Warp module for the equations.  Each kernel's outermost loop runs
over the ``T * H`` image rows in parallel and loops over ``x`` inside, like
the Warp kernels.

One module per concern, as :mod:`ivkernels.kernels.warp.flow_classic`:
:mod:`.grey`, :mod:`.rof`, :mod:`.features`, :mod:`.irls`, :mod:`.solve`,
:mod:`.edges`; each lists its host functions in ``__all__``, gathered here.
"""
from ivkernels.kernels.host import GREY_WEIGHTS  # noqa: F401  (rgb2gray weights, re-exported)
from ivkernels.kernels.taichi.flow_classic.grey import *  # noqa: F401,F403
from ivkernels.kernels.taichi.flow_classic.rof import *  # noqa: F401,F403
from ivkernels.kernels.taichi.flow_classic.features import *  # noqa: F401,F403
from ivkernels.kernels.taichi.flow_classic.irls import *  # noqa: F401,F403
from ivkernels.kernels.taichi.flow_classic.solve import *  # noqa: F401,F403
from ivkernels.kernels.taichi.flow_classic.edges import *  # noqa: F401,F403
