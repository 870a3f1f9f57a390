"""The CPU's native row loops against the per-pixel Warp kernels they stand in for.

On the CPU some Warp host functions run a row per kernel thread as a native
loop that the compiler vectorises (``wp.func_native``); on a GPU the same host
functions launch the per-pixel kernels.  Both must give the same bits, so the
CPU loops are checked here against the per-pixel kernels launched on the CPU,
on odd sizes, rows narrower than the stencil, ties and signed zeros, and the
layouts that fall back (strided views).  The reference tests of each family
(``test_kernels_*``) check both against NumPy.
"""
import numpy as np
import pytest

wp = pytest.importorskip("warp")

from ivkernels.kernels.host import gaussian_kernel  # noqa: E402
from ivkernels.kernels.launch import launch_rows  # noqa: E402
from ivkernels.kernels.warp import median, pyramid  # noqa: E402

SHAPES = [(1, 1, 1, 1), (1, 2, 3, 1), (2, 5, 5, 2), (2, 7, 9, 2), (3, 13, 17, 3), (2, 31, 40, 1), (1, 4, 100, 2)]


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def values(rng, shape, kind):
    """Normal values, or small integers (ties) with signed zeros."""
    if kind == "normal":
        return rng.normal(size=shape).astype(np.float32)
    a = rng.integers(-2, 3, shape).astype(np.float32)
    a[rng.random(shape) < 0.2] = -0.0
    return a


def per_pixel_median(src):
    out = wp.empty(src.shape, dtype=float)
    launch_rows(median.median5x5_rows, src.shape[0] * src.shape[1], [1, src, out])
    return out.numpy()


def per_pixel_blur(src, sigma):
    taps = gaussian_kernel(sigma)
    weights = wp.array(taps, dtype=float)
    radius = (len(taps) - 1) // 2
    scratch, out = wp.empty(src.shape, dtype=float), wp.empty(src.shape, dtype=float)
    rows = src.shape[0] * src.shape[1]
    launch_rows(pyramid.blur_x_rows, rows, [1, src, scratch, weights, radius])
    launch_rows(pyramid.blur_y_rows, rows, [1, scratch, out, weights, radius])
    return out.numpy()


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["normal", "ties"])
def test_median5x5_row_loop_matches_the_per_pixel_kernel(rng, shape, kind):
    src = wp.array(values(rng, shape, kind))
    out = wp.empty(shape, dtype=float)
    median.median5x5(src, out)
    assert same_bits(out.numpy(), per_pixel_median(src))


def test_median5x5_on_a_channel_view_and_a_wide_layout(rng):
    # a view whose pixels are 3 floats apart (the generic stride) and 3 channels
    full = wp.array(values(rng, (2, 9, 23, 3), "normal"))
    view = full[:, :, :, 1:2]
    out = wp.empty(view.shape, dtype=float)
    median.median5x5(view, out)
    assert same_bits(out.numpy(), per_pixel_median(wp.array(view.numpy())))
    out3 = wp.empty(full.shape, dtype=float)
    median.median5x5(full, out3)
    assert same_bits(out3.numpy(), per_pixel_median(full))


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("sigma", [0.3, 1.0, 2.5, 7.0])
def test_blur_row_loops_match_the_per_pixel_kernels(rng, shape, sigma):
    src = wp.array(values(rng, shape, "normal"))
    out, scratch = wp.empty(shape, dtype=float), wp.empty(shape, dtype=float)
    pyramid.gaussian_blur(src, out, scratch, sigma)
    assert same_bits(out.numpy(), per_pixel_blur(src, sigma))


def test_blur_in_place_and_on_a_strided_view(rng):
    a = values(rng, (2, 11, 19, 3), "normal")
    want = per_pixel_blur(wp.array(a), 1.3)
    src = wp.array(a)
    pyramid.gaussian_blur(src, src, wp.empty(src.shape, dtype=float), 1.3)      # out is src
    assert same_bits(src.numpy(), want)
    view = wp.array(np.concatenate([a, a], axis=2))[:, :, ::2, :]                 # pixels 6 floats apart: fallback
    out = wp.empty(view.shape, dtype=float)
    pyramid.gaussian_blur(view, out, wp.empty(view.shape, dtype=float), 1.3)
    assert same_bits(out.numpy(), per_pixel_blur(wp.array(view.numpy()), 1.3))


def temporal_inputs(rng, T, H, W, large_flow):
    yy, xx = np.mgrid[0:H, 0:W]
    flow = np.zeros((T - 1, H, W, 2), np.float32)
    flow[..., 0] = 3 * np.sin(xx / 7.0) + 1.3
    flow[..., 1] = 2 * np.cos(yy / 4.0) - 0.4
    if large_flow:                       # samples far outside the image: clamped corners
        flow += rng.normal(0, 20, flow.shape).astype(np.float32)
    occ = np.where(rng.random((T - 1, H, W)) < 0.8, 1.0, rng.random((T - 1, H, W)) * (rng.random((T - 1, H, W)) < 0.5))
    A = rng.normal(size=(T, H, W, 3)).astype(np.float32) * 3          # many differences beyond Tukey's alpha
    S = rng.normal(size=(T, H, W)).astype(np.float32) * 3
    return A, S, flow, occ.astype(np.float32)


