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


@pytest.mark.parametrize("option, value, message", [
    ("--flow-passes", "0", "flow_passes must be an int >= 1"),
    ("--denoise", "-1", "--denoise must be a multiple of the noise's step in [0, 20]"),
    ("--denoise", "nan", "--denoise must be"),
])
def test_bad_option_is_checked_before_any_output(image_folder, tmp_path, capsys, option, value, message):
    out = tmp_path / "out"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), option, value])
    assert rc == 2 and message in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.glob("*.partial"))


@pytest.mark.slow
def test_flow_passes_one_estimates_the_flow_on_the_input_only(image_folder, tmp_path):
    out = tmp_path / "one"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--flow", "dis", "--flow-passes", "1",
                   "--quiet"])
    assert rc == 0 and np.load(out / "intrinsics.npz")["flow"].shape == (2, 36, 52, 2)


# ----------------------------------------------------------------------------- what the user meets
@pytest.fixture(scope="module")
def odd_folder(tmp_path_factory):
    """Five frames of an odd height (35) and an odd width (51)."""
    seq = synthetic.render_sequence("objects_camera", n_frames=5, size=(35, 51), seed=2)
    folder = tmp_path_factory.mktemp("odd")
    write_png_sequence(folder, seq.frames_srgb8())
    return folder


