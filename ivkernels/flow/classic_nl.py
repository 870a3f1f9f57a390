"""Classic+NL optical flow on the backend's kernels (host side).

Sun, Roth & Black, "A quantitative analysis of current practices in optical
flow estimation and the principles behind them", IJCV 106(2), 2014: the flow
the intrinsic-video paper pre-computes (Kong et al. 2014, Sec. 3).  This
module only schedules kernels; every per-pixel operation runs in a kernel
family of the backend (``flow_classic`` for the parts specific to this
method, ``sampling``, ``derivatives``, ``maps``, ``pyramid``, ``median`` and
``colour`` for the shared ones).

Pipeline, following the public Classic+NL code (settings in
:class:`ClassicNLSettings`):

1. Input: linear RGB frames.  The flow is computed on the 8-bit-style grey
   level (``rgb2gray`` of the sRGB-encoded image, [0, 255]); the weighted
   median uses CIE Lab with each channel rescaled to [0, 255].
2. ROF structure-texture decomposition: grey scaled to [-1, 1], structure
   by ``rof_iters`` steps of Chambolle's projection (theta = 1/8),
   texture = image - 0.95 structure, rescaled to [0, 255].
3. Graduated non-convexity: stage 1 on a pyramid of spacing 2 (as many
   levels as keep the coarsest image about 16 pixels on its long side and
   at least 6 on its short side), purely quadratic penalties; later stages
   on a 2-level pyramid of spacing 1.25, the quadratic weight falling
   linearly to 0 (3 stages: 1, 0.5, 0).  Each level is blurred with
   ``sigma = sqrt(spacing) / sqrt(2)`` before resampling.
4. Per level, ``warps`` times: bicubic warp of the second frame and its
   derivatives; IRLS weights of the generalised Charbonnier (a = 0.45,
   eps = 1e-3) on the linearised data term and on first-order differences
   of the flow; the 2x2-per-pixel linear system solved by red-black SOR;
   the increment clipped to [-1, 1] pixel and added; then the 5x5 median of
   the flow, replaced by the 15x15 weighted median (weights: spatial
   distance, Lab similarity, soft occlusion) in a 5x5 dilation of the
   flow's Sobel edges.

Differences from the public code, each measured with ``perf/eval_flow.py``
on the 8 Middlebury training pairs:

* Each linear system is solved by a fixed number of red-black SOR sweeps
  from a zero increment (15 in the quadratic stage, 60 in the robust ones)
  instead of a sparse direct solve; 300 sweeps change no EPE by more than
  0.001 on Dimetrodon.
* Bicubic warping uses Keys' kernel on the image and on its 5-point
  derivative images (the public code differentiates a Hermite patch).
* The fast setting skips the weighted median at the finest level of the
  quadratic stage (see ``quadratic_wm_finest``).

Measured (warp backend, 2 threads): the public fast setting mean EPE
0.243 px (7.4 CPU s per pair), ``classic_nl`` 0.241 px (61 CPU s; its 10
warps per level converge to a solution that is better on Urban3 and worse
on Dimetrodon, where the fast setting stops earlier), DIS 0.61, Farneback
1.21.

Changing light.  Brightness constancy of the ROF texture image follows moving
shadows and shading: on the synthetic sequences (``perf/eval_flow_synthetic.py``)
it reports 2.2-3.8 px of motion on a static scene under a moving light.  The
data term of ``classic_nl_fast`` is therefore the constancy of the texture
image's x and y derivatives alone (``data_term="gradient"``,
``brightness_weight=0``), which a smooth change of shading barely moves, with
a stronger smoothness weight (lambda = 10) that grows 1.5x per coarser level
of the quadratic GNC stage (``lam_coarse_factor``), where flows that follow
shadows start.  Chosen on the training seed 1; at seed 0 (8 frames,
320x240) mean EPE falls from 4.57 to 2.31 px on ``free_camera``, 2.24 to
0.78 on ``static_moving_light``, 2.07 to 1.71 on ``objects_camera``
(0.80 -> 0.84 on ``rotating_shadows``), and Middlebury's mean goes from
0.243 to 0.242 px.  Census (``data_term="census"``) and a log-grey input
(``log_input``) measured worse.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ivkernels.kernels.workspace import Workspace
from ivkernels.solver.pyramid import coarse_to_fine

#: Data terms of :class:`ClassicNLSettings` (``data_term``).
DATA_TERMS = ("brightness", "gradient", "census")


@dataclass(frozen=True)
class ClassicNLSettings:
    """Parameters of Classic+NL (defaults: the public code's ``classic+nl``).

    Energy
        ``lam`` smoothness weight (lambda = 3); ``lam_quadratic`` the
        smoothness weight of the purely quadratic first GNC stage (0 = ``lam``),
        multiplied by ``lam_coarse_factor ** k`` at its ``k``-th coarser level; ``a``, ``eps`` generalised
        Charbonnier ``(z^2 + eps^2)^a`` on data and smoothness;
        ``quad_sigma`` scale of the quadratic ``z^2 / sigma^2`` of the GNC
        blend (the public code reuses eps = 1e-3, so mixed stages are
        dominated by the quadratic); ``blend`` weight of the warped
        second-image derivatives in ``Ix, Iy`` (0.5 averages both frames).
    Schedule
        ``gnc_stages`` GNC stages; ``warps`` warping steps per level;
        ``spacing`` pyramid spacing of stage 1 and ``gnc_spacing``,
        ``gnc_levels`` of the later stages; ``max_levels`` caps stage 1's
        automatic level count (0 = no cap); ``gnc_start``: the GNC stage a
        run with an initial flow starts at (0 = all of them; 1 skips the
        quadratic stage and its deep pyramid, for a flow that refines a
        good one: the later passes of :func:`ivkernels.decompose`).  A run
        without an initial flow always starts at stage 0.
    Input
        ``rof_iters``, ``rof_theta``, ``texture_alpha``: ROF texture input
        (``texture_alpha = 0`` keeps the plain grey image); ``log_input``:
        start from the log of the linear grey level instead of the sRGB
        grey (shading becomes additive, and the ROF structure removes it
        where it is smooth).
    Solver
        ``sor_sweeps`` red-black sweeps per linear system of the robust
        GNC stages and ``sor_sweeps_quadratic`` in the quadratic first
        stage (0 = ``sor_sweeps``): the quadratic systems are dominated by
        the data term and converge in a few sweeps, the robust ones have
        weights spanning three decades and need more (Urban3: EPE 0.558 at
        30 sweeps, 0.530 at 100); ``sor_omega`` over-relaxation;
        ``limit_update`` clips each increment (pixels).
    Non-local term
        ``median``: apply the 5x5 median and the weighted median;
        ``quadratic_wm_finest``: take the weighted median at the finest
        level of the purely quadratic first GNC stage too (the public code
        does; there the quadratic flow is noisy, its edges cover ~40 % of
        the image and this one level costs a third of the run; the later
        GNC stages redo the weighted median at full resolution, so the fast
        setting skips it: EPE 0.2424 -> 0.2428 on Middlebury, see
        ``perf/eval_flow.py``); ``wm_last_warp``: take the weighted median
        after the last warping step of each level only (the 5x5 median after
        every step);
        ``lab_of_encoded``: compute the Lab image from the sRGB-encoded
        values taken as linear, as the public code's ``RGB2Lab`` does on
        the 8-bit image (it improves the weighted median slightly);
        ``wm_radius`` (7 = 15x15), ``sigma_x`` (pixels), ``sigma_i``
        (Lab units scaled to [0, 255], averaged over channels);
        ``occ_sigma_i`` (texture grey levels) and ``occ_sigma_d``
        (divergence) of the soft occlusion weight; ``edge_scale``: a pixel
        is an edge of u (or v) where its squared Sobel magnitude exceeds
        ``edge_scale`` times the frame's mean and is a local maximum across
        the edge (MATLAB's ``edge(u, 'sobel')``), and its Sobel magnitude
        is at least ``edge_min`` (pixels per pixel; 0 = no floor);
        ``edge_radius`` dilation of the edges (2 = 5x5).
    Data term
        ``data_term``: ``"brightness"`` (Classic+NL's brightness constancy
        of the texture image), ``"gradient"`` (brightness with weight
        ``brightness_weight`` plus constancy of the texture image's x and y
        derivatives with weight ``gradient_weight``, Brox et al. 2004) or
        ``"census"`` (constancy of the soft census transform of the texture
        image: ``census_scale * d / sqrt(d^2 + census_eps^2)`` for each
        difference ``d`` to a neighbour in a ``2 census_radius + 1`` square,
        grey levels of the [0, 255] texture image).  Every channel has its
        own generalised Charbonnier penalty.  ``data_outside``: keep the
        data term where ``x + u`` leaves the image, comparing with the
        replicated border (Classic+NL drops it there, so that in weakly
        textured regions near the border nothing stops the flow from
        running out of the image).
    """

    lam: float = 3.0
    lam_quadratic: float = 0.0
    lam_coarse_factor: float = 1.0
    a: float = 0.45
    eps: float = 1e-3
    quad_sigma: float = 1e-3
    blend: float = 0.5
    gnc_stages: int = 3
    warps: int = 10
    spacing: float = 2.0
    gnc_spacing: float = 1.25
    gnc_levels: int = 2
    max_levels: int = 0
    gnc_start: int = 0
    rof_iters: int = 100
    rof_theta: float = 0.125
    texture_alpha: float = 0.95
    sor_sweeps: int = 60
    sor_sweeps_quadratic: int = 15
    sor_omega: float = 1.9
    limit_update: float = 1.0
    median: bool = True
    quadratic_wm_finest: bool = True
    wm_last_warp: bool = False
    wm_radius: int = 7
    lab_of_encoded: bool = True
    sigma_x: float = 7.0
    sigma_i: float = 7.0
    occ_sigma_i: float = 20.0
    occ_sigma_d: float = 0.3
    edge_scale: float = 4.0
    edge_min: float = 0.0
    edge_radius: int = 2
    log_input: bool = False
    data_outside: bool = False
    data_term: str = "brightness"
    brightness_weight: float = 1.0
    gradient_weight: float = 1.0
    census_radius: int = 1
    census_eps: float = 4.0
    census_scale: float = 16.0

    def __post_init__(self):
        for name in ("gnc_stages", "warps", "gnc_levels", "wm_radius", "rof_iters", "sor_sweeps",
                     "sor_sweeps_quadratic", "max_levels", "edge_radius", "gnc_start"):
            value = getattr(self, name)
            least = 1 if name in ("gnc_stages", "warps", "gnc_levels", "wm_radius") else 0
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
                raise ValueError(f"{name} must be an int >= {least}, got {value!r}")
        for name in ("spacing", "gnc_spacing"):
            if not getattr(self, name) > 1.0:
                raise ValueError(f"{name} must be > 1, got {getattr(self, name)!r}")
        if not self.gnc_start < self.gnc_stages:
            raise ValueError(f"gnc_start must be below gnc_stages ({self.gnc_stages}), got {self.gnc_start!r}")
        if not self.lam_coarse_factor >= 1.0:
            raise ValueError(f"lam_coarse_factor must be >= 1, got {self.lam_coarse_factor!r}")
        if not self.lam_quadratic >= 0.0:
            raise ValueError(f"lam_quadratic must be >= 0, got {self.lam_quadratic!r}")
        for name in ("lam", "eps", "quad_sigma", "sigma_x", "sigma_i", "occ_sigma_i", "occ_sigma_d"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if not 0.0 < self.a <= 1.0:
            raise ValueError(f"a must be in (0, 1], got {self.a!r}")
        if self.data_term not in DATA_TERMS:
            raise ValueError(f"data_term must be one of {DATA_TERMS}, got {self.data_term!r}")
        for name in ("brightness_weight", "gradient_weight"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        if isinstance(self.census_radius, bool) or not isinstance(self.census_radius, (int, np.integer)) \
                or not 1 <= self.census_radius <= 3:
            raise ValueError(f"census_radius must be an int in [1, 3], got {self.census_radius!r}")
        for name in ("census_eps", "census_scale"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if not 0.0 < self.sor_omega < 2.0:
            raise ValueError(f"sor_omega must be in (0, 2), got {self.sor_omega!r}")


#: ``classic_nl``: the public code's ``classic+nl``.  ``classic_nl_fast``: its
#: ``classic+nl-fast`` schedule (2 GNC stages, 3 warps) with the
#: illumination-robust data term: gradient constancy of the texture image
#: alone, lambda = 10, and the quadratic stage's lambda growing 1.5x per
#: coarser level (see the module docstring for the measurements).
PRESETS = {
    "classic_nl": ClassicNLSettings(),
    "classic_nl_fast": ClassicNLSettings(gnc_stages=2, warps=3, quadratic_wm_finest=False,
                                         data_term="gradient", brightness_weight=0.0, lam=10.0,
                                         lam_coarse_factor=1.5),
}


def settings_for(method: str, **options) -> ClassicNLSettings:
    """The preset ``method`` with ``options`` (fields of :class:`ClassicNLSettings`) replaced."""
    if method not in PRESETS:
        raise ValueError(f"unknown Classic+NL setting {method!r}; expected one of {tuple(PRESETS)}")
    names = {f.name for f in dataclasses.fields(ClassicNLSettings)}
    unknown = sorted(set(options) - names)
    if unknown:
        raise TypeError(f"unknown option(s) {unknown} for {method!r}; valid options: {sorted(names)}")
    return dataclasses.replace(PRESETS[method], **options)


def pyramid_sizes(height: int, width: int, spacing: float, levels: int) -> list[tuple[int, int]]:
    """Sizes of a pyramid, finest first: each level ``ceil(size / spacing)`` of the previous."""
    sizes = [(height, width)]
    for _ in range(levels - 1):
        h, w = sizes[-1]
        sizes.append((max(1, math.ceil(h / spacing - 1e-9)), max(1, math.ceil(w / spacing - 1e-9))))
    return sizes


def auto_levels(height: int, width: int, spacing: float) -> int:
    """Stage-1 level count of the public code: the coarsest long side near 16 pixels,
    the coarsest short side at least 6."""
    n1 = 1 + math.floor(math.log(max(height, width) / 16.0) / math.log(spacing))
    n2 = 1 + math.floor(math.log(min(height, width) / 6.0) / math.log(spacing))
    return max(1, min(n1, n2))


def gnc_schedule(stages: int) -> list[float]:
    """Weight of the quadratic penalty in each GNC stage (1 = quadratic, 0 = robust).

    Stage 1 is quadratic; after stage k the weight becomes
    ``min(previous, max(0, 1 - k / (stages - 1)))``: 3 stages give 1, 0.5, 0.
    """
    alphas, alpha = [], 1.0
    for k in range(1, stages + 1):
        alphas.append(alpha)
        if stages > 1:
            alpha = max(0.0, min(alpha, 1.0 - k / (stages - 1)))
    return alphas


def _features(be, s, tex3, gx3, gy3):
    """Feature channels (T, h, w, C) of the data term and their weights (C,).

    tex3 : the texture image (T, h, w); gx3, gy3 : its 5-point derivatives (T, h, w).
    """
    t_all, h, w = tex3.shape
    if s.data_term == "gradient":
        if s.brightness_weight == 0.0:
            feat = be.empty((t_all, h, w, 2))
            be.flow_classic.pack_gradient(gx3, gy3, feat)
            return feat, (s.gradient_weight, s.gradient_weight)
        feat = be.empty((t_all, h, w, 3))
        be.flow_classic.pack_image_gradient(tex3, gx3, gy3, feat)
        return feat, (s.brightness_weight, s.gradient_weight, s.gradient_weight)
    c = (2 * s.census_radius + 1) ** 2 - 1
    feat = be.empty((t_all, h, w, c))
    be.flow_classic.soft_census(tex3, feat, s.census_radius, s.census_eps, s.census_scale)
    return feat, (1.0,) * c


class _Level:
    """Buffers of one pyramid level: images of all T frames and the per-warp work arrays."""

    def __init__(self, be, texture, lab, n_flows: int, settings=None):
        t_all, h, w, _ = texture.shape
        n = n_flows
        self.shape = (h, w)
        self.texture = texture                                  # (T, h, w, 1)
        self.lab = lab                                          # (T, h, w, 3)
        fc = be.flow_classic
        tex3 = texture.reshape((t_all, h, w))
        gx, gy = be.empty((t_all, h, w, 1)), be.empty((t_all, h, w, 1))
        be.derivatives.image_gradient(texture, gx, gy)
        gx3, gy3 = gx.reshape((t_all, h, w)), gy.reshape((t_all, h, w))
        self.i1, self.i1x, self.i1y = tex3[0:n], gx3[0:n], gy3[0:n]
        term = "brightness" if settings is None else settings.data_term
        if term == "brightness":
            self.first = None
            self.pack2 = be.empty((n, h, w, 3))                 # (I2, I2x, I2y)
            fc.pack_image_gradient(tex3[1:n + 1], gx3[1:n + 1], gy3[1:n + 1], self.pack2)
        else:
            feat, weights = _features(be, settings, tex3, gx3, gy3)
            c = feat.shape[3]
            fgx, fgy = be.empty(feat.shape), be.empty(feat.shape)
            be.derivatives.image_gradient(feat, fgx, fgy)
            pack = be.empty((t_all, h, w, 3 * c))               # (F_c, F_cx, F_cy) per channel
            fc.pack_channels_gradient(feat, fgx, fgy, pack)
            self.first, self.pack2 = pack[0:n], pack[1:n + 1]
            self.weights = be.asarray(np.asarray(weights, np.float32))
        # Occlusion input: the texture image as the first of three "colour" channels,
        # so that the maps kernel's colour distance is Classic+NL's |I2(x+u) - I1(x)|.
        zeros = be.zeros((t_all, h, w))
        self.occ_img = be.empty((t_all, h, w, 3))
        fc.pack_image_gradient(tex3, zeros, zeros, self.occ_img)
        self.warped = be.empty(tuple(self.pack2.shape))
        self.inside = be.empty((n, h, w))
        self.everywhere = None
        if settings is not None and settings.data_outside:
            self.everywhere = be.zeros((n, h, w))
            be.flow_classic.scale_shift(self.everywhere.reshape((n, h, w, 1)), self.everywhere.reshape((n, h, w, 1)),
                                        be.asarray(np.zeros(1, np.float32)), be.asarray(np.ones(1, np.float32)))
        self.du = be.zeros((n, h, w, 2))
        self.data = be.empty((n, h, w, 5))
        self.smooth = be.empty((n, h, w, 4))
        self.system = be.empty((n, h, w, 5))
        self.raw = be.empty((n, h, w, 2))
        self.med = be.empty((n, h, w, 2))
        self.wmed = be.empty((n, h, w, 2))
        self.div = be.empty((n, h, w))
        self.occ = be.empty((n, h, w))
        self.sobel = be.empty((n, h, w, 4))
        self.row_energy = be.empty((n * h, 2))
        self.edges = be.empty((n, h, w))
        self.mask = be.empty((n, h, w))


class ClassicNL:
    """Classic+NL flow between consecutive frames, on a backend.

    >>> flow = ClassicNL(get_backend("warp"), PRESETS["classic_nl_fast"])(frames)  # doctest: +SKIP
    """

    def __init__(self, be, settings: ClassicNLSettings):
        self.be = be
        self.s = settings

    # -- small host helpers -------------------------------------------------

    def _min_max(self, a) -> np.ndarray:
        """(C, 2) channel-wise (min, max) of a (T, H, W, C) array."""
        t, h, _, c = a.shape
        rows = self.be.empty((t * h, c, 2))
        self.be.flow_classic.row_min_max(a, rows)
        rows = self.be.numpy(rows)
        return np.stack([rows[:, :, 0].min(0), rows[:, :, 1].max(0)], -1)

    def _rescale(self, a, lo: float, hi: float) -> None:
        """Map each channel of ``a`` linearly onto [lo, hi] (MATLAB ``scale_image``), in place."""
        mm = self._min_max(a).astype(np.float64)
        span = np.where(mm[:, 1] > mm[:, 0], mm[:, 1] - mm[:, 0], 1.0)
        scale = (hi - lo) / span
        shift = lo - mm[:, 0] * scale
        self.be.flow_classic.scale_shift(a, a, self.be.asarray(scale.astype(np.float32)),
                                         self.be.asarray(shift.astype(np.float32)))

    # -- input preparation --------------------------------------------------

    def _texture(self, rgb):
        """(T, H, W, 1) ROF texture of the sRGB grey level, in [0, 255] (step 2)."""
        be, s, fc = self.be, self.s, self.be.flow_classic
        t, h, w, _ = rgb.shape
        grey = be.empty((t, h, w, 1))
        grey3 = grey.reshape((t, h, w))
        if s.log_input:
            fc.log_grey(rgb, grey3, 1e-3)
        else:
            fc.srgb_grey(rgb, grey3)
        if s.texture_alpha == 0.0 or s.rof_iters == 0:
            self._rescale(grey, 0.0, 255.0)
            return grey
        self._rescale(grey, -1.0, 1.0)
        p, q = be.zeros((t, h, w, 2)), be.zeros((t, h, w, 2))
        delta = 1.0 / (4.0 * s.rof_theta)
        for _ in range(s.rof_iters):
            fc.rof_dual_step(grey3, p, q, s.rof_theta, delta)
            p, q = q, p
        texture = be.empty((t, h, w, 1))
        fc.rof_texture(grey3, p, texture.reshape((t, h, w)), s.rof_theta, s.texture_alpha)
        self._rescale(texture, 0.0, 255.0)
        return texture

    def _pyramid(self, images, sizes, spacing: float) -> list:
        """Blur-and-resample pyramid of (T, H, W, C) ``images`` at ``sizes`` (finest first)."""
        be = self.be
        sigma = math.sqrt(spacing) / math.sqrt(2.0)
        levels = [images]
        for h, w in sizes[1:]:
            prev = levels[-1]
            blurred, scratch = be.empty(prev.shape), be.empty(prev.shape)
            be.pyramid.gaussian_blur(prev, blurred, scratch, sigma)
            out = be.empty((prev.shape[0], h, w, prev.shape[3]))
            be.pyramid.resize_bilinear(blurred, out)
            levels.append(out)
        return levels

    # -- the solver ---------------------------------------------------------

    def _warp_step(self, lv: _Level, flow, quad_frac: float, weighted_median: bool, depth: int = 0,
                   workspace: Workspace | None = None) -> None:
        """One warping step at a level: IRLS system, SOR, update, median filtering (step 4);
        ``workspace`` keeps the median kernels' scratch (the run's own)."""
        be, s, fc = self.be, self.s, self.be.flow_classic
        quad_weight = 2.0 / (s.quad_sigma * s.quad_sigma)
        be.sampling.warp_bicubic(lv.pack2, flow, lv.warped, lv.inside)
        self.be.zero(lv.du)
        inside = lv.inside if lv.everywhere is None else lv.everywhere
        if lv.first is None:
            fc.data_coefficients(lv.i1, lv.i1x, lv.i1y, lv.warped, inside, lv.du, lv.data,
                                 s.blend, s.a, s.eps, quad_frac, quad_weight)
        else:
            fc.data_coefficients_channels(lv.first, lv.warped, inside, lv.du, lv.weights, lv.data,
                                          s.blend, s.a, s.eps, quad_frac, quad_weight)
        fc.smoothness_weights(flow, lv.du, lv.smooth, s.a, s.eps, quad_frac, quad_weight)
        sweeps = s.sor_sweeps_quadratic if quad_frac == 1.0 and s.sor_sweeps_quadratic else s.sor_sweeps
        lam = s.lam
        if quad_frac == 1.0:
            lam = (s.lam_quadratic or s.lam) * s.lam_coarse_factor ** depth
        fc.assemble_system(flow, lv.data, lv.smooth, lam, lv.system)
        for _ in range(sweeps):
            fc.sor_full_sweep(lv.du, lv.system, lv.smooth, lam, s.sor_omega)
        if not s.median:
            fc.apply_update(flow, lv.du, flow, s.limit_update)
            return
        fc.apply_update(flow, lv.du, lv.raw, s.limit_update)
        if not weighted_median:
            be.median.median5x5(lv.raw, flow)
            return
        self._median(lv, lv.raw, flow, workspace)

    def _median(self, lv: _Level, raw, out, workspace: Workspace | None = None) -> None:
        """5x5 median everywhere, 15x15 weighted median near flow edges: ``raw`` -> ``out``."""
        be, s = self.be, self.s
        n = raw.shape[0]
        be.derivatives.divergence_negative(raw, lv.div)
        be.maps.occlusion_soft(lv.occ_img, raw, lv.div, lv.occ, s.occ_sigma_i, s.occ_sigma_d)
        # Flow edges as MATLAB's edge(., 'sobel') finds them (automatic threshold,
        # thinned), for u and for v, then dilated into the weighted-median mask.
        h, w = lv.shape
        be.flow_classic.flow_sobel_components(raw, lv.sobel, lv.row_energy)
        energy = be.numpy(lv.row_energy).reshape(n, h, 2).astype(np.float64).sum(axis=1)
        cutoff = np.maximum(s.edge_scale * energy / (h * w), s.edge_min ** 2).astype(np.float32)
        be.flow_classic.thin_edges(lv.sobel, be.asarray(cutoff), lv.edges)
        be.maps.motion_boundary(lv.edges, lv.mask, 0.5, s.edge_radius, workspace=workspace)
        be.median.median5x5(raw, lv.med)
        # Classic+NL averages the squared Lab differences over the 3 channels; the
        # kernel sums them, hence sigma_i * sqrt(3).
        be.median.weighted_median_flow(raw, lv.lab[0:n], lv.occ, lv.mask, lv.wmed,
                                       s.wm_radius, s.sigma_x, s.sigma_i * math.sqrt(3.0),
                                       workspace=workspace)
        be.flow_classic.select_masked(lv.mask, lv.wmed, lv.med, out)

    def __call__(self, frames: np.ndarray, init: np.ndarray | None = None) -> np.ndarray:
        """Flow between consecutive frames.

        frames : (T, H, W, 3) float32 linear RGB in [0, 1], T >= 2 (validated by
            :func:`ivkernels.flow.estimate_flow`).
        init : optional (T-1, H, W, 2) float32 initial flow.
        Returns (T-1, H, W, 2) float32 forward flow in pixels.
        """
        be, s = self.be, self.s
        t_all, height, width, _ = frames.shape
        n = t_all - 1
        rgb = be.asarray(np.ascontiguousarray(frames, np.float32))
        texture = self._texture(rgb)
        lab = be.empty((t_all, height, width, 3))
        if s.lab_of_encoded:
            encoded = be.empty(rgb.shape)
            be.colour.linear_to_srgb(rgb, encoded)
            be.colour.linear_rgb_to_lab(encoded, lab)
        else:
            be.colour.linear_rgb_to_lab(rgb, lab)
        self._rescale(lab, 0.0, 255.0)

        levels = auto_levels(height, width, s.spacing)
        if s.max_levels:
            levels = min(levels, s.max_levels)
        stage1 = pyramid_sizes(height, width, s.spacing, levels)
        later = pyramid_sizes(height, width, s.gnc_spacing, s.gnc_levels)

        # the flow each stage starts from, fitted to that stage's coarsest level
        if init is None:
            flow, first_stage = be.zeros((n, *stage1[-1], 2)), 0
        else:
            # a copy: the stages update their flow in place, and the caller's array must stay
            flow, first_stage = be.asarray(np.array(init, np.float32, copy=True)), s.gnc_start

        def fit(level, shape, flow):
            """``flow`` resized to ``shape`` (vectors scaled with it) unless it has that size."""
            if tuple(flow.shape[1:3]) == tuple(shape):
                return flow
            resized = be.empty((n, *shape, 2))
            be.pyramid.resize_flow(flow, resized)
            return resized

        workspace = Workspace()             # the median kernels' scratch, freed when the run returns
        pyramids = {}
        for stage, quad_frac in enumerate(gnc_schedule(s.gnc_stages)):
            if stage < first_stage:
                continue
            sizes, spacing = (stage1, s.spacing) if stage == 0 else (later, s.gnc_spacing)
            if spacing not in pyramids:
                tex_levels = self._pyramid(texture, sizes, spacing)
                lab_levels = self._pyramid(lab, sizes, spacing)
                pyramids[spacing] = [_Level(be, tx, lb, n, s) for tx, lb in zip(tex_levels, lab_levels)]
            levels = pyramids[spacing]

            def solve_level(depth, shape, flow, levels=levels, quad_frac=quad_frac):
                lv = levels[depth]
                weighted_median = (quad_frac < 1.0 or s.quadratic_wm_finest
                                   or lv.shape != (height, width))
                for k in range(s.warps):
                    last = k == s.warps - 1
                    self._warp_step(lv, flow, quad_frac, weighted_median and (last or not s.wm_last_warp),
                                    depth, workspace)
                return flow

            def init(level, shape, carried=flow):
                # the previous stage's flow (or the initial one), fitted to the coarsest level
                return fit(level, shape, carried)

            flow = coarse_to_fine(sizes, solve_level, init, fit)
        be.synchronize()
        return np.array(be.numpy(flow), dtype=np.float32, copy=True)
