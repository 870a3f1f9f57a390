"""The GPU's row tiles of the flow, sampling, pyramid, map and derivative kernels, run on the CPU.

On a CUDA device the kernels of ``flow_classic``, ``sampling``, ``pyramid``,
``maps`` and ``derivatives`` run one thread per pixel (rows cut into tiles,
:func:`ivkernels.kernels.launch.row_tiles`).  Here ``FORCE_GPU_LAYOUT_TILES``
cuts each row into 3 uneven tiles on the CPU, and every converted host
function is compared with its own CPU layout (one tile per row) on odd sizes
(widths 1, 7, 13; heights 1, 5, 9).  Each pixel does the same arithmetic in
both layouts, so the outputs must be equal bit for bit: a kernel's running
state that a tile did not start afresh (the cached ``v`` of the ROF step, the
sliding count of the boundary dilation) or a tile off by one column would
show.  Written outputs start as NaN, so a pixel no tile writes fails too.
"""
import numpy as np
import pytest
import warp as wp

from gpu_layout_harness import both_layouts
from ivkernels.backends import get_backend
from ivkernels.kernels.workspace import Workspace


#: (frames, height, width): widths 1, 7, 13 (1, 3, 3 tiles of 1..5 pixels), heights 1, 5, 9
SHAPES = [(2, 5, 7), (3, 1, 13), (1, 9, 1), (2, 9, 13)]


@pytest.fixture
def be():
    return get_backend("warp", "cpu")


def assert_same_bits(monkeypatch, call):
    """The GPU layout's outputs are the CPU layout's, bit for bit (NaN nowhere)."""
    cpu, gpu = both_layouts(monkeypatch, call)
    assert len(cpu) == len(gpu) > 0
    for a, b in zip(cpu, gpu):
        assert not np.isnan(a).any()                  # the CPU layout writes every pixel
        np.testing.assert_array_equal(b, a)


def unwritten(be, shape):
    """A NaN-filled float32 output (zero-copy on the CPU, a fresh buffer every call)."""
    return be.asarray(np.full(shape, np.nan, np.float32))


def numpy_copies(be, *arrays):
    return [be.numpy(a).copy() for a in arrays]


def rng_for(shape, salt=0):
    return np.random.default_rng(1000 * salt + 100 * shape[0] + 10 * shape[1] + shape[2])


def f32(x):
    return np.asarray(x, np.float32)


# ----------------------------------------------------------------------------
# flow_classic
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_grey_levels_and_rescale_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 1)
    t, h, w = shape
    rgb = f32(rng.uniform(-0.1, 1.1, (t, h, w, 3)))
    scale, shift = f32(rng.normal(1, 0.3, 3)), f32(rng.normal(0, 1, 3))

    def run():
        srgb, log = unwritten(be, (t, h, w)), unwritten(be, (t, h, w))
        be.flow_classic.srgb_grey(be.asarray(rgb), srgb)
        be.flow_classic.log_grey(be.asarray(rgb), log, floor=1e-3)
        out = unwritten(be, (t, h, w, 3))
        be.flow_classic.scale_shift(be.asarray(rgb), out, be.asarray(scale), be.asarray(shift))
        inplace = be.asarray(rgb.copy())
        be.flow_classic.scale_shift(inplace, inplace, be.asarray(scale), be.asarray(shift))
        rows = unwritten(be, (t * h, 3, 2))           # (a reduction per row: one thread per row in both layouts)
        be.flow_classic.row_min_max(be.asarray(rgb), rows)
        return numpy_copies(be, srgb, log, out, inplace, rows)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
def test_rof_dual_step_and_texture_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 2)
    t, h, w = shape
    img = f32(rng.uniform(-1, 1, (t, h, w)))
    p0 = f32(rng.uniform(-0.7, 0.7, (t, h, w, 2)))
    theta = 0.125

    def run():
        # a few steps, each reading the last: a wrong v at a tile's first column spreads
        p_in, outs = be.asarray(p0.copy()), []
        for _ in range(3):
            p_out = unwritten(be, (t, h, w, 2))
            be.flow_classic.rof_dual_step(be.asarray(img), p_in, p_out, theta, 1.0 / (4.0 * theta))
            outs.append(p_out)
            p_in = p_out
        texture = unwritten(be, (t, h, w))
        be.flow_classic.rof_texture(be.asarray(img), p_in, texture, theta, 0.95)
        inplace = be.asarray(img.copy())
        be.flow_classic.rof_texture(inplace, p_in, inplace, theta, 0.95)
        return numpy_copies(be, *outs, texture, inplace)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
