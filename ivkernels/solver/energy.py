"""The energy of Eq. 2 over one window of frames at one pyramid level.

The unknowns live in one flat backend vector ``X`` of length ``4 * T*h*w``:
``X[:3n]`` is the log albedo ``A`` (T, h, w, 3) and ``X[3n:]`` the log shading
``S`` (T, h, w), n = T*h*w.  Evaluating the energy zeroes the gradient ``G``
(same layout) and lets each term add its part; the terms are kernels of the
backend, called one after the other:

=========================  ===========  ==========================================
term                       paper        kernel
=========================  ===========  ==========================================
data                       Eq. 3        ``energy_data.data_term``
temporal albedo            Eq. 4-5      ``energy_temporal.temporal_terms``, both at
temporal shading           Eq. 8        once (``temporal_term`` on A or S alone)
local shading smoothness   Eq. 9        ``energy_shading.shading_smoothness`` (``_gated``
                                        with the cut at flow jumps, ``motion_maps.
                                        shading_cut_gate``, ``maps.shading_gate`` and
                                        the step evidence, ``step_evidence.step_gate``,
                                        and the light's edges, ``step_evidence.
                                        moving_steps``; ``_paired`` with the stable
                                        steps' pairs too,
                                        ``step_evidence.stable_pairs``)
coupling to S~             Eq. 13       ``energy_shading.coupling_term``
albedo GSM smoothness      Eq. 11       ``energy_albedo_gsm.gsm_smoothness``
albedo global sparsity     Eq. 12       ``energy_albedo_entropy.entropy_term``
=========================  ===========  ==========================================

:class:`ConstrainedEnergy` is what the solver minimises: the same energy on
the data-consistent set ``A = I - S`` (see its docstring for why).

The non-local shading term of Eq. 9 is handled through the coupling variable
``S~`` (Eq. 13): with ``S~`` fixed it is constant, and :meth:`update_coupling`
sets ``S~`` to the 15x15 weighted median of ``S`` near motion boundaries.

Each :class:`WindowEnergy` owns the buffers its kernels need, scratch
included (a :class:`ivkernels.kernels.workspace.Workspace`: the GSM term's
~120 bytes per pixel, the temporal splat weights, the median's window
rows); they are freed with it when the solver moves to the next level.
"""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.workspace import Workspace
from ivkernels.params import Params
from ivkernels.priors import entropy_blur_weights
from ivkernels.solver.motion_maps import shading_cut_gate
from ivkernels.solver.step_evidence import light_edge_factor, multiply_step_gate, stable_pair_weights


