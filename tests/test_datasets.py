"""MIT-Berkeley loader: the real objects when present, a tiny written copy always."""
import cv2
import numpy as np
import pytest

from ivkernels.evaluation import datasets
from ivkernels.evaluation.datasets import MIT_OBJECTS, available_mit_objects, load_mit_object

PRESENT = available_mit_objects()


def _write_object(folder, rng, h=12, w=10):
    """A fake object folder: 16-bit PNGs as the real ones (RGB written BGR, mask 0/65025)."""
    folder.mkdir(parents=True)
    albedo = rng.uniform(0.1, 0.9, (h, w, 3))
    mask = np.zeros((h, w), bool)
    mask[2:10, 2:8] = True
    shading = rng.uniform(0.2, 1.0, (10, h, w))

    def put(name, x):
        x16 = np.round(np.clip(x, 0, 1) * 65535).astype(np.uint16)
        cv2.imwrite(str(folder / name), x16[..., ::-1] if x16.ndim == 3 else x16)

    put("reflectance.png", albedo)
    put("shading.png", shading[0])
    put("diffuse.png", albedo * shading[0][..., None])
    cv2.imwrite(str(folder / "mask.png"), np.where(mask, 65025, 0).astype(np.uint16))
    for k in range(10):
        put(f"light{k + 1:02d}.png", albedo * shading[k][..., None])
    return albedo, shading, mask


def test_load_written_object(tmp_path, rng):
    albedo, shading, mask = _write_object(tmp_path / "apple", rng)
    assert available_mit_objects(tmp_path) == ("apple",)
    obj = load_mit_object("apple", root=tmp_path)
    assert obj.name == "apple"
    assert obj.frames.shape == (10, 12, 10, 3) and obj.frames.dtype == np.float32
    assert obj.albedo.shape == (12, 10, 3) and obj.mask.dtype == np.bool_
    assert obj.frame_shading.shape == (10, 12, 10)
    np.testing.assert_array_equal(obj.mask, mask)
    # read as linear value / 65535, channels in RGB order
    np.testing.assert_allclose(obj.albedo, albedo, atol=1e-4)
    np.testing.assert_allclose(obj.frames[3], albedo * shading[3][..., None], atol=1e-4)
    np.testing.assert_allclose(obj.shading, shading[0], atol=1e-4)
    # the derived per-frame shading is the luminance ratio inside the mask, 0 outside
    ratio = (albedo * shading[..., None]).mean(-1) / albedo.mean(-1)
    np.testing.assert_allclose(obj.frame_shading[:, mask], ratio[:, mask], rtol=1e-3)
    assert np.all(obj.frame_shading[:, ~mask] == 0)


def test_load_scaled_object(tmp_path, rng):
    _write_object(tmp_path / "box", rng)
    obj = load_mit_object("box", root=tmp_path, scale=0.5)
    assert obj.frames.shape == (10, 6, 5, 3) and obj.mask.shape == (6, 5)
    # only pixels wholly inside the object stay in the mask: rows 2..9, cols 2..7 -> 1..4, 1..3
    expect = np.zeros((6, 5), bool)
    expect[1:5, 1:4] = True
    np.testing.assert_array_equal(obj.mask, expect)


def test_load_rejects(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="unknown MIT object"):
        load_mit_object("teapot", root=tmp_path)
    for bad in (0.0, 1.5, -1, True):
        with pytest.raises(ValueError, match="scale"):
            load_mit_object("apple", root=tmp_path, scale=bad)
    with pytest.raises(FileNotFoundError, match="IVKERNELS_MIT_DATA"):
        load_mit_object("apple", root=tmp_path)
    assert available_mit_objects(tmp_path) == ()
    monkeypatch.setenv("IVKERNELS_MIT_DATA", str(tmp_path))
    assert datasets.default_mit_root() == tmp_path