def test_feature_channels_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 3)
    t, h, w = shape
    img, gx, gy = (f32(rng.normal(0, 10, (t, h, w))) for _ in range(3))
    feat, fgx, fgy = (f32(rng.normal(0, 1, (t, h, w, 2))) for _ in range(3))

    def run():
        a = be.asarray
        image_gradient, gradient = unwritten(be, (t, h, w, 3)), unwritten(be, (t, h, w, 2))
        be.flow_classic.pack_image_gradient(a(img), a(gx), a(gy), image_gradient)
        be.flow_classic.pack_gradient(a(gx), a(gy), gradient)
        census1, census2 = unwritten(be, (t, h, w, 8)), unwritten(be, (t, h, w, 24))
        be.flow_classic.soft_census(a(img), census1, radius=1, eps=4.0, scale=1.0)
        be.flow_classic.soft_census(a(img), census2, radius=2, eps=2.0, scale=0.5)
        channels = unwritten(be, (t, h, w, 6))
        be.flow_classic.pack_channels_gradient(a(feat), a(fgx), a(fgy), channels)
        return numpy_copies(be, image_gradient, gradient, census1, census2, channels)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("quad_frac", [0.0, 0.3])
def test_irls_weights_and_system_in_tiles(be, monkeypatch, shape, quad_frac):
    rng = rng_for(shape, 4)
    t, h, w = shape
    i1, i1x, i1y = (f32(rng.normal(0, 1, (t, h, w))) for _ in range(3))
    warped = f32(rng.normal(0, 1, (t, h, w, 3)))
    inside = f32(rng.uniform(0, 1, (t, h, w)) > 0.2)
    du = f32(rng.normal(0, 0.3, (t, h, w, 2)))
    flow = f32(rng.normal(0, 2, (t, h, w, 2)))
    first, warped_c = f32(rng.normal(0, 1, (t, h, w, 6))), f32(rng.normal(0, 1, (t, h, w, 6)))
    weights = f32([1.0, 0.4])
    kw = dict(blend=0.5, a=0.45, eps=1e-3, quad_frac=quad_frac, quad_weight=2.0)

    def run():
        a = be.asarray
        data, data_c, smooth = unwritten(be, (t, h, w, 5)), unwritten(be, (t, h, w, 5)), unwritten(be, (t, h, w, 4))
        be.flow_classic.data_coefficients(a(i1), a(i1x), a(i1y), a(warped), a(inside), a(du), data, **kw)
        be.flow_classic.data_coefficients_channels(a(first), a(warped_c), a(inside), a(du), a(weights), data_c, **kw)
        be.flow_classic.smoothness_weights(a(flow), a(du), smooth, a=0.45, eps=1e-3, quad_frac=quad_frac,
                                           quad_weight=2.0)
        system = unwritten(be, (t, h, w, 5))
        be.flow_classic.assemble_system(a(flow), data, smooth, 3.0, system)
        return numpy_copies(be, data, data_c, smooth, system)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
def test_flow_update_and_selection_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 5)
    t, h, w = shape
    flow, du = f32(rng.normal(0, 2, (t, h, w, 2))), f32(rng.normal(0, 1.5, (t, h, w, 2)))
    mask = f32(rng.uniform(0, 1, (t, h, w)))
    other = f32(rng.normal(0, 1, (t, h, w, 2)))

    def run():
        a = be.asarray
        clipped, free = unwritten(be, (t, h, w, 2)), unwritten(be, (t, h, w, 2))
        be.flow_classic.apply_update(a(flow), a(du), clipped, limit=1.0)
        be.flow_classic.apply_update(a(flow), a(du), free, limit=0.0)
        inplace = a(flow.copy())
        be.flow_classic.apply_update(inplace, a(du), inplace, limit=0.5)
        selected = unwritten(be, (t, h, w, 2))
        be.flow_classic.select_masked(a(mask), a(flow), a(other), selected)
        aliased = a(flow.copy())
        be.flow_classic.select_masked(a(mask), aliased, a(other), aliased)
        return numpy_copies(be, clipped, free, inplace, selected, aliased)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
