"""The GPU's launch layouts, run on the CPU so every machine checks them.

On a CUDA device the albedo GSM term runs one thread per pixel
(``energy_albedo_gsm.gsm_pixels``) instead of one per band of rows, and the
vector operations give each thread 4 elements (256 for reductions) instead of
4096.  Here both layouts are forced on the CPU and compared with the NumPy
references, on odd sizes and at borders.
"""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.reference import energy_albedo_gsm as gsm_ref
from ivkernels.kernels.warp import energy_albedo_gsm as warp_gsm
from ivkernels.kernels.warp import vecops as warp_vecops
from ivkernels.kernels.workspace import Workspace
from ivkernels.priors import load_albedo_prior


@pytest.fixture
def be():
    return get_backend("warp", "cpu")


@pytest.fixture
def gpu_layouts(monkeypatch):
    monkeypatch.setattr(warp_gsm, "pixel_threads", lambda device: True)
    monkeypatch.setattr(warp_vecops, "_chunk",
                        lambda device, reduction=False: (warp_vecops.CUDA_REDUCTION_CHUNK if reduction
                                                         else warp_vecops.CUDA_CHUNK))


@pytest.mark.parametrize("shape, radius", [((2, 13, 17), 2), ((1, 1, 5), 2), ((3, 4, 2), 1), ((1, 9, 11), 3)])
def test_gsm_one_thread_per_pixel_matches_the_reference(be, gpu_layouts, shape, radius):
    rng = np.random.default_rng(7)
    prior = load_albedo_prior()
    t, h, w = shape
    A = rng.normal(-1.0, 0.6, (t, h, w, 3)).astype(np.float32)
    A.reshape(-1, 3)[:: 7] += 3.0                     # some differences beyond the table
    arrays = (prior.sigma_inv.astype(np.float32), prior.table_g.astype(np.float32),
              prior.table_dg.astype(np.float32))
    gA0 = rng.normal(0, 1, A.shape).astype(np.float32)
    e0 = rng.normal(0, 1, t * h)
    gA, er = be.asarray(gA0.copy()), be.asarray(e0.copy())
    for workspace in (None, Workspace()):
        gA, er = be.asarray(gA0.copy()), be.asarray(e0.copy())
        be.energy_albedo_gsm.gsm_smoothness(be.asarray(A), *(be.asarray(a) for a in arrays), prior.r2_max,
                                            gA, er, lam=0.7, radius=radius, workspace=workspace)
        r_er, r_gA = gsm_ref.gsm_smoothness(A, *arrays, prior.r2_max, lam=0.7, radius=radius)
        np.testing.assert_allclose(be.numpy(er) - e0, r_er, rtol=2e-5, atol=1e-9)
        np.testing.assert_allclose(be.numpy(gA) - gA0, r_gA, rtol=1e-4, atol=1e-5 * max(1.0, np.abs(r_gA).max()))


def test_gsm_pixel_and_band_layouts_agree(be, monkeypatch):
    rng = np.random.default_rng(3)
    prior = load_albedo_prior()
    A = be.asarray(rng.normal(-1.0, 0.5, (2, 37, 29, 3)).astype(np.float32))
    arrays = [be.asarray(a) for a in (prior.sigma_inv.astype(np.float32), prior.table_g.astype(np.float32),
                                      prior.table_dg.astype(np.float32))]
    out = {}
    for pixels in (False, True):
        monkeypatch.setattr(warp_gsm, "pixel_threads", lambda device, p=pixels: p)
        gA, er = be.zeros((2, 37, 29, 3)), be.zeros((74,), dtype=np.float64)
        be.energy_albedo_gsm.gsm_smoothness(A, *arrays, prior.r2_max, gA, er, lam=1.0)
        out[pixels] = be.numpy(er).copy(), be.numpy(gA).copy()
    np.testing.assert_allclose(out[True][0], out[False][0], rtol=1e-5)
    np.testing.assert_allclose(out[True][1], out[False][1], rtol=1e-4, atol=1e-5 * np.abs(out[False][1]).max())


@pytest.mark.parametrize("n", [1, 3, 4, 255, 257, 1029, 70001])
def test_vector_operations_with_the_gpu_chunks(be, gpu_layouts, n):
    rng = np.random.default_rng(n)
    x, y = rng.normal(size=n).astype(np.float32), rng.normal(size=n).astype(np.float32)
    v = be.vecops
    X, Y = be.asarray(x.copy()), be.asarray(y.copy())       # (zero-copy on the CPU)
    assert v.dot(X, Y) == pytest.approx(float(x.astype(np.float64) @ y), rel=1e-9, abs=1e-9)
    assert v.norm_inf(X) == pytest.approx(float(np.abs(x).max()))
    out = be.empty((n,))
    v.lincomb(out, 0.5, X, -2.0, Y)
    np.testing.assert_allclose(be.numpy(out), 0.5 * x - 2.0 * y, rtol=1e-6, atol=1e-6)
    v.axpy(3.0, X, out)
    np.testing.assert_allclose(be.numpy(out), 0.5 * x - 2.0 * y + 3.0 * x, rtol=1e-5, atol=1e-5)
    v.scale(-1.5, out)
    v.copy(out, Y)
    np.testing.assert_allclose(be.numpy(Y), -1.5 * (3.5 * x - 2.0 * y), rtol=1e-5, atol=1e-5)
    v.fill(out, 0.25)
    assert np.all(be.numpy(out) == np.float32(0.25))
    basis = rng.normal(size=(5, n)).astype(np.float32)
    B = be.asarray(basis.copy())
    np.testing.assert_allclose(v.dots(B, X, [0, 2, 4]), basis[[0, 2, 4]].astype(np.float64) @ x,
                               rtol=1e-9, atol=1e-9)
    v.combine(out, B, [1, 3], [0.5, -1.0])
    np.testing.assert_allclose(be.numpy(out), 0.5 * basis[1] - basis[3], rtol=1e-5, atol=1e-5)
