"""Classic+NL flow kernels (kernels/*/flow_classic.py) against the NumPy reference."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import flow_classic as ref

T, H, W = 2, 37, 53


def run(be, name, inputs, outputs, *params):
    """Call ``be.flow_classic.<name>(*inputs, *outputs, *params)`` on copies; return the outputs as numpy."""
    args = [be.asarray(np.ascontiguousarray(a, np.float32)) for a in inputs]
    outs = [be.asarray(np.ascontiguousarray(o, np.float32).copy()) for o in outputs]
    getattr(be.flow_classic, name)(*args, *outs, *params)
    result = [be.numpy(o).copy() for o in outs]
    return result[0] if len(result) == 1 else result


def linear_system(rng, t=T, h=H, w=W, quad_frac=0.0):
    """A random but well-posed IRLS system (data coefficients, smoothness weights)."""
    i1 = rng.uniform(0, 255, (t, h, w)).astype(np.float32)
    i1x, i1y = (rng.normal(scale=20, size=(t, h, w)).astype(np.float32) for _ in range(2))
    warped = np.stack([i1 + rng.normal(scale=5, size=(t, h, w)),
                       i1x + rng.normal(scale=3, size=(t, h, w)),
                       i1y + rng.normal(scale=3, size=(t, h, w))], -1).astype(np.float32)
    inside = (rng.random((t, h, w)) > 0.1).astype(np.float32)
    flow = rng.normal(scale=2, size=(t, h, w, 2)).astype(np.float32)
    du = rng.normal(scale=0.3, size=(t, h, w, 2)).astype(np.float32)
    return i1, i1x, i1y, warped, inside, flow, du


def test_srgb_grey(backend, rng):
    rgb = rng.uniform(-0.1, 1.1, (T, H, W, 3)).astype(np.float32)
    out = run(backend, "srgb_grey", [rgb], [np.zeros((T, H, W))])
    np.testing.assert_allclose(out, ref.srgb_grey(rgb), rtol=1e-5, atol=1e-3)
    assert out.min() >= 0 and out.max() <= 255.0 + 1e-3
    white = run(backend, "srgb_grey", [np.ones((1, 2, 3, 3))], [np.zeros((1, 2, 3))])
    np.testing.assert_allclose(white, 255.0 * sum(ref.GREY_WEIGHTS), rtol=1e-6)


def test_row_min_max_and_scale_shift(backend, rng):
    src = rng.normal(size=(T, H, W, 3)).astype(np.float32)
    mm = run(backend, "row_min_max", [src], [np.zeros((T * H, 3, 2))])
    np.testing.assert_array_equal(mm, ref.row_min_max(src))
    scale = np.array([2.0, -1.0, 0.5], np.float32)
    shift = np.array([1.0, 0.0, -3.0], np.float32)
    out = run(backend, "scale_shift", [src], [np.zeros_like(src)], backend.asarray(scale), backend.asarray(shift))
    np.testing.assert_allclose(out, ref.scale_shift(src, scale, shift), rtol=1e-6, atol=1e-6)


def test_rof_step_and_texture(backend, rng):
    img = rng.uniform(-1, 1, (T, H, W)).astype(np.float32)
    p = rng.uniform(-0.7, 0.7, (T, H, W, 2)).astype(np.float32)
    theta, delta = 1 / 8, 2.0
    out = run(backend, "rof_dual_step", [img, p], [np.zeros_like(p)], theta, delta)
    want = ref.rof_dual_step(img, p, theta, delta)
    np.testing.assert_allclose(out, want, atol=2e-6)
    assert np.sqrt((out ** 2).sum(-1)).max() <= 1 + 1e-6
    tex = run(backend, "rof_texture", [img, p], [np.zeros_like(img)], theta, 0.95)
    np.testing.assert_allclose(tex, ref.rof_texture(img, p, theta, 0.95), atol=2e-6)


def test_rof_iterations_smooth_and_keep_mean(backend, rng):
    """Iterating the projection gives a structure image that is smoother than the
    input, has the same mean (the divergence sums to zero), and matches the reference."""
    yy, xx = np.mgrid[0:H, 0:W]
    img = (np.where(xx > W // 2, 0.5, -0.5) + 0.2 * rng.normal(size=(T, H, W))).astype(np.float32)
    be = backend
    a, b = be.zeros((T, H, W, 2)), be.zeros((T, H, W, 2))
    img_b = be.asarray(img)
    p_ref = np.zeros((T, H, W, 2))
    for _ in range(30):
        be.flow_classic.rof_dual_step(img_b, a, b, 1 / 8, 2.0)
        a, b = b, a
        p_ref = ref.rof_dual_step(img, p_ref, 1 / 8, 2.0)
    p = be.numpy(a).copy()
    np.testing.assert_allclose(p, p_ref, atol=1e-4)
    structure = img + (1 / 8) * ref.rof_divergence(p)
    np.testing.assert_allclose(structure.mean(axis=(1, 2)), img.mean(axis=(1, 2)), atol=1e-5)
    tv = lambda z: np.abs(np.diff(z, axis=2)).sum() + np.abs(np.diff(z, axis=1)).sum()
    assert tv(structure) < 0.5 * tv(img)


def test_pack_image_gradient(backend, rng):
    img, gx, gy = (rng.normal(size=(T, H, W)).astype(np.float32) for _ in range(3))
    out = run(backend, "pack_image_gradient", [img, gx, gy], [np.zeros((T, H, W, 3))])
    np.testing.assert_array_equal(out, ref.pack_image_gradient(img, gx, gy))


@pytest.mark.parametrize("quad_frac", [0.0, 0.5, 1.0])
def test_data_coefficients(backend, rng, quad_frac):
    i1, i1x, i1y, warped, inside, flow, du = linear_system(rng)
    params = (0.5, 0.45, 1e-3, quad_frac, 2.0)
    out = run(backend, "data_coefficients", [i1, i1x, i1y, warped, inside, du], [np.zeros((T, H, W, 5))], *params)
    want = ref.data_coefficients(i1, i1x, i1y, warped, inside, du, *params)
    np.testing.assert_allclose(out, want, rtol=2e-4, atol=1e-4 * np.abs(want).max())
    assert np.all(out[inside == 0] == 0)


@pytest.mark.parametrize("quad_frac", [0.0, 0.5, 1.0])
def test_smoothness_weights(backend, rng, quad_frac):
    _, _, _, _, _, flow, du = linear_system(rng)
    flow[0, 3, 4:8] = 1.25                     # exact zero differences reach the eps floor
    du[0, 3, 4:8] = 0.0
    out = run(backend, "smoothness_weights", [flow, du], [np.zeros((T, H, W, 4))], 0.45, 1e-3, quad_frac, 2.0)
    want = ref.smoothness_weights(flow, du, 0.45, 1e-3, quad_frac, 2.0)
    np.testing.assert_allclose(out, want, rtol=2e-4)
    assert np.all(out[:, :, -1, 0] == 0) and np.all(out[:, -1, :, 1] == 0)


def irls_system(rng, t=T, h=H, w=W, quad_frac=0.0, quad_weight=2e6, lam=3.0):
    """Data coefficients, smoothness weights and assembled system of a random problem (float32)."""
    i1, i1x, i1y, warped, inside, flow, _ = linear_system(rng, t, h, w)
    zero = np.zeros((t, h, w, 2), np.float32)
    data = ref.data_coefficients(i1, i1x, i1y, warped, inside, zero, quad_frac=quad_frac,
                                 quad_weight=quad_weight).astype(np.float32)
    smooth = ref.smoothness_weights(flow, zero, quad_frac=quad_frac, quad_weight=quad_weight).astype(np.float32)
    system = ref.assemble_system(flow, data, smooth, lam).astype(np.float32)
    return flow, data, smooth, system


def test_assemble_system(backend, rng):
    flow, data, smooth, _ = irls_system(rng)
    f_b, d_b, s_b = backend.asarray(flow), backend.asarray(data), backend.asarray(smooth)
    out = backend.zeros((T, H, W, 5))
    backend.flow_classic.assemble_system(f_b, d_b, s_b, 3.0, out)
    want = ref.assemble_system(flow, data, smooth, 3.0)
    np.testing.assert_allclose(backend.numpy(out), want, rtol=1e-4, atol=1e-5 * np.abs(want).max())


def test_sor_half_sweeps_match_reference(backend, rng):
    flow, data, smooth, system = irls_system(rng)
    du = rng.normal(scale=0.3, size=(T, H, W, 2)).astype(np.float32)
    want = du.astype(np.float64)
    got = backend.asarray(du.copy())
    sys_b, s_b = backend.asarray(system), backend.asarray(smooth)
    for sweep in range(3):
        for parity in (0, 1):
            backend.flow_classic.sor_sweep(got, sys_b, s_b, 3.0, 1.7, parity)
            want = ref.sor_sweep(want, system, smooth, 3.0, 1.7, parity)
    np.testing.assert_allclose(backend.numpy(got), want, rtol=1e-3, atol=1e-4)


@pytest.mark.parametrize("quad_frac", [0.0, 1.0])
def test_sor_converges_to_solution_of_system(backend, rng, quad_frac):
    """Enough red-black sweeps solve the IRLS system: the float64 residual falls by orders of magnitude."""
    t, h, w = 1, 19, 23
    lam = 3.0
    flow, data, smooth, system = irls_system(rng, t, h, w, quad_frac, 2.0, lam)
    zero = np.zeros((t, h, w, 2), np.float32)
    r0 = np.abs(ref.system_residual(zero, system, smooth, lam)).max()
    du = backend.asarray(zero.copy())
    sys_b, s_b = backend.asarray(system), backend.asarray(smooth)
    for _ in range(300):
        for parity in (0, 1):
            backend.flow_classic.sor_sweep(du, sys_b, s_b, lam, 1.8, parity)
    r = np.abs(ref.system_residual(backend.numpy(du), system, smooth, lam)).max()
    # float32 sweeps on robust weights spanning three decades stall near 1e-3
    assert r < (1e-2 if quad_frac == 0.0 else 1e-4) * r0


def test_apply_update_and_select(backend, rng):
    _, _, _, _, _, flow, du = linear_system(rng)
    du *= 10
    out = run(backend, "apply_update", [flow, du], [np.zeros_like(flow)], 1.0)
    np.testing.assert_allclose(out, ref.apply_update(flow, du, 1.0), atol=1e-6)
    free = run(backend, "apply_update", [flow, du], [np.zeros_like(flow)], 0.0)
    np.testing.assert_allclose(free, flow + du, atol=1e-5)
    mask = (rng.random((T, H, W)) > 0.5).astype(np.float32)
    sel = run(backend, "select_masked", [mask, flow, du], [np.zeros_like(flow)])
    np.testing.assert_array_equal(sel, ref.select_masked(mask, flow, du))


def test_flow_sobel_components(backend, rng):
    flow = rng.normal(size=(T, H, W, 2)).astype(np.float32)
    out, energy = run(backend, "flow_sobel_components", [flow], [np.zeros((T, H, W, 4)), np.zeros((T * H, 2))])
    want, want_energy = ref.flow_sobel_components(flow)
    np.testing.assert_allclose(out, want, atol=1e-5)
    np.testing.assert_allclose(energy, want_energy, rtol=1e-4)


def test_thin_edges_matches_reference(backend, rng):
    flow = rng.normal(size=(T, H, W, 2)).astype(np.float32)
    sobel, energy = ref.flow_sobel_components(flow)
    cutoff = (energy.reshape(T, H, 2).sum(1) / (H * W)).astype(np.float32)
    out = run(backend, "thin_edges", [sobel, cutoff], [np.zeros((T, H, W))])
    np.testing.assert_array_equal(out, ref.thin_edges(sobel, cutoff))
    assert 0 < out.mean() < 0.5


def test_thin_edges_of_a_step_is_one_pixel_wide(backend):
    flow = np.zeros((1, 12, 20, 2), np.float32)
    flow[:, :, 10:, 0] = 2.0                       # u jumps between columns 9 and 10
    sobel, energy = run(backend, "flow_sobel_components", [flow], [np.zeros((1, 12, 20, 4)), np.zeros((12, 2))])
    cutoff = (4 * energy.sum(0) / flow[0, ..., 0].size)[None].astype(np.float32)
    edges = run(backend, "thin_edges", [sobel, cutoff], [np.zeros((1, 12, 20))])
    want = np.zeros((1, 12, 20))
    want[:, :, 9] = 1
    np.testing.assert_array_equal(edges, want)


def test_one_thread_equals_two_threads(rng):
    be = get_backend("warp")
    i1, i1x, i1y, warped, inside, flow, du = linear_system(rng)
    results = []
    for n in (1, 2):
        with threads(n):
            data = run(be, "data_coefficients", [i1, i1x, i1y, warped, inside, du], [np.zeros((T, H, W, 5))])
            smooth = run(be, "smoothness_weights", [flow, du], [np.zeros((T, H, W, 4))])
            system = be.zeros((T, H, W, 5))
            be.flow_classic.assemble_system(be.asarray(flow), be.asarray(data), be.asarray(smooth), 3.0, system)
            d = be.asarray(du.copy())
            for parity in (0, 1, 0, 1):
                be.flow_classic.sor_sweep(d, system, be.asarray(smooth), 3.0, 1.9, parity)
            p = run(be, "rof_dual_step", [i1 / 255, np.zeros((T, H, W, 2))], [np.zeros((T, H, W, 2))], 0.125, 2.0)
            results.append([data, smooth, be.numpy(system).copy(), be.numpy(d).copy(), p])
    for a, b in zip(*results):
        np.testing.assert_array_equal(a, b)


def test_warp_and_taichi_agree(rng):
    wpb, tib = get_backend("warp"), get_backend("taichi")
    i1, i1x, i1y, warped, inside, flow, du = linear_system(rng)
    outs = []
    for be in (wpb, tib):
        data = run(be, "data_coefficients", [i1, i1x, i1y, warped, inside, du], [np.zeros((T, H, W, 5))])
        smooth = run(be, "smoothness_weights", [flow, du], [np.zeros((T, H, W, 4))])
        system = be.zeros((T, H, W, 5))
        be.flow_classic.assemble_system(be.asarray(flow), be.asarray(data), be.asarray(smooth), 3.0, system)
        d = be.asarray(du.copy())
        for parity in (0, 1, 0, 1):
            be.flow_classic.sor_sweep(d, system, be.asarray(smooth), 3.0, 1.9, parity)
        outs.append([data, smooth, be.numpy(system).copy(), be.numpy(d).copy()])
    for a, b in zip(*outs):
        np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-4 * max(1.0, np.abs(a).max()))


def test_bad_input_raises(backend):
    be = backend
    good3 = be.zeros((T, H, W))
    good4 = be.zeros((T, H, W, 2))
    with pytest.raises(ValueError, match="shape"):
        be.flow_classic.srgb_grey(be.zeros((T, H, W, 4)), good3)
    with pytest.raises(ValueError, match="shape"):
        be.flow_classic.smoothness_weights(good4, good4, be.zeros((T, H, W, 3)))
    with pytest.raises(ValueError, match="different arrays"):
        be.flow_classic.rof_dual_step(good3, good4, good4, 0.125, 2.0)
    with pytest.raises(ValueError, match="parity"):
        be.flow_classic.sor_sweep(good4, be.zeros((T, H, W, 5)), be.zeros((T, H, W, 4)), 3.0, 1.9, 2)
    with pytest.raises(ValueError, match="shape"):
        be.flow_classic.assemble_system(good4, be.zeros((T, H, W, 4)), be.zeros((T, H, W, 4)), 3.0,
                                        be.zeros((T, H, W, 5)))
    with pytest.raises(TypeError, match="float32"):
        be.flow_classic.apply_update(be.zeros((T, H, W, 2), np.float64), good4, good4)
    with pytest.raises(TypeError):
        be.flow_classic.apply_update(np.zeros((T, H, W, 2)) if be.name == "warp" else [[0.0]], good4, good4)