def temporal_terms(rng, A, S, flow, occ, per_pixel, alpha):
    from ivkernels.kernels.warp import energy_temporal as et

    T, H, W, _ = A.shape
    arrays = [wp.array(a) for a in (A, S, flow, occ)]
    gA = wp.array(rng.normal(size=A.shape).astype(np.float32))
    gS = wp.array(rng.normal(size=S.shape).astype(np.float32))
    rows = wp.array(np.linspace(0.0, 1.0, T * H))
    if per_pixel:
        weight = wp.empty((T - 1, H, W, 4), dtype=float)
        S4, gS4 = et.with_channel_axis(arrays[1]), et.with_channel_axis(gS)
        launch_rows(et.temporal_pair_gather_rows, (T - 1) * H,
                    [1, arrays[0], S4, arrays[2], arrays[3], gA, gS4, weight, rows, 10.0, 1.0, alpha])
        launch_rows(et.temporal_pair_splat_rows, (T - 1) * H, [1, arrays[2], arrays[3], weight, gA, gS4], align=H)
    else:
        et.temporal_terms(*arrays, gA, gS, rows, 10.0, 1.0, alpha)
    return gA.numpy(), gS.numpy(), rows.numpy()


@pytest.mark.parametrize("size", [(2, 1, 1), (3, 7, 9), (4, 13, 300), (2, 40, 517)])
@pytest.mark.parametrize("large_flow", [False, True])
@pytest.mark.parametrize("alpha", [5.0, 0.7])
def test_temporal_row_loops_match_the_per_pixel_kernels(rng, size, large_flow, alpha):
    inputs = temporal_inputs(rng, *size, large_flow)
    seed = int(rng.integers(1 << 30))
    native = temporal_terms(np.random.default_rng(seed), *inputs, per_pixel=False, alpha=alpha)
    kernel = temporal_terms(np.random.default_rng(seed), *inputs, per_pixel=True, alpha=alpha)
    for got, want in zip(native, kernel):
        assert np.array_equal(got.view(np.uint8), want.view(np.uint8))


def test_temporal_terms_on_strided_views_fall_back(rng):
    from ivkernels.kernels.warp import energy_temporal as et

    A, S, flow, occ = temporal_inputs(rng, 3, 9, 11, False)
    spaced = np.zeros((3, 9, 22, 3), np.float32)
    spaced[:, :, ::2] = A
    wide = wp.array(spaced)[:, :, ::2, :]                                    # A, pixels 6 floats apart
    from ivkernels.kernels.warp._checks import rows_contiguous

    assert not rows_contiguous(wide) and rows_contiguous(wp.array(A), et.with_channel_axis(wp.array(S)))
    gA, gS = wp.zeros(A.shape, dtype=float), wp.zeros(S.shape, dtype=float)
    rows = wp.zeros(3 * 9, dtype=wp.float64)
    et.temporal_terms(wide, wp.array(S), wp.array(flow), wp.array(occ), gA, gS, rows, 10.0, 1.0, 5.0)
    gA2, gS2 = wp.zeros(A.shape, dtype=float), wp.zeros(S.shape, dtype=float)
    rows2 = wp.zeros(3 * 9, dtype=wp.float64)
    et.temporal_terms(wp.array(A), wp.array(S), wp.array(flow), wp.array(occ), gA2, gS2, rows2, 10.0, 1.0, 5.0)
    assert same_bits(gA.numpy(), gA2.numpy()) and same_bits(gS.numpy(), gS2.numpy())
    assert np.array_equal(rows.numpy(), rows2.numpy())


@pytest.mark.parametrize("size", [(1, 1, 1), (2, 3, 5), (2, 9, 13), (3, 31, 40), (1, 7, 1100)])
@pytest.mark.parametrize("spacing", [1, 3, 4, 12])
def test_prolong_row_loop_matches_the_per_pixel_kernel(rng, size, spacing):
    from ivkernels.kernels.host import grid_shape
    from ivkernels.kernels.warp import coarse_basis

    T, H, W = size
    weights = wp.empty((T, H, W, 16), dtype=float)
    coarse_basis.coarse_weights(wp.array(rng.normal(size=(T, H, W, 3)).astype(np.float32)), weights, spacing, 0.5)
    z = wp.array(rng.normal(size=(T, *grid_shape(H, W, spacing))).astype(np.float32))
    base = rng.normal(size=(T, H, W)).astype(np.float32)
    native, kernel = wp.array(base), wp.array(base)
    coarse_basis.prolong_add(z, weights, native, spacing)
    launch_rows(coarse_basis.prolong_add_rows, T * H, [1, z, weights, kernel, spacing])
    assert same_bits(native.numpy(), kernel.numpy())
    # a strided output falls back to the kernel, with the same result
    spaced = np.zeros((T, H, 2 * W), np.float32)
    spaced[:, :, ::2] = base
    view = wp.array(spaced)[:, :, ::2]
    coarse_basis.prolong_add(z, weights, view, spacing)
    assert same_bits(view.numpy(), kernel.numpy())