def test_flow_edges_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 6)
    t, h, w = shape
    flow = f32(rng.normal(0, 1, (t, h, w, 2)))
    flow[:, :, w // 2:, 0] += 4.0                     # a motion boundary down the middle
    sobel_in = f32(rng.normal(0, 1, (t, h, w, 4)))
    b = sobel_in[..., 0::2] ** 2 + sobel_in[..., 1::2] ** 2
    cutoff = f32(np.median(b.reshape(t, -1, 2), axis=1))      # about half the pixels above it

    def run():
        # the row energies: summed in the pixel kernel on the CPU, by a second per-row kernel in
        # the GPU's layout, in the same order with the same operations (the same bits)
        sobel, energy = unwritten(be, (t, h, w, 4)), unwritten(be, (t * h, 2))
        be.flow_classic.flow_sobel_components(be.asarray(flow), sobel, energy)
        edges = unwritten(be, (t, h, w))
        be.flow_classic.thin_edges(be.asarray(sobel_in), be.asarray(cutoff), edges)
        return numpy_copies(be, sobel, energy, edges)

    assert_same_bits(monkeypatch, run)


# ----------------------------------------------------------------------------
# sampling
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("channels", [1, 3])
def test_warps_and_splat_in_tiles(be, monkeypatch, shape, channels):
    rng = rng_for(shape, 7)
    t, h, w = shape
    src = f32(rng.normal(0, 1, (t, h, w, channels)))
    flow = f32(rng.normal(0, 2, (t, h, w, 2)))
    flow.reshape(-1, 2)[::5] *= 1e6                    # a few far outside the image
    values = f32(rng.normal(0, 1, (t, h, w, channels)))
    out0 = f32(rng.normal(0, 1, (t, h, w, channels)))

    def run():
        a = be.asarray
        bilinear, bicubic = unwritten(be, (t, h, w, channels)), unwritten(be, (t, h, w, channels))
        inside_l, inside_c = unwritten(be, (t, h, w)), unwritten(be, (t, h, w))
        be.sampling.warp_bilinear(a(src), a(flow), bilinear, inside_l)
        be.sampling.warp_bicubic(a(src), a(flow), bicubic, inside_c)
        splat = a(out0.copy())                         # adds to what is there
        be.sampling.splat_bilinear(a(values), a(flow), splat)
        return numpy_copies(be, bilinear, bicubic, inside_l, inside_c, splat)

    assert_same_bits(monkeypatch, run)


# ----------------------------------------------------------------------------
# pyramid
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_blur_and_resizing_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 8)
    t, h, w = shape
    src = f32(rng.normal(0, 1, (t, h, w, 3)))
    flow = f32(rng.normal(0, 2, (t, h, w, 2)))
    sizes = [((h + 1) // 2, (w + 1) // 2), (h + 3, w + 4)]          # down (odd) and up

    def run():
        a = be.asarray
        outs = []
        for sigma in (1.0, 0.63, 0.0):
            out, scratch = unwritten(be, src.shape), unwritten(be, src.shape)
            be.pyramid.gaussian_blur(a(src), out, scratch, sigma)
            outs.append(out)
        inplace = a(src.copy())
        be.pyramid.gaussian_blur(inplace, inplace, unwritten(be, src.shape), 1.0)
        outs.append(inplace)
        for hh, ww in sizes:
            image, vectors = unwritten(be, (t, hh, ww, 3)), unwritten(be, (t, hh, ww, 2))
            be.pyramid.resize_bilinear(a(src), image)
            be.pyramid.resize_flow(a(flow), vectors)
            outs += [image, vectors]
        return numpy_copies(be, *outs)

    assert_same_bits(monkeypatch, run)


# ----------------------------------------------------------------------------
# maps
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_occlusion_maps_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 9)
    t, h, w = shape
    lab = f32(rng.normal(50, 15, (t + 1, h, w, 3)))
    flow = f32(rng.normal(0, 1.5, (t, h, w, 2)))
    div = f32(np.minimum(rng.normal(0, 0.3, (t, h, w)), 0.0))

    def run():
        a = be.asarray
        soft, binary = unwritten(be, (t, h, w)), unwritten(be, (t, h, w))
        be.maps.occlusion_soft(a(lab), a(flow), a(div), soft, 20.0, 0.3)
        be.maps.occlusion_binary(a(lab), a(flow), a(div), binary, 20.0, 0.3, 0.5)
        return numpy_copies(be, soft, binary)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
def test_occlusion_clearing_tests_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 10)
    t, h, w = shape
    log_image = f32(rng.normal(-1, 0.5, (t + 1, h, w, 3)))
    flow = f32(rng.normal(0, 1.2, (t, h, w, 2)))
    near = f32(rng.uniform(0, 1, (t, h, w)) > 0.3)
    offsets = f32(rng.normal(0, 0.1, t))

    def run():
        a = be.asarray
        # each updates w_occ in place, clearing about half the pixels: a pixel no tile visits keeps its 1
        reliable, chroma, luminance = (a(np.ones((t, h, w), np.float32)) for _ in range(3))
        be.maps.warp_reliability(a(log_image), a(flow), reliable, 0.3)
        be.maps.chroma_consistency(a(log_image), a(flow), chroma, 0.5)
        be.maps.luminance_consistency(a(log_image), a(flow), a(near), a(offsets), luminance, 0.4)
        return numpy_copies(be, reliable, chroma, luminance)

    cpu, gpu = both_layouts(monkeypatch, run)
    if h * w > 20:
        assert all(0.1 < x.mean() < 0.9 for x in cpu)           # the tests clear some pixels, not all
    for x, y in zip(cpu, gpu):
        np.testing.assert_array_equal(y, x)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("tau_chroma", [0.0, 0.3])