@pytest.mark.skipif(not PRESENT, reason="MIT-Berkeley training objects not present")
def test_real_objects_are_linear_and_consistent():
    assert set(PRESENT) <= set(MIT_OBJECTS)
    obj = load_mit_object(PRESENT[0], scale=0.25)
    assert obj.frames.shape[0] == 10 and obj.frames.shape[1:] == obj.albedo.shape
    assert obj.mask.any() and 0 <= obj.frames.min() and obj.frames.max() <= 1
    # diffuse = reflectance * shading holds as linear values (a few % after the best scale)
    m = obj.mask & (obj.albedo.min(-1) > 0.02)
    prod = (obj.albedo * obj.shading[..., None])[m]
    diff = obj.diffuse[m]
    alpha = np.sum(prod * diff) / np.sum(prod * prod)
    assert np.sqrt(np.mean((alpha * prod - diff) ** 2) / np.mean(diff ** 2)) < 0.1


def test_achromatic_object_is_luminance_in_three_equal_channels(tmp_path, rng):
    albedo, shading, mask = _write_object(tmp_path / "frog1", rng)
    obj = load_mit_object("frog1", root=tmp_path, achromatic=True)
    colour = load_mit_object("frog1", root=tmp_path)
    assert obj.achromatic and not colour.achromatic
    weights = np.array([0.2126, 0.7152, 0.0722])            # Rec. 709
    for grey, rgb in ((obj.frames, colour.frames), (obj.albedo, colour.albedo), (obj.diffuse, colour.diffuse)):
        assert grey.shape == rgb.shape and grey.dtype == np.float32
        np.testing.assert_array_equal(grey[..., 0], grey[..., 1])
        np.testing.assert_array_equal(grey[..., 0], grey[..., 2])
        np.testing.assert_allclose(grey[..., 0], (rgb.astype(np.float64) * weights).sum(-1), rtol=1e-6, atol=1e-7)
    # a white light: lum(frame) = lum(reflectance) * shading, so the derived shading is the written one
    np.testing.assert_allclose(obj.frame_shading[:, mask], shading[:, mask], rtol=2e-3)
    np.testing.assert_array_equal(obj.mask, colour.mask)
    with pytest.raises(TypeError, match="achromatic"):
        load_mit_object("frog1", root=tmp_path, achromatic="yes")


def test_grey_footage_from_a_written_middlebury_pair(tmp_path):
    from ivkernels.colour import srgb_to_linear

    folder = tmp_path / "middlebury" / "Odd"
    folder.mkdir(parents=True)
    rng = np.random.default_rng(2)
    written = []
    for k in (10, 11):
        img = rng.integers(0, 256, (17, 23, 3)).astype(np.uint8)
        cv2.imwrite(str(folder / f"frame{k}.png"), img[..., ::-1])
        written.append(img)
    (tmp_path / "middlebury" / "Empty").mkdir()
    assert datasets.available_footage(tmp_path) == ("middlebury/Odd",)
    grey = datasets.load_grey_footage("middlebury/Odd", root=tmp_path)
    assert grey.shape == (2, 17, 23, 3) and grey.dtype == np.float32
    linear = srgb_to_linear(np.stack(written) / 255.0)
    expected = linear @ np.array([0.2126, 0.7152, 0.0722])
    for c in range(3):
        np.testing.assert_allclose(grey[..., c], expected, rtol=1e-5, atol=1e-6)
    half = datasets.load_grey_footage("middlebury/Odd", root=tmp_path, scale=0.5)
    assert half.shape == (2, 8, 12, 3)                  # round(8.5) = 8, round(11.5) = 12
    with pytest.raises(ValueError, match="unknown footage"):
        datasets.load_grey_footage("holiday.mp4", root=tmp_path)
    with pytest.raises(ValueError, match="n_frames"):
        datasets.load_grey_footage("middlebury/Odd", root=tmp_path, n_frames=1)


@pytest.mark.skipif(datasets.FOOTAGE_CLIP not in datasets.available_footage(), reason="the real clip is not present")
def test_grey_footage_of_the_real_clip():
    grey = datasets.load_grey_footage(datasets.FOOTAGE_CLIP, n_frames=3)
    assert grey.shape == (3, 240, 320, 3)
    np.testing.assert_array_equal(grey[..., 0], grey[..., 2])
