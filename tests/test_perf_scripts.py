"""Smoke test of the benchmark scripts in perf/: they run and print their tables (no timings checked)."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ivkernels.evaluation import datasets, synthetic

PERF = Path(__file__).resolve().parents[1] / "perf"


@pytest.mark.slow
def test_bench_kernels_quick_vecops_prints_a_table():
    proc = subprocess.run(
        [sys.executable, str(PERF / "bench_kernels.py"), "--quick", "--repeat", "1", "--only", "vecops"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    assert "| kernel" in out and "W1/W2" in out
    assert "| vecops.dot" in out and "| vecops.fill" in out
    assert "geometric mean over kernels" in out


def test_accuracy_baselines_on_a_tiny_sequence():
    proc = subprocess.run(
        [sys.executable, str(PERF / "accuracy.py"), "--size", "32", "48", "--frames", "3", "--seed", "5",
         "--kinds", "static_moving_light", "objects_camera", "--no-mit",
         "--methods", "CRET", "CRET-tuned", "Weiss", "Weiss-gtflow", "GT"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    assert "seed 5 is a training seed" in out
    assert "mean over 2 kinds" in out and "flicker" in out
    for name in ("CRET-tuned", "Weiss-gtflow", "GT"):
        assert f"\n{name} " in out
    assert "IV-noflow" not in out
    assert "summary" in out


def test_tune_baselines_refuses_the_evaluation_seed():
    proc = subprocess.run([sys.executable, str(PERF / "tune_baselines.py"), "--seeds", "0", "1"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0 and "evaluation seed" in proc.stderr


@pytest.mark.slow
def test_eval_flow_synthetic_prints_a_table(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(PERF / "eval_flow_synthetic.py"), "--seeds", "1", "--frames", "2", "--size", "32", "48",
         "--kinds", "static_moving_light", "--baselines", "zero", "--cache", str(tmp_path),
         "--candidate", "grad=classic_nl_fast:lam=10.0,data_term=gradient"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "static_moving_light" in proc.stdout and "| zero" not in proc.stdout
    assert "grad " in proc.stdout and "zero " in proc.stdout


@pytest.mark.slow
def test_eval_joint_prints_every_pass():
    proc = subprocess.run(
        [sys.executable, str(PERF / "eval_joint.py"), "--passes", "2", "--frames", "2", "--size", "32", "48",
         "--kinds", "static_moving_light"],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line.startswith("static_moving_light")]
    assert [r[1] for r in rows] == ["1", "2"]


@pytest.mark.slow
def test_eval_flow_passes_prints_a_row_per_pass():
    proc = subprocess.run(
        [sys.executable, str(PERF / "eval_flow_passes.py"), "--passes", "1", "2", "--frames", "2", "--size", "32",
         "48", "--kinds", "static_moving_light", "--seed", "4", "--set", "start_from_guide=false"],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "Params changes: {'start_from_guide': False}" in proc.stdout
    rows = [line.split() for line in proc.stdout.splitlines() if line.startswith("static_moving_light")]
    assert [r[1] for r in rows] == ["1", "2"]
    assert rows[0][9] == "-" and float(rows[1][9]) >= 0.0      # a guide solve only with 2 passes


@pytest.mark.slow
def test_bench_balance_prints_a_row_per_pair(tmp_path):
    import cv2

    from ivkernels.flowio import write_flo
    from ivkernels.evaluation.synthetic import render_sequence

    seq = render_sequence("objects_camera", n_frames=2, size=(40, 56), seed=1)
    pair = tmp_path / "Venus"
    pair.mkdir()
    for name, frame in zip(("frame10.png", "frame11.png"), seq.frames):
        encoded = np.round(np.clip(frame, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)
        cv2.imwrite(str(pair / name), encoded[..., ::-1])
    write_flo(pair / "flow10.flo", seq.flow[0])
    proc = subprocess.run(
        [sys.executable, str(PERF / "bench_balance.py"), "--data", str(tmp_path), "--sequences", "Venus",
         "--threads", "2", "--chunks", "4", "--repeat", "1"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line.startswith("Venus")]
    assert len(rows) == 1 and len(rows[0]) == 2 + 2 * 3        # name, share, 3 configurations x (s, ratio)
    assert "2 x 4" in proc.stdout


def test_energy_at_truth_puts_the_truth_beside_the_solution():
    proc = subprocess.run(
        [sys.executable, str(PERF / "energy_at_truth.py"), "--seeds", "3", "--frames", "3",
         "--size", "24", "32", "--kinds", "static_moving_light", "--set", "lbfgs_iterations=5"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = {line.split()[1]: line.split() for line in proc.stdout.splitlines()
            if line.startswith("static_moving_light/3")}
    assert set(rows) == {"solution", "truth", "weiss"}
    # The synthetic frames are albedo x shading exactly, so A = I - S_truth is the true albedo.
    assert float(rows["truth"][-1]) < 1e-3 < float(rows["solution"][-1])
    totals = {point: float(row[-2]) for point, row in rows.items()}
    assert all(np.isfinite(v) and v > 0 for v in totals.values())


def test_energy_at_truth_refuses_the_evaluation_seed():
    proc = subprocess.run([sys.executable, str(PERF / "energy_at_truth.py"), "--seeds", "0"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "seed 0" in proc.stderr


def test_light_change_prints_a_row_per_sequence():
    """A row per sequence; one lamp followed along its true flow counts once."""
    proc = subprocess.run(
        [sys.executable, str(PERF / "light_change.py"), "--seeds", "3", "--frames", "3", "--size", "40", "56",
         "--kinds", "objects_camera", "static_moving_light"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = {line.split()[0]: line.split() for line in proc.stdout.splitlines() if "/3 " in line}
    assert set(rows) == {"objects_camera/3", "static_moving_light/3"}
    assert float(rows["objects_camera/3"][-1]) == pytest.approx(1.0)


@pytest.mark.parametrize("flow", ["truth", "estimated"])
def test_convergence_prints_every_budget_and_the_reference(flow):
    """A row per budget (the default first, the reference last, at 100% of the drop)."""
    proc = subprocess.run(
        [sys.executable, str(PERF / "convergence.py"), "--seeds", "3", "--frames", "3", "--size", "32", "48",
         "--kinds", "objects_camera", "--budgets", "3", "--reference", "12", "--flow", flow,
         "--set", "lbfgs_iterations=6"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line.startswith("objects_camera/3")]
    iters = [int(row[-6]) for row in rows]
    assert iters == [6, 3, 12]
    assert "(default)" in rows[0]
    assert float(rows[-1][-2]) == pytest.approx(100.0)
    assert all(0.0 < float(row[-1]) < 1.0 for row in rows)           # LMSE


def test_convergence_refuses_the_evaluation_seed():
    proc = subprocess.run([sys.executable, str(PERF / "convergence.py"), "--seeds", "0"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "seed 0" in proc.stderr


def test_bench_solver_one_configuration_takes_params_settings():
    """``--one --set`` times one decomposition with the given Params fields and prints its stages."""
    import json

    base = [sys.executable, str(PERF / "bench_solver.py"), "--one", "--frames", "3", "--height", "32",
            "--width", "40", "--threads", "1", "--flow-passes", "1"]
    proc = subprocess.run(base + ["--set", "coarse_basis_levels=1", "lbfgs_iterations=5"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["total"] > 0 and result["stages"]["solve"] > 0
    proc = subprocess.run(base + ["--set", "coarse_basis_levels=0"], capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0 and "coarse_basis_levels" in proc.stderr


def test_flow_by_object_swaps_only_the_objects_pixels():
    """The swapped flow is the estimated one exactly on object k's pixels of frame t."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("flow_by_object", PERF / "flow_by_object.py")
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(PERF))
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(PERF))
    rng = np.random.default_rng(0)
    ids = rng.integers(0, 3, size=(3, 5, 7))
    truth = rng.normal(size=(2, 5, 7, 2)).astype(np.float32)
    estimated = rng.normal(size=(2, 5, 7, 2)).astype(np.float32)
    out = module.swapped_flow(truth, estimated, ids, 1)
    on = ids[:-1] == 1
    assert on.any() and (~on).any()
    np.testing.assert_array_equal(out[on], estimated[on])
    np.testing.assert_array_equal(out[~on], truth[~on])


