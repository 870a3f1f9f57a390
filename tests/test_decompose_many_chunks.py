"""decompose_many without Ray: the chunk plan, the chunks' windows (against a brute-force
search and against decompose() on the chunk), the stitching (against known gains), the
checks up front, per-video errors, and the local engine against decompose()."""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels import Params
from ivkernels.decompose import window_ranges
from ivkernels.io import write_png_sequence
from ivkernels.parallel import VideoError, chunk_ranges, iter_decompose_many, stitch
from ivkernels.parallel.chunks import CHUNK_WINDOW_FACTOR, chunk_params, chunk_window, fit_offsets
from ivkernels.parallel.engines import task_cpus

SMALL = Params().replace(window=4, overlap=1)


def _truth(T=11, H=9, W=13, seed=3):
    rng = np.random.default_rng(seed)
    albedo = rng.uniform(0.05, 1.0, (T, H, W, 3)).astype(np.float32)
    shading = rng.uniform(0.1, 1.0, (T, H, W)).astype(np.float32)
    flow = rng.normal(0, 1, (T - 1, H, W, 2)).astype(np.float32)
    return albedo, shading, flow


def _chunks_of(albedo, shading, flow, ranges, seed=5):
    """The truth cut into chunks, each with its own per-channel albedo gain and shading gain."""
    rng = np.random.default_rng(seed)
    chunks = []
    for c, (a, b) in enumerate(ranges):
        gain = np.ones(3) if c == 0 else rng.uniform(0.5, 2.0, 3)
        sgain = 1.0 if c == 0 else rng.uniform(0.5, 2.0)
        chunks.append(iv.IntrinsicVideo((albedo[a:b] * gain).astype(np.float32),
                                        (shading[a:b] * sgain).astype(np.float32),
                                        flow[a:b - 1] + 100 * c, np.full((b - a - 1, *flow.shape[1:3]), c, np.float32),
                                        np.zeros((b - a - 1, *flow.shape[1:3]), np.float32), {"chunk": c}))
    return chunks


def _owned(ranges):
    """Frames each chunk adds: from the previous chunk's stop to its own."""
    stops = [0] + [b for _, b in ranges]
    return [b - a for a, b in zip(stops[:-1], stops[1:])]


def _check_plan(ranges, T, n, overlap):
    assert ranges[0][0] == 0 and ranges[-1][1] == T
    owned = _owned(ranges)
    assert sum(owned) == T and min(owned) >= 1 and max(owned) <= n      # chunk_frames is an upper bound
    for (a0, b0), (a1, b1) in zip(ranges, ranges[1:]):
        assert a1 == max(0, b0 - overlap) and a1 >= a0 and b1 > b0


