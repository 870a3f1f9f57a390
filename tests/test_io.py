"""Frame, PNG, NPZ, video and .flo input/output."""
from pathlib import Path

import cv2
import numpy as np
import pytest

from ivkernels.flowio import read_flo, valid_flow_mask, write_flo
from ivkernels.io import (atomic_output, linear_to_srgb, read_frames, read_image, srgb_to_linear,
                          to_linear_float, write_npz, write_png_sequence, write_video)

MIDDLEBURY = Path(__file__).parents[2] / "shared/data/middlebury"
MIDDLEBURY_SEQS = ("Dimetrodon", "Grove2", "Grove3", "Hydrangea", "RubberWhale", "Urban2", "Urban3", "Venus")


# ----------------------------------------------------------------------------- sRGB
def test_srgb_known_values():
    x = np.array([0.0, 0.04045, 0.5, 1.0])
    np.testing.assert_allclose(srgb_to_linear(x), [0.0, 0.04045 / 12.92, 0.21404114, 1.0], rtol=1e-6)
    np.testing.assert_allclose(linear_to_srgb(np.array([0.0, 0.0031308, 0.21404114, 1.0])),
                               [0.0, 0.0031308 * 12.92, 0.5, 1.0], rtol=1e-6)


def test_srgb_round_trip_keeps_shape_and_dtype(rng):
    x = rng.uniform(0, 1, (3, 5, 7, 3)).astype(np.float32)
    y = srgb_to_linear(x)
    assert y.shape == x.shape and y.dtype == np.float32
    np.testing.assert_allclose(linear_to_srgb(y), x, atol=2e-6)
    assert srgb_to_linear(np.float64(0.5)).shape == ()


def test_srgb_rejects_integers():
    with pytest.raises(TypeError, match="to_linear_float"):
        srgb_to_linear(np.array([0, 128, 255], np.uint8))
    with pytest.raises(TypeError, match="floating-point"):
        linear_to_srgb(np.array([1, 2]))


# ----------------------------------------------------------------------------- to_linear_float
def test_to_linear_float_uint8_uint16_float(rng):
    u8 = rng.integers(0, 256, (2, 5, 7, 3), dtype=np.uint8)
    out = to_linear_float(u8)
    assert out.dtype == np.float32 and out.shape == u8.shape and out.flags.c_contiguous
    np.testing.assert_allclose(out, srgb_to_linear(u8 / 255.0), atol=1e-7)
    u16 = rng.integers(0, 65536, (1, 4, 3, 3), dtype=np.uint16)
    np.testing.assert_allclose(to_linear_float(u16), srgb_to_linear(u16 / 65535.0), atol=1e-7)
    f = rng.uniform(0, 1, (2, 3, 4, 3))
    out = to_linear_float(f)
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, f, atol=1e-7)
    # a hair outside [0, 1] from rounding is clipped
    assert to_linear_float(np.full((1, 2, 2, 3), 1.0 + 1e-7)).max() == 1.0


@pytest.mark.parametrize("bad, exc, msg", [
    (np.zeros((5, 7, 3), np.uint8), ValueError, r"image\[None\]"),
    (np.zeros((1, 5, 7, 4), np.uint8), ValueError, "3 colour channels"),
    (np.zeros((1, 5, 7), np.float32), ValueError, r"\(T, H, W, 3\)"),
    (np.zeros((0, 5, 7, 3), np.float32), ValueError, "empty"),
    (np.full((1, 2, 2, 3), np.nan, np.float32), ValueError, "NaN"),
    (np.full((1, 2, 2, 3), 1.5, np.float32), ValueError, r"\[0, 1\]"),
    (np.full((1, 2, 2, 3), -0.1), ValueError, r"\[0, 1\]"),
    (np.zeros((1, 2, 2, 3), np.int32), TypeError, "dtype int32"),
    (np.zeros((1, 2, 2, 3), np.float16), TypeError, "float16"),
    (np.zeros((1, 2, 2, 3), bool), TypeError, "bool"),
])
def test_to_linear_float_rejects(bad, exc, msg):
    with pytest.raises(exc, match=msg):
        to_linear_float(bad)


# ----------------------------------------------------------------------------- image folders
def _write(folder: Path, name: str, img: np.ndarray) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    assert cv2.imwrite(str(folder / name), img)


def _bgr(rgb):
    return np.ascontiguousarray(rgb[..., ::-1])


