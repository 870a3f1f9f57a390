"""Synthetic Lambertian sequences: image formation, ground-truth flow and
visibility, resolution scaling, determinism and input checks."""
import numpy as np
import pytest

import ivkernels.evaluation.synthetic as syn
from ivkernels.evaluation.synthetic import (AMBIENT, HARD_AMBIENT, KINDS, MOTION_KINDS, NEAR_GREY_TINT, SCENE_KINDS,
                                            TEXTURE_KINDS, SyntheticSequence, _build_scene, degrade_frames,
                                            render_kind, render_sequence, scene_kinds)

SIZE = (72, 96)
N_FRAMES = 4


@pytest.fixture(scope="module")
def sequences():
    return {kind: render_sequence(kind, n_frames=N_FRAMES, size=SIZE, seed=1) for kind in MOTION_KINDS}


def bilinear(img, x, y):
    """Sample ``img`` (H, W[, C]) at float coordinates (pixel centres at
    integers); coordinates are clamped to the image."""
    h, w = img.shape[:2]
    x = np.clip(x, 0, w - 1)
    y = np.clip(y, 0, h - 1)
    x0 = np.minimum(np.floor(x).astype(int), w - 2)
    y0 = np.minimum(np.floor(y).astype(int), h - 2)
    fx, fy = x - x0, y - y0
    if img.ndim == 3:
        fx, fy = fx[..., None], fy[..., None]
    return ((1 - fy) * ((1 - fx) * img[y0, x0] + fx * img[y0, x0 + 1])
            + fy * ((1 - fx) * img[y0 + 1, x0] + fx * img[y0 + 1, x0 + 1]))


def local_variation(img):
    """Largest absolute difference to any 8-neighbour, max over channels (H, W)."""
    if img.ndim == 2:
        img = img[..., None]
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = img.shape[:2]
    out = np.zeros((h, w))
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            shifted = p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
            out = np.maximum(out, np.abs(shifted - img).max(axis=-1))
    return out


def test_shapes_dtypes_and_ranges(sequences):
    T, (H, W) = N_FRAMES, SIZE
    for kind, s in sequences.items():
        assert isinstance(s, SyntheticSequence) and s.kind == kind and s.seed == 1
        assert s.frames.shape == (T, H, W, 3) and s.frames.dtype == np.float32
        assert s.albedo.shape == (T, H, W, 3) and s.albedo.dtype == np.float32
        assert s.shading.shape == (T, H, W) and s.shading.dtype == np.float32
        assert s.flow.shape == (T - 1, H, W, 2) and s.flow.dtype == np.float32
        assert s.visibility.shape == (T - 1, H, W) and s.visibility.dtype == np.float32
        assert s.depth.shape == (T, H, W) and s.depth.dtype == np.float32
        assert s.object_id.shape == (T, H, W)
        assert s.albedo.min() >= 0.03 and s.albedo.max() <= 1.0
        assert s.shading.min() >= np.float32(AMBIENT) and s.shading.max() <= 1.0
        assert s.frames.min() > 0.0 and s.frames.max() <= 1.0
        assert s.depth.min() > 0.0
        assert set(np.unique(s.visibility)) <= {0.0, 1.0}
        assert np.isfinite(s.flow).all()


def test_frames_are_albedo_times_shading(sequences):
    for s in sequences.values():
        np.testing.assert_array_equal(s.frames, s.albedo * s.shading[..., None])


@pytest.mark.parametrize("kind", MOTION_KINDS)
def test_every_texture_kind_is_used(kind):
    scene = _build_scene(kind, 2, np.random.default_rng(4))
    assert {obj.texture.kind for obj in scene.objects} == set(TEXTURE_KINDS)


def test_albedo_has_flat_regions_and_edges(sequences):
    s = sequences["free_camera"]
    assert len(np.unique(s.albedo[0].reshape(-1, 3), axis=0)) > 50
    var = local_variation(s.albedo[0])
    assert (var < 0.01).mean() > 0.1 and (var > 0.1).mean() > 0.02


