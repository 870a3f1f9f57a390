"""The input contract: one set of rules for decompose, iter_decompose, estimate_flow,
to_linear_float and the command line, and a clear refusal for every bad input.

Every refusal here happens before any solve, so the cases are fast; inputs
are tiny (16x16, 2-3 frames).
"""
import math

import numpy as np
import pytest

import ivkernels as iv
from ivkernels import Params, cli
from ivkernels import io as ivio
from ivkernels.flow import estimate_flow
from ivkernels.io import read_frames, to_linear_float, write_png_sequence

FAST = Params(outer_iterations=1, lbfgs_iterations=3, lbfgs_iterations_coarse=1)


def _cuda_present() -> bool:
    import warp as wp

    wp.init()
    return wp.is_cuda_available()


@pytest.fixture
def frames_f(frames8):
    return to_linear_float(frames8)


@pytest.fixture
def no_work(monkeypatch):
    """Fails the test if the command line starts reading frames."""
    def refuse(*args, **kwargs):
        raise AssertionError("frames were read before the arguments were checked")

    monkeypatch.setattr(cli, "read_frames", refuse)


# ----------------------------------------------------------------------------- Params
FLOAT_FIELDS = [name for name, value in vars(Params()).items() if isinstance(value, float)]
INT_FIELDS = [name for name, value in vars(Params()).items()
              if isinstance(value, int) and not isinstance(value, bool)]
BOOL_FIELDS = [name for name, value in vars(Params()).items() if isinstance(value, bool)]


@pytest.mark.parametrize("name", FLOAT_FIELDS)
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_params_refuse_non_finite_values(name, value):
    with pytest.raises(ValueError, match=f"Params.{name} must be a finite number"):
        Params(**{name: value})


@pytest.mark.parametrize("name", INT_FIELDS)
@pytest.mark.parametrize("value", [2.5, 3.0, "3", None])
def test_params_integer_fields_must_be_integers(name, value):
    with pytest.raises(TypeError, match=f"Params.{name} must be an integer"):
        Params(**{name: value})


@pytest.mark.parametrize("name", BOOL_FIELDS)
@pytest.mark.parametrize("value", [0, 1, 1.0, "yes", None])
def test_params_switches_must_be_true_or_false(name, value):
    with pytest.raises(TypeError, match=f"Params.{name} must be True or False"):
        Params(**{name: value})
    assert getattr(Params(**{name: np.bool_(False)}), name) is False


def test_params_numpy_numbers_are_stored_as_python_numbers():
    p = Params(window=np.int64(5), lam_coupling=np.float32(2.5), overlap=np.uint8(1))
    assert type(p.window) is int and p.window == 5 and type(p.overlap) is int
    assert type(p.lam_coupling) is float and p.lam_coupling == 2.5


@pytest.mark.parametrize("changes, match", [
    ({"eps_data": 0.0}, "eps_data must be > 0"),
    ({"eps_shading": 0.0}, "eps_shading must be > 0"),
    ({"pyramid_min_size": 0}, "pyramid_min_size must be >= 8"),
    ({"pyramid_min_size": 3}, "pyramid_min_size must be >= 8"),
    ({"pyramid_scale": 0.999}, r"pyramid_scale must be in \(0, 0.9\]"),
    ({"occlusion_threshold": 1.5}, r"occlusion_threshold must be in \[0, 1\]"),
    ({"occlusion_threshold": -0.1}, r"occlusion_threshold must be in \[0, 1\]"),
    ({"pyramid_scale": 1.0}, r"pyramid_scale must be in \(0, 0.9\]"),
    ({"pyramid_scale": 0.0}, r"pyramid_scale must be in \(0, 0.9\]"),
    ({"log_floor": 0.0}, "log_floor"),
    ({"outer_iterations": 0}, "outer_iterations must be >= 1"),
    ({"lbfgs_iterations": 0}, "lbfgs_iterations must be >= 1"),
    ({"guide_lbfgs_iterations": 0}, "guide_lbfgs_iterations must be >= 1"),
    ({"nonlocal_radius": 0}, "nonlocal_radius"),
    ({"nonlocal_radius": 10_000}, "nonlocal_radius"),
    ({"boundary_radius": 10_000}, "boundary_radius"),
    ({"tukey_alpha": 0.0}, "tukey_alpha must be > 0"),
])
def test_params_refuse_values_out_of_range(changes, match):
    with pytest.raises(ValueError, match=match):
        Params(**changes)
    with pytest.raises(ValueError, match=match):
        Params().replace(**changes)


def test_params_refuse_booleans_and_strings_as_numbers():
    with pytest.raises(TypeError, match="Params.lam_coupling must be a number"):
        Params(lam_coupling="10")
    with pytest.raises(TypeError, match="Params.window must be an integer"):
        Params(window=True)


