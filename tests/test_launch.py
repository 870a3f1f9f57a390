"""Row-band launches on N threads: the band split, the thread-count setting
(default, environment variable, per call, command line) and its checks, and
identical results on 1 to 4 threads for gather and scatter kernels."""
import os
import threading

import numpy as np
import pytest
import warp as wp

import ivkernels as iv
from ivkernels import Params, cli
from ivkernels.evaluation import synthetic
from ivkernels.backends import get_backend
from ivkernels.kernels import launch, thread_count
from ivkernels.kernels.launch import (THREADS_ENV, available_cores, get_threads, iterate_with_threads,
                                      launch_rows, min_band_rows, row_bands, set_threads, threads,
                                      threads_from_environment)

FAST = Params(outer_iterations=1, lbfgs_iterations=3)


@wp.kernel
def count_rows(row_begin: int, visits: wp.array(dtype=int), first_row: wp.array(dtype=int)):
    r = row_begin + wp.tid()
    wp.atomic_add(visits, r, 1)
    first_row[r] = row_begin


@pytest.fixture
def split_everything(monkeypatch):
    """Let every launch of >= 2 rows split (small test inputs would stay on one thread)."""
    monkeypatch.setattr(launch, "MIN_BAND_ELEMENTS", 1)


@pytest.fixture
def band_counts(monkeypatch):
    """Record how many bands each split launch used."""
    seen = []
    original = launch.row_bands

    def spy(*args, **kwargs):
        bands = original(*args, **kwargs)
        seen.append(len(bands))
        return bands

    monkeypatch.setattr(launch, "row_bands", spy)
    return seen


@pytest.fixture
def thread_counts(monkeypatch):
    """Record the thread count every launch (and every default lookup) saw."""
    seen = []
    original = launch.get_threads

    def spy():
        n = original()
        seen.append(n)
        return n

    monkeypatch.setattr(launch, "get_threads", spy)
    return seen


# ----------------------------------------------------------------------------- the band split