@pytest.mark.parametrize("kind", MOTION_KINDS)
def test_albedo_is_constant_along_true_flow(sequences, kind):
    """Warp albedo t+1 back by the flow: equals albedo t where visible and
    where the albedo is locally smooth (bilinear interpolation across a texture
    edge cannot reproduce the edge, so such pixels are left out)."""
    s = sequences[kind]
    H, W = SIZE
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    errors, used = [], 0
    for t in range(N_FRAMES - 1):
        x1 = xs + s.flow[t, ..., 0]
        y1 = ys + s.flow[t, ..., 1]
        warped = bilinear(s.albedo[t + 1].astype(np.float64), x1, y1)
        smooth_t = local_variation(s.albedo[t]) < 0.03
        smooth_t1 = bilinear(local_variation(s.albedo[t + 1]), x1, y1) < 0.03
        mask = (s.visibility[t] == 1) & smooth_t & smooth_t1
        used += mask.sum()
        errors.append(np.abs(warped - s.albedo[t]).max(axis=-1)[mask])
    err = np.concatenate(errors)
    assert used > 0.25 * (N_FRAMES - 1) * H * W
    assert np.median(err) < 5e-4
    assert np.percentile(err, 95) < 5e-3


@pytest.mark.parametrize("kind", MOTION_KINDS)
def test_visible_points_land_on_the_same_surface(sequences, kind):
    s = sequences[kind]
    H, W = SIZE
    ys, xs = np.mgrid[0:H, 0:W]
    for t in range(N_FRAMES - 1):
        vis = s.visibility[t] == 1
        x1 = np.clip(np.rint(xs + s.flow[t, ..., 0]).astype(int), 0, W - 1)
        y1 = np.clip(np.rint(ys + s.flow[t, ..., 1]).astype(int), 0, H - 1)
        same = s.object_id[t + 1][y1, x1] == s.object_id[t]
        assert same[vis].mean() > 0.98
        assert vis.mean() > 0.8  # occlusions and exits are a small part of the image


def test_static_moving_light_has_zero_flow_and_changing_shading(sequences):
    s = sequences["static_moving_light"]
    assert np.all(s.flow == 0.0)
    assert np.all(s.visibility == 1.0)
    for t in range(1, N_FRAMES):
        np.testing.assert_array_equal(s.albedo[t], s.albedo[0])
        np.testing.assert_array_equal(s.depth[t], s.depth[0])
        assert np.abs(s.shading[t] - s.shading[t - 1]).mean() > 0.01


@pytest.mark.parametrize("kind", ["free_camera", "objects_camera", "rotating_shadows"])
def test_moving_kinds_move_and_occlude(sequences, kind):
    s = sequences[kind]
    mag = np.linalg.norm(s.flow, axis=-1)
    assert mag.max() > 0.5
    assert (s.visibility == 0).any()
    if kind == "rotating_shadows":  # static camera: the background stays put
        assert np.all(mag[s.object_id[:-1] <= 1] == 0.0)
        assert np.abs(np.diff(s.shading, axis=0)).max() > 0.2   # shadows move
    else:
        assert np.median(mag) > 0.5


def test_free_camera_light_changes_strongly(sequences):
    s = sequences["free_camera"]
    floor = s.object_id == 0
    means = [s.shading[t][floor[t]].mean() for t in range(N_FRAMES)]
    assert np.ptp(means) > 0.15 * np.mean(means)   # relative: the exposure is arbitrary


def _check_flow_scaling(kind, lo_size, seed=2, n_frames=2):
    lo = render_sequence(kind, n_frames=n_frames, size=lo_size, seed=seed)
    hi = render_sequence(kind, n_frames=n_frames, size=(2 * lo_size[0], 2 * lo_size[1]), seed=seed)
    H, W = lo_size
    blocks = lambda a: a.reshape(n_frames - 1, H, 2, W, 2, *a.shape[3:])  # noqa: E731
    hi_flow = blocks(hi.flow).mean(axis=(2, 4)) / 2.0
    hi_vis = blocks(hi.visibility).min(axis=(2, 4))
    ids = blocks(hi.object_id[:-1])
    same_id = (ids.min(axis=(2, 4)) == ids.max(axis=(2, 4))) & (ids[:, :, 0, :, 0] == lo.object_id[:-1])
    smooth = np.stack([local_variation(f) < 0.5 for f in lo.flow])
    mask = (lo.visibility == 1) & (hi_vis == 1) & same_id & smooth
    assert mask.mean() > 0.5
    diff = np.abs(hi_flow - lo.flow)[mask]
    assert np.percentile(np.linalg.norm(lo.flow, axis=-1)[mask], 99) > 0.01 * W  # not trivial
    assert np.median(diff) < 1e-3
    assert np.percentile(diff, 95) < 1e-2