class WindowEnergy:
    """Eq. 2 for a window of ``T`` frames of size ``h x w``.

    Parameters
    ----------
    be : backend.
    log_image : (T, h, w, 3) backend array, ``I = log i``.
    w_lum : (T, h, w) backend array, ``lum(i) + eps`` (Eq. 3).
    flow, occlusion, boundary : (T-1, h, w, 2), (T-1, h, w), (T-1, h, w)
        backend arrays at this level, or ``None`` for the ablation without
        temporal terms and motion weights ("IV w/o flow").
    params : :class:`ivkernels.Params`.
    prior : :class:`ivkernels.priors.AlbedoPrior` (GSM table, whitening).
    n_fixed : the first ``n_fixed`` frames are held fixed (their gradient is
        zeroed): frames carried over from the previous window.
    level_scale : size of this pyramid level relative to the input (1 = full
        resolution); the non-local window radius and sigma_s shrink with it.
    """

    #: The terms of Eq. 2, in evaluation order (names used by ``term_energies``).
    TERM_NAMES = ("data", "temporal_albedo", "temporal_shading", "coupling", "shading_local",
                  "albedo_smooth", "albedo_sparsity")

    def __init__(self, be, log_image, w_lum, flow, occlusion, boundary, params: Params, prior,
                 n_fixed: int = 0, level_scale: float = 1.0):
        T, h, w, _ = log_image.shape
        self.be, self.params, self.prior = be, params, prior
        self.shape = (T, h, w)
        self.n_fixed = n_fixed
        self.level_scale = level_scale
        self.I, self.w_lum = log_image, w_lum
        self.flow, self.occlusion, self.boundary = flow, occlusion, boundary
        n = T * h * w
        self.n = n
        self.X = be.zeros((4 * n,))
        self.G = be.zeros((4 * n,))
        self.A, self.S = self.X[: 3 * n].reshape((T, h, w, 3)), self.X[3 * n:].reshape((T, h, w))
        self.gA, self.gS = self.G[: 3 * n].reshape((T, h, w, 3)), self.G[3 * n:].reshape((T, h, w))
        self.S_tilde = be.empty((T, h, w))
        self._surface_centres = None        # (T-1, h, w, 4): the S~ median's flow clusters, found once
        self.gate = self._local_shading_gate()
        self.stable_pairs = self._stable_pairs()
        if self.stable_pairs is not None and self.gate is None:
            self.gate = be.empty((T, h, w))          # the paired kernel is the gated one with pairs added
            be.vecops.fill(self.gate.reshape((n,)), 1.0)
        self.workspace = Workspace()        # the kernels' scratch buffers, freed with this energy
        self._rows_shape = (T * h,)
        self._gsm = None
        if params.lam_albedo_smooth > 0:
            self._gsm = (be.asarray(prior.sigma_inv.astype(np.float32)),
                         be.asarray(prior.table_g.astype(np.float32)),
                         be.asarray(prior.table_dg.astype(np.float32)),
                         float(prior.r2_max))
        self._entropy = None
        if params.lam_albedo_sparsity > 0:
            ent = be.energy_albedo_entropy
            self._entropy = (be.asarray(prior.whiten.astype(np.float32)), float(prior.hist_lo),
                             float(prior.hist_bin_width),
                             be.asarray(entropy_blur_weights(prior.sigma_p, prior.hist_bin_width)),
                             float(prior.sigma_p),
                             ent.allocate_entropy_scratch(T, int(prior.hist_bins), device=be.device))

    @property
    def temporal(self) -> bool:
        return self.flow is not None and self.shape[0] > 1

    def _local_shading_gate(self):
        """Per-pixel weight of Eq. 9's local term, or ``None`` (weight 1 everywhere).

        The product of the cut at flow discontinuities
        (``Params.shading_cut_threshold``, :func:`ivkernels.solver.motion_maps.
        shading_cut_gate`) and the input's temporal gate
        (``Params.shading_gate_tau``, ``maps.shading_gate``), both needing the
        flow, of the step evidence (``Params.shading_step_gain``,
        :func:`ivkernels.solver.step_evidence.multiply_step_gate`: kernels of the
        ``step_evidence`` family multiply it into the gate on the backend's
        arrays), and of the light's edges (``Params.shading_light_edge_tau``,
        :func:`ivkernels.solver.step_evidence.light_edge_factor`, over at least
        three frames), each where it is on.
        """
        be, params, flow = self.be, self.params, self.flow
        T, h, w = self.shape
        gate = None
        if self.temporal and params.shading_cut_threshold > 0:
            gate = shading_cut_gate(be, flow, params.shading_cut_threshold, T)
        if self.temporal and params.shading_gate_tau > 0:
            edge_gate = be.empty((T, h, w))
            be.maps.shading_gate(self.I, flow, edge_gate, params.shading_gate_tau,
                                 tau_chroma=params.shading_gate_chroma)
            if gate is None:
                gate = edge_gate
            else:
                be.vecops.multiply(gate.reshape((T * h * w,)), edge_gate.reshape((T * h * w,)))
        if params.shading_step_gain > 0:
            if gate is None:
                gate = be.empty((T, h, w))
                be.vecops.fill(gate.reshape((T * h * w,)), 1.0)
            multiply_step_gate(be, self.I, gate, params.shading_step_gain, params.shading_step_tau,
                               params.shading_step_chroma, flow=flow if self.temporal else None,
                               stability=params.shading_step_stability,
                               static_flow=params.shading_step_static_flow,
                               share_radius=params.shading_step_share_radius, noise=params.shading_step_noise,
                               noise_cap=params.shading_step_noise_cap)
        if self.temporal and params.shading_light_edge_tau > 0 and T >= 3:
            factor = light_edge_factor(be, self.I, flow, params.shading_light_edge_tau,
                                       params.shading_light_edge_spread, params.shading_step_static_flow)
            if gate is None:
                gate = factor
            else:
                be.vecops.multiply(gate.reshape((T * h * w,)), factor.reshape((T * h * w,)))
        return gate

    def _stable_pairs(self):
        """Weights of the stable steps' pairs (``Params.shading_stable_gain``), or ``None``.

        Weiss's cue on the horizontal and vertical pairs: a step that keeps
        its contrast under every light of the window is an albedo edge, and
        the shading across it pays ``gain`` times Eq. 9's local weight more
        (:func:`ivkernels.solver.step_evidence.stable_pair_weights`).  Needs the
        flow; the window's light must change (``window_params`` sets the gain to
        0 where it finds one shading).
        """
        p = self.params
        if not (self.temporal and p.shading_stable_gain > 0 and p.lam_shading_local > 0):
            return None
        return stable_pair_weights(self.be, self.I, self.flow, p.shading_step_tau, p.shading_stable_spread,
                                   p.shading_stable_floor, p.shading_step_static_flow)

    # ------------------------------------------------------------------ terms
    def _add_terms(self, rows, terms=None) -> None:
        """Add every term's gradient into G and energy into ``rows``."""
        be, p = self.be, self.params
        T, h, w = self.shape
        want = (lambda name: True) if terms is None else (lambda name: name in terms)
        if want("data"):
            be.energy_data.data_term(self.I, self.A, self.S, self.w_lum, self.gA, self.gS, rows,
                                     lam=p.lam_data, eps=p.eps_data)
        if self.temporal:
            albedo = want("temporal_albedo") and p.lam_temporal_albedo > 0
            shading = want("temporal_shading") and p.lam_temporal_shading > 0
            if albedo and shading:          # both in one pass over the flow (Eq. 4 and 8)
                be.energy_temporal.temporal_terms(self.A, self.S, self.flow, self.occlusion, self.gA, self.gS,
                                                  rows, lam_albedo=p.lam_temporal_albedo,
                                                  lam_shading=p.lam_temporal_shading, alpha=p.tukey_alpha,
                                                  workspace=self.workspace)
            elif albedo:
                be.energy_temporal.temporal_term(self.A, self.flow, self.occlusion, self.gA, rows,
                                                 lam=p.lam_temporal_albedo, alpha=p.tukey_alpha,
                                                 workspace=self.workspace)
            elif shading:
                be.energy_temporal.temporal_term(self.S.reshape((T, h, w, 1)), self.flow,
                                                 self.occlusion, self.gS.reshape((T, h, w, 1)), rows,
                                                 lam=p.lam_temporal_shading, alpha=p.tukey_alpha,
                                                 workspace=self.workspace)
            if want("coupling") and p.lam_coupling > 0:
                be.energy_shading.coupling_term(self.S, self.S_tilde, self.boundary, self.gS, rows,
                                                lam=p.lam_coupling)
        if want("shading_local") and p.lam_shading_local > 0:
            if self.stable_pairs is not None:
                be.energy_shading.shading_smoothness_paired(self.S, self.gate, self.stable_pairs, self.gS, rows,
                                                            lam=p.lam_shading_local, pair_gain=p.shading_stable_gain,
                                                            eps=p.eps_shading)
            elif self.gate is None:
                be.energy_shading.shading_smoothness(self.S, self.gS, rows, lam=p.lam_shading_local,
                                                     eps=p.eps_shading)
            else:
                be.energy_shading.shading_smoothness_gated(self.S, self.gate, self.gS, rows,
                                                           lam=p.lam_shading_local, eps=p.eps_shading)
        if want("albedo_smooth") and self._gsm is not None:
            sigma_inv, table_g, table_dg, r2_max = self._gsm
            be.energy_albedo_gsm.gsm_smoothness(self.A, sigma_inv, table_g, table_dg, r2_max,
                                                self.gA, rows, lam=p.lam_albedo_smooth,
                                                workspace=self.workspace)
        if want("albedo_sparsity") and self._entropy is not None:
            whiten, lo, h, taps, sigma_p, scratch = self._entropy
            be.energy_albedo_entropy.entropy_term(self.A, whiten, lo, h, taps, sigma_p, scratch,
                                                  self.gA, rows, lam=p.lam_albedo_sparsity)

    def __call__(self, X, G) -> float:
        """Energy at ``X`` (must be ``self.X``); writes dE/dX into ``G`` (``self.G``)."""
        if X is not self.X or G is not self.G:
            raise ValueError("WindowEnergy evaluates its own buffers X and G only")
        return self.evaluate()

    def evaluate(self, terms=None) -> float:
        """Energy of ``terms`` (default: all) at ``self.X``; writes its gradient into ``self.G``.

        Raises :class:`FloatingPointError` naming the term whose energy is not
        finite, so a bad weight or input never ends in a silent early stop.
        """
        be = self.be
        be.vecops.fill(self.G, 0.0)
        rows = be.zeros(self._rows_shape, dtype=np.float64)
        self._add_terms(rows, terms)
        if self.n_fixed:
            k = self.n_fixed * self.n // self.shape[0]
            be.vecops.fill(self.G[: 3 * k], 0.0)
            be.vecops.fill(self.G[3 * self.n: 3 * self.n + k], 0.0)
        energy = float(be.numpy(rows).sum())
        if not np.isfinite(energy):
            bad = [name for name, e in self.term_energies().items() if not np.isfinite(e)]
            raise FloatingPointError(
                f"the energy of Eq. 2 is not finite (term(s) {', '.join(bad) or 'unknown'}); "
                "check the weights in Params and the input for NaN or infinite values")
        return energy

    def term_energies(self) -> dict[str, float]:
        """Each term's energy at the current ``X`` (diagnostics; leaves ``G`` dirty)."""
        out = {}
        for name in self.TERM_NAMES:
            rows = self.be.zeros(self._rows_shape, dtype=np.float64)
            self._add_terms(rows, terms={name})
            out[name] = float(self.be.numpy(rows).sum())
        self.be.vecops.fill(self.G, 0.0)
        return out

    # --------------------------------------------------------------- S~ step
    def update_coupling(self) -> None:
        """S~ <- 15x15 weighted median of S near motion boundaries (Eq. 9-10, 13).

        The median's split of each window into surfaces (``median.surface_centres``)
        depends on the flow alone, so it is found at the first update and kept.
        """
        be, p = self.be, self.params
        if not self.temporal:
            be.vecops.copy(self.S.reshape((self.n,)), self.S_tilde.reshape((self.n,)))
            return
        radius = max(2, int(round(p.nonlocal_radius * self.level_scale)))
        sigma_s = max(1.0, p.sigma_s * self.level_scale)
        ratio = p.lam_coupling / p.lam_shading_nonlocal if p.lam_shading_nonlocal > 0 else 0.0
        if self._surface_centres is None:
            # surf of Eq. 10 depends on the flow alone: clustered once, read at every update
            self._surface_centres = be.empty((*self.flow.shape[:3], 4))
            be.median.surface_centres(self.flow, self.boundary, self._surface_centres, radius=radius,
                                      workspace=self.workspace)
        be.median.weighted_median_shading(self.S, self.flow, self.boundary, self.S_tilde,
                                          radius=radius, sigma_s=sigma_s, lam=ratio,
                                          centres=self._surface_centres, workspace=self.workspace)