@pytest.mark.parametrize("n_bands", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("n_rows", [1, 2, 3, 7, 37, 101, 480])
@pytest.mark.parametrize("align", [1, 3, 37])
@pytest.mark.parametrize("min_rows", [1, 5, 64])
def test_bands_cover_every_row_once_aligned_and_balanced(n_rows, n_bands, align, min_rows):
    bands = row_bands(n_rows, n_bands, align, min_rows)
    covered = np.zeros(n_rows, int)
    for begin, count in bands:
        assert count >= 1
        covered[begin:begin + count] += 1
    np.testing.assert_array_equal(covered, 1)
    assert [b for b, _ in bands] == sorted(b for b, _ in bands)
    assert 1 <= len(bands) <= n_bands
    assert all(begin % align == 0 for begin, _ in bands)
    if len(bands) > 1:
        assert all(count >= min_rows for _, count in bands)
        units = [count // align for _, count in bands[:-1]] + [bands[-1][1] // align]
        assert max(units) - min(units) <= 1
    # as many bands as the rules allow
    units = n_rows // align
    assert len(bands) == max(1, min(n_bands, units // -(-min_rows // align)))


def test_band_split_by_hand():
    assert row_bands(10, 3) == [(0, 4), (4, 3), (7, 3)]
    assert row_bands(20, 3, align=4) == [(0, 8), (8, 8), (16, 4)]
    assert row_bands(22, 3, align=4) == [(0, 8), (8, 8), (16, 6)]    # the tail rows join the last band
    assert row_bands(7, 4, align=4) == [(0, 7)]                      # no aligned split
    assert row_bands(100, 4, min_rows=30) == [(0, 34), (34, 33), (67, 33)]
    assert row_bands(0, 4) == [] and row_bands(-3, 2) == []


def test_bad_band_arguments_raise():
    for args in [(10, 0), (10, 2, 0), (10, 2, 1, 0)]:
        with pytest.raises(ValueError, match=">= 1"):
            row_bands(*args)


def test_min_band_rows_counts_elements_of_the_largest_array():
    small = wp.zeros(10, dtype=float, device="cpu")
    image = wp.zeros((2, 48, 64, 3), dtype=float, device="cpu")           # 192 elements per row
    assert min_band_rows(96, [small, 1.5, image], min_elements=1000) == 6   # ceil(1000 / 192)
    assert min_band_rows(96, [small, image], min_elements=192) == 1
    assert min_band_rows(96, [3, 2.0]) == 1                                 # no array: any split
    assert min_band_rows(96, [image]) == -(-launch.MIN_BAND_ELEMENTS // 192)


def test_small_launches_stay_on_one_thread(band_counts):
    visits = wp.zeros(40, dtype=int, device="cpu")
    first = wp.zeros(40, dtype=int, device="cpu")
    with threads(4):
        launch_rows(count_rows, 40, [visits, first])
    assert band_counts == [1]
    np.testing.assert_array_equal(first.numpy(), 0)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("n_rows, align", [(1, 1), (37, 1), (101, 1), (5 * 23, 23), (4 * 23 + 7, 23)])
def test_launch_rows_runs_every_row_once_in_its_band(split_everything, n, n_rows, align):
    visits = wp.zeros(n_rows, dtype=int, device="cpu")
    first = wp.full(n_rows, -1, dtype=int, device="cpu")
    with threads(n):
        for _ in range(2):                       # the first launch compiles, the second races
            launch_rows(count_rows, n_rows, [visits, first], align=align)
    np.testing.assert_array_equal(visits.numpy(), 2)
    expected = np.empty(n_rows, int)
    for begin, count in row_bands(n_rows, n, align):
        expected[begin:begin + count] = begin
    np.testing.assert_array_equal(first.numpy(), expected)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize("n_rows", [1, 7, 101, 480])
def test_balanced_launch_runs_every_row_once_in_chunks(split_everything, n, n_rows):
    visits = wp.zeros(n_rows, dtype=int, device="cpu")
    first = wp.full(n_rows, -1, dtype=int, device="cpu")
    with threads(n):
        for _ in range(2):                       # the first launch compiles, the second races
            launch_rows(count_rows, n_rows, [visits, first], balance=True)
    np.testing.assert_array_equal(visits.numpy(), 2)
    chunks = row_bands(n_rows, n * launch.BALANCE_CHUNKS_PER_THREAD) if n > 1 else [(0, n_rows)]
    expected = np.empty(n_rows, int)
    for begin, count in chunks:
        expected[begin:begin + count] = begin
    np.testing.assert_array_equal(first.numpy(), expected)
    if n > 1 and n_rows >= n * launch.BALANCE_CHUNKS_PER_THREAD:
        assert len(np.unique(first.numpy())) == n * launch.BALANCE_CHUNKS_PER_THREAD


def test_balanced_launch_passes_a_kernel_error_on(split_everything, monkeypatch):
    calls = []

    def failing_launch(kernel, dim, inputs, device):
        calls.append(inputs[0])
        if inputs[0] == 0:
            raise RuntimeError("chunk failed")

    visits = wp.zeros(64, dtype=int, device="cpu")
    first = wp.zeros(64, dtype=int, device="cpu")
    with threads(2):
        launch_rows(count_rows, 64, [visits, first], balance=True)     # compiled and warm
        monkeypatch.setattr(launch.wp, "launch", failing_launch)
        with pytest.raises(RuntimeError, match="chunk failed"):
            launch_rows(count_rows, 64, [visits, first], balance=True)
    assert 0 in calls


# ----------------------------------------------------------------------------- thread count

def test_available_cores_is_the_affinity_mask():
    expected = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert available_cores() == expected >= 1


@pytest.mark.parametrize("value, expected", [("3", 3), (" 1 ", 1), ("16", 16)])
def test_environment_variable_sets_the_default(value, expected):
    assert threads_from_environment({THREADS_ENV: value}) == expected


def test_without_the_environment_variable_every_core_is_used():
    assert threads_from_environment({}) == available_cores()
    assert threads_from_environment({THREADS_ENV: ""}) == available_cores()


@pytest.mark.parametrize("value", ["0", "-2", "two", "2.5", "1e3"])
def test_bad_environment_variable_is_a_clear_error(value):
    with pytest.raises(ValueError, match=f"{THREADS_ENV} must be an integer >= 1"):
        threads_from_environment({THREADS_ENV: value})


def test_default_is_read_from_the_environment(monkeypatch):
    monkeypatch.setattr(thread_count, "_default_threads", None)
    monkeypatch.setenv(THREADS_ENV, "3")
    seen = []
    worker = threading.Thread(target=lambda: seen.append(get_threads()))   # no per-thread setting
    worker.start()
    worker.join()
    assert seen == [3]
    monkeypatch.setattr(thread_count, "_default_threads", None)
    monkeypatch.setenv(THREADS_ENV, "zero")
    with pytest.raises(ValueError, match=THREADS_ENV):
        launch.default_threads()


@pytest.mark.parametrize("bad, error", [(0, ValueError), (-1, ValueError), (1.5, TypeError),
                                        ("2", TypeError), (True, TypeError)])
def test_bad_thread_counts_raise(bad, error):
    with pytest.raises(error, match="threads must be an integer >= 1"):
        set_threads(bad)
    with pytest.raises(error, match="threads must be an integer >= 1"):
        with threads(bad):
            pass


def test_setting_is_per_thread_and_restored():
    before = get_threads()
    with threads(5):
        assert get_threads() == 5
        seen = []
        worker = threading.Thread(target=lambda: seen.append(get_threads()))
        worker.start()
        worker.join()
        assert seen == [launch.default_threads()]
        with threads(np.int64(3)):
            assert get_threads() == 3
        assert get_threads() == 5
    assert get_threads() == before


def test_iterate_with_threads_sets_the_count_only_while_computing():
    def items():
        for _ in range(3):
            yield get_threads()

    with threads(1):
        out = []
        for n in iterate_with_threads(4, items()):
            out.append((n, get_threads()))
    assert out == [(4, 1)] * 3


# ----------------------------------------------------------------------------- per call

@pytest.fixture(scope="module")
def tiny():
    return synthetic.render_sequence("objects_camera", n_frames=2, size=(24, 32), seed=1)


def test_decompose_runs_on_the_threads_asked_for(tiny, thread_counts):
    with threads(1):
        iv.decompose(tiny.frames, flow=tiny.flow, params=FAST, threads=3)
        assert get_threads() == 1
    assert thread_counts and set(thread_counts) == {3}


def test_iter_decompose_runs_on_the_threads_asked_for(tiny, thread_counts):
    with threads(1):
        windows = iv.iter_decompose(tiny.frames, flow=tiny.flow, params=FAST, threads=2)
        for _ in windows:
            assert get_threads() == 1
    assert thread_counts and set(thread_counts) == {2}


def test_estimate_flow_runs_on_the_threads_asked_for(tiny, thread_counts):
    with threads(1):
        iv.estimate_flow(tiny.frames, threads=4, max_levels=1, warps=1, gnc_stages=1)
    assert thread_counts and set(thread_counts) == {4}


@pytest.mark.parametrize("bad, error", [(0, ValueError), (2.0, TypeError), ("4", TypeError)])
def test_bad_threads_argument_raises_before_any_work(tiny, bad, error, thread_counts):
    for call in (lambda: iv.decompose(tiny.frames, flow=tiny.flow, params=FAST, threads=bad),
                 lambda: iv.iter_decompose(tiny.frames, flow=tiny.flow, params=FAST, threads=bad),
                 lambda: iv.estimate_flow(tiny.frames, threads=bad)):
        with pytest.raises(error, match="threads must be an integer >= 1"):
            call()
    assert thread_counts == []


def test_command_line_threads_are_checked(image_folder, tmp_path, capsys):
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--threads", "0"])
    assert rc == 2
    assert "--threads must be an integer >= 1" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_command_line_refuses_a_bad_environment_variable(image_folder, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(thread_count, "_default_threads", None)
    monkeypatch.setenv(THREADS_ENV, "many")
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out")])
    assert rc == 2
    assert f"{THREADS_ENV} must be an integer >= 1" in capsys.readouterr().err


def test_command_line_passes_threads_on(image_folder, tmp_path, thread_counts):
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--flow", "dis",
                   "--threads", "3", "--quiet"])
    assert rc == 0
    assert thread_counts and set(thread_counts) == {3}


def test_taichi_is_initialised_with_the_count_asked_for(tiny):
    pytest.importorskip("taichi")
    from ivkernels.kernels import taichi as ti_kernels

    get_backend("taichi")
    before = ti_kernels.initialised_threads()
    other = 1 if before != 1 else 2
    try:
        iv.decompose(tiny.frames, flow=tiny.flow, params=FAST, backend="taichi", threads=other)
        assert ti_kernels.initialised_threads() == other
    finally:
        ti_kernels.init(before)
    assert ti_kernels.initialised_threads() == before


# ----------------------------------------------------------------------------- identical results

def test_gather_and_scatter_kernels_identical_on_1_to_4_threads(split_everything, band_counts, rng):
    be = get_backend("warp")
    T, H, W = 5, 23, 31
    src = rng.random((T, H, W, 3), dtype=np.float32)
    flow = (rng.standard_normal((T, H, W, 2)) * 3).astype(np.float32)
    S = rng.standard_normal((T, H, W)).astype(np.float32)
    results = {}
    for n in (1, 2, 3, 4):
        gx, gy = be.zeros((T, H, W, 3)), be.zeros((T, H, W, 3))
        splat = be.zeros((T, H, W, 3))
        gS, energy = be.zeros((T, H, W)), be.zeros(T * H, np.float64)
        median = be.zeros((T, H, W, 3))
        wmed = be.zeros((T, H, W, 2))
        lab = be.asarray(src * 100.0)
        occ = be.asarray(np.ones((T, H, W), np.float32))
        mask = np.zeros((T, H, W), np.float32)
        mask[:, :5] = 1.0                                  # all the work in the top rows
        with threads(n):
            be.median.weighted_median_flow(be.asarray(flow), lab, occ, be.asarray(mask), wmed,
                                           radius=3)                                     # balanced
            be.derivatives.image_gradient(be.asarray(src), gx, gy)                            # gather
            be.median.median5x5(be.asarray(src), median)                                     # gather
            be.energy_shading.shading_smoothness(be.asarray(S), gS, energy)                  # gather
            be.sampling.splat_bilinear(be.asarray(src), be.asarray(flow), splat)             # scatter
        results[n] = [be.numpy(a).copy() for a in (gx, gy, median, gS, energy, splat, wmed)]
    assert 4 in band_counts                      # the launches did split
    assert 4 * launch.BALANCE_CHUNKS_PER_THREAD in band_counts      # and the balanced one into chunks
    for n in (2, 3, 4):
        for a, b in zip(results[1], results[n]):
            np.testing.assert_array_equal(a, b)
