"""Lambertian synthetic video sequences with exact ground truth.

A small ray caster (per pixel, vectorised NumPy) renders a room -- a textured
floor and back wall -- holding a few large spheres and cylinders and a box,
lit by a low ambient term and two grey (white) disc-shaped area lights: a
key lamp hanging not far above the objects and a large, dim fill on the
camera side.  Every surface carries a solid texture defined in its own object
coordinates, so a surface point keeps its albedo as it moves: albedo is
exactly constant along the true flow, which is what the temporal albedo term
of the paper (Eq. 4) assumes.

The image formation is the paper's model (Eq. 1, ``i = a * s``)::

    frames[t]  = albedo[t] * shading[t][..., None]             (linear RGB)
    shading(x) = ambient + sum_l (P_l / S_l) sum_j V_lj(x)
                     * max(n . w_lj, 0) * max(-e_l . w_lj, 0) / max(d_lj^2, r_l^2)

Light ``l`` is a Lambertian disc of radius ``r_l`` facing the unit direction
``e_l``, sampled at ``S_l`` points ``y_lj``; ``d_lj`` is the distance from the
surface point to ``y_lj``, ``w_lj`` the unit direction towards it and
``V_lj`` (0 or 1) the visibility of ``y_lj`` (a shadow ray against the
objects).  So shading falls off with the inverse square of the distance
(clamped at the disc radius in the near field), varies smoothly across the
floor, the wall and the curved objects, and shadows are soft: penumbrae are
where only some of the ``S_l`` samples are visible.

The sample points are a fixed golden-angle spiral on the disc (stratified,
the same for every pixel and frame, turned by a seeded angle) carried
rigidly with the light, so shading is a deterministic function of the
surface point and the scene's state: where the scene, the light and the
camera do not move, shading is bitwise the same in every frame.  With a
finite number of samples a penumbra is a staircase of ``S_l`` small steps
rather than a continuous ramp (32 key and 16 fill samples).

Exposure: like a camera exposure fixed for the whole sequence, each light's
power ``P_l`` is set so that its largest contribution to the visible
surfaces (measured without shadows on a fixed grid of camera rays that does
not depend on the image size) is ``KEY_SHARE`` = 0.72 for the key and
``FILL_SHARE`` = 0.2 for the fill, so ``AMBIENT <= shading <= 1`` without
clipping (the 0.05 left over absorbs what the grid misses between its rays).

Geometry and conventions
------------------------
* World: ``Y`` up, floor ``y = 0``, back wall ``z = Z_wall`` facing the
  camera, which looks roughly along ``+z``.  Camera frame: ``x`` right,
  ``y`` down, ``z`` forward.  Pinhole camera with focal length
  ``f = 0.9 * W`` pixels and principal point ``((W-1)/2, (H-1)/2)``; pixel
  centres are at integer coordinates (the array convention of
  :mod:`ivkernels.kernels`).  The field of view depends on the aspect ratio
  only, so the same scene at twice the resolution has exactly twice the flow.
* One ray per pixel centre, no anti-aliasing: albedo, shading and frames are
  point samples, so ``frames == albedo * shading`` holds exactly and texture
  edges are pixel-sharp.  Shading is sharp at creases and occluding contours;
  cast shadows are sharp only where they touch their occluder, and their
  penumbrae widen with the distance from it.
* ``depth`` is the camera-space ``z`` of the surface seen at each pixel centre.
* ``flow[t](x)``: the surface point ``q`` (object coordinates) seen at pixel
  ``x`` of frame ``t`` is moved by its object's pose at ``t + 1`` and
  projected by the camera of ``t + 1``; the flow is that projection minus the
  projection of ``q`` at frame ``t`` (both computed the same way, so a static
  scene and camera give exactly zero).
* ``visibility[t](x)`` is 1 when ``x + flow`` lies inside the image
  (``0 <= x <= W-1``, ``0 <= y <= H-1``) and the point is not hidden in frame
  ``t + 1``: a ray cast at the sub-pixel position ``x + flow`` in frame
  ``t + 1`` (frame ``t+1``'s depth there) finds nothing nearer than the
  point's own depth (relative tolerance 1e-4).
* Textures: crisp piecewise-constant ``patches`` and ``stripes`` cover the
  floor, the wall and most objects; one object has smooth ``noise`` and one a
  nearly ``uniform`` albedo.

Sequence kinds (:data:`KINDS`)
------------------------------
``free_camera``
    Static objects; the camera translates and rotates (yaw, pitch, roll) along
    a smooth path while the key lamp travels around the scene, nearer and
    farther, up and down, changing the shading strongly from frame to frame.
``objects_camera``
    Objects slide back and forth on the floor (spheres roll without slipping,
    boxes and cylinders also turn about the vertical) while the camera
    translates without rotating; fixed lights.
``static_moving_light``
    Static scene and camera (flow exactly zero, visibility one everywhere);
    the key lamp circles above the scene, so shading and shadows change.
``rotating_shadows``
    Static camera and lights; boxes turn about the vertical, tilted cylinders
    precess, spheres spin, and a bar floating above the scene turns under a
    small, high key lamp, so soft cast shadows sweep over textured floor, wall
    and objects.
``turning_objects``
    Static camera; the objects turn in place (8-15 degrees a frame) under a
    low, static key lamp on the camera side, so long shadows turn with them.
``camera_light``
    The camera path of ``free_camera`` with a small lamp mounted on the
    camera (0.25 right of and 0.3 above the lens, facing the view), so the
    shading changes with the viewpoint; static objects and fill.
``fast_light``
    Static scene and camera; the key lamp orbits 70-100 degrees a frame,
    rising and falling.
``two_lights_orbit``
    Static objects and two static key lamps on opposite sides; the camera
    orbits the objects' centre at 3-5 degrees a frame, looking at it.

Options (:func:`render_sequence`), orthogonal to the motion: the palette
(``colour``, ``grey``: achromatic and near-achromatic checkerboards, stripes,
print and dark materials, ``mixed``: a grey checkerboard floor among coloured
surfaces, ``ground``: the grey palette on a pale path across a dark, uniform
ground), the light (``soft`` lamps or ``hard`` point bulbs with little
ambient light), one light colour (folded into the albedo truth), and sensor
noise and JPEG compression of the frames (truth unchanged).  The named
evaluation kinds are :data:`SCENE_KINDS` (:func:`render_kind`); seed 0 of
every kind is kept for reporting.

Nothing here is used by the solver; it produces test and evaluation data.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ivkernels.colour import srgb_encode, srgb_to_linear

__all__ = ["KINDS", "MOTION_KINDS", "PALETTES", "LIGHTS", "SCENE_KINDS", "SceneKind", "SyntheticSequence",
           "degrade_frames", "render_kind", "render_sequence", "scene_kinds"]

#: The project's first four motion kinds (the defaults of the perf scripts).
KINDS = ("free_camera", "objects_camera", "static_moving_light", "rotating_shadows")
#: Every motion kind :func:`render_sequence` draws: :data:`KINDS` and four more.
MOTION_KINDS = KINDS + ("turning_objects", "camera_light", "fast_light", "two_lights_orbit")
#: Motion kinds whose scene and camera stand still while the light moves (Weiss's setting).
STATIC_SCENE_MOTIONS = ("static_moving_light", "fast_light")
PALETTES = ("colour", "grey", "mixed", "ground")
LIGHTS = ("soft", "hard")
NOISE_KINDS = ("gaussian", "poisson")
COMPRESSIONS = ("jpeg",)

TEXTURE_KINDS = ("patches", "stripes", "noise", "uniform")
GREY_TEXTURE_KINDS = ("checker", "glyphs", "path")   # drawn only by the grey, mixed and ground palettes
HARD_AMBIENT = 0.01     # ambient term under a hard light (bounce light only)
HARD_MARGIN = 0.15      # exposure headroom of a bulb (its peak is sharper than a lamp's, see _set_exposure)
NEAR_GREY_TINT = 0.04   # largest relative channel deviation of a near-achromatic grey

ALBEDO_MIN = 0.03
AMBIENT = 0.03
FOCAL_PER_WIDTH = 0.9
#: The relief option's bump field (:class:`_Relief`): how many plane waves, and the range of
#: their wavelengths in scene units (3-8 px at 320 px wide for an object 3 units away).
RELIEF_WAVES = 24
RELIEF_WAVELENGTH = (0.03, 0.08)
KEY_SAMPLES = 32        # shadow rays per pixel towards the key lamp
FILL_SAMPLES = 16       # ... and towards the fill
KEY_SHARE = 0.72        # largest contribution of the key lamp to visible shading
FILL_SHARE = 0.2        # ... and the fill's (AMBIENT + KEY_SHARE + FILL_SHARE <= 1)
_EPS_T = 1e-6           # smallest accepted ray parameter
_DEPTH_TOL = 1e-4       # relative depth tolerance of the visibility test
_CHUNK = 2048           # points per block of shadow rays (keeps blocks in cache)
_EXPOSURE_GRID = 128    # camera rays across the image that set the exposure


@dataclass(frozen=True)
class SyntheticSequence:
    """A rendered sequence and its exact ground truth.

    Attributes
    ----------
    frames : (T, H, W, 3) float32
        Linear RGB, ``albedo * shading[..., None]`` exactly, values in [0, 1].
    albedo : (T, H, W, 3) float32
        Linear RGB reflectance in ``[0.03, 1]``.
    shading : (T, H, W) float32
        Grey linear shading, ``>= AMBIENT`` (0.03) and ``<= 1``.
    flow : (T-1, H, W, 2) float32
        Forward flow t -> t+1 in pixels, component 0 = x (columns), 1 = y.
    visibility : (T-1, H, W) float32
        1 where the point seen at ``x`` in frame t is seen at ``x + flow`` in
        frame t+1 (inside the image, not hidden), else 0.
    depth : (T, H, W) float32
        Camera-space z of the visible surface (scene units, > 0).
    object_id : (T, H, W) int32
        Index of the visible surface: 0 floor, 1 back wall, 2.. objects.
    kind : str
        The motion kind, one of :data:`MOTION_KINDS`.
    seed : int
        Seed of the scene and its motion.
    options : dict
        The rendering options (``palette``, ``light``, ``light_colour`` as
        the (3,) colour applied or None, ``noise``, ``compression``) and, from
        :func:`render_kind`, the catalogue ``name``.  With ``noise`` or
        ``compression`` the frames are degraded copies of
        ``albedo * shading`` (the truth is unchanged).
    """

    frames: np.ndarray
    albedo: np.ndarray
    shading: np.ndarray
    flow: np.ndarray
    visibility: np.ndarray
    depth: np.ndarray
    object_id: np.ndarray
    kind: str
    seed: int
    options: dict = field(default_factory=dict)

    def frames_srgb8(self) -> np.ndarray:
        """Frames encoded with the sRGB transfer function, (T, H, W, 3) uint8."""
        return np.round(srgb_encode(self.frames) * 255.0).astype(np.uint8)


# --------------------------------------------------------------------------- #
# small geometry helpers
# --------------------------------------------------------------------------- #
def _axis_angle(axis, angle) -> np.ndarray:
    """Rotation matrix (3, 3) of ``angle`` radians about ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def _mul(a: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``a @ m`` for row vectors ``a`` (..., 3) and a (3, 3) matrix (einsum is
    several times faster than matmul for this shape)."""
    return np.einsum("...j,jk->...k", a, m)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# --------------------------------------------------------------------------- #
# solid textures (object coordinates -> linear RGB albedo)
# --------------------------------------------------------------------------- #
class _Texture:
    """A solid texture evaluated at 3-D points in object coordinates."""

    def __init__(self, kind: str, rng, scale: float = 1.0, grey: bool = False, planar: bool = False):
        self.kind = kind
        self.planar = planar
        if grey or planar or kind in GREY_TEXTURE_KINDS:
            self._init_grey(kind, rng, scale, grey, planar)
            return
        self.rot = _random_rotation(rng) / scale  # feature sizes grow with ``scale``
        if kind == "patches":
            self.cell = rng.uniform(0.25, 0.55)
            self.offset = rng.uniform(0.0, 1.0, 3)
            self.palette = rng.uniform(0.06, 0.9, (16, 3))
        elif kind == "stripes":
            self.period = rng.uniform(0.18, 0.4)
            self.duty = rng.uniform(0.35, 0.65)
            c = rng.uniform(0.06, 0.9, (2, 3))
            while np.abs(c[0] - c[1]).max() < 0.25:
                c = rng.uniform(0.06, 0.9, (2, 3))
            self.colours = c
        elif kind in ("noise", "uniform"):
            # channel 0 of the waves modulates brightness, 1..3 the colour
            n_waves = 6
            lo, hi = (0.6, 2.0) if kind == "noise" else (1.5, 3.0)
            wavelength = rng.uniform(lo, hi, (4, n_waves))
            direction = _unit(rng.normal(size=(4, n_waves, 3)))
            self.k = direction * (2 * np.pi / wavelength)[..., None]
            self.phase = rng.uniform(0, 2 * np.pi, (4, n_waves))
            if kind == "noise":
                self.base = rng.uniform(0.25, 0.65, 3)
                self.amp = np.array([0.3, 0.12])   # brightness, colour
            else:
                self.base = rng.uniform(0.15, 0.85, 3)
                self.amp = np.array([0.03, 0.01])
        else:  # pragma: no cover - internal
            raise ValueError(kind)

    def _init_grey(self, kind: str, rng, scale: float, grey: bool, planar: bool) -> None:
        """The achromatic textures (``grey``) and the planar ones, drawn from
        ``rng`` (the renderer's second stream, so the colour scenes are
        untouched).  A grey texture's colours are :func:`_grey_levels`
        (equal channels), times a tint of at most ``NEAR_GREY_TINT`` for a
        third of them (near-achromatic: paper, concrete, fabric)."""
        if planar:   # a turn about the plane's normal (local y) keeps the pattern in the plane
            self.rot = _axis_angle([0, 1, 0], rng.uniform(0, 2 * np.pi)) / scale
        else:
            self.rot = _random_rotation(rng) / scale
        tint = np.ones(3)
        if grey and rng.uniform() < 1.0 / 3.0:
            u = rng.normal(size=3)
            u -= u.mean()
            tint = 1.0 + NEAR_GREY_TINT * u / np.abs(u).max()

        def levels(n, lo=0.03, hi=0.85):
            if grey:
                return _grey_levels(rng, n, lo, hi)[:, None] * tint
            return rng.uniform(max(lo, 0.06), hi, (n, 3))

        if kind == "patches":
            self.cell = rng.uniform(0.25, 0.55)
            self.offset = rng.uniform(0.0, 1.0, 3)
            self.palette = levels(16)
        elif kind in ("stripes", "checker"):
            self.period = rng.uniform(0.18, 0.4)
            self.duty = rng.uniform(0.35, 0.65)
            self.cell = rng.uniform(0.25, 0.5)
            self.offset = rng.uniform(0.0, 1.0, 3)
            c = levels(2)
            while np.abs(np.log(c[0] / c[1])).max() < 0.8:   # a clear step (a factor 2.2 at least)
                c = levels(2)
            self.colours = c
        elif kind == "path":     # a pale paved band across a dark, uniform ground (a lawn, tarmac)
            self.centre = rng.uniform(-0.8, 0.8)
            self.half_width = rng.uniform(0.4, 0.9)
            ground = _grey_levels(rng, 1, 0.04, 0.1)[0]
            paving = rng.uniform(0.45, 0.8)
            self.colours = np.array([paving, ground])[:, None] * tint
        elif kind == "glyphs":   # dark print on light paper: rows of 5x7 glyphs, word gaps
            self.char = rng.uniform(0.12, 0.2) * scale   # character width (scene units)
            self.offset = rng.uniform(0.0, 1.0, 2)
            paper = rng.uniform(0.55, 0.85)
            ink = rng.uniform(0.03, 0.12)
            self.colours = np.array([paper, ink])[:, None] * tint if grey else \
                np.array([[paper] * 3, rng.uniform(0.03, 0.3, 3)])
            self.glyphs = _glyph_font(rng)
        elif kind in ("noise", "uniform"):
            n_waves = 6
            lo, hi = (0.6, 2.0) if kind == "noise" else (1.5, 3.0)
            wavelength = rng.uniform(lo, hi, (4, n_waves))
            direction = _unit(rng.normal(size=(4, n_waves, 3)))
            self.k = direction * (2 * np.pi / wavelength)[..., None]
            self.phase = rng.uniform(0, 2 * np.pi, (4, n_waves))
            if kind == "noise":
                self.base = levels(1, 0.2, 0.65)[0]
                self.amp = np.array([0.3, 0.0 if grey else 0.12])
            else:    # a dark material when grey (tyres, coats, slate)
                self.base = levels(1, 0.04, 0.12)[0] if grey else levels(1, 0.15, 0.85)[0]
                self.amp = np.array([0.03, 0.0 if grey else 0.01])
        else:  # pragma: no cover - internal
            raise ValueError(kind)

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """Albedo (N, 3) at points ``q`` (N, 3) in object coordinates."""
        p = _mul(q, self.rot)
        if self.planar:
            p[:, 1] = 0.0      # on the plane: the pattern depends on (x, z) only
        if self.kind == "checker":
            c = np.floor(p / self.cell + self.offset).astype(np.int64)
            out = self.colours[(c[:, 0] + c[:, 1] + c[:, 2]) & 1]
            return np.clip(out, ALBEDO_MIN, 1.0)
        if self.kind == "path":
            off_path = np.abs(p[:, 0] - self.centre) > self.half_width
            return np.clip(self.colours[off_path.astype(np.int64)], ALBEDO_MIN, 1.0)
        if self.kind == "glyphs":
            u = p[:, 0] / self.char + self.offset[0]
            v = (p[:, 2] if self.planar else p[:, 1]) / (1.6 * self.char) + self.offset[1]
            cu, cv = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
            col = np.floor((u - cu) * 7.0).astype(np.int64) - 1        # 5 columns in 7
            row = np.floor((v - cv) * 10.0).astype(np.int64) - 1       # 7 rows in 10
            h = (cu * 73856093) ^ (cv * 19349663)
            gid = h % len(self.glyphs)
            word_gap = (h // 7) % 100 < 18
            inside = (col >= 0) & (col < 5) & (row >= 0) & (row < 7) & ~word_gap
            ink = np.zeros(len(p), bool)
            ink[inside] = self.glyphs[gid[inside], row[inside], col[inside]]
            return np.clip(self.colours[ink.astype(np.int64)], ALBEDO_MIN, 1.0)
        if self.kind == "patches":
            c = np.floor(p / self.cell + self.offset).astype(np.int64)
            h = (c[:, 0] * 73856093) ^ (c[:, 1] * 19349663) ^ (c[:, 2] * 83492791)
            out = self.palette[h % len(self.palette)]
        elif self.kind == "stripes":
            s = np.mod(p[:, 0] / self.period, 1.0) < self.duty
            out = np.where(s[:, None], self.colours[0], self.colours[1])
        else:
            arg = np.einsum("nd,cwd->ncw", p, self.k) + self.phase
            noise = np.cos(arg).sum(axis=-1) / np.sqrt(arg.shape[-1])  # ~unit variance
            out = self.base * (1.0 + self.amp[0] * noise[:, :1]) + self.amp[1] * noise[:, 1:]
        return np.clip(out, ALBEDO_MIN, 1.0)


def _grey_levels(rng, n: int, lo: float = 0.03, hi: float = 0.85) -> np.ndarray:
    """``n`` grey reflectances (n,) in ``[lo, hi]``; when ``lo < 0.1`` three in
    ten are dark materials in ``[lo, 0.1]``, the rest lie in ``[0.1, hi]``."""
    if lo >= 0.1:
        return rng.uniform(lo, hi, n)
    dark = rng.uniform(size=n) < 0.3
    return np.where(dark, rng.uniform(lo, 0.1, n), rng.uniform(0.1, hi, n))


def _glyph_font(rng, n: int = 32) -> np.ndarray:
    """``n`` glyph bitmaps (n, 7, 5) bool, each the union of two to four
    strokes (bars, posts and diagonals on the 5x7 grid of a printed
    character), so that a line of them reads as print, not as noise."""
    font = np.zeros((n, 7, 5), bool)
    rows, cols = np.mgrid[0:7, 0:5]
    for g in range(n):
        for _ in range(int(rng.integers(2, 5))):
            kind = rng.integers(3)
            if kind == 0:     # horizontal bar
                r, c0 = rng.integers(7), rng.integers(0, 3)
                font[g, r, c0:c0 + int(rng.integers(3, 6))] = True
            elif kind == 1:   # vertical post
                c, r0 = rng.integers(5), rng.integers(0, 3)
                font[g, r0:r0 + int(rng.integers(4, 8)), c] = True
            else:             # diagonal
                slope = rng.choice([-1, 1])
                c0 = 0 if slope > 0 else 4
                font[g] |= (cols == c0 + slope * np.round(rows * 4 / 6).astype(int))
    return font


# --------------------------------------------------------------------------- #
# analytic shapes in object coordinates
# --------------------------------------------------------------------------- #
def _intersect(shape: str, size: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Nearest ray parameter ``t > eps`` of rays ``o + t d`` with a shape.

    ``o``, ``d``: (N, 3) in object coordinates (``d`` need not be unit length).
    Returns (N,) float64, ``inf`` where the ray misses.
    """
    inf = np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        if shape == "plane":  # y = 0
            t = -o[:, 1] / d[:, 1]
            return np.where(t > _EPS_T, t, inf)
        if shape == "sphere":
            r = size[0]
            a = np.einsum("ij,ij->i", d, d)
            b = np.einsum("ij,ij->i", o, d)
            c = np.einsum("ij,ij->i", o, o) - r * r
            disc = b * b - a * c
            sq = np.sqrt(np.maximum(disc, 0.0))
            t0 = (-b - sq) / a
            t1 = (-b + sq) / a
            t = np.where(t0 > _EPS_T, t0, np.where(t1 > _EPS_T, t1, inf))
            return np.where(disc >= 0.0, t, inf)
        if shape == "box":
            t1 = (-size - o) / d
            t2 = (size - o) / d
            tmin = np.minimum(t1, t2)
            tmax = np.maximum(t1, t2)
            # rays parallel to a slab: inside -> (-inf, inf), outside -> miss
            par = d == 0.0
            inside = np.abs(o) <= size
            tmin = np.where(par, np.where(inside, -inf, inf), tmin)
            tmax = np.where(par, np.where(inside, inf, -inf), tmax)
            tn = tmin.max(axis=1)
            tf = tmax.min(axis=1)
            t = np.where(tn > _EPS_T, tn, tf)
            return np.where((tn <= tf) & (t > _EPS_T), t, inf)
        if shape == "cylinder":  # axis y, radius size[0], half height size[1]
            r, h = size
            a = d[:, 0] ** 2 + d[:, 2] ** 2
            b = o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2]
            c = o[:, 0] ** 2 + o[:, 2] ** 2 - r * r
            disc = b * b - a * c
            sq = np.sqrt(np.maximum(disc, 0.0))
            best = np.full(len(o), inf)
            for ts in ((-b - sq) / a, (-b + sq) / a):
                y = o[:, 1] + ts * d[:, 1]
                ok = (disc >= 0) & (a > 0) & (ts > _EPS_T) & (np.abs(y) <= h)
                best = np.where(ok & (ts < best), ts, best)
            for cap in (-h, h):
                tc = (cap - o[:, 1]) / d[:, 1]
                x = o[:, 0] + tc * d[:, 0]
                z = o[:, 2] + tc * d[:, 2]
                ok = (tc > _EPS_T) & (x * x + z * z <= r * r)
                best = np.where(ok & (tc < best), tc, best)
            return best
    raise ValueError(shape)  # pragma: no cover - internal