@pytest.mark.parametrize("n", [1, 3, 5, 4095, 4097, 10003])
def test_basis_dots_and_combine_loops_match_the_kernels(rng, n):
    from ivkernels.kernels.warp import vecops

    basis = wp.array(rng.normal(size=(6, n)).astype(np.float32))
    x = wp.array(rng.normal(size=n).astype(np.float32))
    rows, coeffs = [0, 5, 2, 3], [0.5, 0.0, -1.25, 3.0]
    chunk = vecops.CHUNK
    b, rows_wp, coeffs_wp = vecops._basis_rows(basis, rows, coeffs)
    partial = wp.empty((len(rows), vecops._chunks(n, chunk)), dtype=wp.float64)
    x4, = vecops._vec4(x)
    launch_rows(vecops.basis_dots_chunks, vecops._chunks(n, chunk),
                [b, x, vecops._basis_vec4(b, x4.shape[0]), x4, rows_wp, partial, chunk])
    assert np.array_equal(vecops.dots(basis, x, rows), partial.numpy().sum(axis=1))
    native, kernel = wp.empty(n, dtype=float), wp.empty(n, dtype=float)
    vecops.combine(native, basis, rows, coeffs)
    out4, = vecops._vec4(kernel)
    launch_rows(vecops.basis_combine_chunks, vecops._chunks(n, chunk),
                [kernel, b, out4, vecops._basis_vec4(b, out4.shape[0]), rows_wp, coeffs_wp, chunk])
    assert same_bits(native.numpy(), kernel.numpy())


@pytest.mark.parametrize("size", [(1, 1, 1), (2, 2, 5), (2, 3, 2), (2, 9, 13), (3, 31, 40), (1, 5, 600)])
@pytest.mark.parametrize("variant", ["plain", "gated", "paired"])
def test_local_shading_row_loop_matches_the_kernel(rng, size, variant):
    from ivkernels.kernels.warp import energy_shading as es

    T, H, W = size
    S = wp.array((rng.normal(size=size) * rng.choice([0.0, 0.01, 1.0], size=size)).astype(np.float32))
    gate = wp.array(rng.choice([0.0, 0.3, 1.0], size=size).astype(np.float32))
    base = rng.normal(size=size).astype(np.float32)
    rows0 = np.linspace(0.0, 1.0, T * H)
    native_g, kernel_g = wp.array(base), wp.array(base)
    native_e, kernel_e = wp.array(rows0), wp.array(rows0)
    pairs = wp.array(rng.choice([0.0, 0.5, 2.0], size=(H, W, 2)).astype(np.float32))
    if variant == "paired":
        es.shading_smoothness_paired(S, gate, pairs, native_g, native_e, lam=2.0, pair_gain=8.0, eps=0.001)
    elif variant == "gated":
        es.shading_smoothness_gated(S, gate, native_g, native_e, lam=2.0, eps=0.001)
    else:
        es.shading_smoothness(S, native_g, native_e, lam=2.0, eps=0.001)
    gated, paired = variant != "plain", variant == "paired"
    launch_rows(es._local_kernel_for(gated, paired), T * H,
                [1, S, gate if gated else S, pairs if paired else S, kernel_g, kernel_e, 2.0,
                 4.0 if paired else 0.0, 0.001])
    assert same_bits(native_g.numpy(), kernel_g.numpy())
    assert np.array_equal(native_e.numpy(), kernel_e.numpy())


@pytest.mark.parametrize("size", [(1, 1, 1), (2, 2, 3), (2, 9, 13), (3, 31, 40), (1, 4, 1300)])
def test_rof_dual_step_row_loop_matches_the_kernel(rng, size):
    from ivkernels.kernels.warp.flow_classic import rof

    img = wp.array(rng.normal(size=size).astype(np.float32))
    p_in = wp.array((rng.normal(size=(*size, 2)) * 0.7).astype(np.float32))
    native, kernel = wp.empty((*size, 2), dtype=float), wp.empty((*size, 2), dtype=float)
    rof.rof_dual_step(img, p_in, native, 0.125, 0.25)
    launch_rows(rof.rof_dual_step_rows, size[0] * size[1], [1, img, p_in, kernel, 0.125, 0.25])
    assert same_bits(native.numpy(), kernel.numpy())


def test_the_gpu_layouts_forced_for_tests_keep_the_per_pixel_kernels(monkeypatch, rng):
    from ivkernels.kernels import launch
    from ivkernels.kernels.warp._checks import native_rows

    src = wp.array(values(rng, (1, 6, 7, 2), "normal"))
    assert native_rows("cpu", src)
    monkeypatch.setattr(launch, "FORCE_GPU_LAYOUT_TILES", 3)
    assert not native_rows("cpu", src)            # tests/test_gpu_layouts*.py then run the GPU's layouts
