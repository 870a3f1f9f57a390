"""Parameters of the intrinsic video energy (Eq. 2) and of its optimiser.

Every weight of the paper is a default here, with the equation it belongs to.
Weights the paper does not give are marked "chosen" with the reason.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ivkernels.validation import MIN_FRAME_SIZE, Range, check_fields


@dataclass(frozen=True)
class Params:
    """Weights and settings of :func:`ivkernels.decompose`.

    Energy (log domain, Eq. 2 = data + temporal + shading prior + albedo prior)
    ---------------------------------------------------------------------------
    lam_data, eps_data, lum_eps
        Eq. 3: ``lam_data * sum rho_charb(w_lum * (I - A - S))`` with
        ``rho_charb(z) = sqrt(z^2 + eps_data^2)`` and ``w_lum = lum(i) + lum_eps``.
    lam_temporal_albedo, lam_temporal_shading, tukey_alpha
        Eq. 4, 5, 8: ``lam * sum w_occ * rho_tukey(X_{t+1}(x+u) - X_t(x))``,
        continuous Tukey saturating at 1/3 (see DESIGN notes in the kernel).
        Chosen (perf/calibrate.py, synthetic training seed 12, 6 frames at
        160x120, ground-truth flow, mean LMSE over the four kinds; the table
        is in perf/RESULTS.md, "Calibration"): the paper's lambda_TA = 10,
        alpha = 5 is a quadratic of weight lambda_TA / alpha^2 = 0.4 on log
        differences, too weak to act against the albedo prior (0.0192, the
        same as without temporal terms).  alpha = 1 with lambda_TA = 100 /
        300 / 1000 / 3000 gives 0.0180 / 0.0174 / 0.0173 / -, and with the
        shading weight below 0.0166 / 0.0160 / 0.0164 for 300 / 1000 / 3000;
        alpha = 2 is worse at every weight.  lambda_TS = 100 instead of 1
        changed nothing (0.0181 / 0.0180).
        lambda_TA chosen again for the current solver on its default path
        (estimated flow, 8 frames at 320x240; perf/RESULTS.md, "The temporal
        albedo weight again"; ``python perf/accuracy.py --seed S --no-mit
        --methods IV --iv-param lam_temporal_albedo=V``): 500 / 1000 give
        mean LMSE 0.0047 / 0.0047 on training seed 1, 0.0053 / 0.0071 on
        seed 2 and 0.0042 / 0.0046 on seed 12, no kind worse by more than
        0.0002, and MIT mean albedo LMSE 0.0306 / 0.0320 (``--kinds --mit
        --methods IV``); 300 gains as much on the moving cameras but gives
        up the static scene under a moving light (seed 1: 0.0054 against
        0.0045), and 3000 is worse on every kind of seeds 1 and 12 with the
        ground-truth flow (``python perf/calibrate.py --seeds 1 12 --frames
        8 --size 240 320 --no-ablation --grid lam_temporal_albedo=300,3000``).
    sigma_e, sigma_d, occlusion_threshold
        Eq. 6-7: occlusion from Lab difference (sigma_e, Lab units) and the
        negative part of the flow divergence (sigma_d, pixels / pixel).
    occlusion_colour
        Whether Eq. 7's colour term (sigma_e) is used.  Off by default: it
        assumes the colour of a surface point stays the same from frame to
        frame, and where the light changes it marks the pixels whose
        shading changes most as occluded, which switches the temporal terms
        off exactly where they carry the most (7-28% of each MIT object at
        its exact zero flow).  The divergence term, the image border and
        ``warp_spread_max`` still mark occlusions.  Measured with the
        estimated flow of the default path (perf/RESULTS.md, "Eq. 7's
        colour term under a changing light"; ``python perf/accuracy.py
        --seed 1 --no-mit --methods IV GT --iv-param sigma_e=1000``, which
        makes the term 1 everywhere): training seed 1 mean LMSE 0.0053
        against 0.0057 with it, every kind better; MIT mean albedo LMSE
        (``--kinds --methods IV``) 0.0388 against 0.0475.
    warp_spread_max
        The temporal terms are also switched off (w_occ = 0) where the
        bilinear sample ``X_{t+1}(x + u)`` straddles an image edge: where the
        four corners of the sample in the log input differ from the
        interpolated value by ``warp_spread_max`` or more on average
        (``maps.warp_reliability``).  There even the true albedo differs from
        its warp (about 10% of the visible pixels of moving training scenes
        by more than 0.3), so a strong temporal weight would push the
        input's texture into the shading.  Chosen: 0.05 keeps about 80% of the
        visible pixels of moving scenes (all of a static one); with it the
        strong temporal weights below stop hurting moving scenes (seed 12,
        6 frames, 160x120, lambda_TA = 1000, alpha = 1: free_camera LMSE 0.0189
        -> 0.0156, objects_camera 0.0158 -> 0.0144).
    chroma_change_max
        The temporal terms are also switched off where the input's log
        chromaticity ``log I_c - mean_c log I`` changes along the flow by
        ``chroma_change_max`` or more in some channel
        (``maps.chroma_consistency``; 0 switches the test off).  The shading
        is grey, so a change of light scales the channels of a pixel alike
        and leaves its chromaticity to the albedo: where the albedo is
        constant along the flow, so is the input's chromaticity.  Where it is
        not, the flow joins two different surfaces (it is wrong there, or
        the point is hidden in the next frame), and Eq. 4 would pull two
        different albedos together.  Eq. 7's colour term (``sigma_e``) tests
        Lab colour, brightness included, and so marks every pixel whose
        light changes; this test does not.  It matters most where the flow
        follows a moving shadow along a stripe.  Chosen on the training
        seeds (perf/RESULTS.md, "The input's chromaticity along the flow"):
        0.3.  On the default path (estimated flow) over the thirteen
        training seeds 1-13 the mean LMSE falls from 0.0065 to 0.0060 on
        average (better on nine seeds, worse on three, by at most 0.0005);
        the static scene under a moving light of seed 10, whose flow follows
        the moving shadows along the floor's stripes, from 0.0105 to 0.0038,
        and seed 2's free_camera from 0.0043 to 0.0019.  With the
        ground-truth flow it removes the pixels that a moving object covers
        (the divergence test cannot see them): 0.0061 to 0.0059 on average.
        The MIT objects (zero true flow) lose a little: mean albedo LMSE
        0.0306 to 0.0313 (0.0310 at 0.6).
        On the sequences measured first (seeds 1, 2 and 10), values from 0.05
        to 0.6 agree to within 0.0003, except seed 1's objects_camera
        (0.0060-0.0067), and 1.0 loses seed 2's free_camera gain (0.0040);
        0.3, the middle of that flat range, was fixed before the
        thirteen-seed run.  ``python perf/seed_spread.py
        --iv-param chroma_change_max=0`` gives the previous behaviour.
    boundary_threshold, boundary_radius
        w_bnd (Sec. 3.3): Sobel magnitude of the flow (pixels / pixel, Sobel
        normalised by 1/8) above ``boundary_threshold``, dilated by a square of
        radius ``boundary_radius``.  Chosen: 0.25 marks flow jumps of about half
        a pixel or more (a step of d pixels gives a magnitude of about d/2),
        the smallest jump a flow method resolves reliably; radius 3 covers the
        half-width of the 7-pixel smoothing a flow estimator puts on a motion
        edge, so the true surface boundary lies inside the band.
    lam_shading_local, eps_shading
        Eq. 9 local term: Charbonnier over the 3x3 neighbourhood.  Chosen
        with lambda_TA = 1000, alpha = 1 (same sequences): lambda_Ss /
        lambda_As = 2 / 1, 5 / 1, 10 / 1, 20 / 2 give 0.0173 / 0.0165 /
        0.0160 / 0.0161; 5 / 0.3 and 10 / 0.3 give 0.0168 / 0.0194.  The
        ablation without temporal terms is best at 2 / 0.3 (0.0189) and gets
        0.0193 at 10 / 1: its best is 15% worse than intrinsic video here.
    shading_cut_threshold
        Eq. 9's local term is cut where the flow jumps: a pixel whose flow
        Sobel magnitude (pixels per pixel, as ``boundary_threshold``; a step
        of d pixels gives about d/2) exceeds this in a frame pair that
        includes its frame gets no local pair terms of its own
        (:func:`ivkernels.solver.motion_maps.shading_cut_gate`, through the
        gated local term).  The paper applies the local term everywhere and
        stops only its non-local term at motion boundaries, yet a motion
        boundary is where one surface ends and the shading jumps (Sec. 3.3).
        Needs the flow; 0 switches it off.  Chosen on training seeds 1 and 2
        (perf/RESULTS.md, "Eq. 9's local term cut at flow discontinuities";
        ``python perf/accuracy.py --seed S --no-mit --methods IV IV-gtflow
        --iv-param shading_cut_threshold=V``): mean LMSE IV / IV-gtflow off
        0.0052 / 0.0053 (seed 1) and 0.0048 / 0.0046 (seed 2), at 0.25
        0.0053 / 0.0045 and 0.0048 / 0.0045, at 0.5 0.0051 / 0.0047 and
        0.0046 / 0.0044.  Over the thirteen training seeds
        (``perf/seed_spread.py``) mean LMSE IV 0.0060 -> 0.0059 and
        IV-gtflow 0.0059 -> 0.0050.  The gain is largest with an accurate
        flow; an estimated flow's own flow edges cost part of it.
    shading_gate_tau
        A per-pixel gate on the pair terms of Eq. 9's local term, computed
        from the input (``maps.shading_gate``): pair weight ``(g(x) + g(y)) /
        2`` with ``g = exp(-(e / tau)^2)``, ``e`` the largest change, along
        the flow from one frame to the next, of the input's log difference
        to a neighbour (Weiss: an albedo edge keeps its contrast while the
        light or the scene moves, a shading edge does not).  Needs the flow:
        without temporal terms it is not computed.  0 switches it off
        (with ``shading_cut_threshold`` 0 as well, the plain
        ``energy_shading.shading_smoothness``, bit for bit).  Off by
        default: measured (perf/RESULTS.md, "An edge-aware local shading
        term"; ``python perf/calibrate.py --seeds 12 13 --frames 6 --size
        120 160 --no-ablation --grid lam_shading_local=30
        shading_gate_tau=0.05,0.1,0.2`` and ``--kinds --mit --mit-objects
        squirrel teabag2 dinosaur apple phone``), with lambda_Ss = 30 it
        lowers the synthetic training LMSE from 0.0169 (lambda_Ss = 10, no
        gate) to 0.0144 / 0.0160 / 0.0220 at tau = 0.05 / 0.1 / 0.2, but on
        the MIT objects, lit from ten very different directions, the input's
        contrast changes between frames nearly everywhere on the object
        (the gate closes on 60-90% of it at tau = 0.1), so the term loses
        the stronger smoothness those objects need: mean albedo LMSE of
        those five objects 0.0836 / 0.0631 at tau = 0.1 / 0.2 against 0.0406
        without the gate at lambda_Ss = 30 and 0.0694 at 10.
        With the current defaults it is worse on the synthetic sequences
        too (perf/RESULTS.md, "The edge-aware local shading term with the
        current defaults"): training seed 1 mean LMSE 0.0062 against
        0.0047 (only the static kind gains, 0.0022 against 0.0043).
    shading_gate_chroma
        With the gate on and this > 0, a contrast change where the
        input's log chromaticity changes by about this much or more is not
        taken for a shading edge (evidence times ``exp(-(c / tau_c)^2)``).
        0 (default): colour is not used.  Measured with lambda_Ss = 30,
        tau = 0.05 (same section): it brings the MIT objects back near the
        ungated lambda_Ss = 30 (teabag2 / dinosaur / squirrel 0.0229 /
        0.0290 / 0.1060 at tau_c = 0.05) but loses the synthetic gain,
        whose textures change colour everywhere (seed 12: 0.0283 / 0.0259 /
        0.0208 at tau_c = 0.05 / 0.2 / 0.5 against 0.0138 without a gate).
    lam_shading_nonlocal, lam_coupling, sigma_s, nonlocal_radius
        Eq. 9-10, 13: 15x15 (radius 7) weighted L1 near motion boundaries,
        minimised through the coupling variable S~.
    lam_albedo_smooth
        Eq. 11 first term (GSM over 5x5 differences), chosen with
        lambda_Ss as above.  The fitted GSM is log-like (g = 2.9, 6.9, 13.5,
        33 at r2 = 0.001, 0.01, 0.36, 16): it prices any albedo change, so
        the balance with lambda_Ss decides which edges are albedo.
    lam_albedo_sparsity
        Eq. 12 global sparsity (quadratic entropy).  Off by default: on the
        same sequences 10 and 100 changed mean LMSE by +0.3% and -0.6% while
        making each solve 3-4x slower (histogram splat, 3-D blur and slice per
        evaluation).  Set it > 0 to use the term.
    independent_shading_gain
        With temporal terms, both albedo priors (Eq. 11, 12) of a window are
        divided by its number of independent shadings ``n = 1 + gain * (T -
        1) * r`` (:mod:`ivkernels.solver.independent_shadings`): the window
        holds one albedo, tied over its frames by Eq. 4, but up to ``T``
        shadings when the light changes between frames, and Eq. 2's sum
        over frames counts the albedo prior ``T`` times.  ``r`` in [0, 1) is
        the share of the change of the log shading between consecutive
        frames, read off the blurred input along the flow, above the change
        that flow error and a slowly moving lamp give
        (``SHADING_CHANGE_FLOOR`` = 0.025): 0 under one lamp, 0.5-0.9 for
        an object under ten lights.  0 switches the count off (every
        frame's prior counts, as in the paper).  Chosen on training data
        (perf/RESULTS.md, "The count against a fixed floor"; ``python
        perf/accuracy.py --kinds --methods IV --iv-param
        independent_shading_gain=...``, ``perf/calibrate.py --kinds --mit
        --no-ablation --grid independent_shading_gain=...`` and ``--seeds 12
        13 --frames 6 --size 120 160``): gain 1 / 1.5 gives MIT mean albedo
        LMSE 0.0339 / 0.0362 on the default path (the flow estimated) and
        0.0272 / 0.0261 with the exact zero flow (the earlier count, a ratio
        to the frame's own spread, at its gain 3: 0.0388 and 0.0337); the
        synthetic training sequences stay at the 0.0106 of gain 0 (no pair
        there changes by more than the floor; the earlier count: 0.0113).
        The default path decides: 1.  Measured before the blur: a floor of
        0.0125 raises the synthetic mean to 0.0113 (free_camera/13 loses a
        third), one of 0.05 gives the MIT objects 0.0294 at gain 1.

    Optimiser (Sec. 4)
    ------------------
    pyramid_scale, pyramid_min_size
        Coarse to fine: each level is ``pyramid_scale`` times the next finer
        one; the coarsest level's shorter side is at least ``pyramid_min_size``.
    outer_iterations
        Alternations per level of (a) minimising over (A, S) with S~ fixed and
        (b) the S~ weighted-median update.
    lbfgs_iterations
        L-BFGS iterations per alternation at the finest (full-resolution)
        level.  40: on the hardest training sequences (seed 1, 8 frames at
        320x240, the default path with its estimated flow) they reach 99.01
        / 99.15% of the drop from the start energy to a 300-iteration
        reference (rotating_shadows / objects_camera) against 98.31 / 98.88%
        at 35, and no kind of training seeds 1 and 2 is less accurate (mean
        LMSE 0.0047 / 0.0071 against 0.0049 / 0.0071).  With the coarse
        basis's run-by-run transfers 40 iterations cost what 35 did before
        (640x480, 8 frames: 102.8 s against 99.7-102.3 s; perf/RESULTS.md,
        "Forty iterations at the cost of 35").  On seed 12 with the
        ground-truth flow 35 already reached 99.37 / 99.20% (static_moving_light
        / free_camera; "Solver: converging at the default budget").
    lbfgs_memory
        Correction pairs kept by L-BFGS.  Chosen: on synthetic sequences with
        seed 12 (8 frames, ground-truth flow) 4 and 6 pairs give the same mean
        LMSE (0.0277 at 160x120, 0.0193 at 320x240) and 3 a little worse
        (0.0279 at 160x120); each pair costs two more rows in the direction's
        passes over memory.
    lbfgs_iterations_coarse, lbfgs_level_growth
        L-BFGS iterations per alternation at pyramid level ``l >= 1``:
        ``min(lbfgs_iterations_coarse, round(lbfgs_iterations *
        lbfgs_level_growth ** l))``.  A level costs a quarter of the finer
        one per iteration.  Growth 1 (every level gets the finest budget):
        with the coarse basis the finest level's energy does not improve
        with longer coarse solves (training seed 12, 6 frames at 160x120,
        ground-truth flow, 35 at the finest level: static_moving_light /
        free_camera reach 99.36 / 99.34% of the drop to the reference with
        growth 1, 99.31 / 99.31% with 1.5, 99.29 / 99.14% with 2; at 25,
        growth 3 and 4 gain nothing over 2), and growth 1 is the cheapest.
    coarse_basis_spacing, coarse_basis_sigma
        L-BFGS minimises over ``S = s + P z``: the shading plus a coarse field
        ``z`` on nodes every ``coarse_basis_spacing`` pixels, interpolated
        with weights that fall off as ``exp(-|A(x) - A(node)|^2 / sigma^2)``
        across the log albedo (:mod:`ivkernels.solver.coarse_basis`), on
        every level whose shorter side holds four node spacings; 0 switches
        it off.  It moves whole albedo regions, the direction plain L-BFGS
        is slowest along.  Chosen by the energy reached with the default
        budget on training seeds 12 and 13 (6 frames at 160x120,
        ground-truth flow; perf/RESULTS.md, "Solver: the edge-aware coarse
        basis"): spacing 4 and sigma 0.5 give the lowest energy summed over
        the four kinds (sigma 1.0 within 0.01%, 0.2 and spacing 8 higher).
    coarse_basis_levels
        Coarse fields in the basis: level ``k`` has nodes every
        ``coarse_basis_spacing * 3^k`` pixels and enters ``S`` scaled by
        ``3^-k`` (a node's field covers 9 times more pixels than one of the
        level below, so unscaled the coarser fields would be far stiffer
        than the finer ones for L-BFGS's one scalar scaling); a level is
        used where the shorter side holds four of its node spacings.
        Chosen by the energy reached with the default budget on training
        seeds 1 and 12 (8 frames at 320x240, ground-truth flow;
        perf/RESULTS.md, "Solver: a second, scaled coarse level"): two
        levels end lower than one on seven of the eight sequences (the
        eighth 0.002% higher) and lower than three; the error falls with
        the energy (seed 1: 10-15% per kind).
    init_blur
        Coarsest-level start: S = log luminance blurred with a Gaussian whose
        sigma is ``init_blur`` times the shorter side; A = I - S.  Chosen on
        synthetic sequences with seed 12 at 320x240 (mean LMSE relative to
        colour Retinex, start only: 0.75 / 0.81 / 0.94 / 1.10 / 1.20 for
        0.01 / 0.02 / 0.04 / 0.07 / 0.1; after the solve at 0.02: 0.78).
    log_floor
        Floor of the linear input before the log (avoids log 0 on black pixels).

    Flow and intrinsic video together
    ---------------------------------
    flow_guide_scale
        With ``flow_passes`` > 1 (:func:`ivkernels.decompose`), each pass
        before the last solves the window at this fraction of its size; its
        shading, up-sampled, divides the input into the albedo the next
        flow is estimated on (:func:`ivkernels.solver.guide.guide_albedo`).
        Chosen on training seed 1 (8 frames at 320x240, perf/RESULTS.md,
        "Flow and intrinsic video together, per window"): at 0.5 the second
        pass keeps most of what a full-size first pass gives (flow EPE on
        the four kinds 1.087 / 1.305 / 0.054 / 0.186 against 1.085 / 1.249 /
        0.001 / 0.170, from 1.173 / 1.295 / 0.168 / 0.527 with one pass) for
        a quarter of its cost.
    guide_lbfgs_iterations
        L-BFGS iterations per alternation at every level of the guide solve,
        capped by ``lbfgs_iterations``.  The guide only feeds the next flow
        pass and the last solve's start, and a short guide serves both as
        well as a converged one, or better.  Measured with
        ``perf/eval_flow_passes.py --passes 2`` (8 frames at 320x240;
        perf/RESULTS.md, "A shorter guide solve"): mean LMSE on training seed 1 0.0060 / 0.0058 / 0.0061 /
        0.0063 with 8 / 15 / 25 / 35 iterations, on seed 2 0.0055 with both
        15 and 35; flow EPE within 0.04 px; the guide takes half the time
        at 15.
    start_from_guide
        With ``flow_passes`` > 1, or with a given flow (one guide solve with
        it), the window's last solve starts from the
        last guide's log shading at the guide's pyramid level
        (:func:`ivkernels.solver.window_solver.start_level_for`) instead of
        from blurred luminance at the coarsest level: the levels below the
        guide's size, which the guide already solved, are skipped.  Chosen
        on training seed 1 (8 frames at 320x240, estimated flow, two passes;
        perf/RESULTS.md, "The last solve started from the flow guide"):
        LMSE 0.0060 / 0.0102 / 0.0103 / 0.0136 on the four kinds against
        0.0061 / 0.0108 / 0.0113 / 0.0140 from the coarsest level, for 9%
        less CPU time per decomposition.  Starting at the finest level
        instead (the guide's shading up-sampled) saves more time but raised
        the error on every kind (mean 0.0126).  With the ground-truth flow
        given (perf/RESULTS.md, "A guide solve for a given flow"), mean LMSE
        0.0059 against 0.0066 on training seed 1 and 0.0053 against 0.0056
        on seed 2, lower on all eight sequences.
    first_flow_at_guide_size
        With ``flow_passes`` > 1 and an estimated flow, the first pass's
        flow only feeds the guide solve, which works at the guide's size
        (``flow_guide_scale``): it is estimated on the frames resized to that
        size and its vectors up-sampled, instead of at full size.  Chosen on
        training seed 1 (8 frames at 320x240, perf/RESULTS.md, "The first
        flow at the guide's size"): LMSE 0.0060 / 0.0099 / 0.0105 / 0.0135
        on the four kinds against 0.0060 / 0.0102 / 0.0103 / 0.0136 at full
        size, for 17% less CPU time per decomposition (a third less in the
        flow); the last pass's flow EPE rises by 3-5% on the moving kinds
        (1.143 / 1.343 against 1.087 / 1.305 px).
    flow_refine_warps
        With ``flow_passes`` > 1 and a Classic+NL flow, the warping steps per
        pyramid level of the passes after the first, which start from the
        previous pass's flow (the first pass keeps the method's own: 3 for
        ``classic_nl_fast``).  Chosen on training seed 1 (8 frames at
        320x240, perf/RESULTS.md, "Fewer warps in the second flow pass"): at
        2, flow EPE 1.118 / 1.348 / 0.061 / 0.195 px and LMSE 0.0059 /
        0.0100 / 0.0105 / 0.0137 on the four kinds against 1.143 / 1.343 /
        0.061 / 0.189 and 0.0060 / 0.0099 / 0.0105 / 0.0135 at 3, for 6% less
        CPU time (a fifth less in the flow); one warp per level of the
        robust stage only (``gnc_levels`` 1) raised the EPE on every kind.

    Long videos
    -----------
    window, overlap
        Frames per solved window and frames shared with the previous window;
        the shared frames keep the previous window's albedo and shading fixed,
        which carries albedo forward and bounds memory by the window.
    """

    # Eq. 3
    lam_data: float = 10.0
    eps_data: float = 0.001
    lum_eps: float = 0.001
    # Eq. 4, 5, 8
    lam_temporal_albedo: float = 500.0
    lam_temporal_shading: float = 1.0
    tukey_alpha: float = 1.0
    # Eq. 6-7
    sigma_e: float = 20.0
    occlusion_colour: bool = False
    sigma_d: float = 0.3
    occlusion_threshold: float = 0.5
    warp_spread_max: float = 0.05
    chroma_change_max: float = 0.3
    # w_bnd
    boundary_threshold: float = 0.25
    boundary_radius: int = 3
    # Eq. 9, 10, 13
    lam_shading_local: float = 10.0
    eps_shading: float = 0.001
    shading_cut_threshold: float = 0.5
    shading_gate_tau: float = 0.0
    shading_gate_chroma: float = 0.0
    lam_shading_nonlocal: float = 10000.0
    lam_coupling: float = 10.0
    sigma_s: float = 7.0
    nonlocal_radius: int = 7
    # Eq. 11, 12
    lam_albedo_smooth: float = 1.0
    lam_albedo_sparsity: float = 0.0
    independent_shading_gain: float = 1.0
    # optimiser
    pyramid_scale: float = 0.5
    pyramid_min_size: int = 24
    outer_iterations: int = 2
    lbfgs_iterations: int = 40
    lbfgs_iterations_coarse: int = 200
    lbfgs_level_growth: float = 1.0
    lbfgs_memory: int = 4
    coarse_basis_spacing: int = 4
    coarse_basis_levels: int = 2
    coarse_basis_sigma: float = 0.5
    init_blur: float = 0.02
    log_floor: float = 1e-4
    # flow and intrinsic video together
    flow_guide_scale: float = 0.5
    guide_lbfgs_iterations: int = 15
    start_from_guide: bool = True
    first_flow_at_guide_size: bool = True
    flow_refine_warps: int = 2
    # long videos
    window: int = 8
    overlap: int = 2

    def __post_init__(self):
        # Every field against its rule in _RULES (a new int / float field without a
        # rule must be finite and >= 0), then the rules that tie fields together.
        check_fields(self, _RULES, "Params")
        if not self.overlap < self.window:
            raise ValueError(
                f"Params.overlap must satisfy 0 <= overlap < window ({self.window}), got {self.overlap}")

    def replace(self, **changes) -> "Params":
        """A copy with some fields changed (``dataclasses.replace``), validated."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise TypeError(f"unknown parameter(s) {sorted(unknown)}; see help(ivkernels.Params)")
        return dataclasses.replace(self, **changes)


#: Valid values of the fields of :class:`Params`, checked by ``Params.__post_init__``
#: (fields not named here: finite and >= 0, integers for ``int`` fields).
_RULES = {
    "eps_data": Range(float, 0.0, low_open=True, why="the Charbonnier of Eq. 3 needs eps > 0"),
    "eps_shading": Range(float, 0.0, low_open=True, why="the Charbonnier of Eq. 9 needs eps > 0"),
    "tukey_alpha": Range(float, 0.0, low_open=True),
    "sigma_e": Range(float, 0.0, low_open=True),
    "sigma_d": Range(float, 0.0, low_open=True),
    "sigma_s": Range(float, 0.0, low_open=True),
    "occlusion_threshold": Range(float, 0.0, 1.0, why="w_occ lies in [0, 1]"),
    "warp_spread_max": Range(float, 0.0, low_open=True, why="a spread in log units"),
    "chroma_change_max": Range(float, 0.0, why="a change of log chromaticity; 0 switches the test off"),
    "boundary_radius": Range(int, 0, 32, why="the dilation costs radius^2 per pixel"),
    "nonlocal_radius": Range(int, 1, 32, why="the weighted median costs radius^2 per pixel"),
    "pyramid_scale": Range(float, 0.0, 0.9, low_open=True,
                           why="each level is this times the finer one; closer to 1 gives "
                               "hundreds of levels"),
    "pyramid_min_size": Range(int, MIN_FRAME_SIZE, why="the coarsest level's shorter side"),
    "outer_iterations": Range(int, 1),
    "lbfgs_iterations": Range(int, 1),
    "lbfgs_iterations_coarse": Range(int, 0),
    "lbfgs_level_growth": Range(float, 1.0, 16.0, why="each coarser level's budget is this times the finer one's"),
    "lbfgs_memory": Range(int, 1),
    "coarse_basis_spacing": Range(int, 0, 64, why="pixels between the coarse basis' nodes; 0 switches it off"),
    "coarse_basis_levels": Range(int, 1, 8, why="coarse fields, each 3 times coarser than the last"),
    "coarse_basis_sigma": Range(float, 0.0, low_open=True, why="an albedo distance in log units"),
    "log_floor": Range(float, 0.0, 1.0, low_open=True, high_open=True,
                       why="the floor of the linear input before the log"),
    "flow_guide_scale": Range(float, 0.0, 1.0, low_open=True,
                              why="the size of the guide solve relative to the frames"),
    "flow_refine_warps": Range(int, 1, why="warping steps per pyramid level"),
    "guide_lbfgs_iterations": Range(int, 1),
    "window": Range(int, 2, why="frames per solved window"),
    "overlap": Range(int, 0),
    "boundary_threshold": Range(float, 0.0),
    "init_blur": Range(float, 0.0),
    "shading_cut_threshold": Range(float, 0.0, why="a flow Sobel magnitude in pixels per pixel; "
                                                   "0 switches the cut off"),
    "shading_gate_tau": Range(float, 0.0, why="a log-contrast change; 0 switches the gate off"),
    "shading_gate_chroma": Range(float, 0.0, why="a log-chromaticity change; 0: the gate ignores colour"),
}