@pytest.mark.parametrize("kind", ["free_camera", "objects_camera"])
def test_flow_doubles_at_twice_the_resolution(kind):
    _check_flow_scaling(kind, (48, 64))


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["free_camera", "objects_camera", "rotating_shadows"])
def test_flow_doubles_at_640x480(kind):
    _check_flow_scaling(kind, (240, 320))


@pytest.mark.slow
def test_renders_at_640x480():
    s = render_sequence("rotating_shadows", n_frames=3, size=(480, 640), seed=5)
    assert s.frames.shape == (3, 480, 640, 3)
    np.testing.assert_array_equal(s.frames, s.albedo * s.shading[..., None])
    assert s.albedo.min() >= 0.03 and s.frames.max() <= 1.0


def test_deterministic_by_seed():
    a = render_sequence("objects_camera", n_frames=3, size=(32, 40), seed=7)
    b = render_sequence("objects_camera", n_frames=3, size=(32, 40), seed=7)
    for name in ("frames", "albedo", "shading", "flow", "visibility", "depth", "object_id"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_different_seeds_differ():
    a = render_sequence("free_camera", n_frames=2, size=(32, 40), seed=0)
    b = render_sequence("free_camera", n_frames=2, size=(32, 40), seed=1)
    assert not np.array_equal(a.frames, b.frames)
    assert not np.array_equal(a.flow, b.flow)


def test_frames_srgb8(sequences):
    s = sequences["free_camera"]
    out = s.frames_srgb8()
    assert out.dtype == np.uint8 and out.shape == s.frames.shape
    # the sRGB curve is monotonic and maps linear 0.5 to ~188
    order = np.argsort(s.frames.ravel())
    assert np.all(np.diff(out.ravel()[order].astype(int)) >= 0)
    mid = SyntheticSequence(np.full((1, 1, 1, 3), 0.5, np.float32), *([None] * 6), "x", 0)
    assert mid.frames_srgb8()[0, 0, 0, 0] == 188


@pytest.mark.parametrize("args, error, match", [
    (dict(kind="spinning"), ValueError, "free_camera, objects_camera"),
    (dict(kind=3), ValueError, "unknown kind"),
    (dict(n_frames=1), ValueError, "n_frames must be >= 2"),
    (dict(n_frames=2.0), TypeError, "n_frames must be an int"),
    (dict(size=(15, 64)), ValueError, "H must be >= 16"),
    (dict(size=(64, 8)), ValueError, "W must be >= 16"),
    (dict(size=(64,)), ValueError, r"pair \(H, W\)"),
    (dict(size=(64.0, 64)), TypeError, "H must be an int"),
    (dict(seed="0"), TypeError, "seed must be an int"),
])
def test_bad_input_raises(args, error, match):
    kwargs = dict(kind="free_camera", n_frames=2, size=(32, 32), seed=0)
    kwargs.update(args)
    with pytest.raises(error, match=match):
        render_sequence(**kwargs)


# --------------------------------------------------------------------------- #
# area lights: falloff, soft shadows, exposure, consistency
# --------------------------------------------------------------------------- #
def _floor_scene(*objects, light):
    """A scene of the floor, the given objects and one light (no camera)."""
    floor = syn._Object("plane", (), None, np.eye(3)[None], np.zeros((1, 3)), casts_shadow=False)
    return syn._Scene([floor, *objects], [light], np.eye(3)[None], np.zeros((1, 3)))


def _disc_light(centre, radius, n_samples=32, normal=(0.0, -1.0, 0.0)):
    return syn._AreaLight(np.array([centre], float), np.array([normal], float), radius,
                          syn._disc_pattern(n_samples, np.random.default_rng(0)))


def _floor_points(x, z):
    p = np.stack([x, np.zeros_like(x), z], axis=1)
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape)
    return p, n, np.zeros(len(p), np.int64)


