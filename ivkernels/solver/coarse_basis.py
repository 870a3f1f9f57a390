"""Eq. 2 over ``S = s + P z``: the shading plus an edge-aware coarse field.

L-BFGS on the per-pixel shading alone moves slowly along one kind of
direction: smooth changes of ``S`` that stop at albedo edges.  Inside a flat
albedo region the albedo GSM (Eq. 11) is stiff, across the region's edges it
is soft, so the Hessian of Eq. 2 on ``A = I - S`` is a graph Laplacian with
very uneven weights, and a scalar-scaled quasi-Newton method needs hundreds
of iterations to shift a region as a whole (perf/RESULTS.md, "Solver: the
edge-aware coarse basis").  This problem adds a coarse field ``z`` on nodes
every ``spacing`` pixels, interpolated by weights that follow the albedo
(:mod:`ivkernels.kernels.warp.coarse_basis`), and lets L-BFGS optimise both:

    S = s + P z,    dE/ds = dE/dS,    dE/dz = P^T dE/dS.

This is hierarchical-basis preconditioning (Szeliski, "Locally adapted
hierarchical basis preconditioning", SIGGRAPH 2006) with one coarse level
and the albedo as the guide of the interpolation.  The minimum over ``S`` is
the same; only the path to it changes.  Each alternation of the solver
:meth:`start` s afresh: ``s`` = the current shading, ``z = 0``, weights from the
current albedo.
"""
from __future__ import annotations

from ivkernels.kernels.host import grid_shape
from ivkernels.solver.energy import ConstrainedEnergy


def uses_coarse_basis(shape: tuple[int, int], spacing: int) -> bool:
    """Whether a level of ``shape`` (h, w) gets the coarse basis: ``spacing > 0`` and at
    least four node spacings on its shorter side."""
    return spacing > 0 and min(shape) >= 4 * spacing


class CoarseBasisProblem:
    """The objective of :class:`ConstrainedEnergy` over ``X = [s, z]`` (flat, ``n + T Hc Wc``).

    Parameters
    ----------
    problem : the :class:`ConstrainedEnergy` of the level (its ``X`` is the shading ``S``).
    spacing : pixels between coarse nodes.
    sigma : albedo distance (log units) at which a node's weight falls to ``1/e``.
    """

    def __init__(self, problem: ConstrainedEnergy, spacing: int, sigma: float):
        energy = problem.energy
        be = energy.be
        T, h, w = energy.shape
        self.problem, self.be, self.spacing, self.sigma = problem, be, int(spacing), float(sigma)
        hc, wc = grid_shape(h, w, self.spacing)
        n, m = energy.n, T * hc * wc
        self.X = be.zeros((n + m,))
        self.G = be.zeros((n + m,))
        self.s = self.X[:n]
        self.z = self.X[n:].reshape((T, hc, wc))
        self.g_s = self.G[:n]
        self.g_z = self.G[n:].reshape((T, hc, wc))
        self.weights = be.empty((T, h, w, 16))

    def start(self) -> None:
        """``s`` = the current shading, ``z = 0``, and the weights from the albedo ``I - S``."""
        p, be = self.problem, self.be
        p.sync_albedo()
        be.coarse_basis.coarse_weights(p.energy.A, self.weights, self.spacing, self.sigma)
        be.vecops.copy(p.X, self.s)
        be.zero(self.z)

    def finish(self) -> None:
        """Leave ``S = s + P z`` of the current ``X`` in the energy's shading (and ``A = I - S``)."""
        self._set_shading()
        self.problem.sync_albedo()

    def _set_shading(self) -> None:
        p, be = self.problem, self.be
        be.vecops.copy(self.s, p.X)
        be.coarse_basis.prolong_add(self.z, self.weights, p.energy.S, self.spacing)

    def __call__(self, X, G) -> float:
        """Energy at ``S = s + P z``; writes ``dE/ds`` and ``dE/dz = P^T dE/dS`` into ``G``."""
        if X is not self.X or G is not self.G:
            raise ValueError("CoarseBasisProblem evaluates its own buffers X and G only")
        p, be = self.problem, self.be
        self._set_shading()
        value = p(p.X, p.G)
        be.vecops.copy(p.G, self.g_s)
        be.zero(self.g_z)
        be.coarse_basis.restrict_add(p.energy.gS, self.weights, self.g_z, self.spacing)
        return value
