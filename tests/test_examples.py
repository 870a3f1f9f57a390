"""The scripts in examples/ run end to end and write what their docstrings promise.

The README's first command is ``examples/demo_synthetic.py``; these tests
keep it and the other two examples working.  Each script is loaded from its
file and its ``main(argv)`` called in a temporary folder.
"""
import importlib.util
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
import pytest

from ivkernels.evaluation import metrics, synthetic
from ivkernels.evaluation.baselines import color_retinex

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load_example(name: str):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_readme_demo_writes_its_pictures_and_beats_colour_retinex(tmp_path):
    demo = load_example("demo_synthetic")
    out = tmp_path / "demo"
    assert demo.main(["--out", str(out)]) == 0            # the README's defaults

    result = out / "result"
    for name in ("contact_sheet.png", "preview.mp4", "intrinsics.npz"):
        assert (result / name).stat().st_size > 0, name
    for folder in ("albedo", "shading", "flow", "occlusion", "boundary"):
        assert len(list((result / folder).glob("*.png"))) > 0, folder
    sheet = imageio.imread(out / "comparison.png")
    assert sheet.ndim == 3 and sheet.shape[2] == 3
    assert sheet.shape[0] > 5 * 120                         # five labelled rows of 120-pixel frames

    # The result, scored here against the renderer's truth independently of
    # the script's own printout: the demo's point is that it beats a
    # per-frame method (0.005 against 0.026 when written).
    seq = synthetic.render_sequence("free_camera", n_frames=6, size=(120, 160), seed=0)
    data = np.load(result / "intrinsics.npz")
    assert data["albedo"].shape == seq.albedo.shape
    ours = metrics.intrinsic_lmse(data["albedo"], data["shading"], seq.albedo, seq.shading)["mean"]
    retinex = metrics.intrinsic_lmse(*color_retinex(seq.frames), seq.albedo, seq.shading)["mean"]
    assert ours < 0.5 * retinex


@pytest.mark.slow
def test_the_video_example_makes_a_clip_and_writes_every_output(tmp_path, capsys):
    example = load_example("decompose_video")
    out = tmp_path / "clip"
    assert example.main(["--out", str(out)]) == 0
    assert "made" in capsys.readouterr().out                # no input given: it rendered one
    assert (tmp_path / "clip_input.mp4").stat().st_size > 0
    for folder in ("albedo", "shading"):
        assert len(list((out / folder).glob("*.png"))) == 6, folder
    for folder in ("flow", "occlusion", "boundary"):
        assert len(list((out / folder).glob("*.png"))) == 5, folder
    data = np.load(out / "intrinsics.npz")
    assert data["albedo"].shape == (6, 120, 160, 3)


def test_hue_rotation_turns_primaries_into_each_other():
    recolour = load_example("recolour")
    red = np.array([[1.0, 0.0, 0.0]], np.float32)
    assert np.allclose(recolour.rotate_hue(red, 120.0), [[0.0, 1.0, 0.0]], atol=0.01)
    assert np.allclose(recolour.rotate_hue(red, 240.0), [[0.0, 0.0, 1.0]], atol=0.01)
    grey = np.full((1, 3), 0.2, np.float32)
    assert np.allclose(recolour.rotate_hue(grey, 90.0), grey, atol=0.005)   # no hue to turn


def test_recolour_refuses_a_point_outside_the_frames_before_any_work(tmp_path, capsys):
    recolour = load_example("recolour")
    out = tmp_path / "never"
    with pytest.raises(SystemExit) as stop:
        recolour.main(["--out", str(out), "--point", "160", "10"])
    assert stop.value.code == 2
    assert "outside the 160x120 frames" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow
def test_recolour_changes_the_picked_material_and_keeps_the_rest(tmp_path, capsys):
    recolour = load_example("recolour")
    out = tmp_path / "recolour"
    assert recolour.main(["--out", str(out)]) == 0
    share = float(capsys.readouterr().out.split("recoloured ")[1].split("%")[0]) / 100
    assert 0.01 < share < 0.2                   # a visible material, not the whole picture
    for name in ("before.mp4", "after.mp4", "recolour.png"):
        assert (out / name).stat().st_size > 0, name
    before = np.stack(imageio.mimread(out / "before.mp4")).astype(np.int16)
    after = np.stack(imageio.mimread(out / "after.mp4")).astype(np.int16)
    changed = np.abs(after - before).max(axis=-1) > 20      # 8-bit levels; codec noise stays below
    assert 0.5 * share < changed.mean() < 2.0 * share