def _segment_blocked(shape: str, size: np.ndarray, o, d) -> np.ndarray:
    """Whether segments ``o + s d``, ``eps < s < 1``, cross a shape.

    ``o`` and ``d`` are triples of broadcastable arrays (x, y, z components
    in object coordinates; e.g. ``o`` (M,) per point and ``d`` (S, M) per
    light sample and point).  The same tests as :func:`_intersect`, written
    per component so that they run on 2-D blocks of shadow rays.
    """
    ox, oy, oz = o
    dx, dy, dz = d

    def inside(s):
        return (s > _EPS_T) & (s < 1.0)

    with np.errstate(divide="ignore", invalid="ignore"):
        if shape == "sphere":
            a = dx * dx + dy * dy + dz * dz
            b = ox * dx + oy * dy + oz * dz
            c = ox * ox + oy * oy + oz * oz - size[0] ** 2
            disc = b * b - a * c
            sq = np.sqrt(np.maximum(disc, 0.0))
            return (disc >= 0.0) & (inside((-b - sq) / a) | inside((-b + sq) / a))
        if shape == "box":
            tn = tf = None
            for oc, dc, s in ((ox, dx, size[0]), (oy, dy, size[1]), (oz, dz, size[2])):
                t1 = (-s - oc) / dc
                t2 = (s - oc) / dc
                lo, hi = np.minimum(t1, t2), np.maximum(t1, t2)
                par = dc == 0.0
                if np.any(par):  # parallel to the slab: inside -> (-inf, inf), else miss
                    ins = np.abs(oc) <= s
                    lo = np.where(par, np.where(ins, -np.inf, np.inf), lo)
                    hi = np.where(par, np.where(ins, np.inf, -np.inf), hi)
                tn = lo if tn is None else np.maximum(tn, lo)
                tf = hi if tf is None else np.minimum(tf, hi)
            return (tn <= tf) & (inside(tn) | inside(tf))
        if shape == "cylinder":  # axis y, radius size[0], half height size[1]
            r, h = size
            a = dx * dx + dz * dz
            b = ox * dx + oz * dz
            c = ox * ox + oz * oz - r * r
            disc = b * b - a * c
            sq = np.sqrt(np.maximum(disc, 0.0))
            hit = np.zeros(np.broadcast_shapes(np.shape(ox), np.shape(dx)), dtype=bool)
            for s in ((-b - sq) / a, (-b + sq) / a):
                hit |= (disc >= 0.0) & (a > 0.0) & inside(s) & (np.abs(oy + s * dy) <= h)
            for cap in (-h, h):
                s = (cap - oy) / dy
                x = ox + s * dx
                z = oz + s * dz
                hit |= inside(s) & (x * x + z * z <= r * r)
            return hit
    raise ValueError(shape)  # pragma: no cover - internal


