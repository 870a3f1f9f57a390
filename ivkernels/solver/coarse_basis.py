"""Eq. 2 over ``S = s + sum_k c_k P_k z_k``: the shading plus edge-aware coarse fields.

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
guide of the interpolation, over one or more coarse levels: level ``k`` has
nodes every ``spacing * LEVEL_RATIO^k`` pixels, interpolated onto the pixels
by the same rule, and enters scaled by ``c_k = LEVEL_RATIO^-k``:

    S = s + sum_k c_k P_k z_k,    dE/ds = dE/dS,    dE/dz_k = c_k P_k^T dE/dS.

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
    and gradient ``g_z`` (views of the problem's ``X`` and ``G``, (T, Hc, Wc)) and the
    per-pixel interpolation ``weights`` (T, h, w, 16)."""

    def __init__(self, be, shape: tuple[int, int, int], spacing: int, scale: float, X, G, offset: int):
        T, h, w = shape
        hc, wc = grid_shape(h, w, spacing)
        m = T * hc * wc
        self.spacing, self.scale, self.size = int(spacing), float(scale), m
        self.z_flat, self.g_flat = X[offset: offset + m], G[offset: offset + m]
        self.z, self.g_z = self.z_flat.reshape((T, hc, wc)), self.g_flat.reshape((T, hc, wc))
        self.weights = be.empty((T, h, w, 16))


class CoarseBasisProblem:
    """The objective of :class:`ConstrainedEnergy` over ``X = [s, z_0, z_1, ...]`` (flat,
    ``n + sum_k T Hc_k Wc_k``).

    Parameters
    ----------
    problem : the :class:`ConstrainedEnergy` of the level (its ``X`` is the shading ``S``).
    spacings : node spacing (pixels) of each coarse level, finest first
        (:func:`coarse_spacings`); level ``k`` is scaled by ``LEVEL_RATIO^-k``.
    sigma : albedo distance (log units) at which a node's weight falls to ``1/e``.
    """

    def __init__(self, problem: ConstrainedEnergy, spacings, sigma: float):
        energy = problem.energy
        be = energy.be
        if not spacings:
            raise ValueError("CoarseBasisProblem needs at least one coarse level")
        self.problem, self.be, self.sigma = problem, be, float(sigma)
        n = energy.n
        T, h, w = energy.shape
        sizes = [T * math.prod(grid_shape(h, w, int(spacing))) for spacing in spacings]
        self.X = be.zeros((n + sum(sizes),))
        self.G = be.zeros((n + sum(sizes),))
        self.s, self.g_s = self.X[:n], self.G[:n]
        offsets = n + np.cumsum([0] + sizes[:-1])
        self.fields = [CoarseField(be, energy.shape, int(spacing), float(LEVEL_RATIO) ** -k, self.X, self.G,
                                   int(offset))
                       for k, (spacing, offset) in enumerate(zip(spacings, offsets))]
        self._scaled = be.empty((max(f.size for f in self.fields),))     # c_k z_k, prolonged

    def start(self) -> None:
        """``s`` = the current shading, every ``z_k = 0``, and the weights from the albedo ``I - S``."""
        p, be = self.problem, self.be
        p.sync_albedo()
        for f in self.fields:
            be.coarse_basis.coarse_weights(p.energy.A, f.weights, f.spacing, self.sigma)
            be.zero(f.z_flat)
        be.vecops.copy(p.X, self.s)

    def finish(self) -> None:
        """Leave ``S = s + sum_k c_k P_k z_k`` of the current ``X`` in the energy's shading
        (and ``A = I - S``)."""
        self._set_shading()
        self.problem.sync_albedo()

    def _set_shading(self) -> None:
        p, be = self.problem, self.be
        be.vecops.copy(self.s, p.X)
        for f in self.fields:
            z = f.z
            if f.scale != 1.0:
                scaled = self._scaled[: f.size]
                be.vecops.lincomb(scaled, f.scale, f.z_flat, 0.0, f.z_flat)
                z = scaled.reshape(f.z.shape)
            be.coarse_basis.prolong_add(z, f.weights, p.energy.S, f.spacing)

    def __call__(self, X, G) -> float:
        """Energy at ``S = s + sum_k c_k P_k z_k``; writes ``dE/ds`` and
        ``dE/dz_k = c_k P_k^T dE/dS`` into ``G``."""
        if X is not self.X or G is not self.G:
            raise ValueError("CoarseBasisProblem evaluates its own buffers X and G only")
        p, be = self.problem, self.be
        self._set_shading()
        value = p(p.X, p.G)
        be.vecops.copy(p.G, self.g_s)
        for f in self.fields:
            be.zero(f.g_flat)
            be.coarse_basis.restrict_add(p.energy.gS, f.weights, f.g_z, f.spacing)
            if f.scale != 1.0:
                be.vecops.scale(f.scale, f.g_flat)
        return value