def test_area_light_falls_off_with_inverse_square():
    h = 2.5
    light = _disc_light((0.3, h, -0.2), 1e-4)
    x = np.linspace(-4.0, 4.0, 41)
    p, n, which = _floor_points(x, 0.5 * x)
    e = syn._irradiance(_floor_scene(light=light), light, 0, p, n, which)
    d2 = (x - 0.3) ** 2 + (0.5 * x + 0.2) ** 2 + h ** 2
    np.testing.assert_allclose(e, h * h / d2 ** 2, rtol=1e-5)   # cos * cos / d^2
    assert e.max() / e.min() > 4.0                               # a strong gradient


def test_area_light_near_field_is_clamped():
    radius = 0.5
    light = _disc_light((0.0, 0.05, 0.0), radius)
    p, n, which = _floor_points(np.linspace(-0.3, 0.3, 7), np.zeros(7))
    e = syn._irradiance(_floor_scene(light=light), light, 0, p, n, which)
    assert np.all(np.isfinite(e)) and np.all(e > 0) and e.max() <= 1.0 / radius ** 2


def test_shadow_of_a_sphere_has_umbra_and_penumbra():
    sphere = syn._Object("sphere", (0.5,), None, np.eye(3)[None], np.array([[0.0, 1.5, 0.0]]))
    light = _disc_light((0.0, 3.5, 0.0), 0.3)
    x = np.linspace(0.0, 3.0, 601)
    p, n, which = _floor_points(x, np.zeros_like(x))
    scene = _floor_scene(sphere, light=light)
    lit = syn._irradiance(scene, light, 0, p, n, which)
    full = syn._irradiance(scene, light, 0, p, n, which, shadows=False)
    v = lit / full                                    # visible fraction of the lamp
    assert v[0] == 0.0 and v[-1] == 1.0
    partial = v[(v > 0) & (v < 1)]
    assert len(np.unique(partial)) >= 24              # many steps, not one hard edge
    # tangents from the disc's rim (x = +-0.3) to the sphere: the umbra ends at
    # x = 0.654 and the penumbra at x = 1.175 (a little inside with 32 samples)
    assert 0.654 <= x[np.argmax(v > 0)] < 0.75
    assert 1.05 < x[np.argmax(v == 1.0)] <= 1.18


@pytest.mark.parametrize("shape, size", [("sphere", (0.6,)), ("box", (0.5, 0.3, 0.4)),
                                         ("cylinder", (0.4, 0.5))])
def test_shadow_rays_agree_with_ray_intersection(shape, size):
    rng = np.random.default_rng(3)
    obj = syn._Object(shape, size, None, syn._random_rotation(rng)[None], np.array([[0.2, 1.0, 0.1]]))
    p = rng.uniform(-2.0, 2.0, (300, 3)) * [1.0, 0.0, 1.0]
    y = rng.uniform(-1.5, 1.5, (40, 3)) + [0.0, 2.8, 0.0]
    blocked = obj.occludes(0, p, y)                   # (S, M)
    assert blocked.shape == (40, 300) and 0.05 < blocked.mean() < 0.95
    o = np.repeat(p[None], 40, axis=0).reshape(-1, 3)
    d = (y[:, None] - p[None]).reshape(-1, 3)
    o_l = syn._mul(o - obj.translations[0], obj.rotations[0])
    d_l = syn._mul(d, obj.rotations[0])
    reference = syn._intersect(shape, obj.size, o_l, d_l) < 1.0
    assert (blocked.ravel() != reference).mean() < 1e-3


def test_irradiance_of_a_point_does_not_depend_on_the_others():
    """Element-wise per point: the same points in another order (and so in
    other chunks) give bitwise the same values."""
    scene = _build_scene("rotating_shadows", 2, np.random.default_rng(6))
    rng = np.random.default_rng(0)
    n_points = 2 * syn._CHUNK + 123
    p, n, which = _floor_points(rng.uniform(-2.5, 2.5, n_points), rng.uniform(0.5, 5.0, n_points))
    perm = rng.permutation(n_points)
    for light in scene.lights:
        e = syn._irradiance(scene, light, 1, p, n, which)
        np.testing.assert_array_equal(syn._irradiance(scene, light, 1, p[perm], n[perm], which[perm]), e[perm])
        assert (e < syn._irradiance(scene, light, 1, p, n, which, shadows=False)).any()