def test_read_folder_8bit_rgb_natural_order(tmp_path, rng):
    imgs = [rng.integers(0, 256, (9, 11, 3), dtype=np.uint8) for _ in range(3)]
    for name, img in zip(["f10.png", "f2.png", "f1.png"], [imgs[2], imgs[1], imgs[0]]):
        _write(tmp_path, name, _bgr(img))
    (tmp_path / "notes.txt").write_text("not an image")
    frames = read_frames(tmp_path)
    assert frames.shape == (3, 9, 11, 3) and frames.dtype == np.float32
    np.testing.assert_allclose(frames, srgb_to_linear(np.stack(imgs) / 255.0), atol=1e-6)


def test_read_folder_16bit_grey_rgba(tmp_path, rng):
    rgb16 = rng.integers(0, 65536, (6, 5, 3), dtype=np.uint16)
    _write(tmp_path / "a", "0.png", _bgr(rgb16))
    np.testing.assert_allclose(read_frames(tmp_path / "a")[0], srgb_to_linear(rgb16 / 65535.0), atol=1e-6)

    grey = rng.integers(0, 256, (6, 5), dtype=np.uint8)
    _write(tmp_path / "g", "0.png", grey)
    out = read_frames(tmp_path / "g")[0]
    np.testing.assert_allclose(out, np.repeat(srgb_to_linear(grey / 255.0)[..., None], 3, -1), atol=1e-6)

    grey16 = rng.integers(0, 65536, (6, 5), dtype=np.uint16)
    _write(tmp_path / "g16", "0.png", grey16)
    np.testing.assert_allclose(read_frames(tmp_path / "g16")[0, ..., 1], srgb_to_linear(grey16 / 65535.0),
                               atol=1e-6)

    rgba = rng.integers(0, 256, (6, 5, 4), dtype=np.uint8)
    bgra = np.concatenate([_bgr(rgba[..., :3]), rgba[..., 3:]], axis=-1)
    _write(tmp_path / "r", "0.png", bgra)
    np.testing.assert_allclose(read_frames(tmp_path / "r")[0], srgb_to_linear(rgba[..., :3] / 255.0), atol=1e-6)
    np.testing.assert_allclose(read_image(tmp_path / "r" / "0.png"), srgb_to_linear(rgba[..., :3] / 255.0),
                               atol=1e-6)


def test_read_folder_jpg_bmp_tif(tmp_path, rng):
    img = np.full((8, 8, 3), 100, np.uint8)
    for i, ext in enumerate(["jpg", "bmp", "tif"]):
        _write(tmp_path, f"im{i}.{ext}", img)
    frames = read_frames(tmp_path)
    assert frames.shape == (3, 8, 8, 3)
    np.testing.assert_allclose(frames, srgb_to_linear(np.float64(100 / 255)), atol=3e-3)


def test_read_selection_and_scale(tmp_path):
    for i in range(7):
        _write(tmp_path, f"frame_{i}.png", np.full((10, 14, 3), i * 30, np.uint8))
    frames = read_frames(tmp_path, start=1, stop=6, step=2)
    assert frames.shape[0] == 3
    np.testing.assert_allclose(frames[:, 0, 0, 0], srgb_to_linear(np.array([30, 90, 150]) / 255.0), atol=1e-6)
    assert read_frames(tmp_path, scale=0.5).shape == (7, 5, 7, 3)
    assert read_frames(tmp_path, stop=2, scale=1.5).shape == (2, 15, 21, 3)


def test_read_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_frames(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="holds no images"):
        read_frames(tmp_path / "empty")
    _write(tmp_path / "mixed", "a1.png", np.zeros((4, 4, 3), np.uint8))
    _write(tmp_path / "mixed", "a2.png", np.zeros((4, 5, 3), np.uint8))
    with pytest.raises(ValueError, match="share one size"):
        read_frames(tmp_path / "mixed")
    with pytest.raises(ValueError, match="step"):
        read_frames(tmp_path / "mixed", step=0)
    with pytest.raises(ValueError, match="start"):
        read_frames(tmp_path / "mixed", start=-1)
    with pytest.raises(ValueError, match="stop"):
        read_frames(tmp_path / "mixed", start=2, stop=1)
    with pytest.raises(TypeError, match="start"):
        read_frames(tmp_path / "mixed", start=1.0)
    with pytest.raises(ValueError, match="scale"):
        read_frames(tmp_path / "mixed", scale=0)
    with pytest.raises(ValueError, match=r"start 5 \(--start\) is past the end of folder .* holds 2 frames"):
        read_frames(tmp_path / "mixed", start=5)
    (tmp_path / "broken.png").write_bytes(b"not a png")
    with pytest.raises(ValueError, match="could not decode"):
        read_image(tmp_path / "broken.png")
    with pytest.raises(FileNotFoundError):
        read_image(tmp_path / "nothing.png")
    (tmp_path / "junk.mp4").write_text("not a video")
    with pytest.raises(ValueError, match="could not read video"):
        read_frames(tmp_path / "junk.mp4")


