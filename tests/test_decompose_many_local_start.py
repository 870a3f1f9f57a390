"""A decompose_many call that starts its own local Ray cluster: the machine's kernel cache is
warmed in this process while the cluster starts (no warm-up task), the results are those of
decompose(), and the cluster is shut down again, also when the warm-up fails."""
import threading

import numpy as np
import pytest
import ray

import ivkernels as iv
from ivkernels import Params
from ivkernels.parallel import engines, tasks

SMALL = Params().replace(window=4, overlap=1)


@pytest.fixture
def no_cluster():
    if ray.is_initialized():
        ray.shutdown()
    engines._warmed.clear()
    yield
    if ray.is_initialized():
        ray.shutdown()


@pytest.mark.slow
def test_a_cluster_started_for_the_call_is_warmed_here(no_cluster, monkeypatch):
    where = []
    real = tasks.warm_up_here

    def recorded(options, flow):
        where.append(threading.current_thread().name)
        return real(options, flow)

    monkeypatch.setattr(tasks, "warm_up_here", recorded)
    seqs = [iv.synthetic.render_sequence("objects_camera", 4, size=(24, 32), seed=s) for s in (1, 2)]
    serial = [iv.decompose(s.frames, params=SMALL) for s in seqs]

    engine = engines.RayEngine({"params": SMALL})
    try:
        assert ray.is_initialized()
        assert engine.warmed == []                   # no warm-up task: the node was warmed here...
        assert where and where[0].startswith("ivkernels-warm-up")      # ...in a thread, during ray.init
        node = ray.get_runtime_context().get_node_id()
        assert (node, ("warp", "cpu", True, None)) in engines._warmed
    finally:
        engine.close()
    assert not ray.is_initialized()                  # the cluster it started is shut down

    videos = iv.decompose_many([s.frames for s in seqs], engine="ray", params=SMALL)
    assert not ray.is_initialized()
    for a, b in zip(serial, videos):
        assert np.abs(a.albedo - b.albedo).max() <= 1e-4


def test_a_failed_warm_up_raises_and_leaves_no_cluster(no_cluster, monkeypatch):
    def broken(options, flow):
        raise RuntimeError("warm-up broke")

    monkeypatch.setattr(tasks, "warm_up_here", broken)
    with pytest.raises(RuntimeError, match="warm-up broke"):
        engines.RayEngine({"params": SMALL})
    assert not ray.is_initialized()
    assert not engines._warmed