@pytest.mark.parametrize("T, n, overlap", [(36, 12, 2), (37, 12, 2), (10, 3, 1), (5, 12, 2), (12, 4, 3)])
def test_chunk_ranges_cover_the_video_sharing_overlap_frames(T, n, overlap):
    ranges = chunk_ranges(T, n, overlap)
    assert len(ranges) == -(-T // n)
    _check_plan(ranges, T, n, overlap)
    owned = _owned(ranges)
    assert max(owned) - min(owned) <= 1


def test_chunk_ranges_without_chunks_is_the_whole_video():
    assert chunk_ranges(7, None, 2) == [(0, 7)]
    assert chunk_ranges(36, 12, 2) == [(0, 12), (10, 24), (22, 36)]


def test_chunk_frames_is_an_upper_bound_on_the_frames_a_chunk_owns():
    assert chunk_ranges(37, 12, 2) == [(0, 9), (7, 18), (16, 28), (26, 37)]
    for T in range(1, 61):
        for n in range(2, 17):
            for overlap in range(1, n):
                ranges = chunk_ranges(T, n, overlap)
                assert len(ranges) == -(-T // n), (T, n, overlap)
                _check_plan(ranges, T, n, overlap)


def test_chunk_window_is_the_shortest_that_covers_a_chunk_in_the_fewest_windows():
    assert [chunk_window(n, 8, 2) for n in (5, 8, 12, 14, 16, 17, 26, 40)] == [8, 8, 12, 14, 16, 10, 14, 15]
    for window in range(2, 11):
        longest = CHUNK_WINDOW_FACTOR * window
        for overlap in range(0, window):
            for n in range(1, 70):
                w = chunk_window(n, window, overlap)
                if n <= window:                   # one window already: unchanged
                    assert w == window
                    continue
                # brute force: every allowed length, the windows decompose() would lay out with it
                counts = {length: len(window_ranges(n, length, overlap))
                          for length in range(window, longest + 1)}
                fewest = min(counts.values())
                assert w == min(length for length, count in counts.items() if count == fewest), \
                    (n, window, overlap)
                assert window <= w <= longest


def test_chunk_params_changes_the_window_only():
    params = Params()
    assert chunk_params(params, 8) is params and chunk_params(params, 3) is params
    longer = chunk_params(params, 14)
    assert longer.window == 14 and longer.replace(window=params.window) == params


@pytest.mark.parametrize("n_tasks, cpus, node_cpus, expected", [
    (4, 2, 2, 1), (5, 2, 2, 1), (2, 2, 2, 1), (3, 2, 2, 0.6666), (7, 4, 4, 0.5714), (5, 3, 1, 0.6),
    (1, 2, 2, 2), (1, 8, 4, 4), (3, 8, 8, 2), (0, 2, 2, 1)])
def test_task_cpus_keeps_every_cpu_busy_to_the_end(n_tasks, cpus, node_cpus, expected):
    share = task_cpus(n_tasks, cpus, node_cpus)
    assert share == expected
    if cpus < n_tasks < 2 * cpus:       # all at once, on Ray's 1e-4 grid, without a CPU to spare
        assert n_tasks * share <= cpus < n_tasks * (share + 1e-4)
    if n_tasks < cpus:                  # whole CPUs, as many as one node has
        assert share == int(share) and n_tasks * share <= cpus and share <= node_cpus


def test_fit_offsets_recovers_known_gains_despite_outliers():
    albedo, shading, _ = _truth(T=3)
    gain, sgain = np.array([0.5, 1.7, 1.2]), 0.8
    other_a, other_s = albedo * gain, shading * sgain
    other_a[:, :2] = 9.0                  # a fifth of the pixels disagree entirely
    a, s = fit_offsets(albedo, shading, other_a, other_s)
    np.testing.assert_allclose(np.exp(a), 1 / gain, rtol=1e-5)
    assert np.exp(s) == pytest.approx(1 / sgain, rel=1e-5)


@pytest.mark.parametrize("overlap", [1, 2, 3])
def test_stitch_puts_every_chunk_on_the_first_chunks_scale(overlap):
    albedo, shading, flow = _truth()
    ranges = chunk_ranges(albedo.shape[0], 4, overlap)
    assert len(ranges) >= 3
    out = stitch(_chunks_of(albedo, shading, flow, ranges), ranges)
    np.testing.assert_allclose(out.albedo, albedo, rtol=1e-5)
    np.testing.assert_allclose(out.shading, shading, rtol=1e-5)
    assert len(out.diagnostics["seams"]) == len(ranges) - 1
    assert [d["chunk"] for d in out.diagnostics["chunk_diagnostics"]] == list(range(len(ranges)))
    # each frame pair's flow and maps come from one chunk: the later one from the middle of the overlap
    for c, (start, stop) in enumerate(ranges):
        first = start + (overlap // 2 if c else 0)
        last = ranges[c + 1][0] + overlap // 2 if c + 1 < len(ranges) else stop - 1
        np.testing.assert_array_equal(out.flow[first:last], flow[first:last] + 100 * c)
        assert (out.occlusion[first:last] == c).all()


def test_stitch_blends_the_shared_frames_linearly_in_log():
    H, W = 4, 5
    ones = np.ones((3, H, W, 3), np.float32)
    # two chunks of 3 frames sharing 2 that disagree: 1 against e (same median scale after
    # the fit only on half the pixels, so the blend is what is left)
    first = iv.IntrinsicVideo(ones.copy(), np.ones((3, H, W), np.float32), None, None, None, {})
    second_a = ones.copy()
    second_a[:2, :, :3] = np.e                 # 15 of 20 pixels per frame: the median moves too
    second = iv.IntrinsicVideo(second_a, np.ones((3, H, W), np.float32), None, None, None, {})
    out = stitch([first, second], [(0, 3), (1, 4)])
    a_off = np.array(out.diagnostics["seams"][0]["albedo_log_offset"])
    np.testing.assert_allclose(a_off, -1.0, atol=1e-6)
    la = np.log(out.albedo)
    for j, t in enumerate((1, 2)):             # weights 1/3 and 2/3 for the second chunk
        w = (j + 1) / 3
        np.testing.assert_allclose(la[t, :, :3], w * (1 + a_off[0]), atol=1e-5)
        np.testing.assert_allclose(la[t, :, 3:], w * a_off[0], atol=1e-5)
    np.testing.assert_allclose(la[3], a_off[0], atol=1e-5)
    assert out.flow is None


def test_stitch_returns_a_single_chunk_unchanged():
    albedo, shading, flow = _truth(T=4)
    video = _chunks_of(albedo, shading, flow, [(0, 4)])[0]
    assert stitch([video], [(0, 4)]) is video


def _clip(seed, T=4, size=(24, 32), kind="objects_camera"):
    return iv.synthetic.render_sequence(kind, T, size=size, seed=seed)


def test_local_engine_gives_decompose_results_and_a_chunked_solve_near_the_sequential_one():
    seqs = [_clip(1), _clip(2, T=3, kind="static_moving_light")]
    serial = [iv.decompose(s.frames, flow=s.flow, params=SMALL) for s in seqs]
    many = iv.decompose_many([s.frames for s in seqs], engine="local", flow=[s.flow for s in seqs],
                             params=SMALL)
    for a, b in zip(serial, many):
        np.testing.assert_array_equal(a.albedo, b.albedo)
        np.testing.assert_array_equal(a.shading, b.shading)
        np.testing.assert_array_equal(a.flow, b.flow)


def test_local_chunked_solve_stays_near_the_sequential_one():
    seq = _clip(4, T=9, kind="static_moving_light")
    # the layers as solved: at 24x32 in three-frame chunks the light's change between frames
    # reads as noise, and the noise taken out would leave albedo * shading short of the input
    exact = SMALL.replace(layer_denoise=0.0)
    whole = iv.decompose(seq.frames, flow=seq.flow, params=exact)
    chunked = iv.decompose_many([seq.frames], engine="local", flow=[seq.flow], params=exact,
                                chunk_frames=3)[0]
    assert chunked.diagnostics["chunks"] == [(0, 3), (2, 6), (5, 9)]
    assert chunked.albedo.shape == whole.albedo.shape and chunked.flow.shape == whole.flow.shape
    # the reconstruction holds through the seams, and the albedo is as good as the sequential one
    np.testing.assert_allclose(chunked.reconstruct(), seq.frames, atol=2e-3)
    l_whole = iv.metrics.lmse(whole.albedo, seq.albedo)
    l_chunk = iv.metrics.lmse(chunked.albedo, seq.albedo)
    assert l_chunk <= 1.25 * l_whole + 0.005, (l_chunk, l_whole)


def test_each_chunk_is_decompose_of_its_frames_in_its_own_windows_then_stitched():
    seq = _clip(6, T=12, kind="static_moving_light")
    chunked = iv.decompose_many([seq.frames], engine="local", flow=[seq.flow], params=SMALL,
                                chunk_frames=6)[0]
    ranges = [(0, 6), (5, 12)]
    assert chunked.diagnostics["chunks"] == ranges
    # chunks of 6 and 7 frames: one window each, where Params.window (4) would give two
    assert [d["windows"] for d in chunked.diagnostics["chunk_diagnostics"]] == [[(0, 6)], [(0, 7)]]
    # the reference: decompose() on each chunk's frames with its window, stitched
    alone = [iv.decompose(seq.frames[a:b], flow=seq.flow[a:b - 1], params=SMALL.replace(window=b - a),
                          threads=1) for a, b in ranges]
    expected = stitch(alone, ranges)
    np.testing.assert_array_equal(chunked.albedo, expected.albedo)
    np.testing.assert_array_equal(chunked.shading, expected.shading)


def test_a_video_of_one_chunk_keeps_params_window_and_equals_decompose():
    seq = _clip(7, T=6, kind="static_moving_light")
    whole = iv.decompose(seq.frames, flow=seq.flow, params=SMALL)
    one = iv.decompose_many([seq.frames], engine="local", flow=[seq.flow], params=SMALL, chunk_frames=8)[0]
    assert one.diagnostics["windows"] == whole.diagnostics["windows"] == [(0, 4), (2, 6)]
    np.testing.assert_array_equal(one.albedo, whole.albedo)
    np.testing.assert_array_equal(one.shading, whole.shading)


def test_paths_are_read_and_give_the_same_result(tmp_path):
    frames8 = (np.clip(_clip(6, T=3).frames, 0, 1) ** (1 / 2.2) * 255).round().astype(np.uint8)
    folder = tmp_path / "clip"
    write_png_sequence(folder, frames8)
    via_path = iv.decompose_many([folder], engine="local", flow="dis", params=SMALL)[0]
    direct = iv.decompose(iv.io.read_frames(folder), flow="dis", params=SMALL)
    np.testing.assert_array_equal(via_path.albedo, direct.albedo)


def test_a_bad_video_raises_before_any_work_naming_it(tmp_path):
    good = _clip(7, T=2).frames
    calls = []

    def reader(path):
        calls.append(path)
        return iv.io.read_frames(path)

    with pytest.raises(VideoError, match=r"videos\[2\].*at least 8x8"):
        iter_decompose_many([good, tmp_path, good[:, :5, :5]], engine="local", reader=reader,
                            probe=lambda p: (2, 24, 32))
    assert calls == []                      # nothing read, nothing solved
    with pytest.raises(VideoError, match=r"videos\[1\].*does not exist"):
        iv.decompose_many([good, tmp_path / "missing.mp4"], engine="local")
    with pytest.raises(VideoError, match=r"videos\[0\].*\[0, 1\]"):
        iv.decompose_many([good * 3], engine="local")


def test_errors_return_reports_each_failed_video_and_finishes_the_rest(tmp_path):
    seq = _clip(8, T=3)

    def reader(path):
        raise OSError(f"cannot decode {path.name}")

    out = iv.decompose_many([seq.frames, np.zeros((2, 4, 4, 3), np.uint8), tmp_path, seq.frames[:2]],
                            engine="local", errors="return", reader=reader,
                            probe=lambda p: (3, 24, 32), flow=[seq.flow, None, None, seq.flow[:1]],
                            params=SMALL)
    assert isinstance(out[1], VideoError) and "videos[1]" in str(out[1]) and out[1].index == 1
    assert isinstance(out[2], VideoError) and "cannot decode" in str(out[2])
    assert isinstance(out[2].cause, OSError)
    assert isinstance(out[0], iv.IntrinsicVideo) and out[0].albedo.shape == seq.frames.shape
    assert isinstance(out[3], iv.IntrinsicVideo) and out[3].albedo.shape[0] == 2
    with pytest.raises(VideoError, match=r"videos\[0\].*cannot decode") as info:    # errors="raise"
        iv.decompose_many([tmp_path], engine="local", reader=reader, probe=lambda p: (3, 24, 32))
    assert isinstance(info.value.__cause__, OSError)


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(engine="spark"), ValueError, "engine"),
    (dict(errors="ignore"), ValueError, "errors"),
    (dict(chunk_frames=1), ValueError, "chunk_frames"),
    (dict(chunk_frames=4, chunk_overlap=4), ValueError, "chunk_overlap"),
    (dict(chunk_overlap=0), ValueError, "chunk_overlap"),
    (dict(max_retries=-1), ValueError, "max_retries"),
    (dict(window=3), TypeError, "window"),
    (dict(backend="opencl"), ValueError, "opencl"),
    (dict(params={"window": 3}), TypeError, "Params"),
    (dict(flow=np.zeros((1, 24, 32, 2))), TypeError, "one entry"),
    (dict(flow=[None, None]), ValueError, "one per video"),
    (dict(flow="lucas_kanade"), ValueError, "lucas_kanade"),
])
def test_bad_arguments_are_refused_in_one_line(kwargs, error, match):
    with pytest.raises(error, match=match) as info:
        iv.decompose_many([np.zeros((2, 24, 32, 3), np.uint8)], **dict(dict(engine="local"), **kwargs))
    assert "\n" not in str(info.value)