# ----------------------------------------------------------------------------- writing
def test_png_sequence_round_trip_8_and_16_bit(tmp_path, rng):
    frames = rng.uniform(0, 1, (3, 7, 9, 3)).astype(np.float32)
    paths = write_png_sequence(tmp_path / "a", frames, prefix="albedo")
    assert [p.name for p in paths] == ["albedo_00000.png", "albedo_00001.png", "albedo_00002.png"]
    back = read_frames(tmp_path / "a")
    # 8-bit sRGB quantisation: at most half a code step of sRGB, ~0.0045 in linear near 1
    np.testing.assert_allclose(back, frames, atol=5e-3)
    write_png_sequence(tmp_path / "b", frames, bits=16)
    assert cv2.imread(str(tmp_path / "b" / "frame_00000.png"), cv2.IMREAD_UNCHANGED).dtype == np.uint16
    np.testing.assert_allclose(read_frames(tmp_path / "b"), frames, atol=1e-4)


def test_png_sequence_grey_maps_as_is_and_start_index(tmp_path, rng):
    maps = rng.uniform(0, 1, (2, 5, 6))
    paths = write_png_sequence(tmp_path, maps, prefix="occ", start_index=7)
    assert [p.name for p in paths] == ["occ_00007.png", "occ_00008.png"]
    img = cv2.imread(str(paths[1]), cv2.IMREAD_UNCHANGED)
    assert img.ndim == 2 and img.dtype == np.uint8
    np.testing.assert_array_equal(img, np.round(maps[1] * 255).astype(np.uint8))
    u8 = rng.integers(0, 256, (1, 4, 4, 3), dtype=np.uint8)
    p = write_png_sequence(tmp_path / "u8", u8)[0]
    np.testing.assert_array_equal(cv2.imread(str(p))[..., ::-1], u8[0])
    assert not [f for f in tmp_path.rglob("*") if ".part" in f.name]


@pytest.mark.parametrize("kwargs, frames, exc, msg", [
    ({}, np.zeros((2, 3)), ValueError, "expected"),
    ({}, np.full((1, 2, 2, 3), np.nan), ValueError, "NaN"),
    ({"bits": 12}, np.zeros((1, 2, 2, 3)), ValueError, "bits"),
    ({"prefix": "a/b"}, np.zeros((1, 2, 2, 3)), ValueError, "prefix"),
    ({"start_index": -1}, np.zeros((1, 2, 2, 3)), ValueError, "start_index"),
    ({}, np.zeros((1, 2, 2, 3), np.int64), TypeError, "dtype"),
])
def test_png_sequence_rejects(tmp_path, kwargs, frames, exc, msg):
    with pytest.raises(exc, match=msg):
        write_png_sequence(tmp_path, frames, **kwargs)


def test_atomic_output_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out" / "result.npz"
    with pytest.raises(RuntimeError):
        with atomic_output(target) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("interrupted")
    assert not target.exists()
    assert list((tmp_path / "out").iterdir()) == []
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with atomic_output(target) as tmp:
            raise RuntimeError("interrupted")
    assert target.read_bytes() == b"old"


def test_write_npz_round_trip(tmp_path, rng):
    a = rng.normal(size=(2, 3)).astype(np.float32)
    path = write_npz(tmp_path / "x" / "intrinsics.npz", albedo=a, n=np.int64(3))
    with np.load(path) as z:
        np.testing.assert_array_equal(z["albedo"], a)
        assert int(z["n"]) == 3
    with pytest.raises(ValueError, match="at least one"):
        write_npz(tmp_path / "y.npz")
    with pytest.raises(TypeError, match="object"):
        write_npz(tmp_path / "y.npz", bad=np.array([{}, []], dtype=object))
    assert not (tmp_path / "y.npz").exists()


def test_video_round_trip_pads_to_even(tmp_path):
    t, h, w = 5, 31, 47
    yy, xx = np.mgrid[0:h, 0:w]
    frames = np.stack([np.stack([(xx * 5 + 10 * i) % 256, yy * 8, np.full_like(xx, 128)], -1)
                       for i in range(t)]).astype(np.uint8)
    path = write_video(tmp_path / "clip.mp4", frames, fps=10)
    assert path.exists() and not [f for f in tmp_path.iterdir() if ".part" in f.name]
    back = read_frames(path)
    assert back.shape == (t, h + 1, w + 1, 3)
    back8 = np.round(linear_to_srgb(back) * 255.0)
    err = np.abs(back8[:, :h, :w].astype(float) - frames.astype(float))
    assert err.mean() < 4.0
    sel = read_frames(path, start=1, step=2)
    np.testing.assert_allclose(sel, back[1::2], atol=1e-6)
    grey = write_video(tmp_path / "grey.mkv", frames[..., 0])
    assert read_frames(grey).shape == (t, h + 1, w + 1, 3)