def test_static_background_keeps_its_shading_exactly(sequences):
    s = sequences["rotating_shadows"]          # static camera and lights
    background = (s.object_id[1:] <= 1) & (s.object_id[:-1] <= 1)
    same = s.shading[1:] == s.shading[:-1]
    assert same[background].mean() > 0.5
    assert not same[background].all()          # the soft shadows move


def test_exposure_does_not_depend_on_the_image_size():
    lo = render_sequence("static_moving_light", n_frames=2, size=(48, 64), seed=3)
    hi = render_sequence("static_moving_light", n_frames=2, size=(96, 128), seed=3)
    ys, xs = np.mgrid[0:48, 0:64].astype(np.float64)
    for t in range(2):
        hi_at_lo = bilinear(hi.shading[t].astype(np.float64), 2 * xs + 0.5, 2 * ys + 0.5)
        smooth = (local_variation(lo.shading[t]) < 0.01) & (lo.object_id[t] == hi.object_id[t][::2, ::2])
        assert smooth.mean() > 0.3
        ratio = hi_at_lo[smooth] / lo.shading[t][smooth]
        assert abs(np.median(ratio) - 1.0) < 2e-3 and np.percentile(np.abs(ratio - 1.0), 90) < 2e-2


@pytest.mark.parametrize("seed", range(4))
def test_crisp_textures_dominate(seed):
    for kind in KINDS:
        scene = _build_scene(kind, 2, np.random.default_rng(seed))
        kinds = [obj.texture.kind for obj in scene.objects]
        assert set(kinds[:2]) == {"patches", "stripes"}          # floor and wall
        assert kinds.count("noise") == 1 and kinds.count("uniform") == 1
        assert kinds.count("patches") + kinds.count("stripes") >= 4


def test_curved_objects_fill_much_of_the_frame(sequences):
    covered = []
    for kind, s in sequences.items():
        scene = _build_scene(kind, N_FRAMES, np.random.default_rng(1))
        curved = np.array([obj.shape in ("sphere", "cylinder") for obj in scene.objects])
        covered.append(curved[s.object_id].mean())
    assert np.mean(covered) > 0.1


# --------------------------------------------------------------------------- #
# what people film: palettes, hard light, coloured light, noise, new motions
# --------------------------------------------------------------------------- #
STYLE_SIZE = (45, 61)      # odd sizes


@pytest.fixture(scope="module")
def styled():
    """One scene (static_moving_light, seed 3) in every palette and light."""
    return {(p, lt): render_sequence("static_moving_light", n_frames=3, size=STYLE_SIZE, seed=3, palette=p, light=lt)
            for p in ("colour", "grey", "mixed", "ground") for lt in ("soft", "hard")}