def test_one_array_instead_of_a_list_is_refused():
    with pytest.raises(TypeError, match=r"\[video\]"):
        iv.decompose_many(np.zeros((2, 24, 32, 3), np.uint8), engine="local")


def test_the_ray_engine_without_ray_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "ray", None)      # import ray fails
    with pytest.raises(ImportError, match=r"ivkernels\[ray\]"):
        iv.decompose_many([np.zeros((2, 24, 32, 3), np.uint8)], engine="ray")


def _panned(T, H, W, shift, seed=8):
    """A textured albedo panning ``shift`` px a frame to the left (its true flow ``(-shift, 0)``)
    under a grey shading, and the flow."""
    rng = np.random.default_rng(seed)
    world = rng.uniform(0.2, 0.9, (H, W + shift * T, 3)).astype(np.float32)
    albedo = np.stack([world[:, k * shift:k * shift + W] for k in range(T)])
    shading = np.full((T, H, W), 0.7, np.float32)
    flow = np.zeros((T - 1, H, W, 2), np.float32)
    flow[..., 0] = -shift
    return albedo, shading, flow


@pytest.mark.parametrize("shift", [0, 1])
def test_stitch_carries_what_one_gain_leaves_along_the_flow(shift):
    # the second chunk splits the scene differently region by region: a smooth ramp of log
    # gain across the view (attached to the surfaces, so it moves with the pan) on top of one gain
    T, H, W = 10, 60, 64
    albedo, shading, flow = _panned(T, H, W, shift)
    ranges = [(0, 5), (3, T)]
    x = np.arange(W, dtype=np.float32)
    ramps = np.stack([0.2 * (x + shift * k) / W for k in range(T)])[:, None, :]  # surface-attached
    first = iv.IntrinsicVideo(albedo[:5], shading[:5], flow[:4], np.ones((4, H, W), np.float32),
                              np.zeros((4, H, W), np.float32), {})
    bent = albedo[3:] * 1.3 * np.exp(ramps[3:])[..., None]
    second = iv.IntrinsicVideo(bent.astype(np.float32), (shading[3:] / 1.3 / np.exp(ramps[3:])).astype(np.float32),
                               flow[3:], np.ones((T - 4, H, W), np.float32), np.zeros((T - 4, H, W), np.float32), {})
    out = stitch([first, second], ranges)
    seam = out.diagnostics["seams"][0]
    assert seam["field_rms"] > 0.02                        # the ramp's spread is what the gain left
    inner = (slice(None), slice(20, 40), slice(20, 44))    # away from the blur's borders
    err = np.abs(np.log(out.albedo[5:]) - np.log(albedo[5:]))[inner]
    assert err.max() < 0.01, err.max()                     # the ramp is taken out along the pan
    # without the field, one gain leaves up to half the ramp's 0.2 in place
    no_field = stitch([first, iv.IntrinsicVideo(second.albedo, second.shading, None, None, None, {})], ranges)
    assert np.abs(np.log(no_field.albedo[5:]) - np.log(albedo[5:]))[inner].max() > 0.03
    # the field moves between albedo and shading only: every frame still reconstructs its input
    np.testing.assert_allclose(out.albedo * out.shading[..., None], albedo * shading[..., None], rtol=1e-4)


def test_residual_field_is_the_blurred_luminance_difference_and_carry_follows_the_flow():
    from ivkernels.parallel.chunks import FIELD_SIGMA, carry_field, residual_field
    rng = np.random.default_rng(2)
    prev, here = rng.normal(0, 0.1, (2, 30, 40, 3)).astype(np.float32)
    field = residual_field(prev, here)
    lum = ((prev - here) @ np.array([0.2126, 0.7152, 0.0722], np.float32)).astype(np.float32)
    import cv2
    np.testing.assert_allclose(field, cv2.GaussianBlur(lum, (0, 0), FIELD_SIGMA * 30), atol=1e-6)
    # carried by a flow of (+3, -2) px: what was at (y, x) is at (y - 2, x + 3), the edge held
    flow = np.zeros((30, 40, 2), np.float32)
    flow[..., 0], flow[..., 1] = 3, -2
    moved = carry_field(field, flow)
    np.testing.assert_allclose(moved[:28, 3:], field[2:, :37], atol=1e-6)
    np.testing.assert_allclose(moved[:28, 0], field[2:, 0], atol=1e-6)      # entering at the left edge
