"""Coarse-to-fine minimisation of Eq. 2 over one window of frames (Sec. 4).

At each pyramid level, starting from the up-sampled coarser solution, the
solver alternates (a) L-BFGS over all ``S_t`` of the window at once, with
``A_t = I_t - S_t`` (Eq. 3 as a constraint, :class:`ConstrainedEnergy`) and the
coupling variable ``S~`` fixed (on levels large enough, over
``S = s + P_0 (c_0 z_0 + Q_1 (c_1 z_1 + ...))`` with nested edge-aware coarse fields ``z_k``,
:class:`CoarseBasisProblem`), and (b)
the ``S~`` weighted-median update (Eq. 13).  The coarsest level starts from ``S`` = heavily blurred log
luminance.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ivkernels.params import Params
from ivkernels.solver.coarse_basis import CoarseBasisProblem, coarse_spacings
from ivkernels.solver.energy import ConstrainedEnergy, WindowEnergy
from ivkernels.solver.independent_shadings import independent_shadings, window_params
from ivkernels.solver.lbfgs import LBFGS
from ivkernels.solver.motion_maps import resample_mask, window_occlusion
from ivkernels.solver.pyramid import (coarse_to_fine, image_pyramid, level_shapes, resize,
                                      resize_flow)


@dataclass
class SolveLog:
    """Diagnostics of a solve: energy per iteration and level, and seconds per stage."""

    energy: list = field(default_factory=list)     # (window, level, outer, iteration, E)
    levels: list = field(default_factory=list)     # one dict per (window, level): see solve_window
    terms: list = field(default_factory=list)      # (window, level, {term: E}) after each level
    shadings: list = field(default_factory=list)   # (window, n): independent shadings, see solve_window
    noise_levels: list = field(default_factory=list)   # per window: median noise step (solver.denoise)
    seconds: dict = field(default_factory=dict)    # stage -> seconds

    def add_time(self, stage: str, seconds: float) -> None:
        self.seconds[stage] = self.seconds.get(stage, 0.0) + seconds


def level_iterations(params: Params, level: int) -> int:
    """L-BFGS iterations per alternation at pyramid ``level`` (0 = finest); see
    ``Params.lbfgs_iterations_coarse``."""
    if level == 0:
        return int(params.lbfgs_iterations)
    grown = int(round(params.lbfgs_iterations * params.lbfgs_level_growth ** level))
    return min(int(params.lbfgs_iterations_coarse), grown)


def log_and_weight(be, frames_linear, params: Params):
    """``I = log max(i, floor)`` (T, h, w, 3) and ``w_lum = lum(i) + eps`` (T, h, w) (Eq. 3)."""
    T, h, w, _ = frames_linear.shape
    log_image = be.empty((T, h, w, 3))
    be.colour.log_floor(frames_linear, log_image, params.log_floor)
    w_lum = be.empty((T, h, w))
    be.colour.luminance(frames_linear, w_lum)
    w_lum_np = be.numpy(w_lum)
    if params.lum_eps:
        w_lum = be.asarray(w_lum_np + np.float32(params.lum_eps))
    return log_image, w_lum


def _initial_shading(be, log_image, params: Params):
    """Coarsest-level start: S = log luminance of the input, heavily blurred."""
    T, h, w, _ = log_image.shape
    lum = be.numpy(log_image).mean(axis=3, keepdims=True).astype(np.float32)
    src = be.asarray(lum)
    out, scratch = be.empty(src.shape), be.empty(src.shape)
    be.pyramid.gaussian_blur(src, out, scratch, params.init_blur * min(h, w))
    return out.reshape((T, h, w))


def start_level_for(shapes: list[tuple[int, int]], start_shape: tuple[int, int]) -> int:
    """The pyramid level a start of size ``start_shape`` enters at: the coarsest
    level at least as large on both sides (its own level when the sizes match)."""
    h, w = start_shape
    fits = [level for level, (lh, lw) in enumerate(shapes) if lh >= h and lw >= w]
    return max(fits) if fits else 0


def solve_window(be, frames_linear, flow, occlusion, boundary, params: Params, prior, *,
                 carried=None, window_index: int = 0, log: SolveLog | None = None,
                 progress=None, start_shading=None):
    """Minimise Eq. 2 over one window; returns full-resolution log ``(A, S)``.

    Parameters
    ----------
    be : backend.
    frames_linear : (T, H, W, 3) backend array, linear RGB in [0, 1].
    flow, occlusion, boundary : (T-1, H, W[, 2]) backend arrays, or all
        ``None`` for the ablation without temporal terms.
    params : :class:`ivkernels.Params`.
    prior : :class:`ivkernels.priors.AlbedoPrior`.
    carried : optional ``(A, S)`` NumPy arrays (k, H, W, 3), (k, H, W) of log
        albedo and shading for the first ``k`` frames, solved by the previous
        window; they are held fixed and carry albedo forward (their albedo is
        ``I - S`` of the same frames, so ``S`` alone is used).
    log : :class:`SolveLog` collecting energies and timings, the window's
        number of independent shadings ``n`` (``log.shadings``; both albedo
        priors are divided by it, ``Params.independent_shading_gain``), and per level
        (``log.levels``) why each L-BFGS run stopped and whether all of them
        converged (stopped on the tolerance, not on the iteration budget).
    progress : optional callable ``progress(n_done_levels)``.
    start_shading : optional (T, h, w) NumPy array, log shading of this
        window solved at a reduced size (the flow guide's solve,
        :func:`ivkernels.solver.guide.guide_solve`).  The solve starts from it at
        the level :func:`start_level_for` gives (resized to that level if the
        sizes differ) and skips the coarser levels, which that solve already
        did; without it the coarsest level starts from blurred log luminance.

    Returns
    -------
    A : (T, H, W, 3) float32 NumPy array, log albedo.
    S : (T, H, W) float32 NumPy array, log shading.
    """
    log = log if log is not None else SolveLog()
    T, H, W, _ = frames_linear.shape
    shapes = level_shapes(H, W, params.pyramid_scale, params.pyramid_min_size)
    n_fixed = 0 if carried is None else carried[0].shape[0]
    t0 = time.perf_counter()
    pyramid = image_pyramid(be, frames_linear, shapes)
    carried_shading = None          # (k, h, w, 1) per level: the carried frames' log shading
    if carried is not None:
        carried_shading = image_pyramid(be, be.asarray(carried[1][..., None]), shapes)
    log.add_time("pyramid", time.perf_counter() - t0)
    # A window that carries frames continues the previous, full window's albedo.
    n_shadings = independent_shadings(be, frames_linear, flow, params.independent_shading_gain,
                                      params.log_floor,
                                      n_frames=T if carried is None else max(T, int(params.window)))
    log.shadings.append((window_index, n_shadings))
    # One albedo, n independent shadings: the albedo priors count once per scene point,
    # and Weiss's cue is read only where the light changes (n > 1).
    params = window_params(params, n_shadings)
    # Under a still light, brightness along the flow also tells where it joins two surfaces.
    occlusion = window_occlusion(be, frames_linear, flow, occlusion, params, n_shadings)

    def make_energy(level, shape):
        t = time.perf_counter()
        log_image, w_lum = log_and_weight(be, pyramid[level], params)
        lflow = locc = lbnd = None
        if flow is not None:
            lflow = flow if level == 0 else resize_flow(be, flow, shape)
            locc = resample_mask(be, occlusion, shape)
            lbnd = resample_mask(be, boundary, shape)
        energy = WindowEnergy(be, log_image, w_lum, lflow, locc, lbnd, params, prior,
                              n_fixed=n_fixed, level_scale=shape[0] / H)
        log.add_time("levels", time.perf_counter() - t)
        return energy

    def init(level, shape):
        energy = make_energy(level, shape)
        if start_shading is None:
            S0 = _initial_shading(be, energy.I, params)
        else:
            start = np.empty((*start_shading.shape, 1), np.float32)
            start[..., 0] = start_shading
            S0 = be.asarray(start)
            if tuple(start_shading.shape[1:]) != tuple(shape):
                S0 = resize(be, S0, shape)
        be.vecops.copy(S0.reshape((energy.n,)), energy.S.reshape((energy.n,)))
        return energy

    def upsample(level, shape, energy):
        # Shading is smooth and survives resampling; the albedo follows it
        # through A = I - S, so it keeps the texture the coarser level could not see.
        S_up = resize(be, energy.S.reshape((*energy.shape, 1)), shape)
        finer = make_energy(level, shape)
        be.vecops.copy(S_up.reshape((finer.n,)), finer.S.reshape((finer.n,)))
        return finer

    def solve_level(level, shape, energy):
        if carried_shading is not None:
            S_now = be.numpy(energy.S).copy()
            S_now[:n_fixed] = be.numpy(carried_shading[level])[..., 0]
            be.vecops.copy(be.asarray(S_now.reshape(-1)), energy.S.reshape((energy.n,)))
        t = time.perf_counter()
        problem = ConstrainedEnergy(energy)           # sets A = I - S at each evaluation
        target = problem                  # what L-BFGS minimises: S, or S over the coarse basis
        spacings = coarse_spacings(shape, params.coarse_basis_spacing, params.coarse_basis_levels)
        if spacings:
            target = CoarseBasisProblem(problem, spacings, params.coarse_basis_sigma)
        lbfgs = LBFGS(be, target.X.shape[0], memory=int(params.lbfgs_memory))
        iterations = level_iterations(params, level)
        reasons = []
        for outer in range(int(params.outer_iterations)):
            tm = time.perf_counter()
            energy.update_coupling()
            log.add_time("median", time.perf_counter() - tm)
            lbfgs.reset()

            def record(k, e, outer=outer):
                log.energy.append((window_index, level, outer, k, e))

            if target is not problem:
                target.start()                        # s = S, z_k = 0, weights from the albedo
            lbfgs.minimize(target, target.X, target.G, iterations, on_iteration=record)
            if target is not problem:
                target.finish()                       # S = s + P_0 (c_0 z_0 + Q_1 (...))
            reasons.append(lbfgs.stop_reason)
        problem.sync_albedo()
        log.levels.append({"window": window_index, "level": level, "shape": tuple(shape),
                           "stop_reasons": reasons,
                           "converged": all(r != "budget" for r in reasons)})
        log.terms.append((window_index, level, energy.term_energies()))
        log.add_time("solve", time.perf_counter() - t)
        if progress is not None:
            progress(1)
        return energy

    start_level = None
    if start_shading is not None:
        if start_shading.ndim != 3 or start_shading.shape[0] != T:
            raise ValueError(f"start_shading must be ({T}, h, w) log shading, got {start_shading.shape}")
        start_level = start_level_for(shapes, start_shading.shape[1:])
        if progress is not None and start_level < len(shapes) - 1:
            progress(len(shapes) - 1 - start_level)          # the skipped levels
    final = coarse_to_fine(shapes, solve_level, init, upsample, start_level=start_level)
    A = np.array(be.numpy(final.A), dtype=np.float32, copy=True)
    S = np.array(be.numpy(final.S), dtype=np.float32, copy=True)
    return A, S