class ConstrainedEnergy:
    """Eq. 2 on the data-consistent set ``A = I - S``; the unknown is ``S`` alone.

    The data term (Eq. 3, lambda_D = 10, Charbonnier eps = 0.001) is an almost
    hard constraint: across ``A + S = I`` its curvature is about
    ``lambda_D w_lum / eps`` (10^3 to 10^4), while the priors and the temporal
    terms act *along* it (A up, S down).  Minimising over the raw ``(A, S)``
    leaves a descent method in that narrow valley, and worse, the soft
    constraint lets the albedo priors buy a lower energy by leaving the valley:
    on the training sequences (seed 12, 6 frames, 120x90), 200 L-BFGS
    iterations on the raw variables reach 5.2e6 against 8.9e6 at the truth,
    with the input's texture moved into the data residual and LMSE 0.043
    (0.035 after 40 iterations), whereas this parametrisation settles at 8.94e6,
    beside the truth's 8.99e6, with LMSE 0.022 (perf/RESULTS.md, "Solver").
    The data term here is the exact-penalty limit of Eq. 3: its energy is the
    constant ``3 lambda_D eps sum w_lum`` and its gradient zero, so it is not
    evaluated.  The valley becomes the axis ``S``: ``A = I - S`` per pixel
    (``energy_data.constrained_albedo``) and ``dE/dS = dE/dS - sum_c dE/dA_c``
    (``energy_data.constrained_gradient``).

    ``X`` and ``G`` are views of the wrapped :class:`WindowEnergy`'s ``S`` and
    ``dE/dS`` (flat, length ``T*h*w``), so the solver's unknown is the
    energy's shading buffer itself.
    """

    TERMS = tuple(name for name in WindowEnergy.TERM_NAMES if name != "data")

    def __init__(self, energy: WindowEnergy):
        self.energy = energy
        n = energy.n
        self.X = energy.X[3 * n:]
        self.G = energy.G[3 * n:]

    def sync_albedo(self) -> None:
        """``A = I - S`` from the current ``S``."""
        e = self.energy
        e.be.energy_data.constrained_albedo(e.I, e.S, e.A)

    def __call__(self, X, G) -> float:
        """Energy at ``X`` (must be ``self.X``); writes dE/dS along ``A = I - S`` into ``G``."""
        if X is not self.X or G is not self.G:
            raise ValueError("ConstrainedEnergy evaluates its own buffers X and G only")
        return self.value_and_gradient(self.G)

    def value_and_gradient(self, out) -> float:
        """Energy at ``X``; writes dE/dS along ``A = I - S`` into ``out`` (flat, ``T*h*w``:
        ``self.G``, or the buffer of a problem built on this one, which then needs no copy)."""
        e = self.energy
        self.sync_albedo()
        value = e.evaluate(self.TERMS)
        e.be.energy_data.constrained_gradient(e.gA, e.gS, out.reshape(e.shape))
        return value