@pytest.fixture(scope="module")
def odd_run(odd_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("odd_out") / "result"
    assert cli.main(["decompose", str(odd_folder), "-o", str(out), "--flow", "dis", "--window", "3",
                     "--flow-passes", "1", "--quiet"]) == 0
    return out


def _read_video(path):
    """uint8 RGB frames as OpenCV decodes them."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame[:, :, ::-1])
    cap.release()
    return np.stack(frames)


@pytest.mark.slow
def test_preview_of_odd_sized_frames_is_padded_not_empty(odd_run):
    video = _read_video(odd_run / "preview.mp4")
    # five frames; four panels of 51 columns (204, even), 35 rows padded to 36
    assert video.shape == (5, 36, 4 * 51, 3)
    # the padding repeats the last row: it is no black line
    assert np.abs(video[:, 35].astype(int) - video[:, 34].astype(int)).mean() < 8


@pytest.mark.slow
def test_flow_panel_shows_the_pair_of_each_frame(odd_run):
    """Windows (0, 3), (2, 5): frame 2, the last new frame of the first window, has its pair
    2 -> 3 in the second window; it must be that pair, not a black panel."""
    import imageio.v2 as imageio

    video = _read_video(odd_run / "preview.mp4")[:, :35, 3 * 51:].astype(float)
    flows = [imageio.imread(odd_run / "flow" / f"frame_{t:05d}.png").astype(float) for t in range(4)]
    for t in range(5):
        pair = min(t, 3)                    # the last frame shows the last pair
        diffs = [np.abs(video[t] - f).mean() for f in flows]
        assert int(np.argmin(diffs)) == pair and diffs[pair] < 6, (t, diffs)
    sheet = imageio.imread(odd_run / "contact_sheet.png")
    assert sheet.ndim == 3


@pytest.mark.slow
def test_linear_outputs_for_compositing(odd_run):
    import cv2

    data = np.load(odd_run / "intrinsics.npz")
    assert {k: data[k].dtype for k in data.files} == dict.fromkeys(
        ["albedo", "shading", "flow", "occlusion", "boundary"], np.float16)
    assert data["albedo"].shape == (5, 35, 51, 3)
    for t in (0, 4):
        albedo = cv2.imread(str(odd_run / "albedo_linear" / f"frame_{t:05d}.png"), cv2.IMREAD_UNCHANGED)
        shading = cv2.imread(str(odd_run / "shading_linear" / f"frame_{t:05d}.png"), cv2.IMREAD_UNCHANGED)
        assert albedo.dtype == np.uint16 and albedo.shape == (35, 51, 3)
        assert shading.dtype == np.uint16 and shading.shape == (35, 51)
        # linear values (not sRGB-encoded): the npz's, clipped to [0, 1], in 16 bits
        want_a = np.clip(data["albedo"][t].astype(np.float32), 0, 1)
        want_s = np.clip(data["shading"][t].astype(np.float32), 0, 1)
        np.testing.assert_allclose(albedo[:, :, ::-1] / 65535.0, want_a, atol=2e-3)
        np.testing.assert_allclose(shading / 65535.0, want_s, atol=2e-3)


@pytest.mark.slow
@pytest.mark.parametrize("choice", ["float32", "none"])
def test_npz_choice(image_folder, tmp_path, choice):
    out = tmp_path / "r"
    assert cli.main(["decompose", str(image_folder), "-o", str(out), "--no-temporal", "--quiet",
                     "--npz", choice]) == 0
    if choice == "none":
        assert not (out / "intrinsics.npz").exists()
    else:
        data = np.load(out / "intrinsics.npz")
        assert data["albedo"].dtype == np.float32 and data["albedo"].shape == (3, 36, 52, 3)
    assert len(list((out / "albedo_linear").glob("*.png"))) == 3


def test_help_shows_the_defaults(capsys):
    with pytest.raises(SystemExit):
        cli.main(["decompose", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for default in ["(default: warp)", "(default: cpu)", "(default: 2)", "(default: 0)", "(default: 1)",
                    "(default: 1.0)", "(default: 10.0)", "(default: float16)", "(default: classic_nl_fast",
                    "(default: 8, sharing 2"]:
        assert default in text, default


@pytest.mark.slow
def test_denoise_zero_keeps_the_noise_in_the_layers(tmp_path, capsys):
    seq = synthetic.render_sequence("objects_camera", n_frames=3, size=(36, 52), seed=1, noise=("gaussian", 0.03))
    folder = tmp_path / "noisy"
    write_png_sequence(folder, seq.frames_srgb8())
    layers, told = {}, {}
    for k in ("0", "2"):
        out = tmp_path / f"d{k}"
        assert cli.main(["decompose", str(folder), "-o", str(out), "--denoise", k, "--npz", "float32"]) == 0
        told[k] = "the input is noisy" in capsys.readouterr().err
        data = np.load(out / "intrinsics.npz")
        layers[k] = data["albedo"] * data["shading"][..., None]
    assert told == {"0": False, "2": True}          # the user is told when the layers lost the noise
    # without the filter the layers multiply back to the input; with it, to a smoother picture
    rough = {k: np.abs(np.diff(v, axis=2)).mean() for k, v in layers.items()}
    assert rough["2"] < 0.8 * rough["0"]


@pytest.mark.slow
def test_summary_before_work_and_no_cuda_warning(image_folder, tmp_path):
    import os
    import subprocess
    import sys
    from pathlib import Path

    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).parents[1]) + os.pathsep + env.get("PYTHONPATH", "")
    run = subprocess.run([sys.executable, "-m", "ivkernels.cli", "decompose", str(image_folder), "-o",
                          str(tmp_path / "r"), "--no-temporal", "--window", "2", "--threads", "1"],
                         env=env, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    err = run.stderr
    assert "Warp CUDA" not in err and "CUDA driver" not in err, err
    assert "3 frames of 52x36" in err and "2 windows of up to 2 frames, 1 shared" in err, err
    assert "estimated time: about" in err and "per pixel and frame" in err, err
    # the progress bar counts frames, over the windows
    assert "3/3 [" in err and "frame" in err and "window 2/2" in err, err
    assert err.index("estimated time") < err.index("3/3 [")


# -- several inputs: decompose_many, OUT/<input name>/ each ---------------------------------

@pytest.fixture(scope="module")
def second_folder(tmp_path_factory):
    seq = synthetic.render_sequence("static_moving_light", n_frames=4, size=(36, 52), seed=2)
    folder = tmp_path_factory.mktemp("second") / "clip_b"
    write_png_sequence(folder, seq.frames_srgb8())
    return folder


def test_several_inputs_are_written_each_and_a_missing_one_fails_alone(image_folder, second_folder,
                                                                        tmp_path, capsys):
    out = tmp_path / "out"
    missing = tmp_path / "missing.mp4"
    rc = cli.main(["decompose", str(image_folder), str(missing), str(second_folder), "-o", str(out),
                   "--flow", "dis", "--flow-passes", "1", "--window", "3", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 1
    assert f"{missing}: " in err and "does not exist" in err and "1 of 3 inputs failed" in err
    for folder, n in ((out / image_folder.name, 3), (out / "clip_b", 4)):
        assert len(list((folder / "albedo").glob("*.png"))) == n
        assert np.load(folder / "intrinsics.npz")["albedo"].shape == (n, 36, 52, 3)
    assert not (out / "missing").exists() and not list(out.glob("*.partial"))


def test_an_existing_output_fails_its_input_only(image_folder, second_folder, tmp_path, capsys):
    out = tmp_path / "out"
    (out / "clip_b").mkdir(parents=True)
    (out / "clip_b" / "mine.txt").write_text("keep")
    rc = cli.main(["decompose", str(image_folder), str(second_folder), "-o", str(out), "--engine", "local",
                   "--flow", "dis", "--flow-passes", "1", "--quiet"])
    assert rc == 1 and "clip_b" in capsys.readouterr().err
    assert (out / "clip_b" / "mine.txt").read_text() == "keep"
    assert (out / image_folder.name / "intrinsics.npz").exists()


def test_inputs_with_one_output_name_are_refused_before_any_work(image_folder, tmp_path, capsys):
    other = tmp_path / "x" / image_folder.name
    other.mkdir(parents=True)
    rc = cli.main(["decompose", str(image_folder), str(other), "-o", str(tmp_path / "out")])
    assert rc == 2 and "rename one" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_chunks_on_ray_match_chunks_in_this_process(second_folder, tmp_path):
    runs = {}
    for engine in ("local", "ray"):
        out = tmp_path / engine
        rc = cli.main(["decompose", str(second_folder), "-o", str(out), "--engine", engine,
                       "--chunk-frames", "2", "--window", "2", "--flow", "dis", "--flow-passes", "1",
                       "--quiet"])
        assert rc == 0
        runs[engine] = np.load(out / "clip_b" / "intrinsics.npz")
    assert runs["ray"]["albedo"].shape == (4, 36, 52, 3)
    assert np.abs(runs["ray"]["albedo"] - runs["local"]["albedo"]).max() <= 1e-4
