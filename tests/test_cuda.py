"""The Warp backend on a CUDA device gives the answers it gives on the CPU.

The kernel batteries already run on ``warp-cuda`` when a device is present
(``conftest.py`` parametrises them over every device the registry finds);
these tests check the whole pipeline end to end: flow, decomposition and the
windowed stream, each compared with the same call on the CPU.  Float32
arithmetic is ordered differently on the two devices, and L-BFGS amplifies
such differences a little, so the comparisons use error measures with
tolerances rather than bitwise equality.  Skipped where no CUDA device is
present (CI has none).
"""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels import Params
from ivkernels.evaluation import metrics, synthetic
from ivkernels.backends import cuda_device_count

pytestmark = [pytest.mark.cuda,
              pytest.mark.skipif("cuda_device_count() == 0", reason="no CUDA device")]

FAST = Params(outer_iterations=2, lbfgs_iterations=15)


@pytest.fixture(scope="module")
def seq():
    return synthetic.render_sequence("objects_camera", n_frames=4, size=(45, 61), seed=3)


def test_flow_on_cuda_matches_the_cpu(seq):
    on_cpu = iv.estimate_flow(seq.frames, device="cpu")
    on_gpu = iv.estimate_flow(seq.frames, device="cuda")
    assert on_gpu.shape == on_cpu.shape and np.isfinite(on_gpu).all()
    assert metrics.endpoint_error(on_gpu, on_cpu) < 0.05
    # and both are estimates of the true flow of the same quality
    err_cpu = metrics.endpoint_error(on_cpu, seq.flow)
    err_gpu = metrics.endpoint_error(on_gpu, seq.flow)
    assert abs(err_gpu - err_cpu) < 0.05 * max(err_cpu, 0.1)


def test_decomposition_on_cuda_matches_the_cpu(seq):
    a = iv.decompose(seq.frames, flow=seq.flow, params=FAST, device="cpu")
    b = iv.decompose(seq.frames, flow=seq.flow, params=FAST, device="cuda")
    assert b.albedo.shape == a.albedo.shape and np.isfinite(b.albedo).all()
    between = metrics.intrinsic_lmse(b.albedo, b.shading, a.albedo, a.shading)["mean"]
    assert between < 2e-3
    # the GPU answer is as close to the truth as the CPU one
    to_truth_cpu = metrics.intrinsic_lmse(a.albedo, a.shading, seq.albedo, seq.shading)["mean"]
    to_truth_gpu = metrics.intrinsic_lmse(b.albedo, b.shading, seq.albedo, seq.shading)["mean"]
    assert to_truth_gpu < 1.1 * to_truth_cpu + 1e-4


@pytest.mark.slow
def test_estimated_flow_and_windows_on_cuda(seq):
    frames = np.concatenate([seq.frames, seq.frames[::-1]])         # 8 frames, windows of 5
    params = Params(outer_iterations=1, lbfgs_iterations=10, window=5, overlap=2)
    a = iv.decompose(frames, params=params, device="cpu", flow_passes=1)
    b = iv.decompose(frames, params=params, device="cuda:0", flow_passes=1)
    assert b.albedo.shape == a.albedo.shape == (8, 45, 61, 3)
    assert np.isfinite(b.flow).all() and np.isfinite(b.albedo).all()
    assert metrics.intrinsic_lmse(b.albedo, b.shading, a.albedo, a.shading)["mean"] < 5e-3