@pytest.mark.parametrize("name, frames, fps, exc, msg", [
    ("a.mp4", np.zeros((2, 4, 4, 3), np.float32), 10, TypeError, "uint8"),
    ("a.mp4", np.zeros((2, 4, 4, 2), np.uint8), 10, ValueError, "expected"),
    ("a.gif", np.zeros((2, 4, 4, 3), np.uint8), 10, ValueError, "end in"),
    ("a.mp4", np.zeros((2, 4, 4, 3), np.uint8), 0, ValueError, "fps"),
    ("a.mp4", np.zeros((0, 4, 4, 3), np.uint8), 10, ValueError, "empty"),
])
def test_video_rejects(tmp_path, name, frames, fps, exc, msg):
    with pytest.raises(exc, match=msg):
        write_video(tmp_path / name, frames, fps=fps)
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- .flo
def test_flo_round_trip_keeps_unknown(tmp_path, rng):
    flow = rng.normal(scale=5, size=(13, 17, 2)).astype(np.float32)
    flow[2, 3] = [1e10, 1e10]
    flow[4, 5, 1] = np.float32(1.7e9)
    path = write_flo(tmp_path / "f.flo", flow)
    data = path.read_bytes()
    assert data[:4] == b"PIEH" and len(data) == 12 + 13 * 17 * 8
    assert np.frombuffer(data[4:12], "<i4").tolist() == [17, 13]
    back = read_flo(path)
    assert back.dtype == np.float32 and back.shape == (13, 17, 2)
    np.testing.assert_array_equal(back, flow)
    valid = valid_flow_mask(back)
    assert not valid[2, 3] and not valid[4, 5] and valid.sum() == 13 * 17 - 2


def test_valid_flow_mask_nan_and_shapes():
    f = np.zeros((2, 3, 4, 2))
    f[0, 1, 1, 0] = np.nan
    f[1, 2, 3, 1] = -2e9
    m = valid_flow_mask(f)
    assert m.shape == (2, 3, 4) and m.sum() == 22
    with pytest.raises(ValueError, match=r"\(\.\.\., H, W, 2\)"):
        valid_flow_mask(np.zeros((3, 4)))


def test_flo_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_flo(tmp_path / "none.flo")
    good = write_flo(tmp_path / "g.flo", np.zeros((3, 4, 2), np.float32)).read_bytes()
    (tmp_path / "tag.flo").write_bytes(b"XXXX" + good[4:])
    with pytest.raises(ValueError, match="PIEH"):
        read_flo(tmp_path / "tag.flo")
    (tmp_path / "short.flo").write_bytes(good[:-5])
    with pytest.raises(ValueError, match="truncated"):
        read_flo(tmp_path / "short.flo")
    (tmp_path / "hdr.flo").write_bytes(good[:7])
    with pytest.raises(ValueError, match="truncated"):
        read_flo(tmp_path / "hdr.flo")
    (tmp_path / "long.flo").write_bytes(good + b"\0\0\0\0")
    with pytest.raises(ValueError, match="trailing"):
        read_flo(tmp_path / "long.flo")
    (tmp_path / "size.flo").write_bytes(b"PIEH" + np.array([-3, 4], "<i4").tobytes())
    with pytest.raises(ValueError, match="implausible"):
        read_flo(tmp_path / "size.flo")
    with pytest.raises(ValueError, match=r"\(H, W, 2\)"):
        write_flo(tmp_path / "w.flo", np.zeros((3, 4, 3)))
    with pytest.raises(TypeError, match="numeric"):
        write_flo(tmp_path / "w.flo", np.zeros((3, 4, 2), bool).astype(object))
    assert not (tmp_path / "w.flo").exists()


@pytest.mark.skipif(not MIDDLEBURY.is_dir(), reason="Middlebury data not present")
@pytest.mark.parametrize("seq", MIDDLEBURY_SEQS)
def test_read_middlebury_flo(seq):
    flow = read_flo(MIDDLEBURY / seq / "flow10.flo")
    frame = cv2.imread(str(MIDDLEBURY / seq / "frame10.png"))
    assert flow.shape == frame.shape[:2] + (2,) and flow.dtype == np.float32
    valid = valid_flow_mask(flow)
    assert valid.mean() > 0.5
    assert np.abs(flow[valid]).max() < 100.0