# ----------------------------------------------------------------------------- frames: one rule everywhere
def _validators():
    """Every public entry point, called so that it only validates."""
    from ivkernels.flow import as_linear_rgb

    return {
        "iter_decompose": lambda x: iv.iter_decompose(x, flow="dis", params=FAST),
        "estimate_flow": lambda x: as_linear_rgb(x),
        "to_linear_float": lambda x: to_linear_float(x),
    }


BAD_FRAMES = [
    ("float 0..255", np.full((2, 16, 16, 3), 128.0, np.float32), ValueError, r"\[0, 1\]"),
    ("negative float", np.full((2, 16, 16, 3), -0.25, np.float64), ValueError, r"\[0, 1\]"),
    ("NaN", np.full((2, 16, 16, 3), np.nan, np.float32), ValueError, "NaN"),
    ("inf", np.full((2, 16, 16, 3), np.inf, np.float64), ValueError, "NaN or infinite"),
    ("int32", np.zeros((2, 16, 16, 3), np.int32), TypeError, "dtype int32"),
    ("float16", np.zeros((2, 16, 16, 3), np.float16), TypeError, "float16"),
    ("bool", np.zeros((2, 16, 16, 3), bool), TypeError, "bool"),
    ("4 channels", np.zeros((2, 16, 16, 4), np.uint8), ValueError, "3 colour channels"),
    ("no channels", np.zeros((2, 16, 16), np.float32), ValueError, r"\(T, H, W, 3\)"),
    ("empty", np.zeros((0, 16, 16, 3), np.uint8), ValueError, "empty"),
]


@pytest.mark.parametrize("label, bad, exc, match", BAD_FRAMES, ids=[c[0] for c in BAD_FRAMES])
def test_every_entry_point_refuses_the_same_frames(label, bad, exc, match):
    for entry, call in _validators().items():
        with pytest.raises(exc, match=match):
            call(bad)


def test_estimate_flow_refuses_float_frames_in_0_255(frames8):
    # the same array decompose refuses; formerly a flow of exactly zero
    with pytest.raises(ValueError, match="uint8"):
        estimate_flow(frames8.astype(np.float32), method="dis")
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        iv.decompose(frames8.astype(np.float32), flow="dis", params=FAST)


def test_estimate_flow_refuses_negative_floats(frames_f):
    bad = frames_f.copy()
    bad[1, 3, 3, 0] = -0.5
    with pytest.raises(ValueError, match=r"frames\[1\].*\[0, 1\]"):
        estimate_flow(bad, method="dis")


def test_uint16_frames_are_accepted_everywhere(frames8):
    from ivkernels.flow import as_linear_rgb

    u16 = frames8.astype(np.uint16) * 257        # the same sRGB codes at 16 bits
    np.testing.assert_allclose(as_linear_rgb(u16), to_linear_float(frames8), atol=1e-6)
    assert estimate_flow(u16, method="dis").shape == (2, 16, 16, 2)
    # uint8 is decoded the same way by the flow and by decompose
    np.testing.assert_array_equal(estimate_flow(frames8, method="dis"),
                                  estimate_flow(to_linear_float(frames8), method="dis"))


def test_iter_decompose_validates_at_the_call():
    # no next(): the bad input must raise when iter_decompose is called
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        iv.iter_decompose(np.full((2, 16, 16, 3), 2.0, np.float32))
    with pytest.raises(ValueError, match="unknown flow method"):
        iv.iter_decompose(np.zeros((2, 16, 16, 3), np.uint8), flow="raft")
    with pytest.raises(TypeError, match="Params"):
        iv.iter_decompose(np.zeros((2, 16, 16, 3), np.uint8), params={"window": 3})


def test_frames_of_different_sizes_name_the_bad_frame(frames8):
    frames = [frames8[0], frames8[1], np.zeros((20, 16, 3), np.uint8)]
    for call in _validators().values():
        with pytest.raises(ValueError, match=r"frames\[2\] is 20x16x3 but frames\[0\] is 16x16x3"):
            call(frames)
    mixed = [frames8[0], to_linear_float(frames8)[1]]
    with pytest.raises(ValueError, match=r"frames\[1\] has dtype float32"):
        iv.iter_decompose(mixed)
    # frames of one size are stacked
    np.testing.assert_array_equal(to_linear_float(list(frames8)), to_linear_float(frames8))
    assert estimate_flow(list(frames8), method="dis").shape == (2, 16, 16, 2)


def test_a_single_frame_is_taken_as_one_frame(frames8):
    windows = list(iv.iter_decompose(frames8[0], params=FAST))
    assert len(windows) == 1 and windows[0].albedo.shape == (1, 16, 16, 3)
    video = iv.decompose(to_linear_float(frames8)[0], params=FAST)
    assert video.albedo.shape == (1, 16, 16, 3) and video.flow is None
    with pytest.raises(ValueError, match="at least 2 frames"):
        estimate_flow(frames8[0])