def test_the_defaults_are_the_colour_soft_scene_and_the_classic_catalogue_entries():
    for kind in KINDS:
        a = render_sequence(kind, n_frames=2, size=(20, 28), seed=4)
        b = render_sequence(kind, n_frames=2, size=(20, 28), seed=4, palette="colour", light="soft")
        c = render_kind(kind, n_frames=2, size=(20, 28), seed=4)
        for f in ("frames", "albedo", "shading", "flow", "visibility", "depth", "object_id"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
            np.testing.assert_array_equal(getattr(a, f), getattr(c, f))
        assert c.options["name"] == kind and a.options["palette"] == "colour"


def test_palette_and_light_keep_the_geometry_and_motion(styled):
    ref = styled[("colour", "soft")]
    for s in styled.values():
        np.testing.assert_array_equal(s.depth, ref.depth)
        np.testing.assert_array_equal(s.object_id, ref.object_id)
        np.testing.assert_array_equal(s.flow, ref.flow)
        np.testing.assert_array_equal(s.frames, s.albedo * s.shading[..., None])


def _channel_ratio(albedo):
    return albedo.max(axis=-1) / albedo.min(axis=-1)


def test_grey_palette_is_achromatic_or_near_achromatic(styled):
    for light in ("soft", "hard"):
        a = styled[("grey", light)].albedo
        ratio = _channel_ratio(a)
        assert ratio.max() <= (1 + NEAR_GREY_TINT) / (1 - NEAR_GREY_TINT) + 1e-5
        assert (ratio == 1.0).mean() > 0.3                  # most surfaces exactly grey
        assert np.percentile(a.mean(axis=-1), 5) < 0.1      # dark materials and ink
        assert _channel_ratio(styled[("colour", light)].albedo).max() > 1.5


def test_mixed_palette_has_a_grey_checkerboard_floor_among_colours(styled):
    s = styled[("mixed", "soft")]
    floor = s.object_id == 0
    ratio = _channel_ratio(s.albedo)
    assert ratio[floor].max() <= (1 + NEAR_GREY_TINT) / (1 - NEAR_GREY_TINT) + 1e-5
    levels = np.unique(np.round(s.albedo[floor][:, 0], 6))
    assert len(levels) == 2 and levels[1] / levels[0] > 2.0      # two greys, a clear step
    assert ratio[~floor].max() > 1.5                              # coloured walls and objects


def test_ground_palette_is_a_pale_path_across_a_dark_uniform_ground():
    """Two flat grey materials on the floor, one dark (0.04-0.1) and one pale (0.45-0.8),
    each a large region, split by long straight edges; the rest is the grey palette."""
    for seed in (1, 2, 3):
        s = render_sequence("turning_objects", n_frames=2, size=(60, 80), seed=seed, palette="ground")
        floor = s.object_id[0] == 0
        grey = s.albedo[0][floor]
        assert _channel_ratio(grey).max() <= (1 + NEAR_GREY_TINT) / (1 - NEAR_GREY_TINT) + 1e-5
        levels, counts = np.unique(np.round(grey[:, 0], 6), return_counts=True)
        assert len(levels) <= 2 and 0.04 * 0.9 <= levels[0] <= 0.1 * 1.1
        if len(levels) == 2:
            assert 0.45 * 0.9 <= levels[1] <= 0.8 * 1.1
        dark = counts[0] / counts.sum()
        assert dark > 0.2                                            # a large dark region
    assert render_kind("ground_turning_soft", n_frames=2, size=(20, 28), seed=1).options["palette"] == "ground"


def test_hard_light_casts_shadows_with_no_direct_light(styled):
    s = styled[("grey", "hard")]
    assert s.shading.min() == np.float32(HARD_AMBIENT)
    # The floor faces the bulb above it everywhere, so where its shading is the ambient
    # term alone, a shadow ray was blocked: a cast shadow with zero direct light.
    floor = s.object_id == 0
    shadow = floor & (s.shading == np.float32(HARD_AMBIENT))
    assert shadow.mean() > 0.005
    lit = floor & ~shadow
    assert np.median(s.shading[lit]) > 3 * HARD_AMBIENT
    assert styled[("grey", "soft")].shading.min() >= np.float32(AMBIENT)


def test_point_light_shadow_of_a_sphere_is_hard():
    """A bulb, a sphere and a floor: a floor point is dark exactly when the segment to
    the bulb passes within the radius of the sphere's centre (no penumbra)."""
    T = 1
    eye = np.broadcast_to(np.eye(3), (T, 3, 3))
    sphere = syn._Object("sphere", [0.5], None, eye, np.broadcast_to([0.0, 1.0, 0.0], (T, 3)))
    floor = syn._Object("plane", (), None, eye, np.zeros((T, 3)), casts_shadow=False)
    bulb_at = np.array([0.3, 3.0, -0.2])
    bulb = syn._AreaLight(np.broadcast_to(bulb_at, (T, 3)), np.broadcast_to([0.0, -1.0, 0.0], (T, 3)), 0.0,
                          np.zeros((1, 2)), isotropic=True)
    scene = syn._Scene([floor, sphere], [bulb], np.broadcast_to(np.eye(3), (T, 3, 3)), np.zeros((T, 3)))
    rng = np.random.default_rng(0)
    p = np.stack([rng.uniform(-2, 2, 4000), np.zeros(4000), rng.uniform(-2, 2, 4000)], axis=1)
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape).copy()
    e = syn._irradiance(scene, bulb, 0, p, n, np.zeros(len(p), np.int32))
    v = bulb_at - p
    s = np.clip(((sphere.translations[0] - p) * v).sum(axis=1) / (v * v).sum(axis=1), 0, 1)
    dist = np.linalg.norm(p + s[:, None] * v - sphere.translations[0], axis=1)
    d2 = (v * v).sum(axis=1)
    expected = np.where(dist < 0.5, 0.0, v[:, 1] / np.sqrt(d2) / d2)     # cos / d^2, power 1
    clear = np.abs(dist - 0.5) > 1e-6
    np.testing.assert_allclose(e[clear], expected[clear], rtol=1e-5, atol=1e-9)
    assert (dist < 0.5).sum() > 50


