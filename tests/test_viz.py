"""Flow colour coding, sRGB previews, side-by-side stacks and contact sheets."""
import flow_vis
import numpy as np
import pytest

from ivkernels.io import srgb_to_linear

from ivkernels.viz import (albedo_to_srgb8, contact_sheet, flow_to_color, gray_to_rgb8, shading_to_srgb8,
                           side_by_side)


def test_flow_to_color_matches_flow_vis_on_one_image(rng):
    flow = rng.normal(scale=3, size=(17, 23, 2)).astype(np.float32)
    out = flow_to_color(flow)
    assert out.shape == (17, 23, 3) and out.dtype == np.uint8
    np.testing.assert_array_equal(out, flow_vis.flow_to_color(flow))


def test_flow_to_color_zero_is_white_and_unknown_black():
    flow = np.zeros((4, 5, 2))
    flow[0, 0] = [1e10, 0.0]
    flow[1, 1] = [np.nan, 0.0]
    flow[3, 4] = [2.0, 0.0]
    out = flow_to_color(flow)
    np.testing.assert_array_equal(out[0, 0], 0)
    np.testing.assert_array_equal(out[1, 1], 0)
    np.testing.assert_array_equal(out[2, 2], 255)


def test_flow_to_color_shares_the_sequence_maximum():
    seq = np.zeros((2, 6, 6, 2))
    seq[0, ..., 0] = 1.0
    seq[1, ..., 0] = 4.0
    out = flow_to_color(seq)
    assert out.shape == (2, 6, 6, 3)
    # alone, frame 0 would be fully saturated; with the shared maximum (4) it is paler
    alone = flow_to_color(seq[0])
    assert out[0].astype(int).sum() > alone.astype(int).sum()
    np.testing.assert_array_equal(out[1], flow_to_color(seq[1]))
    np.testing.assert_array_equal(out[0], flow_to_color(seq[0], max_magnitude=4.0))
    # vectors beyond max_magnitude are drawn darkened, not wrapped
    assert flow_to_color(seq[1], max_magnitude=1.0).max() < 255


@pytest.mark.parametrize("flow, kw, exc, msg", [
    (np.zeros((4, 5)), {}, ValueError, r"\(H, W, 2\)"),
    (np.zeros((4, 5, 3)), {}, ValueError, r"\(H, W, 2\)"),
    (np.zeros((0, 5, 2)), {}, ValueError, "empty"),
    (np.zeros((4, 5, 2)), {"max_magnitude": -1.0}, ValueError, "max_magnitude"),
])
def test_flow_to_color_rejects(flow, kw, exc, msg):
    with pytest.raises(exc, match=msg):
        flow_to_color(flow, **kw)


def test_gray_to_rgb8():
    g = np.array([[0.0, 0.5, 1.0, 2.0, -1.0]])
    out = gray_to_rgb8(g)
    assert out.shape == (1, 5, 3) and out.dtype == np.uint8
    np.testing.assert_array_equal(out[0, :, 0], [0, 128, 255, 255, 0])
    np.testing.assert_array_equal(gray_to_rgb8(g, vmin=-1.0, vmax=2.0)[0, :, 1], [85, 128, 170, 255, 0])
    np.testing.assert_array_equal(gray_to_rgb8(np.array([[True, False]]))[0, :, 2], [255, 0])
    u8 = np.array([[[3, 4]]], np.uint8)
    np.testing.assert_array_equal(gray_to_rgb8(u8), np.repeat(u8[..., None], 3, -1))
    with pytest.raises(ValueError, match="vmin"):
        gray_to_rgb8(g, vmin=1.0, vmax=1.0)
    with pytest.raises(ValueError, match=r"\(\.\.\., H, W\)"):
        gray_to_rgb8(np.zeros(3))
    with pytest.raises(ValueError, match="NaN"):
        gray_to_rgb8(np.full((2, 2), np.nan))


