"""Lambertian synthetic video sequences with exact ground truth.

A small ray caster (per pixel, vectorised NumPy) renders a room -- a textured
floor and back wall -- holding a few spheres, boxes and cylinders, lit by an
ambient term and grey (white) directional or point lights with cast shadows.
Every surface carries a solid texture defined in its own object coordinates,
so a surface point keeps its albedo as it moves: albedo is exactly constant
along the true flow, which is what the temporal albedo term of the paper
(Eq. 4) assumes.

The image formation is the paper's model (Eq. 1, ``i = a * s``)::

    frames[t]  = albedo[t] * shading[t][..., None]             (linear RGB)
    shading(x) = ambient + sum_l  k_l * max(n . l, 0) * V_l(x) * falloff_l(x)

with ``V_l`` the visibility of light ``l`` (a shadow ray against the objects).

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
  and shadow edges are pixel-sharp.
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

Sequence kinds (:data:`KINDS`)
------------------------------
``free_camera``
    Static objects; the camera translates and rotates (yaw, pitch, roll) along
    a smooth path while the key directional light swings strongly in azimuth
    and elevation from frame to frame.
``objects_camera``
    Objects slide back and forth on the floor (spheres roll without slipping,
    boxes and cylinders also turn about the vertical) while the camera
    translates without rotating; fixed lights.
``static_moving_light``
    Static scene and camera (flow exactly zero, visibility one everywhere);
    a point light circles above the scene, so shading and shadows change.
``rotating_shadows``
    Static camera and light; boxes turn about the vertical, tilted cylinders
    precess, spheres spin, and a bar floating above the scene turns, so cast
    shadows sweep over textured floor, wall and objects.

Nothing here is used by the solver; it produces test and evaluation data.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KINDS", "SyntheticSequence", "render_sequence"]

KINDS = ("free_camera", "objects_camera", "static_moving_light", "rotating_shadows")

TEXTURE_KINDS = ("patches", "stripes", "noise", "uniform")

ALBEDO_MIN = 0.03
AMBIENT = 0.06
FOCAL_PER_WIDTH = 0.9
_EPS_T = 1e-6           # smallest accepted ray parameter
_DEPTH_TOL = 1e-4       # relative depth tolerance of the visibility test


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
        Grey linear shading, ``>= AMBIENT`` (0.06) and ``<= 1``.
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
        One of :data:`KINDS`.
    seed : int
        Seed of the scene and its motion.
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

    def frames_srgb8(self) -> np.ndarray:
        """Frames encoded with the sRGB transfer function, (T, H, W, 3) uint8."""
        x = np.clip(self.frames.astype(np.float64), 0.0, 1.0)
        srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
        return np.round(srgb * 255.0).astype(np.uint8)


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

    def __init__(self, kind: str, rng, scale: float = 1.0):
        self.kind = kind
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

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """Albedo (N, 3) at points ``q`` (N, 3) in object coordinates."""
        p = _mul(q, self.rot)
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


@dataclass
class _Light:
    """Grey light: ``vectors[t]`` is the unit direction towards the light
    (directional) or its position (point); point lights fall off as
    ``d0^2 / (d0^2 + dist^2)`` so that their contribution never exceeds
    ``intensity``."""

    kind: str
    vectors: np.ndarray  # (T, 3)
    intensity: float
    d0: float = 3.0


@dataclass
class _Scene:
    objects: list
    lights: list
    cam_rot: np.ndarray     # (T, 3, 3) world -> camera
    cam_pos: np.ndarray     # (T, 3)


# --------------------------------------------------------------------------- #
# scene construction
# --------------------------------------------------------------------------- #
def _camera_rotation(yaw, pitch, roll) -> np.ndarray:
    """World -> camera rotation; yaw about world Y, pitch down > 0, roll about z."""
    base = np.diag([1.0, -1.0, 1.0])  # camera y points down
    c2w = _axis_angle([0, 1, 0], yaw) @ _axis_angle([1, 0, 0], pitch) \
        @ _axis_angle([0, 0, 1], roll) @ base
    return c2w.T


def _direction(azimuth, elevation) -> np.ndarray:
    """Unit vector towards a light at ``azimuth`` (in the floor plane, from +x
    towards +z) and ``elevation`` above the floor, radians."""
    return np.array([np.cos(elevation) * np.cos(azimuth), np.sin(elevation),
                     np.cos(elevation) * np.sin(azimuth)])


def _segment_distance(a0, a1, b0, b1) -> float:
    s = np.linspace(0.0, 1.0, 33)
    pa = a0 + s[:, None] * (a1 - a0)
    pb = b0 + s[:, None] * (b1 - b0)
    return float(np.linalg.norm(pa[:, None] - pb[None], axis=-1).min())


def _build_scene(kind: str, n_frames: int, rng) -> _Scene:
    T = n_frames
    tt = np.arange(T, dtype=np.float64)
    z_wall = rng.uniform(5.5, 6.5)
    cam_height = rng.uniform(1.4, 1.8)
    cam_z = -1.8
    pitch0 = np.deg2rad(rng.uniform(12.0, 17.0))
    yaw0 = np.deg2rad(rng.uniform(-4.0, 4.0))

    # textures: every kind appears, in a seed-dependent order
    order = list(rng.permutation(len(TEXTURE_KINDS)))

    def next_texture(scale=1.0):
        if not order:
            order.extend(rng.permutation(len(TEXTURE_KINDS)))
        return _Texture(TEXTURE_KINDS[order.pop(0)], rng, scale)

    identity = np.broadcast_to(np.eye(3), (T, 3, 3))
    wall_rot = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])  # local +y -> world -z
    objects = [
        # coarser textures on the floor and wall limit aliasing at grazing angles
        _Object("plane", (), next_texture(1.8), identity, np.zeros((T, 3)), casts_shadow=False),
        _Object("plane", (), next_texture(1.5), np.broadcast_to(wall_rot, (T, 3, 3)),
                np.broadcast_to([0.0, 0.0, z_wall], (T, 3)), casts_shadow=False),
    ]

    # ---- objects: shape, size, footprint, rest pose, then motion per kind
    n_obj = int(rng.integers(4, 7))
    shapes = ["sphere", "box", "cylinder"] + list(rng.choice(["sphere", "box", "cylinder"], n_obj - 3))
    shapes = [shapes[i] for i in rng.permutation(n_obj)]
    placed = []  # (segment start, segment end, footprint radius)
    for shape in shapes:
        if shape == "sphere":
            size = np.array([rng.uniform(0.3, 0.55)])
            foot = size[0]
            rest_y = size[0]
        elif shape == "box":
            size = rng.uniform(0.2, 0.45, 3)
            foot = float(np.hypot(size[0], size[2]))
            rest_y = size[1]
        else:
            size = np.array([rng.uniform(0.18, 0.35),
                             rng.uniform(0.3, 0.5 if kind == "rotating_shadows" else 0.6)])
            foot = size[0]
            rest_y = size[1]
        tilt = 0.0
        if kind == "rotating_shadows" and shape == "cylinder":
            tilt = np.deg2rad(rng.uniform(20.0, 40.0))
            foot = size[1] * np.sin(tilt) + size[0] * np.cos(tilt)
            rest_y = size[1] * np.cos(tilt) + size[0] * np.sin(tilt)

        amp, direction = 0.0, np.zeros(3)
        if kind == "objects_camera":
            amp = rng.uniform(0.2, 0.4)
            a = rng.uniform(0, 2 * np.pi)
            direction = np.array([np.cos(a), 0.0, np.sin(a)])
        for _ in range(200):
            z = rng.uniform(0.9, z_wall - 1.3)
            half = 0.42 * (z - cam_z)
            x = rng.uniform(-half + foot, half - foot) if half > foot else 0.0
            c = np.array([x, rest_y, z])
            s0, s1 = c - amp * direction, c + amp * direction
            if max(s0[2], s1[2]) + foot > z_wall - 0.2 or min(s0[2], s1[2]) < 0.6:
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
        elif kind == "rotating_shadows":
            rate = np.deg2rad(rng.uniform(6.0, 12.0)) * rng.choice([-1, 1])
            axis = _unit(rng.normal(size=3)) if shape == "sphere" else np.array([0.0, 1.0, 0.0])
            rots = np.stack([_axis_angle(axis, rate * k) @ rot0 for k in tt])
        objects.append(_Object(shape, size, next_texture(), rots, trans))

    if kind == "rotating_shadows":  # a bar floating above everything (tops < 1.3), turning
        size = np.array([rng.uniform(0.9, 1.2), 0.05, rng.uniform(0.08, 0.14)])
        c = np.array([rng.uniform(-0.5, 0.5), rng.uniform(1.5, 1.7), rng.uniform(2.2, 3.2)])
        rate = np.deg2rad(rng.uniform(7.0, 11.0)) * rng.choice([-1, 1])
        a0 = rng.uniform(0, 2 * np.pi)
        rots = np.stack([_axis_angle([0, 1, 0], a0 + rate * k) for k in tt])
        objects.append(_Object("box", size, next_texture(), rots, np.broadcast_to(c, (T, 3))))

    # ---- camera path
    cam_pos = np.broadcast_to([0.0, cam_height, cam_z], (T, 3)).copy()
    yaw = np.full(T, yaw0)
    pitch = np.full(T, pitch0)
    roll = np.zeros(T)
    if kind in ("free_camera", "objects_camera"):
        amp = np.array([0.45, 0.12, 0.35]) if kind == "free_camera" else np.array([0.35, 0.08, 0.3])
        omega = rng.uniform(0.18, 0.3, 3)
        phase = rng.uniform(0, 2 * np.pi, 3)
        cam_pos = cam_pos + amp * np.sin(omega * tt[:, None] + phase)
    if kind == "free_camera":
        amp = np.deg2rad([7.0, 3.0, 3.0])
        omega = rng.uniform(0.2, 0.3, 3)
        phase = rng.uniform(0, 2 * np.pi, 3)
        yaw = yaw + amp[0] * np.sin(omega[0] * tt + phase[0])
        pitch = pitch + amp[1] * np.sin(omega[1] * tt + phase[1])
        roll = roll + amp[2] * np.sin(omega[2] * tt + phase[2])
    cam_rot = np.stack([_camera_rotation(y, p, r) for y, p, r in zip(yaw, pitch, roll)])

    # ---- lights (all from the camera side of the wall: azimuth in (-pi, 0))
    fill = _Light("directional", np.broadcast_to(
        _direction(np.deg2rad(rng.uniform(-120, -60)), np.deg2rad(rng.uniform(55, 75))), (T, 3)), 0.14)
    key_az = np.deg2rad(rng.uniform(-150, -30))
    key_el = np.deg2rad(rng.uniform(40, 60))
    if kind == "free_camera":
        az = np.deg2rad(-90.0 + 62.0 * np.sin(0.45 * tt + rng.uniform(0, 2 * np.pi)))
        el = np.deg2rad(45.0 + 17.0 * np.sin(0.35 * tt + rng.uniform(0, 2 * np.pi)))
        key = _Light("directional", np.stack([_direction(a, e) for a, e in zip(az, el)]), 0.72)
    elif kind == "static_moving_light":
        centre = np.array([0.0, 0.0, 0.5 * z_wall])
        theta = rng.uniform(0, 2 * np.pi) + 0.5 * rng.choice([-1, 1]) * tt
        radius = rng.uniform(1.8, 2.3)
        height = 2.9 + 0.3 * np.sin(0.7 * tt)
        pos = centre + np.stack([radius * np.cos(theta), height, radius * np.sin(theta)], axis=1)
        key = _Light("point", pos, 0.72, d0=rng.uniform(2.8, 3.4))
    else:
        if kind == "rotating_shadows":
            key_el = np.deg2rad(rng.uniform(50, 62))
        key = _Light("directional", np.broadcast_to(_direction(key_az, key_el), (T, 3)), 0.72)
    return _Scene(objects, [key, fill], cam_rot, cam_pos)


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


def _shade(scene, t, p, n, which):
    """Shading (N,) of world points ``p`` with normals ``n`` owned by objects
    ``which`` (the paper's grey shading s; Lambertian with cast shadows)."""
    shading = np.full(len(p), AMBIENT)
    for light in scene.lights:
        if light.kind == "directional":
            l = np.broadcast_to(light.vectors[t], p.shape)
            dist = np.full(len(p), np.inf)
        else:
            l = light.vectors[t] - p
            dist = np.sqrt(np.einsum("ij,ij->i", l, l))
            l = l / dist[:, None]
        ndotl = np.einsum("ij,ij->i", n, l)
        idx = np.flatnonzero(ndotl > 0)
        p_i, l_i, w_i, dist_i = p[idx], l[idx], which[idx], dist[idx]
        blocked = np.zeros(len(idx), dtype=bool)
        for k, obj in enumerate(scene.objects):
            if obj.casts_shadow:
                # convex objects never shadow themselves where n.l > 0
                blocked |= (obj.intersect(t, p_i, l_i) < dist_i) & (w_i != k)
        lit = idx[~blocked]
        gain = light.intensity * ndotl[lit]
        if light.kind == "point":
            gain = gain * light.d0 ** 2 / (light.d0 ** 2 + dist[lit] ** 2)
        shading[lit] += gain
    return shading


def _project(scene, t, p, focal, cx, cy):
    pc = _mul(p - scene.cam_pos[t], scene.cam_rot[t].T)
    z = pc[:, 2]
    return focal * pc[:, 0] / z + cx, focal * pc[:, 1] / z + cy, z


def _check_args(kind, n_frames, size, seed):
    if not isinstance(kind, str) or kind not in KINDS:
        raise ValueError(f"unknown kind {kind!r}; expected one of {', '.join(KINDS)}")
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


def render_sequence(kind: str, n_frames: int = 8, size: tuple[int, int] = (240, 320),
                    seed: int = 0) -> SyntheticSequence:
    """Render a Lambertian sequence with exact albedo, shading, flow and visibility.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS` (see the module docstring).
    n_frames : int
        Number of frames T >= 2.
    size : (H, W)
        Image size in pixels, both >= 16.  The scene and its motion depend on
        ``seed`` only, so a larger size renders the same sequence with flow
        scaled by the size ratio.
    seed : int
        Seed of ``numpy.random.default_rng`` for the scene and motion.

    Returns
    -------
    SyntheticSequence
        ``frames = albedo * shading[..., None]`` in linear RGB (paper Eq. 1)
        with its ground truth; see :class:`SyntheticSequence`.

    Examples
    --------
    >>> seq = render_sequence("static_moving_light", n_frames=3, size=(48, 64))
    >>> seq.frames.shape, seq.flow.shape
    ((3, 48, 64, 3), (2, 48, 64, 2))
    >>> bool(abs(seq.flow).max() == 0.0)
    True
    """
    T, H, W, seed = _check_args(kind, n_frames, size, seed)
    scene = _build_scene(kind, T, np.random.default_rng(seed))
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
            n[m] = _mul(_normal(obj.shape, obj.size, q), obj.rotations[t].T)
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
    return SyntheticSequence(
        frames=albedo_img * shading_img[..., None],
        albedo=albedo_img,
        shading=shading_img,
        flow=flow.reshape(T - 1, H, W, 2),
        visibility=visibility.reshape(T - 1, H, W),
        depth=depth.reshape(T, H, W),
        object_id=object_id.reshape(T, H, W),
        kind=kind,
        seed=seed,
    )