def test_light_colour_is_folded_into_the_albedo():
    white = render_sequence("rotating_shadows", n_frames=2, size=(24, 33), seed=5)
    warm = render_sequence("rotating_shadows", n_frames=2, size=(24, 33), seed=5, light_colour=(1.0, 0.8, 0.5))
    np.testing.assert_array_equal(warm.shading, white.shading)
    np.testing.assert_allclose(warm.albedo, white.albedo * np.float32([1.0, 0.8, 0.5]), rtol=1e-6)
    np.testing.assert_array_equal(warm.frames, warm.albedo * warm.shading[..., None])
    tinted = render_sequence("rotating_shadows", n_frames=2, size=(24, 33), seed=5, light_colour="random")
    c = np.array(tinted.options["light_colour"])
    assert c.max() == 1.0 and 0.5 <= c.min() < 0.9
    np.testing.assert_allclose(tinted.albedo, white.albedo * c.astype(np.float32), rtol=1e-6)


@pytest.mark.parametrize("std", [0.005, 0.02])
def test_gaussian_noise_has_the_requested_std(std):
    frames = np.full((3, 41, 57, 3), 0.4, np.float32)
    noisy = degrade_frames(frames, noise=("gaussian", std), seed=7)
    d = (noisy - frames).astype(np.float64)
    assert abs(d.std() / std - 1) < 0.03 and abs(d.mean()) < 3 * std / np.sqrt(d.size)
    np.testing.assert_array_equal(noisy, degrade_frames(frames, noise=("gaussian", std), seed=7))
    assert not np.array_equal(noisy, degrade_frames(frames, noise=("gaussian", std), seed=8))


def test_poisson_noise_std_follows_the_signal():
    frames = np.concatenate([np.full((2, 30, 40, 3), 0.1), np.full((2, 30, 40, 3), 0.6)], axis=1)
    noisy = degrade_frames(frames, noise=("poisson", 500.0), seed=1)
    for rows, v in ((slice(0, 30), 0.1), (slice(30, 60), 0.6)):
        d = noisy[:, rows] - v
        assert abs(d.mean()) < 0.002
        assert abs(d.std() / np.sqrt(v / 500.0) - 1) < 0.05


def test_jpeg_compression_changes_frames_a_little_and_truth_not_at_all():
    clean = render_sequence("objects_camera", n_frames=2, size=(40, 56), seed=2, palette="grey")
    jpeg = render_sequence("objects_camera", n_frames=2, size=(40, 56), seed=2, palette="grey",
                           compression=("jpeg", 60))
    np.testing.assert_array_equal(jpeg.albedo, clean.albedo)
    np.testing.assert_array_equal(jpeg.shading, clean.shading)
    codes = syn.srgb_encode(jpeg.frames.astype(np.float64)) * 255.0
    assert np.abs(codes - np.round(codes)).max() < 1e-3                  # decoded 8-bit values
    err = np.abs(syn.srgb_encode(jpeg.frames.astype(np.float64)) - syn.srgb_encode(clean.frames.astype(np.float64)))
    assert 0.002 < err.mean() < 0.05
    noisy = render_sequence("objects_camera", n_frames=2, size=(40, 56), seed=2, palette="grey",
                            noise=("gaussian", 0.01))
    assert abs((noisy.frames - clean.frames).std() - 0.01) < 0.002