def test_shading_and_albedo_to_srgb8():
    s = np.array([[0.0, srgb_to_linear(128 / 255.0), 1.0, 3.0]])
    out = shading_to_srgb8(s)
    assert out.shape == (1, 4, 3)
    np.testing.assert_array_equal(out[0, :, 0], [0, 128, 255, 255])
    # scale=None divides by the 99th percentile first
    assert shading_to_srgb8(np.full((2, 2), 0.25), scale=None).min() == 255
    a = np.zeros((2, 3, 4, 3))
    a[..., 1] = 1.0
    out = albedo_to_srgb8(a)
    assert out.shape == a.shape and out.dtype == np.uint8
    np.testing.assert_array_equal(out[..., 1], 255)
    np.testing.assert_array_equal(albedo_to_srgb8(a * 0.5, scale=2.0), out)
    with pytest.raises(ValueError, match=r"\(\.\.\., H, W, 3\)"):
        albedo_to_srgb8(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="scale"):
        albedo_to_srgb8(a, scale=0.0)
    with pytest.raises(TypeError, match="numeric"):
        shading_to_srgb8(np.array([["x", "y"]]))


def test_side_by_side(rng):
    a = rng.integers(0, 256, (3, 5, 7, 3), dtype=np.uint8)
    b = rng.integers(0, 256, (3, 5, 4), dtype=np.uint8)
    out = side_by_side(a, b, a)
    assert out.shape == (3, 5, 18, 3)
    np.testing.assert_array_equal(out[:, :, :7], a)
    np.testing.assert_array_equal(out[:, :, 7:11, 2], b)
    with pytest.raises(ValueError, match="stack 1"):
        side_by_side(a, a[:2])
    with pytest.raises(TypeError, match="uint8"):
        side_by_side(a.astype(np.float32))
    with pytest.raises(ValueError, match="at least one"):
        side_by_side()


def test_contact_sheet_layout(rng):
    h, w = 12, 10
    a = rng.integers(1, 256, (3, h, w, 3), dtype=np.uint8)
    b = rng.integers(1, 256, (2, h, w), dtype=np.uint8)
    sheet = contact_sheet([("input", a), ("shading", b)], gap=2)
    assert sheet.dtype == np.uint8 and sheet.ndim == 3
    label_w = sheet.shape[1] - (3 * (w + 2) - 2)
    assert sheet.shape[0] == 2 * h + 2 and label_w > 0
    assert sheet[:h, :label_w].max() > 0                           # the label was drawn
    for c in range(3):
        x0 = label_w + c * (w + 2)
        np.testing.assert_array_equal(sheet[:h, x0:x0 + w], a[c])
    np.testing.assert_array_equal(sheet[h + 2:, label_w + w + 2:label_w + 2 * w + 2, 0], b[1])
    np.testing.assert_array_equal(sheet[h + 2:, label_w + 2 * (w + 2):], 0)  # padded black
    two = contact_sheet([("input", a), ("shading", b)], n_cols=2)
    assert two.shape[1] == label_w + 2 * (w + 2) - 2


@pytest.mark.parametrize("rows, kw, exc, msg", [
    ([], {}, ValueError, "non-empty"),
    ([("a",)], {}, TypeError, "pair"),
    ([(1, np.zeros((1, 4, 4, 3), np.uint8))], {}, TypeError, "label"),
    ([("a", np.zeros((1, 4, 4, 3), np.float32))], {}, TypeError, "uint8"),
    ([("a", np.zeros((1, 4, 4, 3), np.uint8)), ("b", np.zeros((1, 4, 5, 3), np.uint8))], {}, ValueError,
     "expected 4x4"),
    ([("a", np.zeros((1, 4, 4, 3), np.uint8))], {"n_cols": 0}, ValueError, "n_cols"),
])
def test_contact_sheet_rejects(rows, kw, exc, msg):
    with pytest.raises(exc, match=msg):
        contact_sheet(rows, **kw)
