"""Eq. 2 over ``S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...))``: the shading plus nested edge-aware coarse fields.

L-BFGS on the per-pixel shading alone moves slowly along one kind of
direction: smooth changes of ``S`` that stop at albedo edges.  Inside a flat
albedo region the albedo GSM (Eq. 11) is stiff, across the region's edges it
is soft, so the Hessian of Eq. 2 on ``A = I - S`` is a graph Laplacian with
very uneven weights, and a scalar-scaled quasi-Newton method needs hundreds
of iterations to shift a region as a whole (perf/RESULTS.md, "Solver: the
edge-aware coarse basis").  This problem adds a coarse field ``z`` on nodes
every ``spacing`` pixels, interpolated by weights that follow the albedo
(:mod:`ivkernels.kernels.warp.coarse_basis`), and lets L-BFGS optimise both,
``S = s + P z``, ``dE/ds = dE/dS``, ``dE/dz = P^T dE/dS``.

This is hierarchical-basis preconditioning (Szeliski, "Locally adapted
hierarchical basis preconditioning", SIGGRAPH 2006) with the albedo as the
guide of the interpolation, over one or more nested coarse levels: level 0
has nodes every ``spacing`` pixels, interpolated onto the pixels by ``P_0``;
level ``k >= 1`` has a node on every ``LEVEL_RATIO``-th node of level ``k - 1``
(so every ``spacing * LEVEL_RATIO^k`` pixels), interpolated onto level
``k - 1``'s nodes by ``Q_k``, the same rule with the albedo read at those
nodes.  Level ``k`` enters scaled by ``c_k = LEVEL_RATIO^-k``:

    S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + Q_2 (c_2 z_2 + ...))),
    dE/ds = dE/dS,    dE/dz_k = c_k Q_k^T ... Q_1^T P_0^T dE/dS.

Only ``P_0`` holds weights per pixel (16 floats a pixel, sixteen times
the shading): an evaluation reads them once to prolong and once to restrict,
however many levels there are.  Each level with its own per-pixel weights,
as before, read them once more per level and evaluation (8 frames at
640x480, two levels: 9.8 s of the 45 s of ``decompose()``, perf/RESULTS.md,
"The coarse basis nested"); nested, the energy reached at the default
budget is the same within 0.02%.

The scale keeps the levels' curvatures alike for L-BFGS's one scalar
scaling: a node's field covers ``LEVEL_RATIO^2`` times more pixels than a
node of the level below, so the per-pixel terms (temporal, coupling)
stiffen it by that much, and ``c_k`` brings it back (perf/RESULTS.md,
"Solver: a second, scaled coarse level"; unscaled, a second level raises
the energy reached).  The minimum over ``S`` is the same; only the path to
it changes.  Each alternation of the solver :meth:`start` s afresh: ``s`` =
the current shading, every ``z_k = 0``, weights from the current albedo.
"""
from __future__ import annotations

import math

import numpy as np

from ivkernels.kernels.host import grid_shape
from ivkernels.solver.energy import ConstrainedEnergy

#: Each coarse level's node spacing over the finer one's; level ``k`` is scaled by ``LEVEL_RATIO^-k``.
LEVEL_RATIO = 3


def uses_coarse_basis(shape: tuple[int, int], spacing: int) -> bool:
    """Whether a level of ``shape`` (h, w) gets a coarse field of node ``spacing``:
    ``spacing > 0`` and at least four node spacings on its shorter side."""
    return spacing > 0 and min(shape) >= 4 * spacing


def coarse_spacings(shape: tuple[int, int], spacing: int, levels: int) -> list[int]:
    """Node spacings of the coarse levels a pyramid level of ``shape`` (h, w) gets:
    ``spacing * LEVEL_RATIO^k`` for ``k < levels``, those with four node spacings on
    the shorter side (empty: no basis)."""
    spacings = [spacing * LEVEL_RATIO ** k for k in range(max(0, int(levels)))]
    return [s for s in spacings if uses_coarse_basis(shape, s)]


class CoarseField:
    """One coarse level: node ``spacing`` (pixels), ``scale`` ``c_k``, its unknowns ``z``
    and gradient ``g_z`` (views of the problem's ``X`` and ``G``, (T, Hc, Wc)), its
    interpolation ``weights`` onto the level below (T, Hb, Wb, 16): the pixels for
    level 0, level ``k - 1``'s nodes for ``k >= 1``, and ``ratio``, its node spacing in
    the units of the level below (``spacing`` for level 0, ``LEVEL_RATIO`` above), a
    buffer ``work`` (T, Hc, Wc) for the prolonged sums, and, where a coarser level
    nests on it, ``node_albedo`` (T, Hc, Wc, C): the albedo at its own nodes, from which
    the next level's weights are made (:meth:`CoarseBasisProblem.start`)."""

    def __init__(self, be, frames: int, below: tuple[int, int], ratio: int, spacing: int, scale: float, X, G,
                 offset: int):
        hc, wc = grid_shape(*below, ratio)
        m = frames * hc * wc
        self.spacing, self.ratio, self.scale, self.size = int(spacing), int(ratio), float(scale), m
        self.z_flat, self.g_flat = X[offset: offset + m], G[offset: offset + m]
        self.z, self.g_z = self.z_flat.reshape((frames, hc, wc)), self.g_flat.reshape((frames, hc, wc))
        self.weights = be.empty((frames, *below, 16))
        self.work = be.empty((frames, hc, wc))
        self.node_albedo = None