def test_new_motion_kinds_move_as_described(sequences):
    fast = sequences["fast_light"]
    assert np.all(fast.flow == 0.0) and np.all(fast.visibility == 1.0)
    step = [np.abs(fast.shading[t + 1] - fast.shading[t]).mean() for t in range(N_FRAMES - 1)]
    slow = sequences["static_moving_light"]
    assert np.mean(step) > np.mean([np.abs(np.diff(slow.shading, axis=0)).mean()])
    turning = sequences["turning_objects"]
    mag = np.linalg.norm(turning.flow, axis=-1)
    assert np.all(mag[turning.object_id[:-1] <= 1] == 0.0) and mag.max() > 0.5     # static camera
    orbit = sequences["two_lights_orbit"]
    assert np.median(np.linalg.norm(orbit.flow, axis=-1)) > 0.5
    scene = _build_scene("two_lights_orbit", N_FRAMES, np.random.default_rng(1))
    assert len([lt for lt in scene.lights if lt.role == "key"]) == 2
    assert all(np.ptp(lt.centres, axis=0).max() == 0.0 for lt in scene.lights)      # static lamps
    cam = _build_scene("camera_light", N_FRAMES, np.random.default_rng(1))
    offset = cam.lights[0].centres - cam.cam_pos
    in_camera = np.einsum("tk,tjk->tj", offset, cam.cam_rot)                         # world -> camera
    np.testing.assert_allclose(in_camera, np.broadcast_to([0.25, -0.3, 0.0], in_camera.shape), atol=1e-12)


def test_catalogue_entries_render_and_suites_partition():
    assert set(scene_kinds("classic")) == set(KINDS)
    assert set(scene_kinds("classic")) | set(scene_kinds("new")) == set(SCENE_KINDS)
    assert not set(scene_kinds("classic")) & set(scene_kinds("new"))
    assert {SCENE_KINDS[n].motion for n in SCENE_KINDS} == set(MOTION_KINDS)
    assert all(SCENE_KINDS[n].static_scene for n in scene_kinds("static"))
    for name in scene_kinds("new"):
        s = render_kind(name, n_frames=2, size=(16, 20), seed=1)
        k = SCENE_KINDS[name]
        assert s.kind == k.motion and s.options["name"] == name and s.options["light"] == k.light
        assert 0.0 <= s.frames.min() and s.frames.max() <= 1.0 and s.shading.max() <= 1.0
    with pytest.raises(ValueError, match="unknown scene kind"):
        render_kind("grey_flying_cars")
    with pytest.raises(ValueError, match="unknown suite"):
        scene_kinds("everything")


@pytest.mark.parametrize("kwargs, match", [
    (dict(palette="sepia"), "unknown palette"),
    (dict(light="neon"), "unknown light"),
    (dict(light_colour=(1.0, 0.0, 0.5)), "light_colour"),
    (dict(noise=("salt", 0.1)), "noise must be"),
    (dict(noise=("gaussian", -0.1)), "std"),
    (dict(compression=("png", 5)), "compression must be"),
    (dict(compression=("jpeg", 101)), "jpeg quality"),
    (dict(relief=-0.1), "relief must be a number"),
    (dict(relief=1.5), "relief must be a number"),
    (dict(relief="rough"), "relief must be a number"),
])
def test_bad_options_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        render_sequence("static_moving_light", n_frames=2, size=(16, 16), **kwargs)


def test_relief_bumps_the_shading_finely_and_keeps_the_rest():
    smooth = render_sequence("fast_light", n_frames=3, size=(60, 80), seed=2, palette="grey")
    bumpy = render_sequence("fast_light", n_frames=3, size=(60, 80), seed=2, palette="grey", relief=0.35)
    assert bumpy.options["relief"] == 0.35 and smooth.options["relief"] == 0.0
    # the geometry, the motion and the materials are the smooth scene's
    for name in ("albedo", "flow", "visibility", "depth", "object_id"):
        np.testing.assert_array_equal(getattr(bumpy, name), getattr(smooth, name), err_msg=name)
    np.testing.assert_allclose(bumpy.frames, bumpy.albedo * bumpy.shading[..., None], rtol=1e-6, atol=1e-7)
    # the shading gains fine detail (its log's pixel-to-pixel steps grow) ...
    def fine(shading):
        return float(np.median(np.abs(np.diff(np.log(np.maximum(shading, 1e-4)), axis=-1))))
    assert fine(bumpy.shading) > 3.0 * fine(smooth.shading)
    # ... whose steps change as the key lamp moves (the fill lamp holds still, so only in part)
    detail = np.log(np.maximum(bumpy.shading, 1e-4)) - np.log(np.maximum(smooth.shading, 1e-4))
    steps = np.diff(detail, axis=-1)
    assert np.median(np.abs(steps[2] - steps[0])) > 0.2 * np.median(np.abs(steps[0]))