def test_shading_gate_in_tiles(be, monkeypatch, shape, tau_chroma):
    rng = rng_for(shape, 11)
    t, h, w = shape
    log_image = f32(rng.normal(-1, 0.5, (t + 1, h, w, 3)))
    flow = f32(rng.normal(0, 1.2, (t, h, w, 2)))

    def run():
        gate = unwritten(be, (t + 1, h, w))
        be.maps.shading_gate(be.asarray(log_image), be.asarray(flow), gate, 0.2, tau_chroma)
        return numpy_copies(be, gate)

    assert_same_bits(monkeypatch, run)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("radius", [0, 1, 2, 5])
def test_motion_boundary_in_tiles(be, monkeypatch, shape, radius):
    from ivkernels.kernels.warp import maps as warp_maps

    rng = rng_for(shape, 12 + radius)
    t, h, w = shape
    magnitude = f32(rng.uniform(0, 1, (t, h, w)))
    threshold = 0.85                                   # sparse edges, so the windows' counts matter

    def run():
        # the row pass's scratch starts as NaN too: a pixel of it no tile writes shows in the output
        workspace = Workspace()
        hits = workspace.buffer(f"{warp_maps.__name__}.boundary_hits", (t, h, w), wp.float32,
                                lambda: unwritten(be, (t, h, w)), be.asarray(magnitude).device)
        out = unwritten(be, (t, h, w))
        be.maps.motion_boundary(be.asarray(magnitude), out, threshold, radius, workspace=workspace)
        return numpy_copies(be, hits, out)

    assert_same_bits(monkeypatch, run)


# ----------------------------------------------------------------------------
# derivatives
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_derivatives_in_tiles(be, monkeypatch, shape):
    rng = rng_for(shape, 13)
    t, h, w = shape
    src = f32(rng.normal(0, 1, (t, h, w, 3)))
    flow = f32(rng.normal(0, 2, (t, h, w, 2)))

    def run():
        a = be.asarray
        gx, gy = unwritten(be, src.shape), unwritten(be, src.shape)
        be.derivatives.image_gradient(a(src), gx, gy)
        magnitude, div = unwritten(be, (t, h, w)), unwritten(be, (t, h, w))
        be.derivatives.flow_sobel_magnitude(a(flow), magnitude)
        be.derivatives.divergence_negative(a(flow), div)
        return numpy_copies(be, gx, gy, magnitude, div)

    assert_same_bits(monkeypatch, run)
