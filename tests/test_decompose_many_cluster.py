"""decompose_many on a simulated 3-node Ray cluster (ray.cluster_utils.Cluster, one CPU per
node, one cluster per module): joined by its address, every node warmed once, tasks spread
over the nodes, and the results those of decompose() (whole videos) and of the local engine
(chunks)."""
import numpy as np
import pytest
import ray
from ray.cluster_utils import Cluster

import ivkernels as iv
from ivkernels import Params
from ivkernels.parallel import engines

SMALL = Params().replace(window=4, overlap=1)


@pytest.fixture(scope="module")
def three_nodes():
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    for _ in range(2):
        cluster.add_node(num_cpus=1)
    cluster.wait_for_nodes()
    yield cluster
    if ray.is_initialized():
        ray.shutdown()
    cluster.shutdown()


def _clip(seed, T=4, size=(24, 32), kind="objects_camera"):
    return iv.synthetic.render_sequence(kind, T, size=size, seed=seed)


@pytest.mark.slow
def test_three_nodes_give_the_serial_results(three_nodes):
    seqs = [_clip(1), _clip(2, kind="free_camera"), _clip(3, kind="static_moving_light"), _clip(4)]
    long = _clip(5, T=9, kind="rotating_shadows")
    serial = [iv.decompose(s.frames, flow=s.flow, params=SMALL) for s in seqs]
    chunked_here = iv.decompose_many([long.frames], engine="local", flow=[long.flow], params=SMALL,
                                     chunk_frames=3)[0]

    assert not ray.is_initialized()
    engines._warmed.clear()
    videos = iv.decompose_many([s.frames for s in seqs] + [long.frames], engine="ray",
                               address=three_nodes.address, flow=[s.flow for s in seqs] + [long.flow],
                               params=SMALL)
    assert not ray.is_initialized()         # the connection it opened is closed again
    for a, b in zip(serial, videos):
        assert np.abs(a.albedo - b.albedo).max() <= 1e-4
        assert np.abs(a.shading - b.shading).max() <= 1e-4 * max(1.0, float(a.shading.max()))

    warmed = {node for node, _ in engines._warmed}
    ray.init(address=three_nodes.address)
    assert warmed == {n["NodeID"] for n in ray.nodes() if n["Alive"]}      # every node warmed...
    assert engines.RayEngine({"params": SMALL}, warm_up_flow=long.flow).warmed == []   # ...once
    chunked = iv.decompose_many([long.frames], engine="ray", flow=[long.flow], params=SMALL,
                                chunk_frames=3)[0]
    assert np.abs(chunked.albedo - chunked_here.albedo).max() <= 1e-4
    nodes = {d["task"]["node"] for d in chunked.diagnostics["chunk_diagnostics"]}
    assert len(nodes) >= 2, nodes           # three one-CPU tasks at once cannot share one node
