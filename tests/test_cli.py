"""The command line: outputs on a folder of images, and clear errors."""
import numpy as np
import pytest

from ivkernels import cli
from ivkernels.evaluation import synthetic
from ivkernels.io import write_png_sequence


@pytest.fixture(scope="module")
def image_folder(tmp_path_factory):
    seq = synthetic.render_sequence("objects_camera", n_frames=3, size=(36, 52), seed=1)
    folder = tmp_path_factory.mktemp("frames")
    write_png_sequence(folder, seq.frames_srgb8())
    return folder


@pytest.mark.slow
def test_decompose_writes_every_output(image_folder, tmp_path):
    out = tmp_path / "result"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--flow", "dis", "--quiet"])
    assert rc == 0
    for sub, n in [("albedo", 3), ("shading", 3), ("flow", 2), ("occlusion", 2), ("boundary", 2)]:
        assert len(list((out / sub).glob("*.png"))) == n, sub
    data = np.load(out / "intrinsics.npz")
    assert data["albedo"].shape == (3, 36, 52, 3) and data["flow"].shape == (2, 36, 52, 2)
    assert (out / "preview.mp4").stat().st_size > 0
    assert (out / "contact_sheet.png").stat().st_size > 0
    assert not list(tmp_path.glob("*.partial"))


def test_missing_input_is_a_clear_error(tmp_path, capsys):
    rc = cli.main(["decompose", str(tmp_path / "nope"), "-o", str(tmp_path / "out")])
    assert rc == 2
    assert "does not exist" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_existing_output_is_not_overwritten(image_folder, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    rc = cli.main(["decompose", str(image_folder), "-o", str(out)])
    assert rc == 2 and "already exists" in capsys.readouterr().err


def test_failure_leaves_no_output(image_folder, tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--flow", "not_a_method"])
    assert rc == 2 and "unknown flow method" in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.glob("*.partial"))


def test_flow_passes_is_checked_before_any_output(image_folder, tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--flow-passes", "0"])
    assert rc == 2 and "flow_passes must be an int >= 1" in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.glob("*.partial"))


@pytest.mark.slow
def test_flow_passes_one_estimates_the_flow_on_the_input_only(image_folder, tmp_path):
    out = tmp_path / "one"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--flow", "dis", "--flow-passes", "1",
                   "--quiet"])
    assert rc == 0 and np.load(out / "intrinsics.npz")["flow"].shape == (2, 36, 52, 2)
