"""decompose_many on a local Ray cluster of 2 CPUs (one per module): the same results as
decompose() one by one and as the local engine, per-video errors, a killed worker retried."""
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import ray

import ivkernels as iv
from ivkernels import Params
from ivkernels.parallel import VideoError
from ivkernels.parallel.engines import RayEngine

SMALL = Params().replace(window=4, overlap=1)


@pytest.fixture(scope="module")
def cluster():
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level="warning")
    yield
    ray.shutdown()


def _clip(seed, T=4, size=(24, 32), kind="objects_camera"):
    return iv.synthetic.render_sequence(kind, T, size=size, seed=seed)


def test_whole_videos_on_ray_equal_decompose_one_by_one(cluster):
    seqs = [_clip(1), _clip(2, T=3, kind="static_moving_light"), _clip(3, T=5, size=(21, 30))]
    flows = [seqs[0].flow, "dis", None]
    serial = [iv.decompose(s.frames, flow=f, params=SMALL) for s, f in zip(seqs, flows)]
    many = iv.decompose_many([s.frames for s in seqs], engine="ray", flow=flows, params=SMALL)
    assert ray.is_initialized()                 # a cluster it joined is left running
    for a, b in zip(serial, many):
        assert np.abs(a.albedo - b.albedo).max() <= 1e-4
        assert np.abs(a.shading - b.shading).max() <= 1e-4 * max(1.0, float(a.shading.max()))
        assert np.abs(a.flow - b.flow).max() <= 1e-4
        assert b.albedo.flags.writeable and b.diagnostics["task"]["pid"] != os.getpid()
        # three tasks on 2 CPUs run at once, sharing them; the kernels on one thread each
        assert b.diagnostics["task"]["cpus"] == 0.6666 and b.diagnostics["task"]["threads"] == 1


def test_one_video_on_two_cpus_holds_both_with_the_kernels_on_two_threads(cluster):
    seq = _clip(8, T=3, kind="static_moving_light")
    alone = iv.decompose_many([seq.frames], engine="ray", flow=[seq.flow], params=SMALL)[0]
    assert alone.diagnostics["task"]["cpus"] == 2 and alone.diagnostics["task"]["threads"] == 2
    serial = iv.decompose(seq.frames, flow=seq.flow, params=SMALL, threads=1)
    assert np.abs(alone.albedo - serial.albedo).max() <= 1e-4


def test_chunks_on_ray_equal_chunks_in_this_process(cluster):
    seq = _clip(4, T=9, kind="static_moving_light")
    kwargs = dict(flow=[seq.flow], params=SMALL, chunk_frames=3)
    local = iv.decompose_many([seq.frames], engine="local", **kwargs)[0]
    on_ray = iv.decompose_many([seq.frames], engine="ray", progress=True, **kwargs)[0]
    assert on_ray.diagnostics["chunks"] == local.diagnostics["chunks"] == [(0, 3), (2, 6), (5, 9)]
    assert np.abs(on_ray.albedo - local.albedo).max() <= 1e-4
    assert np.abs(on_ray.flow - local.flow).max() <= 1e-4
    pids = {d["task"]["pid"] for d in on_ray.diagnostics["chunk_diagnostics"]}
    assert os.getpid() not in pids


def test_chunks_on_ray_are_solved_in_their_own_windows(cluster):
    # the chunk's Params (longer windows, chunks.chunk_params) reach the worker with its task
    seq = _clip(6, T=12, kind="static_moving_light")
    kwargs = dict(flow=[seq.flow], params=SMALL, chunk_frames=6)
    local = iv.decompose_many([seq.frames], engine="local", **kwargs)[0]
    on_ray = iv.decompose_many([seq.frames], engine="ray", **kwargs)[0]
    assert [d["windows"] for d in on_ray.diagnostics["chunk_diagnostics"]] == [[(0, 6)], [(0, 7)]]
    assert np.abs(on_ray.albedo - local.albedo).max() <= 1e-4


def test_a_task_that_raises_fails_its_video_alone(cluster, tmp_path):
    seq = _clip(5, T=3)
    engine = RayEngine({"params": SMALL}, max_retries=0)
    engine.submit("bad", "not frames", None)
    engine.submit("good", seq.frames, seq.flow)
    done = dict(engine.next_done() for _ in range(2))
    assert isinstance(done["bad"], TypeError) and "numpy array" in str(done["bad"])
    assert isinstance(done["good"], iv.IntrinsicVideo)
    engine.close()
    assert ray.is_initialized()

    def reader(path):
        raise OSError(f"{path.name}: moov atom not found")

    out = iv.decompose_many([seq.frames, tmp_path], engine="ray", errors="return", reader=reader,
                            probe=lambda p: (3, 24, 32), flow=[seq.flow, None], params=SMALL)
    assert isinstance(out[1], VideoError) and "moov atom" in str(out[1])
    assert np.abs(out[0].albedo - iv.decompose(seq.frames, flow=seq.flow, params=SMALL).albedo).max() <= 1e-4


def _descendants_named(title: str) -> list[int]:
    """Processes under this one (Ray's workers are children of the raylet this test started)
    whose title is ``title``."""
    parents, titles = {}, {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            titles[int(entry.name)] = (entry / "cmdline").read_bytes().split(b"\0")[0].decode()
        except (OSError, UnicodeDecodeError):
            continue
        parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    me, found = os.getpid(), []
    for pid, name in titles.items():
        p = pid
        while p in parents and p not in (0, 1, me):
            p = parents[p]
        if p == me and name.strip() == title:
            found.append(pid)
    return found


@pytest.mark.slow
def test_a_worker_killed_mid_task_is_retried_and_the_output_is_complete(cluster):
    seqs = [_clip(6, T=5, size=(32, 48)), _clip(7, T=5, size=(32, 48), kind="free_camera")]
    serial = [iv.decompose(s.frames, flow=s.flow, params=SMALL) for s in seqs]
    out, killed = {}, []

    def run():
        out["videos"] = iv.decompose_many([s.frames for s in seqs], engine="ray", max_retries=2,
                                          flow=[s.flow for s in seqs], params=SMALL)

    thread = threading.Thread(target=run)
    thread.start()
    deadline = time.monotonic() + 120
    while not killed and thread.is_alive() and time.monotonic() < deadline:
        busy = _descendants_named("ray::solve_in_worker")
        if busy:
            os.kill(busy[0], signal.SIGKILL)
            killed.append(busy[0])
        time.sleep(0.02)
    thread.join(300)
    assert killed, "no task was seen running"
    videos = out["videos"]
    assert all(isinstance(v, iv.IntrinsicVideo) for v in videos)
    for a, b in zip(serial, videos):
        assert np.abs(a.albedo - b.albedo).max() <= 1e-4
    assert killed[0] not in {v.diagnostics["task"]["pid"] for v in videos}
