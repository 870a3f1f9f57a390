"""Per-pixel kernels of the Classic+NL optical flow (Sun, Roth & Black, IJCV 2014).

The flow of the intrinsic video (paper Sec. 3, "pre-computed ... using
Classic+NL") minimises, per pyramid level and per warping step, the
linearised energy

    E(du) = sum_x rho_D(It + Ix du + Iy dv)
          + lam * sum_{x ~ y} rho_S((u + du)(y) - (u + du)(x)) + (same for v),

with rho the generalised Charbonnier ``rho(z) = (z^2 + eps^2)^a`` (a = 0.45,
eps = 1e-3), blended with a quadratic during graduated non-convexity (GNC).
One iteratively-reweighted least-squares (IRLS) step replaces each rho by
its weight ``psi(z) = rho'(z) / z`` at the current estimate and solves the
resulting 2x2-per-pixel sparse linear system for ``(du, dv)``:

    (psi_D Ix^2 + lam sum_n w^u_n) du + psi_D Ix Iy dv - lam sum_n w^u_n du_n
        = -psi_D Ix It - lam sum_n w^u_n (u - u_n)          (and the same for v)

(the normal equations of the Classic+NL "flow operator"; ``n`` runs over the
4-neighbours joined by an existing first-order difference).  The system is
solved data-parallel by red-black successive over-relaxation: pixels with
``(x + y) % 2 == parity`` read only neighbours of the other colour, so a
sweep of one colour is race-free and can be split into row bands anywhere.

One module per concern, their host functions gathered here:

* :mod:`.grey`: the input's grey level (sRGB-encoded, or the log of the
  linear grey) and the per-row min/max and per-channel affine rescale the
  host normalises images with, as the public Classic+NL code does;
* :mod:`.rof`: the ROF structure-texture decomposition the flow is computed
  on (Chambolle's dual projection);
* :mod:`.features`: the channels of the data term (an image and its
  derivatives, a soft census);
* :mod:`.irls`: the IRLS weights (data coefficients, smoothness weights);
* :mod:`.solve`: the per-pixel system and its red-black SOR solve, and the
  flow update;
* :mod:`.edges`: the flow's Sobel edges, thinned.

Each lists its host functions in ``__all__``; they are gathered here, so a
host function added to one of them needs no line here.

Array layout: see :mod:`ivkernels.kernels`.  Every kernel runs one thread per
image row (``row = t * H + y``) and loops over ``x``; all are gathers except
:func:`sor_sweep`, which updates ``du`` in place one colour at a time.  On a
GPU all but :func:`row_min_max` (a reduction per row) cut the rows into
tiles of one pixel (:func:`ivkernels.kernels.launch.row_tiles`).

The sweep reads only ``du``: :func:`assemble_system` first folds the data
coefficients, the smoothness weights and the current flow into each pixel's
2x2 block and right-hand side, which keeps a sweep's memory traffic low.
"""
from ivkernels.kernels.host import GREY_WEIGHTS  # noqa: F401  (rgb2gray weights, re-exported)
from ivkernels.kernels.warp.flow_classic.grey import *  # noqa: F401,F403
from ivkernels.kernels.warp.flow_classic.rof import *  # noqa: F401,F403
from ivkernels.kernels.warp.flow_classic.features import *  # noqa: F401,F403
from ivkernels.kernels.warp.flow_classic.irls import *  # noqa: F401,F403
from ivkernels.kernels.warp.flow_classic.solve import *  # noqa: F401,F403
from ivkernels.kernels.warp.flow_classic.edges import *  # noqa: F401,F403