def _normal(shape: str, size: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Outward unit normal (N, 3) at surface points ``q`` in object coordinates."""
    n = np.zeros_like(q)
    if shape == "plane":
        n[:, 1] = 1.0
    elif shape == "sphere":
        n = q / size[0]
    elif shape == "box":
        axis = np.argmin(size - np.abs(q), axis=1)
        rows = np.arange(len(q))
        n[rows, axis] = np.sign(q[rows, axis])
    elif shape == "cylinder":
        r, h = size
        rad = np.hypot(q[:, 0], q[:, 2])
        cap = (h - np.abs(q[:, 1])) < (r - rad)
        n[:, 0] = np.where(cap, 0.0, q[:, 0] / np.maximum(rad, 1e-12))
        n[:, 2] = np.where(cap, 0.0, q[:, 2] / np.maximum(rad, 1e-12))
        n[:, 1] = np.where(cap, np.sign(q[:, 1]), 0.0)
    return _unit(n)


class _Object:
    """A shape with a texture and one pose ``p = R_t q + T_t`` per frame."""

    def __init__(self, shape, size, texture, rotations, translations, casts_shadow=True):
        self.shape = shape
        self.size = np.asarray(size, dtype=np.float64)
        self.texture = texture
        self.rotations = np.asarray(rotations, dtype=np.float64)        # (T, 3, 3)
        self.translations = np.asarray(translations, dtype=np.float64)  # (T, 3)
        self.casts_shadow = casts_shadow
        self.bound = 1.0001 * float(np.linalg.norm(self.size)) if shape != "cylinder" \
            else 1.0001 * float(np.hypot(*self.size))  # bounding-sphere radius

    def to_local(self, t, p):
        return _mul(p - self.translations[t], self.rotations[t])

    def to_world(self, t, q):
        return _mul(q, self.rotations[t].T) + self.translations[t]

    def intersect(self, t, o, d):
        """Ray parameters (N,) of rays ``o + s d`` (world; ``o`` (3,) or (N, 3))
        hitting this object at frame ``t``, ``inf`` where they miss.  Rays
        that miss the bounding sphere are skipped."""
        n = len(d)
        o_l = _mul(o - self.translations[t], self.rotations[t])
        if self.shape == "plane":
            return _intersect(self.shape, self.size, np.broadcast_to(o_l, d.shape),
                              _mul(d, self.rotations[t]))
        w = self.translations[t] - o
        wd = np.einsum("...j,...j->...", w, np.broadcast_to(d, d.shape))
        dd = np.einsum("ij,ij->i", d, d)
        dist2 = np.einsum("...j,...j->...", w, w) - wd * wd / dd
        cand = np.flatnonzero(dist2 <= self.bound ** 2)
        out = np.full(n, np.inf)
        if len(cand):
            o_c = o_l if o_l.ndim == 1 else o_l[cand]
            d_c = _mul(d[cand], self.rotations[t])
            out[cand] = _intersect(self.shape, self.size, np.broadcast_to(o_c, d_c.shape), d_c)
        return out

    def occludes(self, t, p, y) -> np.ndarray:
        """Shadow test (S, M) of the segments from points ``p`` (M, 3) to
        light samples ``y`` (S, 3) (world) against this object at frame ``t``;
        True where the segment crosses the object (end points excluded)."""
        o = _mul(p - self.translations[t], self.rotations[t])   # (M, 3)
        e = _mul(y - self.translations[t], self.rotations[t])   # (S, 3)
        o = tuple(o[:, k].copy() for k in range(3))
        d = tuple(e[:, k:k + 1] - o[k] for k in range(3))
        return _segment_blocked(self.shape, self.size, o, d)


_GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


def _disc_pattern(n: int, rng) -> np.ndarray:
    """``n`` stratified points (n, 2) on the unit disc: a golden-angle
    (Vogel) spiral, equal area per point, turned by a random angle."""
    k = np.arange(n) + 0.5
    radius = np.sqrt(k / n)
    angle = rng.uniform(0.0, 2.0 * np.pi) + _GOLDEN_ANGLE * np.arange(n)
    return np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)


@dataclass
class _AreaLight:
    """Grey Lambertian disc emitter (a lamp shade, a soft box, a window).

    ``centres[t]`` (T, 3) is the disc's centre and ``normals[t]`` (T, 3) the
    unit direction it faces at frame ``t``; ``pattern`` (S, 2) holds the
    fixed sample points on the unit disc, scaled by ``radius`` and carried
    rigidly with the disc.  Each sample is a point emitter of power
    ``power / S`` with a cosine lobe about the normal and inverse-square
    falloff, clamped at distance ``radius`` (the near field of the disc).
    """

    centres: np.ndarray  # (T, 3)
    normals: np.ndarray  # (T, 3)
    radius: float
    pattern: np.ndarray  # (S, 2)
    power: float = 1.0
    share: float = KEY_SHARE   # largest contribution to visible shading (_set_exposure)
    role: str = "key"          # "key" or "fill" (a fill is dropped under a hard light)
    isotropic: bool = False    # a bare bulb: no cosine lobe about ``normals``

    def samples(self, t: int) -> np.ndarray:
        """World positions (S, 3) of the sample points at frame ``t``."""
        e = self.normals[t]
        helper = np.array([1.0, 0.0, 0.0]) if abs(e[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
        u = _unit(np.cross(e, helper))
        v = np.cross(e, u)
        return self.centres[t] + self.radius * (self.pattern[:, :1] * u + self.pattern[:, 1:] * v)


@dataclass
class _Relief:
    """A fine relief on every surface: a bump field ``h(q) = sum_k sin(w_k . q + phi_k) / |w_k|``
    in each object's own coordinates, so that it moves with the object, drawn as the normal it
    tilts (the geometry, the flow and the shadows' outlines are those of the smooth surface).

    ``waves`` (K, 3) are the wave vectors (wavelengths ``RELIEF_WAVELENGTH`` in scene units,
    a few pixels at the objects' distance), ``phases`` (K,), ``slope`` the RMS slope.
    """

    waves: np.ndarray
    phases: np.ndarray
    slope: float

    @classmethod
    def draw(cls, slope: float, rng) -> "_Relief":
        k = RELIEF_WAVES
        lengths = rng.uniform(*RELIEF_WAVELENGTH, k)
        return cls(_unit(rng.normal(size=(k, 3))) * (2.0 * np.pi / lengths)[:, None],
                   rng.uniform(0.0, 2.0 * np.pi, k), float(slope))

    def tilt(self, n: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Unit normals (N, 3) of the bumped surface at points ``q`` (N, 3) whose smooth unit
        normals are ``n``, both in object coordinates: ``n`` tilted against the tangential part
        of ``grad h`` (RMS ``slope``)."""
        unit_waves = self.waves / np.linalg.norm(self.waves, axis=1, keepdims=True)
        g = np.cos(q @ self.waves.T + self.phases) @ unit_waves * (self.slope * np.sqrt(2.0 / len(self.phases)))
        g = g - (g * n).sum(axis=1, keepdims=True) * n
        return _unit(n - g)


@dataclass
class _Scene:
    objects: list
    lights: list
    cam_rot: np.ndarray     # (T, 3, 3) world -> camera
    cam_pos: np.ndarray     # (T, 3)
    ambient: float = AMBIENT
    relief: _Relief | None = None


# --------------------------------------------------------------------------- #
# scene construction
# --------------------------------------------------------------------------- #
def _camera_rotation(yaw, pitch, roll) -> np.ndarray:
    """World -> camera rotation; yaw about world Y, pitch down > 0, roll about z."""
    base = np.diag([1.0, -1.0, 1.0])  # camera y points down
    c2w = _axis_angle([0, 1, 0], yaw) @ _axis_angle([1, 0, 0], pitch) \
        @ _axis_angle([0, 0, 1], roll) @ base
    return c2w.T


def _segment_distance(a0, a1, b0, b1) -> float:
    s = np.linspace(0.0, 1.0, 33)
    pa = a0 + s[:, None] * (a1 - a0)
    pb = b0 + s[:, None] * (b1 - b0)
    return float(np.linalg.norm(pa[:, None] - pb[None], axis=-1).min())


def _aim(centres, target) -> np.ndarray:
    """Unit directions (T, 3) from ``centres`` towards ``target``."""
    return _unit(np.asarray(target, dtype=np.float64) - centres)


def _build_scene(kind: str, n_frames: int, rng, aspect: float = 0.75, style: dict | None = None,
                 style_rng=None, relief: _Relief | None = None) -> _Scene:
    """The room, objects, camera path and lights of one sequence (see the
    module docstring), drawn from ``rng``; ``aspect`` (``H / W``) sets the
    field of view used for the exposure.  ``style`` (palette, light) is
    applied by :func:`_restyle` with draws from ``style_rng``; ``relief``
    bumps every surface (the exposure sees it)."""
    T = n_frames
    tt = np.arange(T, dtype=np.float64)
    z_wall = rng.uniform(5.5, 6.5)
    cam_height = rng.uniform(1.4, 1.8)
    cam_z = -1.8
    pitch0 = np.deg2rad(rng.uniform(12.0, 17.0))
    yaw0 = np.deg2rad(rng.uniform(-4.0, 4.0))

    # Textures: crisp patches and stripes dominate (floor, wall, most objects);
    # exactly one object has smooth noise and one a nearly uniform albedo.
    floor_kind, wall_kind = rng.permutation(["patches", "stripes"])
    identity = np.broadcast_to(np.eye(3), (T, 3, 3))
    wall_rot = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])  # local +y -> world -z
    objects = [
        # coarser textures on the floor and wall limit aliasing at grazing angles
        _Object("plane", (), _Texture(floor_kind, rng, 2.4), identity, np.zeros((T, 3)),
                casts_shadow=False),
        _Object("plane", (), _Texture(wall_kind, rng, 2.0), np.broadcast_to(wall_rot, (T, 3, 3)),
                np.broadcast_to([0.0, 0.0, z_wall], (T, 3)), casts_shadow=False),
    ]

    # ---- objects: shape, size, footprint, rest pose, then motion per kind.
    # Mostly large curved shapes; under the floating bar of rotating_shadows
    # everything stays below 1.35.
    low = kind == "rotating_shadows"
    n_obj = int(rng.integers(4, 6))
    shapes = ["sphere", "sphere", "cylinder", "box"] + list(rng.choice(["sphere", "cylinder"], n_obj - 4))
    shapes = [shapes[i] for i in rng.permutation(n_obj)]
    placed = []  # (segment start, segment end, footprint radius)
    for shape in shapes:
        if shape == "sphere":
            size = np.array([rng.uniform(0.35, 0.6) if low else rng.uniform(0.45, 0.85)])
            foot = size[0]
            rest_y = size[0]
        elif shape == "box":
            size = rng.uniform(0.2, 0.4, 3)
            foot = float(np.hypot(size[0], size[2]))
            rest_y = size[1]
        else:
            size = np.array([rng.uniform(0.25, 0.42) if low else rng.uniform(0.3, 0.55),
                             rng.uniform(0.3, 0.45) if low else rng.uniform(0.4, 0.75)])
            foot = size[0]
            rest_y = size[1]
        tilt = 0.0
        if low and shape == "cylinder":
            tilt = np.deg2rad(rng.uniform(20.0, 40.0))
            foot = size[1] * np.sin(tilt) + size[0] * np.cos(tilt)
            rest_y = size[1] * np.cos(tilt) + size[0] * np.sin(tilt)

        amp, direction = 0.0, np.zeros(3)
        if kind == "objects_camera":
            amp = rng.uniform(0.2, 0.4)
            a = rng.uniform(0, 2 * np.pi)
            direction = np.array([np.cos(a), 0.0, np.sin(a)])
        for _ in range(200):
            z = 1.0 + (z_wall - 2.0) * rng.uniform() ** 1.5   # nearer objects more often
            half = 0.42 * (z - cam_z)
            x = rng.uniform(-half + foot, half - foot) if half > foot else 0.0
            c = np.array([x, rest_y, z])
            s0, s1 = c - amp * direction, c + amp * direction
            if max(s0[2], s1[2]) + foot > z_wall - 0.2 or min(s0[2], s1[2]) < 0.9:
                continue
            if all(_segment_distance(s0, s1, p0, p1) > foot + f + 0.12 for p0, p1, f in placed):
                break
        else:
            continue  # no room for this object: leave it out
        placed.append((s0, s1, foot))

        rot0 = _axis_angle([0, 1, 0], rng.uniform(0, 2 * np.pi))
        if shape == "sphere":
            rot0 = _random_rotation(rng)
        if tilt:
            rot0 = _axis_angle([1, 0, 0], tilt) @ rot0
        rots = np.broadcast_to(rot0, (T, 3, 3)).copy()
        trans = np.broadcast_to(c, (T, 3)).copy()
        if kind == "objects_camera":
            omega = rng.uniform(0.2, 0.35)
            phase = rng.uniform(0, 2 * np.pi)
            disp = amp * np.sin(omega * tt + phase)
            trans = c + disp[:, None] * direction
            if shape == "sphere":  # roll without slipping: axis = up x direction
                axis = np.cross([0.0, 1.0, 0.0], direction)
                rots = np.stack([_axis_angle(axis, s / size[0]) @ rot0 for s in disp])
            else:
                turn = rng.uniform(0.3, 0.8) * rng.choice([-1, 1])
                rots = np.stack([_axis_angle([0, 1, 0], turn * np.sin(omega * k + phase)) @ rot0
                                 for k in tt])
        elif kind == "turning_objects":   # turning in place, a little faster
            rate = np.deg2rad(rng.uniform(8.0, 15.0)) * rng.choice([-1, 1])
            axis = _unit(rng.normal(size=3)) if shape == "sphere" else np.array([0.0, 1.0, 0.0])
            rots = np.stack([_axis_angle(axis, rate * k) @ rot0 for k in tt])
        elif kind == "rotating_shadows":
            rate = np.deg2rad(rng.uniform(6.0, 12.0)) * rng.choice([-1, 1])
            axis = _unit(rng.normal(size=3)) if shape == "sphere" else np.array([0.0, 1.0, 0.0])
            rots = np.stack([_axis_angle(axis, rate * k) @ rot0 for k in tt])
        objects.append(_Object(shape, size, None, rots, trans))

    # object textures, assigned once the objects that fit are known
    n_placed = len(objects) - 2
    kinds = ["noise", "uniform"] + list(rng.choice(["patches", "stripes"], max(n_placed - 2, 0)))
    for obj, i in zip(objects[2:], rng.permutation(n_placed)):
        obj.texture = _Texture(kinds[i], rng)

    if low:  # a bar floating above everything, turning
        size = np.array([rng.uniform(0.9, 1.2), 0.05, rng.uniform(0.1, 0.16)])
        c = np.array([rng.uniform(-0.5, 0.5), rng.uniform(1.55, 1.75), rng.uniform(2.2, 3.2)])
        rate = np.deg2rad(rng.uniform(7.0, 11.0)) * rng.choice([-1, 1])
        a0 = rng.uniform(0, 2 * np.pi)
        rots = np.stack([_axis_angle([0, 1, 0], a0 + rate * k) for k in tt])
        objects.append(_Object("box", size, _Texture(rng.choice(["patches", "stripes"]), rng),
                               rots, np.broadcast_to(c, (T, 3))))

    # ---- camera path
    cam_pos = np.broadcast_to([0.0, cam_height, cam_z], (T, 3)).copy()
    yaw = np.full(T, yaw0)
    pitch = np.full(T, pitch0)
    roll = np.zeros(T)
    centre = np.array([0.0, 0.0, 0.0])
    if len(objects) > 2:
        centre = np.mean([obj.translations[0] for obj in objects[2:]], axis=0)
    centre[1] = 0.0
    if kind in ("free_camera", "objects_camera", "camera_light"):
        amp = np.array([0.35, 0.08, 0.3]) if kind == "objects_camera" else np.array([0.45, 0.12, 0.35])
        omega = rng.uniform(0.18, 0.3, 3)
        phase = rng.uniform(0, 2 * np.pi, 3)
        cam_pos = cam_pos + amp * np.sin(omega * tt[:, None] + phase)
    if kind == "two_lights_orbit":   # about the objects' centre, looking at it, 3-5 degrees a frame
        radius = centre[2] - cam_z
        rate = np.deg2rad(rng.uniform(3.0, 5.0)) * rng.choice([-1, 1])
        phi = rate * (tt - (T - 1) / 2.0) + np.deg2rad(rng.uniform(-5.0, 5.0))
        cam_pos = np.stack([centre[0] + radius * np.sin(phi), np.full(T, cam_height),
                            centre[2] - radius * np.cos(phi)], axis=1)
        yaw = -phi
    if kind in ("free_camera", "camera_light"):
        amp = np.deg2rad([7.0, 3.0, 3.0])
        omega = rng.uniform(0.2, 0.3, 3)
        phase = rng.uniform(0, 2 * np.pi, 3)
        yaw = yaw + amp[0] * np.sin(omega[0] * tt + phase[0])
        pitch = pitch + amp[1] * np.sin(omega[1] * tt + phase[1])
        roll = roll + amp[2] * np.sin(omega[2] * tt + phase[2])
    cam_rot = np.stack([_camera_rotation(y, p, r) for y, p, r in zip(yaw, pitch, roll)])

    # ---- lights: a key lamp above the objects, on the camera side of their
    # centre, and a large dim fill beside the camera on the other side.
    target = centre + [0.0, 0.4, 0.0]
    if kind == "free_camera":      # travels around the scene, nearer and farther, up and down
        theta = rng.uniform(0, 2 * np.pi) + 0.55 * rng.choice([-1, 1]) * tt
        rho = 2.0 + 0.8 * np.sin(0.7 * tt + rng.uniform(0, 2 * np.pi))
        height = 3.0 + 0.6 * np.sin(0.6 * tt + rng.uniform(0, 2 * np.pi))
        radius = rng.uniform(0.25, 0.4)
    elif kind == "static_moving_light":   # circles above the scene
        theta = rng.uniform(0, 2 * np.pi) + 0.5 * rng.choice([-1, 1]) * tt
        rho = np.full(T, rng.uniform(1.6, 2.2))
        height = 3.0 + 0.3 * np.sin(0.7 * tt)
        radius = rng.uniform(0.25, 0.4)
    elif kind == "fast_light":   # orbits at 70-100 degrees a frame, rising and falling
        theta = rng.uniform(0, 2 * np.pi) + np.deg2rad(rng.uniform(70.0, 100.0)) * rng.choice([-1, 1]) * tt
        rho = np.full(T, rng.uniform(1.6, 2.4))
        height = 2.9 + 0.5 * np.sin(1.3 * tt + rng.uniform(0, 2 * np.pi))
        radius = rng.uniform(0.25, 0.4)
    elif kind == "turning_objects":   # low and static, on the camera side: long shadows
        theta = np.full(T, np.deg2rad(rng.uniform(-160, -20)))
        rho = np.full(T, rng.uniform(2.6, 3.4))
        height = np.full(T, rng.uniform(1.0, 1.5))
        radius = rng.uniform(0.2, 0.3)
    elif kind == "camera_light":   # a lamp on the camera: placed below, after the camera path
        theta = rho = height = np.zeros(T)
        radius = rng.uniform(0.08, 0.12)
    else:
        theta = np.full(T, np.deg2rad(rng.uniform(-150, -30)))
        if low:   # small and high: the bar's shadow keeps a core
            rho = np.full(T, rng.uniform(0.6, 1.4))
            height = np.full(T, rng.uniform(3.3, 3.6))
            radius = rng.uniform(0.12, 0.2)
        else:
            rho = np.full(T, rng.uniform(1.0, 2.0))
            height = np.full(T, rng.uniform(2.8, 3.3))
            radius = rng.uniform(0.25, 0.4)
    key_pos = centre + np.stack([rho * np.cos(theta), height, rho * np.sin(theta)], axis=1)
    key_pos[:, 2] = np.minimum(key_pos[:, 2], z_wall - 0.6)
    key_dir = _aim(key_pos, target)
    if kind == "camera_light":   # 0.25 right of and 0.3 above the lens, facing the view direction
        key_pos = cam_pos + np.einsum("j,tjk->tk", [0.25, -0.3, 0.0], cam_rot)
        key_dir = np.einsum("j,tjk->tk", [0.0, 0.0, 1.0], cam_rot)
    key = _AreaLight(key_pos, key_dir, radius, _disc_pattern(KEY_SAMPLES, rng))

    side = -np.sign(key_pos[0, 0] - centre[0]) or 1.0
    fill_pos = np.array([centre[0] + side * rng.uniform(1.8, 2.8), rng.uniform(1.9, 2.5),
                         cam_z + rng.uniform(-0.3, 1.2)])
    fill_pos = np.broadcast_to(fill_pos, (T, 3)).copy()
    fill = _AreaLight(fill_pos, _aim(fill_pos, target), rng.uniform(0.7, 1.0),
                      _disc_pattern(FILL_SAMPLES, rng), share=FILL_SHARE, role="fill")
    lights = [key, fill]
    if kind == "two_lights_orbit":   # a second static lamp on the other side, a little weaker
        theta2 = np.arctan2(key_pos[0, 2] - centre[2], key_pos[0, 0] - centre[0]) + np.pi \
            + np.deg2rad(rng.uniform(-40.0, 40.0))
        rho2, height2 = rng.uniform(1.4, 2.2), rng.uniform(2.4, 3.2)
        pos2 = centre + np.array([rho2 * np.cos(theta2), height2, rho2 * np.sin(theta2)])
        pos2[2] = min(pos2[2], z_wall - 0.6)
        pos2 = np.broadcast_to(pos2, (T, 3)).copy()
        key.share, fill.share = 0.45, 0.12
        lights.append(_AreaLight(pos2, _aim(pos2, target), rng.uniform(0.2, 0.35),
                                 _disc_pattern(KEY_SAMPLES, rng), share=0.3))
    scene = _Scene(objects, lights, cam_rot, cam_pos, relief=relief)
    if style is not None:
        _restyle(scene, style, style_rng)
    _set_exposure(scene, aspect)
    return scene


def _restyle(scene: _Scene, style: dict, rng) -> None:
    """Apply the palette and the light of ``style`` to a built scene, drawing
    from ``rng`` (a stream apart from the scene's, so geometry, motion and
    light positions are those of the colour scene with the same seed).

    ``palette="grey"``: every surface achromatic or near-achromatic (see
    :class:`_Texture`): a grey checkerboard or grey stripes on the floor,
    print (glyphs) or grey patches on the wall, grey patches, stripes and
    checkers on the objects, smooth grey noise on one, a dark material on
    another.  ``palette="mixed"``: a grey checkerboard floor and one dark grey
    object; the wall and the other objects keep their colours.
    ``palette="ground"``: the grey palette's wall and objects on a floor of
    large uniform regions, a pale paved band across a dark ground (a path
    over a lawn): a long straight step between two flat grey materials.
    ``light="hard"``: every key lamp becomes a bare point bulb at its centre
    (isotropic, one shadow ray: hard cast shadows), the fills go, and the
    ambient term drops to ``HARD_AMBIENT``; the bulbs share the exposure in
    the ratio of the lamps they replace.
    """
    palette, light = style.get("palette", "colour"), style.get("light", "soft")
    floor, wall, objs = scene.objects[0], scene.objects[1], scene.objects[2:]
    if palette in ("grey", "mixed", "ground"):
        if palette == "ground":
            floor.texture = _Texture("path", rng, 1.0, grey=True, planar=True)
        else:
            floor.texture = _Texture("checker" if palette == "mixed" or rng.uniform() < 0.7 else "stripes",
                                     rng, 2.4, grey=True, planar=True)
        dark = [o for o in objs if o.texture.kind == "uniform"]
        for o in dark:
            o.texture = _Texture("uniform", rng, grey=True)
    if palette in ("grey", "ground"):
        if rng.uniform() < 0.6:    # a printed wall (a poster, a notice board) or grey patches
            wall.texture = _Texture("glyphs", rng, 2.5, grey=True, planar=True)
        else:
            wall.texture = _Texture("patches", rng, 2.0, grey=True, planar=True)
        for o in objs:
            kind = o.texture.kind
            if kind in ("patches", "stripes") and rng.uniform() < 0.3:
                kind = str(rng.choice(["checker", "glyphs"]))
            if o.texture.kind != "uniform":
                o.texture = _Texture(kind, rng, 1.5 if kind == "glyphs" else 1.0, grey=True)
    if light == "hard":
        keys = [lt for lt in scene.lights if lt.role == "key"]
        total = sum(lt.share for lt in keys)
        budget = 1.0 - HARD_AMBIENT - HARD_MARGIN
        scene.lights = [_AreaLight(lt.centres, lt.normals, 0.0, np.zeros((1, 2)), share=budget * lt.share / total,
                                   isotropic=True) for lt in keys]
        scene.ambient = HARD_AMBIENT


# --------------------------------------------------------------------------- #
# rendering
# --------------------------------------------------------------------------- #
def _rays(scene, t, xs, ys, focal, cx, cy):
    """World origin (3,) and directions (N, 3) with camera-space z = 1, so the
    ray parameter equals depth."""
    d_cam = np.stack([(xs - cx) / focal, (ys - cy) / focal, np.ones_like(xs)], axis=1)
    return scene.cam_pos[t], _mul(d_cam, scene.cam_rot[t])


def _cast(scene, t, o, d):
    """Nearest hit of rays (o, d) among the objects of frame ``t``:
    ray parameter (N,) and object index (N,) (-1 where nothing is hit)."""
    best = np.full(len(d), np.inf)
    which = np.full(len(d), -1, dtype=np.int32)
    for k, obj in enumerate(scene.objects):
        tk = obj.intersect(t, o, d)
        closer = tk < best
        best = np.where(closer, tk, best)
        which = np.where(closer, k, which)
    return best, which


def _irradiance(scene, light, t, p, n, which, shadows=True):
    """Contribution (N,) of one area light to the shading of world points
    ``p`` (N, 3) with unit normals ``n`` owned by objects ``which``: the sum
    over the light's samples in the module docstring, with one shadow ray
    per point and sample (none if ``shadows`` is False).

    Every operation is element-wise per point (no BLAS, a fixed order of the
    sum over samples), so a point's value depends only on the point, its
    normal and the scene, never on the other points or on the chunking.
    """
    y = light.samples(t)                    # (S, 3)
    y32 = y.astype(np.float32)
    e32 = light.normals[t].astype(np.float32)
    centre = light.centres[t]
    r2 = light.radius ** 2
    casters = [(k, obj) for k, obj in enumerate(scene.objects) if obj.casts_shadow and shadows]
    out = np.empty(len(p))
    for a in range(0, len(p), _CHUNK):
        px, py, pz = (p[a:a + _CHUNK, k].copy() for k in range(3))
        wc = which[a:a + _CHUNK]
        # (S, M) blocks in float32: sample j, point i; l = y_j - p_i
        lx = y32[:, 0:1] - px.astype(np.float32)
        ly = y32[:, 1:2] - py.astype(np.float32)
        lz = y32[:, 2:3] - pz.astype(np.float32)
        d2 = lx * lx
        d2 += ly * ly
        d2 += lz * lz
        nx, ny, nz = (n[a:a + _CHUNK, k].astype(np.float32) for k in range(3))
        cos_s = nx * lx                     # cosines times d
        cos_s += ny * ly
        cos_s += nz * lz
        if light.isotropic:                 # a point emitter: cosine 1, times d
            cos_e = np.sqrt(d2)
        else:
            cos_e = e32[0] * lx             # -(e . l)
            cos_e += e32[1] * ly
            cos_e += e32[2] * lz
            np.negative(cos_e, out=cos_e)
        np.maximum(cos_s, 0.0, out=cos_s)
        np.maximum(cos_e, 0.0, out=cos_e)
        g = cos_s * cos_e
        g /= d2 * np.maximum(d2, np.float32(r2))
        if casters:
            rows = np.flatnonzero((g > 0.0).any(axis=0))
            # every shadow ray of p stays within ``radius`` of the segment p -> centre
            vx, vy, vz = centre[0] - px[rows], centre[1] - py[rows], centre[2] - pz[rows]
            vv = vx * vx + vy * vy + vz * vz
            for k, obj in casters:
                c = obj.translations[t]
                wx, wy, wz = c[0] - px[rows], c[1] - py[rows], c[2] - pz[rows]
                s = np.clip((wx * vx + wy * vy + wz * vz) / vv, 0.0, 1.0)
                wx -= s * vx
                wy -= s * vy
                wz -= s * vz
                near = wx * wx + wy * wy + wz * wz <= (obj.bound + light.radius) ** 2
                # convex objects never shadow themselves where n.l > 0
                cand = rows[near & (wc[rows] != k)]
                if len(cand):
                    blocked = obj.occludes(t, p[a + cand], y)     # (S, M')
                    g[:, cand] = np.where(blocked, np.float32(0.0), g[:, cand])
        total = np.zeros(g.shape[1])
        for j in range(g.shape[0]):
            total += g[j]
        out[a:a + _CHUNK] = total
    return (light.power / len(y)) * out


def _shade(scene, t, p, n, which):
    """Shading (N,) of world points ``p`` with normals ``n`` owned by objects
    ``which`` (the paper's grey shading s; Lambertian with soft cast shadows)."""
    shading = np.full(len(p), scene.ambient)
    for light in scene.lights:
        shading += _irradiance(scene, light, t, p, n, which)
    return shading


def _set_exposure(scene, aspect: float) -> None:
    """Set each light's ``power`` so that its largest unshadowed contribution
    to what the camera sees, in any frame, equals its share (``KEY_SHARE``,
    ``FILL_SHARE``): a camera exposure fixed for the whole sequence.

    The contribution is measured at the surface points hit by a fixed grid of
    ``_EXPOSURE_GRID`` camera rays across the image (the field of view
    depends on the aspect ratio ``H / W`` only), so the exposure does not
    depend on the image size.  Between grid rays the contribution can exceed
    the share only by the little it changes over a grid spacing (0.45
    degrees), which the margin ``1 - AMBIENT - KEY_SHARE - FILL_SHARE``
    absorbs.
    """
    w = _EXPOSURE_GRID
    h = max(2, int(round(w * aspect)))
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    xs, ys = xs.ravel(), ys.ravel()
    peaks = np.zeros(len(scene.lights))
    for light in scene.lights:
        light.power = 1.0
    for t in range(len(scene.cam_pos)):
        o, d = _rays(scene, t, xs, ys, FOCAL_PER_WIDTH * w, (w - 1) / 2.0, (h - 1) / 2.0)
        depth, which = _cast(scene, t, o, d)
        hit = which >= 0
        p, which = o + depth[hit, None] * d[hit], which[hit]
        n = np.empty_like(p)
        for k, obj in enumerate(scene.objects):
            m = which == k
            if m.any():
                q = obj.to_local(t, p[m])
                n[m] = _world_normal(scene, obj, t, q)
        for i, light in enumerate(scene.lights):
            peaks[i] = max(peaks[i], float(_irradiance(scene, light, t, p, n, which, shadows=False).max()))
    for light, peak in zip(scene.lights, peaks):
        light.power = light.share / peak if peak > 0.0 else 0.0


def _world_normal(scene, obj, t, q) -> np.ndarray:
    """World unit normals (N, 3) of ``obj`` in frame ``t`` at its surface points ``q`` (N, 3)
    in object coordinates, tilted by the scene's relief where it has one."""
    n = _normal(obj.shape, obj.size, q)
    if scene.relief is not None:
        n = scene.relief.tilt(n, q)
    return _mul(n, obj.rotations[t].T)


def _project(scene, t, p, focal, cx, cy):
    pc = _mul(p - scene.cam_pos[t], scene.cam_rot[t].T)
    z = pc[:, 2]
    return focal * pc[:, 0] / z + cx, focal * pc[:, 1] / z + cy, z


def _check_args(kind, n_frames, size, seed):
    if not isinstance(kind, str) or kind not in MOTION_KINDS:
        raise ValueError(f"unknown kind {kind!r}; expected one of {', '.join(MOTION_KINDS)}")
    if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)):
        raise TypeError(f"n_frames must be an int, got {type(n_frames).__name__}")
    if n_frames < 2:
        raise ValueError(f"n_frames must be >= 2, got {n_frames}")
    try:
        h, w = size
    except (TypeError, ValueError):
        raise ValueError(f"size must be a pair (H, W), got {size!r}") from None
    for name, v in (("H", h), ("W", w)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise TypeError(f"size {name} must be an int, got {type(v).__name__}")
        if v < 16:
            raise ValueError(f"size {name} must be >= 16, got {v}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an int, got {type(seed).__name__}")
    return int(n_frames), int(h), int(w), int(seed)


def _check_number(name: str, v, lo: float, hi: float) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not (lo <= v <= hi):
        raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {v!r}")
    return float(v)


def _check_options(palette, light, light_colour, noise, compression):
    if palette not in PALETTES:
        raise ValueError(f"unknown palette {palette!r}; expected one of {', '.join(PALETTES)}")
    if light not in LIGHTS:
        raise ValueError(f"unknown light {light!r}; expected one of {', '.join(LIGHTS)}")
    if light_colour is not None and not (isinstance(light_colour, str) and light_colour == "random"):
        c = np.asarray(light_colour, dtype=np.float64) if np.ndim(light_colour) == 1 else None
        if c is None or c.shape != (3,) or not np.all(np.isfinite(c)) or c.min() <= 0:
            raise ValueError(f"light_colour must be None, 'random' or three positive numbers, got {light_colour!r}")
    if noise is not None:
        if not isinstance(noise, (tuple, list)) or len(noise) != 2 or noise[0] not in NOISE_KINDS:
            raise ValueError(f"noise must be None, ('gaussian', std) or ('poisson', photons at white), "
                             f"got {noise!r}")
        if noise[0] == "gaussian":
            _check_number("gaussian noise std", noise[1], 0.0, 1.0)
        else:
            _check_number("poisson photons at white", noise[1], 1.0, 1e9)
    if compression is not None:
        if not isinstance(compression, (tuple, list)) or len(compression) != 2 or compression[0] not in COMPRESSIONS:
            raise ValueError(f"compression must be None or ('jpeg', quality 1-100), got {compression!r}")
        q = compression[1]
        if isinstance(q, bool) or not isinstance(q, (int, np.integer)) or not 1 <= q <= 100:
            raise ValueError(f"jpeg quality must be an int in [1, 100], got {q!r}")


def _light_colour(light_colour, rng) -> np.ndarray | None:
    """The light colour (3,) with its largest channel 1, or None for white.
    ``"random"``: a warm (tungsten, sunset) or cool (overcast, LED) tint,
    the weakest channel 0.55-0.85 of the strongest."""
    if light_colour is None:
        return None
    if isinstance(light_colour, str):
        g, b = rng.uniform(0.75, 0.92), rng.uniform(0.55, 0.85)
        c = np.array([1.0, g, b]) if rng.uniform() < 0.6 else np.array([b, g, 1.0])
    else:
        c = np.asarray(light_colour, dtype=np.float64)
    return c / c.max()


def degrade_frames(frames: np.ndarray, noise=None, compression=None, seed: int = 0) -> np.ndarray:
    """Sensor noise and compression applied to linear frames, as a camera does.

    Parameters
    ----------
    frames : (T, H, W, 3) float, linear RGB in [0, 1].
    noise : None, ``("gaussian", std)`` (additive, linear units) or
        ``("poisson", photons)`` (shot noise: a value ``v`` becomes
        ``Poisson(v * photons) / photons``, so its std is ``sqrt(v / photons)``).
        The result is clipped to [0, 1] (a sensor saturates and reads no
        negative light).
    compression : None or ``("jpeg", quality)``: every frame is encoded to
        8-bit sRGB, through JPEG at that quality (OpenCV, 4:2:0 chroma
        subsampling as in H.264) and decoded back to linear.
    seed : seed of the noise (``numpy.random.default_rng``).

    Returns
    -------
    (T, H, W, 3) float32 linear RGB in [0, 1].
    """
    _check_options("colour", "soft", None, noise, compression)
    out = np.asarray(frames, dtype=np.float64)
    rng = np.random.default_rng(seed)
    if noise is not None:
        if noise[0] == "gaussian":
            out = out + rng.normal(0.0, float(noise[1]), out.shape)
        else:
            out = rng.poisson(np.clip(out, 0.0, None) * float(noise[1])) / float(noise[1])
        out = np.clip(out, 0.0, 1.0)
    if compression is not None:
        params = [cv2.IMWRITE_JPEG_QUALITY, int(compression[1])]
        codes = np.round(srgb_encode(out) * 255.0).astype(np.uint8)
        decoded = np.empty_like(codes)
        for t in range(len(codes)):
            ok, buf = cv2.imencode(".jpg", np.ascontiguousarray(codes[t, ..., ::-1]), params)
            if not ok:  # pragma: no cover - OpenCV failure
                raise RuntimeError("JPEG encoding failed")
            decoded[t] = cv2.imdecode(buf, cv2.IMREAD_COLOR)[..., ::-1]
        out = srgb_to_linear(decoded / 255.0)
    return out.astype(np.float32)


#: Albedo of the floor around :func:`dark_disc`'s disc.
DISC_FLOOR_ALBEDO = 0.5


def dark_disc(size: tuple[int, int] = (120, 160), n_frames: int = 8, radius: int = 20, dark: float = 0.08,
              noise: float = 0.0, per_channel: bool = True, seed: int = 0):
    """The smallest case of a dark material: a still disc of albedo ``dark`` on a floor of
    :data:`DISC_FLOOR_ALBEDO` under a smooth static light, with a camera's Gaussian noise
    (``noise``, std in linear units) drawn per colour channel (a colour camera) or shared by
    the channels (greyscale footage).  No motion: the flow is zero.

    Returns ``(frames (T, H, W, 3) float32 in [0, 1], inside (H, W) bool, floor (H, W) bool)``,
    the masks leaving 2 px either side of the disc's edge out.
    """
    h, w = size
    yy, xx = np.mgrid[0:h, 0:w]
    r2 = (yy - h / 2) ** 2 + (xx - w / 2) ** 2
    albedo = np.where(r2 < radius ** 2, dark, DISC_FLOOR_ALBEDO)
    light = 0.4 + 0.6 * (xx / w) * (0.6 + 0.4 * yy / h)
    video = np.repeat((albedo * light)[None, :, :, None], 3, axis=-1).repeat(n_frames, axis=0)
    rng = np.random.default_rng(seed)
    video = video + rng.normal(0.0, noise, video.shape[:3] + ((3,) if per_channel else (1,)))
    return np.clip(video, 0.0, 1.0).astype(np.float32), r2 < (radius - 2) ** 2, r2 > (radius + 2) ** 2


def render_sequence(kind: str, n_frames: int = 8, size: tuple[int, int] = (240, 320),
                    seed: int = 0, *, palette: str = "colour", light: str = "soft", light_colour=None,
                    noise=None, compression=None, relief: float = 0.0) -> SyntheticSequence:
    """Render a Lambertian sequence with exact albedo, shading, flow and visibility.

    Parameters
    ----------
    kind : str
        The motion, one of :data:`MOTION_KINDS` (see the module docstring).
    n_frames : int
        Number of frames T >= 2.
    size : (H, W)
        Image size in pixels, both >= 16.  The scene, its motion and its
        lighting depend on ``seed`` (and the exposure on the aspect ratio
        ``H / W``) only, so a larger size renders the same sequence with flow
        scaled by the size ratio.
    seed : int
        Seed of ``numpy.random.default_rng`` for the scene and motion.
    palette : ``"colour"`` (random RGB), ``"grey"`` (achromatic and
        near-achromatic: grey checkerboards, stripes, print, dark materials),
        ``"mixed"`` (a grey checkerboard floor and a dark grey object among
        coloured surfaces) or ``"ground"`` (the grey palette on a floor of a
        pale path across a dark, uniform ground).  The scene's geometry,
        motion and light positions do not depend on it.
    light : ``"soft"`` (disc lamps, a fill and an ambient term) or ``"hard"``
        (bare point bulbs, hard cast shadows, ambient ``HARD_AMBIENT``).
    light_colour : None (white), ``"random"`` or a triple: one colour for every
        lamp.  The model's shading is grey, so the colour is folded into the
        truth: ``albedo`` is the reflectance times the colour (largest channel
        1), ``shading`` is unchanged, and ``frames = albedo * shading`` still.
    noise, compression : see :func:`degrade_frames`; applied to the frames
        only (seeded by ``seed``), the truth stays exact.
    relief : float in [0, 1]
        RMS slope of a fine relief on every surface (bumps 3-8 px across,
        drawn as tilted normals and moving with each surface), whose shading
        changes with every move of the light, as a sculpted or furred
        object's does; it is in the truth's shading.  0 (default): smooth.

    The defaults reproduce the sequences of the four original kinds bit for
    bit: the options draw from a second stream (``default_rng([seed, 33, m])``,
    ``m`` the index of ``kind`` in :data:`MOTION_KINDS`).

    Returns
    -------
    SyntheticSequence
        ``frames = albedo * shading[..., None]`` in linear RGB (paper Eq. 1)
        with its ground truth (up to the noise and compression asked for);
        see :class:`SyntheticSequence`.

    Examples
    --------
    >>> seq = render_sequence("static_moving_light", n_frames=3, size=(48, 64))
    >>> seq.frames.shape, seq.flow.shape
    ((3, 48, 64, 3), (2, 48, 64, 2))
    >>> bool(abs(seq.flow).max() == 0.0)
    True
    """
    T, H, W, seed = _check_args(kind, n_frames, size, seed)
    _check_options(palette, light, light_colour, noise, compression)
    relief = _check_number("relief", relief, 0.0, 1.0)
    style_rng = np.random.default_rng([seed, 33, MOTION_KINDS.index(kind)])
    style = None if (palette, light) == ("colour", "soft") else {"palette": palette, "light": light}
    bumps = _Relief.draw(relief, np.random.default_rng([seed, 34, MOTION_KINDS.index(kind)])) if relief else None
    scene = _build_scene(kind, T, np.random.default_rng(seed), aspect=H / W, style=style, style_rng=style_rng,
                         relief=bumps)
    colour = _light_colour(light_colour, style_rng)
    focal = FOCAL_PER_WIDTH * W
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    xs, ys = xs.ravel(), ys.ravel()
    N = H * W

    albedo = np.empty((T, N, 3), np.float32)
    shading = np.empty((T, N), np.float32)
    depth = np.empty((T, N), np.float32)
    object_id = np.empty((T, N), np.int32)
    local = np.empty((T, N, 3))  # surface point in object coordinates
    for t in range(T):
        o, d = _rays(scene, t, xs, ys, focal, cx, cy)
        tk, which = _cast(scene, t, o, d)
        if (which < 0).any():  # pragma: no cover - the room closes every view
            raise RuntimeError("a camera ray left the room")
        p = o + tk[:, None] * d
        n = np.empty_like(p)
        a = np.empty_like(p)
        for k, obj in enumerate(scene.objects):
            m = which == k
            if not m.any():
                continue
            q = obj.to_local(t, p[m])
            local[t, m] = q
            n[m] = _world_normal(scene, obj, t, q)
            a[m] = obj.texture(q)
        albedo[t] = a
        shading[t] = _shade(scene, t, p, n, which)
        depth[t] = tk
        object_id[t] = which

    flow = np.empty((T - 1, N, 2), np.float32)
    visibility = np.empty((T - 1, N), np.float32)
    for t in range(T - 1):
        x0, y0, x1, y1, z1 = np.empty((5, N))
        for k, obj in enumerate(scene.objects):
            m = object_id[t] == k
            if not m.any():
                continue
            q = local[t, m]
            x0[m], y0[m], _ = _project(scene, t, obj.to_world(t, q), focal, cx, cy)
            x1[m], y1[m], z1[m] = _project(scene, t + 1, obj.to_world(t + 1, q), focal, cx, cy)
        flow[t, :, 0] = x1 - x0
        flow[t, :, 1] = y1 - y0
        # visibility is decided at x + flow as stored (float32)
        tx = xs + flow[t, :, 0].astype(np.float64)
        ty = ys + flow[t, :, 1].astype(np.float64)
        inside = (z1 > 0) & (tx >= 0) & (tx <= W - 1) & (ty >= 0) & (ty <= H - 1)
        idx = np.flatnonzero(inside)
        o, d = _rays(scene, t + 1, tx[idx], ty[idx], focal, cx, cy)
        t_hit, _ = _cast(scene, t + 1, o, d)
        seen = t_hit >= z1[idx] * (1.0 - _DEPTH_TOL)
        vis = np.zeros(N, np.float32)
        vis[idx[seen]] = 1.0
        visibility[t] = vis

    shading_img = shading.reshape(T, H, W)
    albedo_img = albedo.reshape(T, H, W, 3)
    if colour is not None:
        albedo_img = (albedo_img * colour.astype(np.float32)).astype(np.float32)
    frames = albedo_img * shading_img[..., None]
    if noise is not None or compression is not None:
        frames = degrade_frames(frames, noise, compression, seed=seed)
    options = dict(palette=palette, light=light, light_colour=None if colour is None else tuple(colour),
                   noise=None if noise is None else tuple(noise),
                   compression=None if compression is None else tuple(compression), relief=relief)
    return SyntheticSequence(
        frames=frames,
        albedo=albedo_img,
        shading=shading_img,
        flow=flow.reshape(T - 1, H, W, 2),
        visibility=visibility.reshape(T - 1, H, W),
        depth=depth.reshape(T, H, W),
        object_id=object_id.reshape(T, H, W),
        kind=kind,
        seed=seed,
        options=options,
    )


# --------------------------------------------------------------------------- #
# the catalogue of evaluation kinds
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class SceneKind:
    """One evaluation kind: a motion and the options of :func:`render_sequence`."""

    motion: str
    palette: str = "colour"
    light: str = "soft"
    light_colour: object = None
    noise: tuple | None = None
    compression: tuple | None = None
    relief: float = 0.0

    @property
    def static_scene(self) -> bool:
        """Scene and camera still, the light moving: where the Weiss median applies."""
        return self.motion in STATIC_SCENE_MOTIONS


#: The named evaluation kinds.  The first four are the project's original
#: kinds (``render_kind(name) == render_sequence(name)``); the others span what
#: people film: achromatic and near-achromatic albedo (grey checkerboards,
#: stripes, print, dark materials), hard cast shadows from point bulbs with
#: little ambient light, coloured light, sensor noise and compression, and the
#: motions ``turning_objects`` (objects turning in place under a low static
#: lamp), ``camera_light`` (a lamp on the moving camera), ``fast_light`` (a
#: lamp orbiting 70-100 degrees a frame) and ``two_lights_orbit`` (two static
#: lamps, the camera orbiting the objects).  The ``ground`` kinds put a long
#: straight step between two large flat grey materials on the floor (a pale
#: path across a dark lawn), the case of street footage.  The ``relief`` kind
#: bumps every surface finely (a hammered or sculpted finish), so that the
#: steps of its shading change as the key lamp moves (the fill holds still).
SCENE_KINDS = {
    "free_camera": SceneKind("free_camera"),
    "objects_camera": SceneKind("objects_camera"),
    "static_moving_light": SceneKind("static_moving_light"),
    "rotating_shadows": SceneKind("rotating_shadows"),
    "grey_turning_hard": SceneKind("turning_objects", "grey", "hard"),
    "mixed_turning_hard": SceneKind("turning_objects", "mixed", "hard"),
    "mixed_moving_light_hard": SceneKind("static_moving_light", "mixed", "hard"),
    "mixed_objects_hard": SceneKind("objects_camera", "mixed", "hard"),
    "mixed_camera_light_hard": SceneKind("camera_light", "mixed", "hard"),
    "mixed_fast_light_hard": SceneKind("fast_light", "mixed", "hard"),
    "mixed_two_lights_orbit_hard": SceneKind("two_lights_orbit", "mixed", "hard"),
    "grey_moving_light_soft": SceneKind("static_moving_light", "grey"),
    "grey_rotating_hard": SceneKind("rotating_shadows", "grey", "hard"),
    "grey_two_lights_orbit_soft": SceneKind("two_lights_orbit", "grey"),
    "grey_free_camera_noisy": SceneKind("free_camera", "grey", noise=("gaussian", 0.01),
                                        compression=("jpeg", 80)),
    "colour_turning_warm_light": SceneKind("turning_objects", light_colour="random"),
    "colour_fast_light_noisy": SceneKind("fast_light", noise=("poisson", 400.0), compression=("jpeg", 70)),
    "ground_turning_soft": SceneKind("turning_objects", "ground"),
    "ground_objects_soft": SceneKind("objects_camera", "ground"),
    "grey_turning_noisy": SceneKind("turning_objects", "grey", noise=("poisson", 400.0), compression=("jpeg", 85)),
    "grey_relief_fast_light": SceneKind("fast_light", "grey", relief=0.35),
}


def scene_kinds(suite: str = "all") -> tuple[str, ...]:
    """Names of :data:`SCENE_KINDS`: ``"classic"`` (the four of :data:`KINDS`),
    ``"new"`` (the others), ``"all"``, ``"static"`` (static scene, moving
    light), ``"achromatic"`` (grey palette) or ``"hard"`` (hard light)."""
    pick = {
        "classic": lambda n, k: n in KINDS,
        "new": lambda n, k: n not in KINDS,
        "all": lambda n, k: True,
        "static": lambda n, k: k.static_scene,
        "achromatic": lambda n, k: k.palette == "grey",
        "hard": lambda n, k: k.light == "hard",
    }
    if suite not in pick:
        raise ValueError(f"unknown suite {suite!r}; expected one of {', '.join(pick)}")
    return tuple(n for n, k in SCENE_KINDS.items() if pick[suite](n, k))


def render_kind(name: str, n_frames: int = 8, size: tuple[int, int] = (240, 320),
                seed: int = 0) -> SyntheticSequence:
    """Render the evaluation kind ``name`` of :data:`SCENE_KINDS`.

    Seed 0 of every kind is for reporting only (``perf/accuracy.py``): choose
    weights, thresholds and designs on other seeds.  The scene is that of
    ``render_sequence(kind.motion, ..., seed)`` with the kind's options; the
    returned sequence's ``options["name"]`` is ``name``.

    Examples
    --------
    >>> seq = render_kind("grey_turning_hard", n_frames=2, size=(24, 32), seed=1)
    >>> seq.kind, seq.options["palette"], seq.options["light"]
    ('turning_objects', 'grey', 'hard')
    """
    if not isinstance(name, str) or name not in SCENE_KINDS:
        raise ValueError(f"unknown scene kind {name!r}; expected one of {', '.join(SCENE_KINDS)}")
    k = SCENE_KINDS[name]
    seq = render_sequence(k.motion, n_frames, size, seed, palette=k.palette, light=k.light,
                          light_colour=k.light_colour, noise=k.noise, compression=k.compression,
                          relief=k.relief)
    seq.options["name"] = name
    return seq
