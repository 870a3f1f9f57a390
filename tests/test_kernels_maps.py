"""Occlusion, warp reliability and motion-boundary maps (kernels/*/maps.py): the generic
contract from the case table, plus hand-computed occlusion likelihoods, whole- and
half-pixel reliability, the clipped boundary window, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import maps as ref
from ivkernels.kernels.workspace import Workspace
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("maps")

T, H, W = 2, 37, 53


def occlusion(be, fn, lab, flow, div_neg, *args):
    out = be.zeros(flow.shape[:3])
    getattr(be.maps, fn)(be.asarray(lab), be.asarray(flow), be.asarray(div_neg), out, *args)
    return be.numpy(out).copy()


def boundary(be, mag, threshold, radius, **kw):
    out = be.zeros(mag.shape)
    be.maps.motion_boundary(be.asarray(mag), out, threshold, radius, **kw)
    return be.numpy(out).copy()


def test_occlusion_hand_cases(kernel_backend):
    lab = np.zeros((2, H, W, 3), np.float32)
    lab[1, ..., 0] = 20.0                            # L differs by sigma_e: o = exp(-1/2)
    flow = np.zeros((1, H, W, 2), np.float32)
    div = np.zeros((1, H, W), np.float32)
    soft = occlusion(kernel_backend, "occlusion_soft", lab, flow, div)
    np.testing.assert_allclose(soft, np.exp(-0.5), rtol=1e-6)
    np.testing.assert_array_equal(occlusion(kernel_backend, "occlusion_binary", lab, flow, div), 1)
    np.testing.assert_array_equal(occlusion(kernel_backend, "occlusion_binary", lab, flow, div, 20.0, 0.3, 0.7), 0)
    div[0, 5, 5] = -0.3                              # compression of sigma_d: another factor exp(-1/2)
    np.testing.assert_allclose(occlusion(kernel_backend, "occlusion_soft", lab, flow, div)[0, 5, 5], np.exp(-1),
                               rtol=1e-6)
    flow[0, 10, 10] = (0.0, -11.0)                   # lands above the image
    assert occlusion(kernel_backend, "occlusion_binary", lab, flow, div)[0, 10, 10] == 0
    assert occlusion(kernel_backend, "occlusion_soft", lab, flow, div)[0, 10, 10] == 0


def test_motion_boundary_hand_case(kernel_backend):
    mag = np.zeros((1, H, W), np.float32)
    mag[0, 1, 20] = 2.0
    mag[0, 30, 40] = 1.0                             # equal to the threshold: not an edge
    out = boundary(kernel_backend, mag, 1.0, 2)
    want = np.zeros_like(out)
    want[0, 0:4, 18:23] = 1                          # clipped at the top border
    np.testing.assert_array_equal(out, want)


def test_bad_input_raises(kernel_backend):
    m = kernel_backend.maps
    lab, flow, div, out = (kernel_backend.zeros(s) for s in ((T + 1, H, W, 3), (T, H, W, 2), (T, H, W), (T, H, W)))
    with pytest.raises(ValueError, match="flow"):
        m.occlusion_soft(kernel_backend.zeros((T, H, W, 3)), flow, div, out)
    with pytest.raises(ValueError, match="lab"):
        m.occlusion_binary(kernel_backend.zeros((T + 1, H, W, 1)), flow, div, out)
    with pytest.raises(ValueError, match="div_neg"):
        m.occlusion_soft(lab, flow, kernel_backend.zeros((T, H, W - 1)), out)
    with pytest.raises(ValueError, match="sigma"):
        m.occlusion_soft(lab, flow, div, out, sigma_e=0.0)
    with pytest.raises(ValueError, match="radius"):
        m.motion_boundary(div, out, 0.5, -1)
    with pytest.raises(ValueError, match="out"):
        m.motion_boundary(div, kernel_backend.zeros((T, H, W, 1)), 0.5, 1)
    with pytest.raises(TypeError, match="float32"):
        m.motion_boundary(kernel_backend.zeros((T, H, W), np.float64), out, 0.5, 1)
    with pytest.raises(TypeError, match="workspace must be"):
        m.motion_boundary(div, out, 0.5, 1, workspace=[])


# ------------------------------------------------ warp reliability (temporal terms' weight)
def reliability(be, log_image, flow, occ, max_spread):
    out = be.asarray(occ.copy())
    be.maps.warp_reliability(be.asarray(log_image), be.asarray(flow), out, max_spread)
    return be.numpy(out).copy()


def test_warp_reliability_hand_cases(kernel_backend):
    """Whole-pixel flow and flat images keep w_occ; a half-pixel sample across a step clears it."""
    t, h, w = 2, 9, 11
    step = np.zeros((t, h, w, 3), np.float32)
    step[:, :, 5:] = 1.0
    occ = np.ones((t - 1, h, w), np.float32)
    whole = np.zeros((t - 1, h, w, 2), np.float32)
    whole[..., 0] = 2.0
    assert reliability(kernel_backend, step, whole, occ, 0.01).all()
    half = np.zeros((t - 1, h, w, 2), np.float32)
    half[..., 0] = 0.5
    flat = np.full((t, h, w, 3), 0.3, np.float32)
    assert reliability(kernel_backend, flat, half, occ, 0.01).all()
    got = reliability(kernel_backend, step, half, occ, 0.01)
    assert not got[:, :, 4].any()                         # sample at x = 4.5 straddles the step
    assert got[:, :, :4].all() and got[:, :, 5:].all()


def test_warp_reliability_bad_input(kernel_backend):
    img = kernel_backend.asarray(np.zeros((2, 4, 4, 3), np.float32))
    flow = kernel_backend.asarray(np.zeros((1, 4, 4, 2), np.float32))
    with pytest.raises(ValueError, match="occ must have shape"):
        kernel_backend.maps.warp_reliability(img, flow, kernel_backend.asarray(np.zeros((2, 4, 4), np.float32)), 0.1)
    with pytest.raises(ValueError, match="max_spread"):
        kernel_backend.maps.warp_reliability(img, flow, kernel_backend.asarray(np.zeros((1, 4, 4), np.float32)), 0.0)


# ------------------------------------------------ chromaticity along the flow (temporal terms' weight)
def chroma_check(be, log_image, flow, occ, max_change):
    out = be.asarray(occ.copy())
    be.maps.chroma_consistency(be.asarray(log_image), be.asarray(flow), out, max_change)
    return be.numpy(out).copy()


def test_chroma_consistency_hand_cases(kernel_backend):
    """A grey light change keeps w_occ, a flow onto another colour clears it, whatever the
    brightness; already-cleared pixels stay cleared."""
    t, h, w = 2, 9, 12
    red, green = np.log([0.6, 0.1, 0.1]), np.log([0.1, 0.5, 0.1])
    img = np.empty((t, h, w, 3), np.float32)
    img[:, :, :6] = red
    img[:, :, 6:] = green
    img[1] += np.linspace(-2.0, 1.0, w, dtype=np.float32)[None, :, None]   # grey light ramp, x-dependent
    occ = np.ones((t - 1, h, w), np.float32)
    occ[0, 0, 0] = 0.0
    still = np.zeros((t - 1, h, w, 2), np.float32)
    got = chroma_check(kernel_backend, img, still, occ, 0.05)
    np.testing.assert_array_equal(got, occ)                 # same surfaces: the light alone changed
    right = np.zeros((t - 1, h, w, 2), np.float32)
    right[..., 0] = 3.0
    got = chroma_check(kernel_backend, img, right, occ, 0.05)
    assert not got[:, :, 3:6].any()                          # red at x lands on green at x + 3
    np.testing.assert_array_equal(got[:, :, :3], occ[:, :, :3])
    np.testing.assert_array_equal(got[:, :, 6:], occ[:, :, 6:])   # green stays green (clamped border)
    half = np.zeros((t - 1, h, w, 2), np.float32)
    half[..., 0] = 0.25                                       # x = 5.25: a quarter of the way into green
    change = ref.chroma_change(img, half)[0, 0, 5]
    assert 0.05 < change < 1.0
    assert chroma_check(kernel_backend, img, half, occ, change * 1.01)[0, 0, 5] == 1.0
    assert chroma_check(kernel_backend, img, half, occ, change * 0.99)[0, 0, 5] == 0.0


def test_chroma_consistency_bad_input(kernel_backend):
    img = kernel_backend.asarray(np.zeros((2, 4, 4, 3), np.float32))
    flow = kernel_backend.asarray(np.zeros((1, 4, 4, 2), np.float32))
    occ = kernel_backend.asarray(np.zeros((1, 4, 4), np.float32))
    with pytest.raises(ValueError, match="occ must have shape"):
        kernel_backend.maps.chroma_consistency(img, flow, kernel_backend.asarray(np.zeros((2, 4, 4), np.float32)), 0.1)
    with pytest.raises(ValueError, match="max_change"):
        kernel_backend.maps.chroma_consistency(img, flow, occ, 0.0)
    with pytest.raises(ValueError, match="log_image"):
        kernel_backend.maps.chroma_consistency(kernel_backend.asarray(np.zeros((2, 4, 4, 1), np.float32)), flow,
                                               occ, 0.1)


# ------------------------------------------------ brightness along the flow near flow jumps
def luminance_check(be, log_image, flow, near, offsets, occ, max_change):
    out = be.asarray(occ.copy())
    be.maps.luminance_consistency(be.asarray(log_image), be.asarray(flow), be.asarray(near),
                                  be.asarray(np.asarray(offsets, np.float32)), out, max_change)
    return be.numpy(out).copy()


def test_luminance_consistency_hand_cases(kernel_backend):
    """A grey scene under a global exposure change keeps w_occ; a flow from a dark grey
    surface onto a light grey one clears it where ``near`` is set, and only there."""
    t, h, w = 2, 9, 12
    img = np.empty((t, h, w, 3), np.float32)
    img[:, :, :6] = np.log(0.05)                              # dark grey
    img[:, :, 6:] = np.log(0.6)                               # light grey
    img[1] += 0.3                                             # the exposure rises by 0.3 log units
    occ = np.ones((t - 1, h, w), np.float32)
    occ[0, 0, 0] = 0.0
    near = np.ones((t - 1, h, w), np.float32)
    still = np.zeros((t - 1, h, w, 2), np.float32)
    np.testing.assert_array_equal(luminance_check(kernel_backend, img, still, near, [0.3], occ, 0.1), occ)
    assert not luminance_check(kernel_backend, img, still, near, [0.0], occ, 0.1).any()   # no offset: all change
    right = np.zeros((t - 1, h, w, 2), np.float32)
    right[..., 0] = 3.0
    got = luminance_check(kernel_backend, img, right, near, [0.3], occ, 0.1)
    assert not got[:, :, 3:6].any()                           # dark at x lands on light at x + 3
    np.testing.assert_array_equal(got[:, :, :3], occ[:, :, :3])
    np.testing.assert_array_equal(got[:, :, 6:], occ[:, :, 6:])   # light stays light (clamped border)
    far = near.copy()
    far[:, :, 3:5] = 0.0                                      # not near a flow jump: not tested
    got = luminance_check(kernel_backend, img, right, far, [0.3], occ, 0.1)
    np.testing.assert_array_equal(got[:, :, 3:5], occ[:, :, 3:5])
    assert not got[:, :, 5].any()
    half = np.zeros((t - 1, h, w, 2), np.float32)
    half[..., 0] = 0.25                                       # x = 5.25: a quarter of the way into light
    D, _ = ref.log_change(img, half)
    change = abs(D[0, 0, 5] - 0.3)
    assert 0.1 < change < 1.0
    assert luminance_check(kernel_backend, img, half, near, [0.3], occ, change * 1.01)[0, 0, 5] == 1.0
    assert luminance_check(kernel_backend, img, half, near, [0.3], occ, change * 0.99)[0, 0, 5] == 0.0


def test_luminance_consistency_bad_input(kernel_backend):
    be = kernel_backend
    img = be.asarray(np.zeros((2, 4, 4, 3), np.float32))
    flow = be.asarray(np.zeros((1, 4, 4, 2), np.float32))
    near = be.asarray(np.ones((1, 4, 4), np.float32))
    offsets = be.asarray(np.zeros(1, np.float32))
    occ = be.asarray(np.zeros((1, 4, 4), np.float32))
    with pytest.raises(ValueError, match="occ must have shape"):
        be.maps.luminance_consistency(img, flow, near, offsets, be.asarray(np.zeros((2, 4, 4), np.float32)), 0.1)
    with pytest.raises(ValueError, match="offsets"):
        be.maps.luminance_consistency(img, flow, near, be.asarray(np.zeros(2, np.float32)), occ, 0.1)
    with pytest.raises(ValueError, match="max_change"):
        be.maps.luminance_consistency(img, flow, near, offsets, occ, 0.0)


def test_motion_boundary_workspace_reused_across_shapes(kernel_backend, rng):
    mags = [rng.random(shape, dtype=np.float32) ** 8 for shape in ((T, H, W), (1, 9, 11))]
    ws = Workspace()
    for _ in range(2):          # the second round finds the buffers left by the first
        for mag in mags:
            np.testing.assert_array_equal(boundary(kernel_backend, mag, 0.8, 2, workspace=ws),
                                          ref.motion_boundary(mag, 0.8, 2))
    assert len(ws) == 2


# ------------------------------------------------ forward-backward check of the flow
def round_trip(be, flow, back_flow, occ, max_distance):
    out = be.asarray(occ.copy())
    be.maps.round_trip_consistency(be.asarray(flow), be.asarray(back_flow), out, max_distance)
    return be.numpy(out).copy()


def test_round_trip_consistency_hand_cases(kernel_backend):
    """A translation and its inverse keep w_occ; a block whose forward flow jumps one
    texture period is cleared; the backward flow is read where the forward flow lands,
    not at x; cleared pixels stay cleared; the distance is compared as >=."""
    p, h, w = 2, 11, 15
    occ = np.ones((p, h, w), np.float32)
    occ[1, 0, 0] = 0.0
    fwd = np.zeros((p, h, w, 2), np.float32)
    fwd[..., 0] = 2.0
    back = -fwd.copy()
    np.testing.assert_array_equal(round_trip(kernel_backend, fwd, back, occ, 0.5), occ)
    wrong = fwd.copy()
    wrong[0, 3:6, 4:8, 0] += 6.0                          # a match one period (6 px) to the right
    got = round_trip(kernel_backend, wrong, back, occ, 4.0)
    assert not got[0, 3:6, 4:8].any()
    got[0, 3:6, 4:8] = 1.0
    np.testing.assert_array_equal(got, occ)
    # The backward flow differs only at x + u = (6, 5): only the pixel landing there sees it.
    moved = back.copy()
    moved[0, 5, 6] = (3.0, 0.0)                         # round trip 2 + 3 = 5 px from (4, 5)
    got = round_trip(kernel_backend, fwd, moved, occ, 4.0)
    assert got[0, 5, 4] == 0.0 and got[0, 5, 6] == 1.0
    assert got.sum() == occ.sum() - 1
    half = fwd.copy()
    half[0, 2, 2, 1] = 1.5                              # lands between rows 3 and 4 of the backward flow
    d = ref.round_trip_distance(half, back)[0, 2, 2]
    assert d > 1.0
    assert round_trip(kernel_backend, half, back, occ, d * 1.01)[0, 2, 2] == 1.0
    assert round_trip(kernel_backend, half, back, occ, d * 0.99)[0, 2, 2] == 0.0


def test_round_trip_consistency_bad_input(kernel_backend):
    be = kernel_backend
    fwd = be.asarray(np.zeros((1, 4, 4, 2), np.float32))
    occ = be.asarray(np.zeros((1, 4, 4), np.float32))
    with pytest.raises(ValueError, match="back_flow"):
        be.maps.round_trip_consistency(fwd, be.asarray(np.zeros((2, 4, 4, 2), np.float32)), occ, 1.0)
    with pytest.raises(ValueError, match="occ must have shape"):
        be.maps.round_trip_consistency(fwd, fwd, be.asarray(np.zeros((1, 4, 5), np.float32)), 1.0)
    with pytest.raises(ValueError, match="max_distance"):
        be.maps.round_trip_consistency(fwd, fwd, occ, 0.0)


# ------------------------------------------------ still surfaces (Weiss's median of the gradients)
def still(be, log_image, tau, radius, share):
    out = be.asarray(np.full(log_image.shape[1:3], np.nan, np.float32))
    be.maps.still_surface(be.asarray(log_image), out, tau, radius, share)
    return be.numpy(out).copy()


def checkerboard(t, h, w, period=4):
    y, x = np.mgrid[:h, :w]
    board = np.where((y // period + x // period) % 2 == 0, -0.2, -1.6).astype(np.float32)
    return np.repeat(np.repeat(board[None, :, :, None], t, 0), 3, 3)


def test_still_surface_hand_cases(kernel_backend):
    """A still checkerboard under a moving hard shadow and a changing light is still; a
    print sliding three pixels a frame is not; a flat region
    is still whether it moves or not; the share counts frames; one frame is still."""
    t, h, w = 6, 16, 24
    board = checkerboard(t, h, w)
    lit = board + np.float32(0.2) * np.arange(t, dtype=np.float32)[:, None, None, None]
    shadowed = lit.copy()
    for k in range(t):
        shadowed[k, :, 4 * k: 4 * k + 6] -= 2.5                    # a shadow band 4 px further each frame
    got = still(kernel_backend, shadowed, 0.05, 1, 0.5)
    np.testing.assert_array_equal(got, 1.0)
    print_ = np.random.default_rng(3).normal(-1.0, 0.5, (h, w, 1)).astype(np.float32).repeat(3, 2)
    sliding = np.stack([np.roll(print_, (k, 3 * k), axis=(0, 1)) for k in range(t)])
    got = still(kernel_backend, sliding, 0.05, 1, 0.5)
    assert got.sum() == 0
    flat = np.full((t, h, w, 3), -0.7, np.float32)
    np.testing.assert_array_equal(still(kernel_backend, flat, 0.05, 1, 0.5), 1.0)
    np.testing.assert_array_equal(still(kernel_backend, sliding[:1], 0.05, 2, 1.0), 1.0)
    # four frames of six show the board, two the print: a share of 0.6 (3.6 frames) holds
    # everywhere, 0.7 (4.2) only where the print happens to agree
    four = np.concatenate([board[:4], sliding[4:]])
    np.testing.assert_array_equal(still(kernel_backend, four, 0.05, 1, 0.6), 1.0)
    got = still(kernel_backend, four, 0.05, 1, 0.7)
    assert got.mean() < 0.2
    np.testing.assert_array_equal(got, ref.still_surface(four, 0.05, 1, 0.7))


def test_still_surface_bad_input(kernel_backend):
    be = kernel_backend
    img = be.asarray(np.zeros((3, 4, 5, 3), np.float32))
    out = be.asarray(np.zeros((4, 5), np.float32))
    with pytest.raises(ValueError, match="out must have shape"):
        be.maps.still_surface(img, be.asarray(np.zeros((3, 4, 5), np.float32)), 0.1, 1, 0.5)
    with pytest.raises(ValueError, match="tau"):
        be.maps.still_surface(img, out, 0.0, 1, 0.5)
    with pytest.raises(ValueError, match="share"):
        be.maps.still_surface(img, out, 0.1, 1, -1.0)
    with pytest.raises(ValueError, match="radius"):
        be.maps.still_surface(img, out, 0.1, -1, 0.5)


# ------------------------------------------------ shading gate (Eq. 9's local term)
def gate(be, log_image, flow, tau):
    out = be.zeros(log_image.shape[:3])
    be.maps.shading_gate(be.asarray(log_image), be.asarray(flow), out, tau)
    return be.numpy(out).copy()


def test_shading_gate_hand_cases(kernel_backend):
    """A static edge under a global light change keeps the gate at 1; a moving shadow edge
    closes it on both of its sides, in every frame it crosses; one frame gives 1."""
    t, h, w = 3, 8, 12
    albedo_edge = np.zeros((t, h, w, 3), np.float32)
    albedo_edge[:, :, 6:] = (-1.0, -0.5, -2.0)
    albedo_edge += np.float32(0.3) * np.arange(t, dtype=np.float32)[:, None, None, None]   # brighter light
    still = np.zeros((t - 1, h, w, 2), np.float32)
    np.testing.assert_array_equal(gate(kernel_backend, albedo_edge, still, 0.1), 1.0)
    shadow = albedo_edge.copy()
    for k in range(t):
        shadow[k, : 2 + 2 * k] -= 0.4                                # a shadow edge 2 rows lower each frame
    got = gate(kernel_backend, shadow, still, 0.4)
    # frame 0: D = 0 on rows < 2 and rows >= 4, -0.4 on rows 2, 3; |D(x) - D(y)| = 0.4 across rows 1|2 and 3|4
    want = np.ones((h, w), np.float32)
    want[1:5] = np.exp(-1.0)
    np.testing.assert_allclose(got[0], want, rtol=1e-5)
    np.testing.assert_allclose(got[2], got[1], rtol=1e-6)               # the last frame uses the pair before it
    np.testing.assert_array_equal(gate(kernel_backend, shadow[:1], still[:0], 0.4), 1.0)


def test_shading_gate_follows_the_flow(kernel_backend):
    """A textured frame moved by a whole pixel: zero change along the true flow, a closed gate with zero flow."""
    rng = np.random.default_rng(5)
    frame = np.log(rng.uniform(0.1, 1.0, (1, 9, 14, 3))).astype(np.float32)
    moved = np.concatenate([frame, np.roll(frame, 1, axis=2)])          # content moves one pixel right
    flow = np.zeros((1, 9, 14, 2), np.float32)
    flow[..., 0] = 1.0
    got = gate(kernel_backend, moved, flow, 0.05)
    np.testing.assert_array_equal(got[:, :, :-1], 1.0)                  # the last column samples outside
    assert gate(kernel_backend, moved, np.zeros_like(flow), 0.05).mean() < 0.1


def test_shading_gate_bad_input(kernel_backend):
    m = kernel_backend.maps
    img = kernel_backend.zeros((2, 4, 5, 3))
    with pytest.raises(ValueError, match="tau"):
        m.shading_gate(img, kernel_backend.zeros((1, 4, 5, 2)), kernel_backend.zeros((2, 4, 5)), 0.0)
    with pytest.raises(ValueError, match="flow"):
        m.shading_gate(img, kernel_backend.zeros((2, 4, 5, 2)), kernel_backend.zeros((2, 4, 5)), 0.1)
    with pytest.raises(ValueError, match="gate"):
        m.shading_gate(img, kernel_backend.zeros((1, 4, 5, 2)), kernel_backend.zeros((1, 4, 5)), 0.1)
    with pytest.raises(ValueError, match="log_image"):
        m.shading_gate(kernel_backend.zeros((2, 4, 5, 1)), kernel_backend.zeros((1, 4, 5, 2)),
                       kernel_backend.zeros((2, 4, 5)), 0.1)


def test_shading_gate_chroma_keeps_a_colour_edge_open(kernel_backend):
    """A moving edge of one channel (a colour edge): without tau_chroma the gate closes across
    it like across a shadow; with it the rows where this frame's colour changes stay open."""
    t, h, w = 2, 8, 12
    img = np.zeros((t, h, w, 3), np.float32)
    for k in range(t):
        img[k, : 2 + 2 * k, :, 0] -= 0.6                           # red drops above the edge, 2 rows lower in frame 1
    still = np.zeros((t - 1, h, w, 2), np.float32)
    plain = gate(kernel_backend, img, still, 0.2)
    np.testing.assert_allclose(plain[0, 1:5], np.exp(-1.0), rtol=1e-5)   # |dD| = 0.6 / 3 across rows 1|2 and 3|4
    out = kernel_backend.zeros((t, h, w))
    kernel_backend.maps.shading_gate(kernel_backend.asarray(img), kernel_backend.asarray(still), out, 0.2,
                                     tau_chroma=0.1)
    chroma = kernel_backend.numpy(out)
    np.testing.assert_allclose(chroma[0, 1:3], 1.0, atol=1e-6)          # frame 0's colour edge: rows 1|2
    np.testing.assert_allclose(chroma[0, 3:5], np.exp(-1.0), rtol=1e-5)  # no colour change in frame 0 there
    with pytest.raises(ValueError, match="tau_chroma"):
        kernel_backend.maps.shading_gate(kernel_backend.asarray(img), kernel_backend.asarray(still), out, 0.2,
                                         tau_chroma=-1.0)