class CoarseBasisProblem:
    """The objective of :class:`ConstrainedEnergy` over ``X = [s, z_0, z_1, ...]`` (flat,
    ``n + sum_k T Hc_k Wc_k``).

    The levels nest (Szeliski's hierarchical basis): level 0's nodes are
    interpolated onto the pixels by ``P_0``, level ``k``'s onto level ``k - 1``'s
    nodes by ``Q_k`` (node spacing ``LEVEL_RATIO`` in those nodes, weights from
    the albedo at them), so ``P_k = P_0 Q_1 ... Q_k`` and

        S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + Q_2 (...))),
        dE/dz_k = c_k Q_k^T ... Q_1^T P_0^T dE/dS.

    Only ``P_0`` holds weights per pixel (16 per pixel, the bulk of the basis's
    memory and traffic): each evaluation reads them twice, once to prolong and
    once to restrict, whatever the number of levels.

    Parameters
    ----------
    problem : the :class:`ConstrainedEnergy` of the level (its ``X`` is the shading ``S``).
    spacings : node spacing (pixels) of each coarse level, finest first
        (:func:`coarse_spacings`: ``spacing * LEVEL_RATIO^k``); level ``k`` is scaled by ``LEVEL_RATIO^-k``.
    sigma : albedo distance (log units) at which a node's weight falls to ``1/e``.
    """

    def __init__(self, problem: ConstrainedEnergy, spacings, sigma: float):
        energy = problem.energy
        be = energy.be
        if not spacings:
            raise ValueError("CoarseBasisProblem needs at least one coarse level")
        spacings = [int(s) for s in spacings]
        if any(b != a * LEVEL_RATIO for a, b in zip(spacings, spacings[1:])):
            raise ValueError(f"coarse spacings must grow by {LEVEL_RATIO} from level to level, got {spacings}")
        self.problem, self.be, self.sigma = problem, be, float(sigma)
        n = energy.n
        T, h, w = energy.shape
        belows, ratios = [(h, w)], [spacings[0]]
        for _ in spacings[1:]:
            belows.append(grid_shape(*belows[-1], ratios[-1]))
            ratios.append(LEVEL_RATIO)
        sizes = [T * math.prod(grid_shape(*below, ratio)) for below, ratio in zip(belows, ratios)]
        self.X = be.zeros((n + sum(sizes),))
        self.G = be.zeros((n + sum(sizes),))
        self.s, self.g_s = self.X[:n], self.G[:n]
        offsets = n + np.cumsum([0] + sizes[:-1])
        self.fields = [CoarseField(be, T, below, ratio, spacing, float(LEVEL_RATIO) ** -k, self.X, self.G, int(offset))
                       for k, (below, ratio, spacing, offset) in enumerate(zip(belows, ratios, spacings, offsets))]
        channels = energy.A.shape[3]
        for f in self.fields[:-1]:
            f.node_albedo = be.empty((*f.z.shape, channels))

    def start(self) -> None:
        """``s`` = the current shading, every ``z_k = 0``, and the weights from the albedo
        ``I - S``: ``P_0``'s at the pixels, each ``Q_k``'s at level ``k - 1``'s nodes."""
        p, be = self.problem, self.be
        p.sync_albedo()
        guide = p.energy.A                  # what the level's weights are made from
        for below, f in zip([None] + self.fields[:-1], self.fields):
            if below is not None:
                # the albedo at the level below's nodes, gathered on the backend's device
                be.coarse_basis.node_samples(guide, below.node_albedo, below.ratio)
                guide = below.node_albedo
            be.coarse_basis.coarse_weights(guide, f.weights, f.ratio, self.sigma)
            be.zero(f.z_flat)
        be.vecops.copy(p.X, self.s)

    def finish(self) -> None:
        """Leave ``S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...))`` of the current ``X`` in the
        energy's shading (and ``A = I - S``)."""
        self._set_shading()
        self.problem.sync_albedo()

    def _set_shading(self) -> None:
        p, be = self.problem, self.be
        be.vecops.copy(self.s, p.X)
        finest = self.fields[0]
        if len(self.fields) == 1 and finest.scale == 1.0:
            be.coarse_basis.prolong_add(finest.z, finest.weights, p.energy.S, finest.spacing)
            return
        # from the coarsest level down: work_k = c_k z_k + Q_{k+1} work_{k+1}
        above = None
        for f in reversed(self.fields):
            be.vecops.lincomb(f.work.reshape((f.size,)), f.scale, f.z_flat, 0.0, f.z_flat)
            if above is not None:
                be.coarse_basis.prolong_add(above.work, above.weights, f.work, above.ratio)
            above = f
        be.coarse_basis.prolong_add(finest.work, finest.weights, p.energy.S, finest.spacing)

    def __call__(self, X, G) -> float:
        """Energy at ``S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...))``; writes ``dE/ds`` and
        ``dE/dz_k = c_k Q_k^T ... Q_1^T P_0^T dE/dS`` into ``G``."""
        if X is not self.X or G is not self.G:
            raise ValueError("CoarseBasisProblem evaluates its own buffers X and G only")
        p, be = self.problem, self.be
        self._set_shading()
        value = p.value_and_gradient(self.g_s)          # dE/ds = dE/dS, written in place
        values = self.g_s.reshape(p.energy.shape)
        for f in self.fields:
            # the unscaled sums: P_0^T dE/dS, then each Q_k^T of the level below's (scaled after)
            be.zero(f.g_flat)
            be.coarse_basis.restrict_add(values, f.weights, f.g_z, f.ratio)
            values = f.g_z
        for f in self.fields:
            if f.scale != 1.0:
                be.vecops.scale(f.scale, f.g_flat)
        return value