def test_too_small_frames_are_refused():
    with pytest.raises(ValueError, match="at least 8x8"):
        iv.iter_decompose(np.zeros((2, 7, 16, 3), np.uint8))


# ----------------------------------------------------------------------------- memory
HUGE = np.broadcast_to(np.zeros((1, 1, 1, 3), np.uint8), (100_000, 4000, 4000, 3))   # no memory


@pytest.mark.parametrize("entry", ["decompose", "iter_decompose", "estimate_flow", "to_linear_float"])
def test_memory_is_checked_before_allocating(entry):
    call = {
        "decompose": lambda: iv.decompose(HUGE, flow="dis"),
        "iter_decompose": lambda: iv.iter_decompose(HUGE, flow="dis"),
        "estimate_flow": lambda: estimate_flow(HUGE, method="dis"),
        "to_linear_float": lambda: to_linear_float(HUGE),
    }[entry]
    with pytest.raises(MemoryError, match=r"needs about [\d.]+ [KMGTP]iB of memory .* is available"):
        call()


def test_memory_error_is_also_a_value_error():
    with pytest.raises(ValueError, match="needs about"):
        iv.iter_decompose(HUGE)


def test_read_frames_checks_memory_before_reading(image_folder, monkeypatch):
    from ivkernels import validation

    monkeypatch.setattr(validation, "available_memory", lambda: 1000)
    with pytest.raises(MemoryError, match=r"reading 3 frames of 16x16 .* needs about 9.0 KiB"):
        read_frames(image_folder)


# ----------------------------------------------------------------------------- flow
def test_flow_that_overflows_float32_is_refused(frames8):
    flow = np.zeros((2, 16, 16, 2), np.float64)
    flow[1, 4, 4, 0] = 1e39
    with pytest.raises(ValueError, match=r"flow\[1\] has a component of 1e\+39 pixels"):
        iv.iter_decompose(frames8, flow=flow)
    flow[1, 4, 4, 0] = 1e9               # Middlebury's "unknown" marker
    with pytest.raises(ValueError, match="Middlebury"):
        iv.iter_decompose(frames8, flow=flow)


@pytest.mark.parametrize("bad, exc, match", [
    (np.zeros((2, 16, 16, 2), np.int32), TypeError, "float"),
    (np.full((2, 16, 16, 2), np.nan), ValueError, "NaN"),
    (np.zeros((1, 16, 16, 2)), ValueError, r"\(T-1, H, W, 2\)"),
])
def test_bad_flow_is_refused(frames8, bad, exc, match):
    with pytest.raises(exc, match=match):
        iv.iter_decompose(frames8, flow=bad)


def test_bad_initial_flow_is_refused(frames_f):
    init = np.zeros((2, 16, 16, 2))
    init[0, 0, 0, 1] = 1e39
    with pytest.raises(ValueError, match="init"):
        estimate_flow(frames_f, init=init)


# ----------------------------------------------------------------------------- backend and device
@pytest.mark.parametrize("device, exc, match", [
    (None, TypeError, "device must be a string"),
    (0, TypeError, "device must be a string"),
    ("gpu", ValueError, r"'cpu' or 'cuda\[:N\]'"),
    ("cuda:x", ValueError, r"'cpu' or 'cuda\[:N\]'"),
])
def test_bad_device_is_a_clear_error(frames8, device, exc, match):
    with pytest.raises(exc, match=match):
        iv.iter_decompose(frames8, device=device)
    with pytest.raises(exc, match=match):
        estimate_flow(frames8, device=device)


@pytest.mark.skipif("_cuda_present()")
def test_cuda_without_a_gpu_is_a_clear_error(frames8):
    with pytest.raises(ValueError, match="no CUDA device"):
        iv.iter_decompose(frames8, device="cuda")
    with pytest.raises(ValueError, match="no CUDA device"):
        estimate_flow(frames8, device="cuda:0")


def test_taichi_runs_on_the_cpu_only(frames8):
    with pytest.raises(ValueError, match="taichi"):
        iv.iter_decompose(frames8, backend="taichi", device="cuda")


def test_too_many_pyramid_levels_are_refused(monkeypatch, frames8):
    from ivkernels import validation

    monkeypatch.setattr(validation, "MAX_PYRAMID_LEVELS", 1)
    with pytest.raises(ValueError, match="pyramid levels"):
        iv.iter_decompose(np.zeros((2, 64, 64, 3), np.uint8), params=Params(pyramid_min_size=8))