def test_flow_by_object_prints_a_row_per_object():
    proc = subprocess.run(
        [sys.executable, str(PERF / "flow_by_object.py"), "--seeds", "3", "--frames", "3", "--size", "32", "48",
         "--kinds", "objects_camera", "--min-share", "0.05", "--set", "lbfgs_iterations=4"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "objects_camera/3: LMSE mean" in proc.stdout
    rows = [line.split() for line in proc.stdout.splitlines() if line.strip()[:1].isdigit()]
    assert len(rows) >= 2 and {int(row[0]) for row in rows} >= {0}      # the floor at least
    assert all(float(row[1]) >= 0.05 for row in rows)                   # --min-share
    assert all(0.0 <= float(cell) < 1.0 for row in rows for cell in row[4:])


def test_flow_by_object_refuses_the_evaluation_seed():
    proc = subprocess.run([sys.executable, str(PERF / "flow_by_object.py"), "--seeds", "0"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "seed 0" in proc.stderr


def test_seed_spread_keeps_the_evaluation_seed_out_of_the_summary():
    proc = subprocess.run(
        [sys.executable, str(PERF / "seed_spread.py"), "--seeds", "0", "3", "4", "--size", "32", "48",
         "--frames", "3", "--kinds", "static_moving_light", "objects_camera", "--ratio", "CRET", "CRET-tuned"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    rows = {line.split()[0]: [float(v) for v in line.split()[1:]] for line in out.splitlines()
            if line.split() and line.split()[0] in ("0*", "3", "4")}
    assert set(rows) == {"0*", "3", "4"}
    for num, den, ratio, static, objects in rows.values():
        # the printed means are rounded to 4 decimals, the ratio to 3
        assert (num - 5e-5) / (den + 5e-5) - 5e-4 <= ratio <= (num + 5e-5) / (den - 5e-5) + 5e-4
        # the ratio of the means is a weighted mean of the per-kind ratios
        assert min(static, objects) - 2e-3 <= ratio <= max(static, objects) + 2e-3
    training = [rows["3"][2], rows["4"][2]]
    assert f"range {min(training):.3f}-{max(training):.3f}" in out
    assert "of 2 seeds" in out and "not in the summary" in out


@pytest.mark.parametrize("argv, message", [
    (["--ratio", "IV", "GT"], "not a method to compare"),
    (["--ratio", "IV", "IV"], "must differ"),
    (["--seeds", "1", "1"], "distinct seeds"),
    (["--ratio", "CRET", "Weiss", "--iv-param", "lam_coupling=3"], "IV methods only"),
])
def test_seed_spread_refuses_bad_arguments(argv, message):
    proc = subprocess.run([sys.executable, str(PERF / "seed_spread.py"), *argv],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and message in proc.stderr


def _run(script, *argv, timeout=600):
    proc = subprocess.run([sys.executable, str(PERF / script), *argv], capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return proc.stdout


def _method_rows(out: str, title_start: str) -> dict:
    """``{method: [numbers]}`` of the first table whose title starts with ``title_start``."""
    lines = out.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(title_start))
    rows = {}
    for line in lines[i + 2:]:
        if not line.strip():
            break
        name, *values = line.split()
        rows[name] = [float(v) for v in values]
    return rows


def test_accuracy_ratio_table_puts_the_worst_kind_first():
    kinds = ["grey_turning_hard", "mixed_fast_light_hard", "static_moving_light"]
    out = _run("accuracy.py", "--size", "24", "32", "--frames", "3", "--seed", "4", "--kinds", *kinds, "--no-mit",
               "--no-footage", "--drift-kinds", "--methods", "IV", "LRET", "CRET-tuned", "Weiss", "--iv-param", "lbfgs_iterations=3")
    lines = out.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith("issue 33: IV / best per-frame"))
    table = [line.split() for line in lines[start + 2:start + 2 + len(kinds)]]
    assert sorted(row[0] for row in table) == sorted(kinds)
    worst = []
    for row in table:
        rows = _method_rows(out, f"{row[0]}: seed 4")
        iv = rows["IV"][2]                                          # LMSE mean
        best = min(("LRET", "CRET-tuned"), key=lambda m: rows[m][2])
        assert row[2] == best and float(row[4]) == pytest.approx(iv / rows[best][2], abs=2e-3)
        ratios = [iv / rows[best][2]]
        if row[0] != "grey_turning_hard":                            # static scenes: also against Weiss
            assert float(row[6]) == pytest.approx(iv / rows["Weiss"][2], abs=2e-3)
            ratios.append(iv / rows["Weiss"][2])
        else:
            assert row[5] == row[6] == "-"
        worst.append(max(ratios))
    assert worst == sorted(worst, reverse=True)
    assert "mean over 3 kinds: IV / best per-frame" in out


@pytest.mark.parametrize("argv, message", [
    (["--suite", "everything"], "invalid choice"),
    (["--kinds", "grey_flying_cars"], "unknown grey_flying_cars"),
])
def test_accuracy_refuses_unknown_kind_sets(argv, message):
    proc = subprocess.run([sys.executable, str(PERF / "accuracy.py"), "--no-mit", "--no-footage", *argv],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and message in proc.stderr


def test_accuracy_drift_check_against_the_truth(tmp_path):
    """The drift check renders the kind long and prints IV's drift against the truth,
    saved and read back with --load."""
    rows = tmp_path / "rows.json"
    out = _run("accuracy.py", "--kinds", "--no-mit", "--no-footage", "--methods", "IV", "--seed", "3",
               "--iv-param", "lbfgs_iterations=3", "--drift-kinds", "objects_camera", "--drift-frames", "6",
               "--drift-size", "24", "32", "--save", str(rows))
    line = next(l for l in out.splitlines() if l.strip().startswith("objects_camera") and " IV " in l)
    assert line.split()[1] == "6x32x24"
    drift = float(line.split()[3])
    assert np.isfinite(drift) and ("met" in line or "missed by" in line)
    again = _run("accuracy.py", "--load", str(rows))
    assert line in again.splitlines()


def test_accuracy_greyscale_footage_check(tmp_path):
    """Two grey frames with a dark band: the input keeps it dark (dark ratio well below 1)."""
    import cv2

    folder = tmp_path / "middlebury" / "Tiny"
    folder.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for k in (10, 11):
        img = np.full((30, 41, 3), 200, np.uint8)
        img[:, 5:12] = 30
        img = np.clip(img + rng.integers(-3, 4, img.shape), 0, 255).astype(np.uint8)
        cv2.imwrite(str(folder / f"frame{k}.png"), img)
    out = _run("accuracy.py", "--kinds", "--no-mit", "--data-root", str(tmp_path), "--middlebury-scale", "1",
               "--methods", "LRET", "input")
    row = next(line.split() for line in out.splitlines() if line.startswith("middlebury/Tiny "))
    assert row[1] == "2x41x30"
    input_dark = float(row[4])
    assert input_dark < 0.3                                      # the band is 7 of 41 columns at 30 / 200
    assert "greyscale footage: dark ratio" in out


@pytest.mark.skipif(not datasets.available_mit_objects(), reason="MIT-Berkeley training objects not present")
def test_accuracy_mit_objects_in_colour_and_grey():
    out = _run("accuracy.py", "--kinds", "--no-footage", "--mit-objects", "apple", "--mit-scale", "0.1",
               "--methods", "LRET", "CRET-tuned", "Weiss", "input")
    colour = _method_rows(out, "MIT apple (colour)")
    grey = _method_rows(out, "MIT apple (achromatic)")
    assert set(colour) == set(grey) == {"LRET", "CRET-tuned", "Weiss", "input"}
    assert colour["input"] != grey["input"]
    assert "MIT (achromatic): mean over 1 objects" in out


def test_seed_spread_takes_a_suite_of_new_kinds():
    out = _run("seed_spread.py", "--seeds", "3", "--size", "24", "32", "--frames", "2", "--suite", "static",
               "--ratio", "LRET", "CRET-tuned")
    header = next(line for line in out.splitlines() if line.split()[:1] == ["seed"])
    n_static = len(synthetic.scene_kinds("static"))
    assert len(header.split()) == 4 + n_static
    row = next(line.split() for line in out.splitlines() if line.split()[:1] == ["3"])
    assert len(row) == 4 + n_static


def test_calibrate_runs_a_new_kind_and_refuses_the_evaluation_seed():
    out = _run("calibrate.py", "--seeds", "3", "--frames", "2", "--size", "24", "32", "--kinds",
               "grey_turning_hard", "--grid", "lbfgs_iterations=3", "--no-ablation")
    row = next(line.split() for line in out.splitlines() if line.startswith("lbfgs_iterations=3"))
    assert row[1] == "IV" and 0.0 < float(row[2]) == pytest.approx(float(row[3]))
    proc = subprocess.run([sys.executable, str(PERF / "calibrate.py"), "--seeds", "0"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "evaluation seed" in proc.stderr


def test_tune_baselines_searches_the_luminance_threshold():
    out = _run("tune_baselines.py", "--seeds", "3", "--frames", "2", "--size", "24", "32", "--suite", "achromatic",
               "--mit-scale", "0", "--skip-weiss")
    rows = [line.split() for line in out.splitlines() if line.split() and line.split()[0][:1].isdigit()]
    criteria = {float(r[0]): float(r[3]) for r in rows if len(r) == 4}
    assert len(criteria) >= 10
    best_line = next(line for line in out.splitlines() if line.startswith("best: threshold="))
    best = float(best_line.split("=")[1].split(":")[0])
    assert criteria[best] == min(criteria.values())
    assert "best: threshold_gray=" in out                  # the colour search ran too


def test_dark_disc_prints_a_row_per_noise_channels_and_setting():
    proc = subprocess.run(
        [sys.executable, str(PERF / "dark_disc.py"), "--size", "32", "40", "--frames", "3", "--radius", "8",
         "--noise", "0", "0.003", "--grid", "shading_step_noise=0,2.5"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line.strip().startswith(("0.0000", "0.0030"))]
    assert [(r[1], r[2]) for r in rows] == [("-", "shading_step_noise=0"), ("-", "shading_step_noise=2.5"),
                                            ("per", "shading_step_noise=0"), ("per", "shading_step_noise=2.5"),
                                            ("shared", "shading_step_noise=0"), ("shared", "shading_step_noise=2.5")]
    assert all(0.0 < float(r[3]) < 2.0 for r in rows) and "truth 0.160" in proc.stdout
    bad = subprocess.run([sys.executable, str(PERF / "dark_disc.py"), "--size", "32", "40", "--radius", "30"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode != 0 and "--radius" in bad.stderr


def test_perf_scripts_import_only_the_common_module():
    """The evaluation scripts share perf/common.py and never import each other."""
    scripts = {p.stem for p in PERF.glob("*.py")} - {"common"}
    for stem in ("accuracy", "seed_spread", "calibrate", "convergence", "energy_at_truth", "flow_by_object",
                 "tune_baselines"):
        text = (PERF / f"{stem}.py").read_text()
        assert "from common import" in text, stem
        for name in scripts:
            assert f"from {name} import" not in text and f"import {name}\n" not in text, (stem, name)


def test_hold_out_chooses_leaving_one_kind_out(tmp_path):
    """Two settings on two kinds: the ratio table, the held-out choice per kind, and --load
    reading the saved rows back without running anything."""
    rows = tmp_path / "ho.json"
    out = _run("hold_out.py", "--seeds", "3", "--frames", "3", "--size", "24", "32", "--kinds", "objects_camera",
               "grey_turning_hard", "--gt-flow", "--base", "lbfgs_iterations=3",
               "--grid", "shading_step_share_radius=0,0.3", "--save", str(rows))
    assert "Leave one kind out" in out
    held = [line.split() for line in out.splitlines() if line.startswith("  ") and " chosen " in line]
    assert sorted(r[0] for r in held) == ["grey_turning_hard", "objects_camera"]
    assert all(float(r[-1]) > 0 for r in held)
    again = _run("hold_out.py", "--load", str(rows))
    assert [l for l in again.splitlines() if "held-out" in l] == [l for l in out.splitlines() if "held-out" in l]
    with pytest.raises(AssertionError, match="evaluation seed"):
        _run("hold_out.py", "--seeds", "0", "--kinds", "objects_camera")


def test_long_video_prints_a_row_per_part():
    proc = subprocess.run(
        [sys.executable, str(PERF / "long_video.py"), "--frames", "30", "--size", "32", "40", "--parts", "3",
         "--flow", "dis"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line.split() and "-" in line.split()[0]
            and line.split()[0].replace("-", "").isdigit()]
    assert [r[0] for r in rows] == ["0-10", "10-20", "20-30"]
    assert all(float(r[1]) > 0 and float(r[3]) > 0 for r in rows)
    assert rows[0][2] == "1.00"
    assert "windows" in proc.stdout.splitlines()[-1]


def test_long_video_refuses_too_few_frames():
    proc = subprocess.run([sys.executable, str(PERF / "long_video.py"), "--frames", "1"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "--frames must be >= 2" in proc.stderr


@pytest.mark.slow
def test_stream_fps_prints_each_window_and_the_rate():
    proc = subprocess.run([sys.executable, str(PERF / "stream_fps.py"), "--frames", "10", "--size", "40", "48",
                           "--set", "lbfgs_iterations=5", "outer_iterations=1"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    assert "10 frames at 48x40 on cpu" in out
    assert "    0    0-7 " in out and "    1    2-9 " in out
    assert "after the first window: 2 frames in" in out and "frames/s" in out


def test_side_by_side_times_a_named_kind():
    proc = subprocess.run(
        [sys.executable, str(PERF / "side_by_side.py"), "tiny", "--kind", "mixed_fast_light_hard",
         "--size", "40", "56", "--frames", "3", "--threads", "1"],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("tiny: ") and "solve" in proc.stdout
    bad = subprocess.run([sys.executable, str(PERF / "side_by_side.py"), "x", "--kind", "grey_flying_cars"],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode != 0 and "invalid choice" in bad.stderr
