"""The noise taken out of the solved layers (ivkernels.solver.denoise): the noise step read from
the frames, the gate that leaves clean windows as solved, and decompose() on a noisy video against
the same video's truth."""
import numpy as np
import pytest

import ivkernels as iv
from ivkernels.backends import get_backend
from ivkernels.evaluation import metrics, synthetic
from ivkernels.params import Params
from ivkernels.solver.denoise import NOISE_TO_SMOOTH, denoise_layers, noise_step


@pytest.fixture
def be():
    return get_backend("warp", "cpu")


def flat_noisy(rng, sigma, level=0.25, shape=(4, 40, 50)):
    frames = np.full((*shape, 3), level, np.float32)
    return np.clip(frames + rng.normal(0.0, sigma, frames.shape[:3] + (1,)), 1e-3, 1).astype(np.float32)


def expected_step(sigma, level=0.25, offset=0.02, n=400_000, seed=5):
    """The statistic the noise step reads, simulated from its definition (no kernels, no
    histogram): the median of the larger of a pixel's right and lower steps of
    ``log(i + offset)`` under grey Gaussian noise, in ``log i`` (times ``(i + offset) / i``).
    About 1.42 sigma / i for small noise."""
    rng = np.random.default_rng(seed)
    centre, right, lower = (np.log(level + offset + sigma * rng.normal(size=n)) for _ in range(3))
    steps = np.maximum(np.abs(right - centre), np.abs(lower - centre))
    return float(np.median(steps)) * (level + offset) / level


@pytest.mark.parametrize("sigma", [0.005, 0.02])
def test_the_noise_step_follows_the_noise(be, rng, sigma):
    """Grey noise of deviation sigma on a flat level: the step read, from one frame or along a
    flow, is the simulated statistic (the frame's pixels share their neighbours, the
    simulation's do not; the histogram's bins are 7% wide)."""
    frames = flat_noisy(rng, sigma)
    flow = np.zeros((3, 40, 50, 2), np.float32)
    for given in (None, be.asarray(flow)):
        step = be.numpy(noise_step(be, be.asarray(frames), given, Params()))
        np.testing.assert_allclose(np.median(step), expected_step(sigma), rtol=0.1)


def test_clean_frames_are_left_as_solved(be, rng):
    # blocks of 8x8 pixels: within one frame most neighbour steps are 0
    blocks = np.kron(rng.uniform(0.1, 0.9, (4, 5, 3)), np.ones((8, 8, 1)))[None].astype(np.float32)
    # a per-pixel texture, still over three frames: the change along the (zero) flow is 0
    fine = rng.uniform(0.1, 0.9, (1, 32, 40, 3)).astype(np.float32)
    for frames, flow in ((blocks, None), (np.repeat(fine, 3, axis=0), np.zeros((2, 32, 40, 2), np.float32))):
        A = np.log(frames)
        S = np.zeros(frames.shape[:3], np.float32)
        given = None if flow is None else be.asarray(flow)
        A2, S2, noise = denoise_layers(be, be.asarray(frames), given, A, S, Params())
        assert noise < NOISE_TO_SMOOTH and A2 is A and S2 is S
        assert denoise_layers(be, be.asarray(frames), given, A, S, Params(layer_denoise=0.0)) == (A, S, None)
    # the same texture in one frame alone is read as noise: nothing tells the two apart there
    assert denoise_layers(be, be.asarray(fine), None, np.log(fine), np.zeros((1, 32, 40), np.float32),
                          Params())[2] > NOISE_TO_SMOOTH


def test_noisy_layers_are_smoothed_and_their_edges_kept(be, rng):
    frames = flat_noisy(rng, 0.02)
    frames[:, :, 25:] *= 0.2                       # an albedo edge of log 5 = 1.6
    A = np.log(frames)
    S = np.zeros(frames.shape[:3], np.float32)
    A2, S2, noise = denoise_layers(be, be.asarray(frames), None, A, S, Params())
    assert noise >= NOISE_TO_SMOOTH
    assert A2[:, 5:-5, 5:20].std() < A[:, 5:-5, 5:20].std() / 3
    assert abs(A2[:, :, 24].mean() - A[:, :, 24].mean()) < 0.05
    assert abs(A2[:, :, 25].mean() - A[:, :, 25].mean()) < 0.05
    assert np.array_equal(S2, S)                   # a flat layer stays flat


@pytest.mark.slow
def test_decompose_takes_the_noise_out_of_both_layers():
    seq = synthetic.render_sequence("objects_camera", n_frames=4, size=(96, 128), seed=3, palette="grey",
                                    noise=("gaussian", 0.01))
    kept = iv.decompose(seq.frames, flow=seq.flow, params=Params(layer_denoise=0.0))
    out = iv.decompose(seq.frames, flow=seq.flow)
    assert kept.diagnostics["noise_levels"] == [None]
    assert out.diagnostics["noise_levels"][0] >= NOISE_TO_SMOOTH
    before = metrics.intrinsic_lmse(kept.albedo, kept.shading, seq.albedo, seq.shading)
    after = metrics.intrinsic_lmse(out.albedo, out.shading, seq.albedo, seq.shading)
    assert after["albedo"] < 0.9 * before["albedo"] and after["mean"] < before["mean"]
    # the reconstruction is the input less the noise: nearer the clean frames than the input is
    clean = seq.albedo * seq.shading[..., None]
    assert np.abs(out.reconstruct() - clean).mean() < 0.5 * np.abs(seq.frames - clean).mean()
    np.testing.assert_allclose(kept.reconstruct(), seq.frames, atol=2e-3)