# ----------------------------------------------------------------------------- video files
def _faststart_video(path, frames):
    """An mp4 with its index first, so a truncated copy still opens."""
    import imageio_ffmpeg

    writer = imageio_ffmpeg.write_frames(str(path), frames.shape[2:0:-1], fps=10, codec="libx264",
                                         pix_fmt_out="yuv420p", macro_block_size=1,
                                         ffmpeg_log_level="error",
                                         output_params=["-movflags", "+faststart"])
    writer.send(None)
    for f in frames:
        writer.send(np.ascontiguousarray(f))
    writer.close()


def test_truncated_video_is_detected(tmp_path):
    frames = np.random.default_rng(1).integers(0, 256, (20, 16, 16, 3), dtype=np.uint8)
    full = tmp_path / "full.mp4"
    _faststart_video(full, frames)
    assert read_frames(full).shape == (20, 16, 16, 3)
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(full.read_bytes()[: full.stat().st_size // 2])
    with pytest.raises(ValueError, match=r"ends after \d+ frames but its header announces about 20"):
        read_frames(cut)
    assert read_frames(cut, stop=3).shape[0] == 3      # frames before the damage are readable


# ----------------------------------------------------------------------------- command line
def _one_line_error(rc, err):
    lines = err.strip().splitlines()
    assert rc == 2, err
    assert len(lines) == 1 and lines[0].startswith("ivkernels: error: "), err
    return lines[0]


@pytest.mark.parametrize("extra, match", [
    (["--fps", "0"], "--fps"),
    (["--fps", "-5"], "--fps"),
    (["--fps", "nan"], "--fps"),
    (["--fps", "inf"], "--fps"),
    (["--scale", "0"], "--scale"),
    (["--scale", "nan"], "--scale"),
    (["--step", "0"], "--step"),
    (["--start", "-1"], "--start"),
    (["--start", "5", "--stop", "2"], "--stop"),
    (["--window", "1"], "--window"),
    (["--device", "gpu"], "device"),
    (["--backend", "taichi", "--device", "cuda"], "taichi"),
    (["--flow", "raft"], "unknown flow method"),
])
def test_cli_checks_arguments_before_any_work(image_folder, tmp_path, capsys, no_work, extra, match):
    out = tmp_path / "out"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--quiet", *extra])
    assert match in _one_line_error(rc, capsys.readouterr().err)
    assert not out.exists() and not list(tmp_path.glob("*.partial"))


@pytest.mark.parametrize("argv", [
    ["decompose", "in", "-o", "out", "--fps", "ten"],
    ["decompose", "in"],
    ["decompose", "in", "-o", "out", "--backend", "torch"],
    ["compose"],
])
def test_cli_usage_errors_are_one_line_and_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(argv)
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert len(err.strip().splitlines()) == 1 and "error:" in err and "--help" in err, err


@pytest.mark.skipif("_cuda_present()")
def test_cli_cuda_without_a_gpu_is_one_line_and_exit_2(image_folder, tmp_path, capsys, no_work):
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--device", "cuda"])
    assert "no CUDA device" in _one_line_error(rc, capsys.readouterr().err)


def test_cli_window_sets_a_valid_overlap(image_folder, tmp_path, capsys, monkeypatch):
    seen = {}

    def fake_iter(frames, **kwargs):
        seen.update(kwargs)
        raise ValueError("stop here")

    monkeypatch.setattr(cli, "iter_decompose", fake_iter)
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--window", "2"])
    assert rc == 2 and seen["params"].window == 2 and seen["params"].overlap == 1


def test_cli_bad_input_files_are_one_line_and_exit_2(tmp_path, capsys, frames8):
    mixed = tmp_path / "mixed"
    write_png_sequence(mixed, frames8[:2])
    write_png_sequence(mixed, np.zeros((1, 20, 16, 3), np.uint8), prefix="more")
    empty = tmp_path / "empty"
    empty.mkdir()
    video = tmp_path / "v.mp4"
    _faststart_video(video, np.random.default_rng(2).integers(0, 256, (20, 16, 16, 3), np.uint8))
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(video.read_bytes()[: video.stat().st_size // 2])
    broken = tmp_path / "broken.mp4"
    broken.write_bytes(b"not a video at all")
    for src, match in [(mixed, "share one size"), (empty, "holds no images"), (cut, "truncated"),
                       (broken, "could not read video"), (tmp_path / "nope", "does not exist")]:
        out = tmp_path / f"out_{src.name}"
        rc = cli.main(["decompose", str(src), "-o", str(out), "--quiet", "--flow", "dis"])
        assert match in _one_line_error(rc, capsys.readouterr().err), src
        assert not out.exists()
    assert not list(tmp_path.glob("*.partial"))


def test_cli_memory_is_checked_before_reading(image_folder, tmp_path, capsys, monkeypatch, no_work):
    from ivkernels import validation

    monkeypatch.setattr(validation, "available_memory", lambda: 10_000)
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--quiet"])
    line = _one_line_error(rc, capsys.readouterr().err)
    assert "decomposing 3 frames of 16x16 needs about" in line and "--scale" in line
