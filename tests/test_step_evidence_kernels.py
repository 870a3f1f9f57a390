"""The step evidence of Eq. 9's local term as the energy computes it, on every backend
(solver.step_evidence.multiply_step_gate and WindowEnergy's gate, through the kernels of the
``step_evidence`` family), against the host NumPy computation written out pixel by pixel:
odd sizes, one-pixel-wide images, one and two frames, dark pixels, still and moving pixels."""
import numpy as np
import pytest

from ivkernels import Params
from ivkernels.evaluation import synthetic
from ivkernels.kernels.reference import maps as ref_maps
from ivkernels.kernels.reference import step_evidence as ref
from ivkernels.priors import load_albedo_prior
from ivkernels.solver.energy import WindowEnergy
from ivkernels.solver.motion_maps import shading_cut_gate
from ivkernels.solver.step_evidence import (DARK_OFFSET, SHARE_PRIOR_STEPS, STATIC_FLOW, chromatic_share,
                                            local_chromatic_share, multiply_step_gate, share_radius_pixels)
from test_step_evidence import reference_floor

SIZES = {"odd": (3, 9, 13), "two-frames": (2, 7, 11), "one-frame": (1, 5, 7), "one-column": (2, 6, 1),
         "one-row": (2, 1, 9)}


def _pairs_of(I, t, y, x, axes_only=False, floor=None, k=0.0):
    """``(d L, d C)`` of pixel ``(t, y, x)`` of ``I`` (T, h, w, 3) with each neighbour inside the image
    (the 8 neighbours, or only the right and lower ones); with a noise ``floor`` (T, h, w, 2) and
    ``k > 0``, each net of it: ``sqrt(max(d^2 - k^2 (f(x)^2 + f(y)^2) / 2, 0))``."""
    T, h, w, _ = I.shape
    offsets = ((0, 1), (1, 0)) if axes_only else \
        [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
    for dy, dx in offsets:
        yy, xx = y + dy, x + dx
        if 0 <= yy < h and 0 <= xx < w:
            a, b = I[t, y, x], I[t, yy, xx]
            steps = [abs(a.mean() - b.mean()), np.abs((a - a.mean()) - (b - b.mean())).max()]
            if floor is not None and k > 0:
                steps = [np.sqrt(max(d * d - k * k * (floor[t, y, x, c] ** 2 + floor[t, yy, xx, c] ** 2) / 2, 0.0))
                         for c, d in enumerate(steps)]
            yield steps[0], steps[1]


def host_step_weight(log_image, flow, gain, tau, tau_chroma, stability):
    """``1 + gain (1 - s)^2 w evidence`` (T, h, w), float64, pixel by pixel: the docstring's formula."""
    s, weight, ev = host_parts(log_image, flow, tau, tau_chroma, stability)
    return 1.0 + gain * (1.0 - s) ** 2 * weight * ev


def host_floor(log_image, flow, cap=Params().shading_step_noise_cap):
    """The noise floor (T, h, w, 2) by the references (:func:`test_step_evidence.reference_floor`)
    of the offset log image ``log(i + DARK_OFFSET)``."""
    I = np.log(np.exp(np.asarray(log_image, np.float64)) + DARK_OFFSET).astype(np.float32)
    return reference_floor(I, flow, cap)


def host_parts(log_image, flow, tau, tau_chroma, stability, floor=None, k=0.0):
    """``(s, w, evidence)``: the chromatic share, Weiss's cue where still (1 elsewhere) and the
    evidence (T, h, w), float64, pixel by pixel; the steps net of the noise ``floor`` at ``k``."""
    I = np.log(np.exp(np.asarray(log_image, np.float64)) + DARK_OFFSET)
    T, h, w, _ = I.shape
    sharp = chromatic = 0
    ev = np.zeros((T, h, w))
    for t, y, x in np.ndindex(T, h, w):
        for dl, dc in _pairs_of(I, t, y, x, axes_only=True, floor=floor, k=k):
            chromatic += bool(dc > tau_chroma)
            sharp += bool(dc > tau_chroma or dl > tau)
        ev[t, y, x] = max([(1 - np.exp(-(dl / tau) ** 2)) * np.exp(-(dc / tau_chroma) ** 2)
                           for dl, dc in _pairs_of(I, t, y, x, floor=floor, k=k)], default=0.0)
    s = chromatic / sharp if sharp else 0.0
    weight = np.ones((T, h, w))
    if flow is not None and T > 1 and stability > 0:
        speed = np.sqrt((np.asarray(flow, np.float64) ** 2).sum(-1))
        moving = np.zeros((T, h, w), bool)
        moving[:-1] |= speed >= STATIC_FLOW
        moving[1:] |= speed >= STATIC_FLOW
        weight = np.where(moving, 1.0, ref_maps.shading_gate(log_image, flow, stability))
    return s, weight, ev


def scene(T, h, w, seed=0):
    """Log input with grey and coloured blocks, noise and dark pixels, and a flow that is 0 on the
    left half, 1 pixel on the right (and 0.1 px, still, in a column of the right half)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    grey = np.where(((yy // 2) + (xx // 3)) % 2 == 0, 0.6, 0.15)
    colour = np.where(yy >= h // 2, 1.0, 0.0)[..., None] * np.array([0.0, -0.5, -0.2])
    i = grey[None, ..., None] * np.exp(colour)[None] * rng.uniform(0.9, 1.1, (T, h, w, 3))
    i[:, ::3, ::4] = 1e-4                                                   # dark pixels
    flow = np.zeros((max(T - 1, 0), h, w, 2))
    flow[:, :, w // 2:, 0] = 1.0
    flow[:, :, w - 1, 0] = 0.1
    return np.log(i).astype(np.float32), flow.astype(np.float32)


@pytest.mark.parametrize("size", SIZES.values(), ids=SIZES.keys())
@pytest.mark.parametrize("stability", [0.3, 0.0])
def test_the_backend_gate_is_the_host_formula(any_backend, size, stability):
    be = any_backend
    log_image, flow = scene(*size)
    gain, tau, tau_chroma = 8.0, 0.1, 0.05
    want = host_step_weight(log_image, flow, gain, tau, tau_chroma, stability)
    start = np.random.default_rng(1).uniform(0.5, 1.0, size).astype(np.float32)
    gate = be.asarray(start.copy())
    multiply_step_gate(be, be.asarray(log_image), gate, gain, tau, tau_chroma, flow=be.asarray(flow),
                       stability=stability)
    # float32 log steps of inputs down to log(1e-4): the evidence to ~5e-6, times a gain of 8
    np.testing.assert_allclose(be.numpy(gate), start * want, rtol=1e-5, atol=5e-5)


def test_without_colour_or_flow_the_gain_is_not_scaled(any_backend):
    be = any_backend
    log_image, _ = scene(2, 7, 11)
    want = host_step_weight(log_image, None, 4.0, 0.1, np.inf, 0.0)
    gate = be.asarray(np.ones((2, 7, 11), np.float32))
    multiply_step_gate(be, be.asarray(log_image), gate, 4.0, 0.1, 0.0)
    np.testing.assert_allclose(be.numpy(gate), want, rtol=1e-5, atol=3e-5)


@pytest.mark.parametrize("size", [(2, 7, 11), (1, 5, 7)], ids=["two-frames", "one-frame"])
@pytest.mark.parametrize("share_radius", [None, 0.0], ids=["default", "whole-video-share"])
def test_window_energy_gate_is_the_cut_times_the_host_step_weight(any_backend, size, share_radius):
    """The energy's gate with the default Params (and with the whole video's share): the cut at
    flow jumps (where there is a flow) times the step weight, computed on the host, its steps
    net of the noise floor."""
    be = any_backend
    T, h, w = size
    log_image, flow = scene(T, h, w, seed=2)
    params = Params() if share_radius is None else Params(shading_step_share_radius=share_radius)
    temporal = T > 1
    energy = WindowEnergy(be, be.asarray(log_image), be.asarray(np.exp(log_image).mean(-1) + 1e-3),
                          be.asarray(flow) if temporal else None,
                          be.asarray(np.ones((T - 1, h, w), np.float32)) if temporal else None,
                          be.asarray(np.zeros((T - 1, h, w), np.float32)) if temporal else None,
                          params, load_albedo_prior())
    floor = host_floor(log_image, flow if temporal else None)
    k = params.shading_step_noise
    s_whole, weight, evidence = host_parts(log_image, flow if temporal else None, params.shading_step_tau,
                                           params.shading_step_chroma, params.shading_step_stability, floor, k)
    share = s_whole
    if params.shading_step_share_radius > 0:
        counts = ref.pixel_counts(log_image, DARK_OFFSET, params.shading_step_tau, params.shading_step_chroma,
                                  floor, k)
        share = ref.local_share(counts, share_radius_pixels(params.shading_step_share_radius, h, w), SHARE_PRIOR_STEPS)
    want = 1.0 + params.shading_step_gain * (1.0 - share) ** 2 * weight * evidence
    if temporal:
        want = want * be.numpy(shading_cut_gate(be, be.asarray(flow), params.shading_cut_threshold, T))
    np.testing.assert_allclose(be.numpy(energy.gate), want, rtol=1e-5, atol=5e-5)


@pytest.mark.parametrize("share_radius", [0.0, Params().shading_step_share_radius], ids=["whole", "local"])
def test_the_step_gate_reads_nothing_back_to_the_host(backend, monkeypatch, share_radius):
    """Every step runs on the backend's arrays: no ``be.numpy`` between the launches (with the
    whole video's share and with the share read around each pixel, the default)."""
    log_image, flow = scene(3, 9, 13)
    I, F, gate = backend.asarray(log_image), backend.asarray(flow), backend.asarray(np.ones((3, 9, 13), np.float32))

    def refuse(a):
        raise AssertionError("the step gate read an array back to the host")

    monkeypatch.setattr(backend, "numpy", refuse)
    multiply_step_gate(backend, I, gate, 8.0, 0.1, 0.05, flow=F, stability=0.3, share_radius=share_radius)
    monkeypatch.undo()
    assert np.isfinite(backend.numpy(gate)).all() and (backend.numpy(gate) > 1).any()


def test_the_chromatic_share_of_the_kernels_counts_is_the_references(any_backend):
    """The share is a ratio of integer counts of pairs; the kernels decide each pair in float32,
    so a pair within float32 rounding (1e-5 log units) of ``tau`` or ``tau_chroma`` may be counted
    either way.  Off those ties the counts are equal and the share is equal to float64 rounding;
    with them it may move by (tied pairs) / (sharp pairs).  It enters the gain squared."""
    be = any_backend
    frames = synthetic.render_sequence("objects_camera", n_frames=2, size=(60, 80), seed=1).frames
    log_image = np.log(np.maximum(frames, 1e-4)).astype(np.float32)
    tau, tau_chroma = 0.1, 0.05
    offset = be.empty((2, 60, 80, 3))
    be.step_evidence.offset_log(be.asarray(log_image), offset, DARK_OFFSET)
    counts = be.empty((2 * 60, 2), np.int32)
    be.step_evidence.step_counts(offset, counts, tau, tau_chroma)
    c = be.numpy(counts).astype(np.int64).sum(axis=0)
    I = np.log(np.exp(log_image.astype(np.float64)) + DARK_OFFSET)
    steps = [p for t, y, x in np.ndindex(2, 60, 80) for p in _pairs_of(I, t, y, x, axes_only=True)]
    tied = sum(abs(dl - tau) < 1e-5 or abs(dc - tau_chroma) < 1e-5 for dl, dc in steps)
    sharp = sum(dc > tau_chroma or dl > tau for dl, dc in steps)
    chromatic = sum(dc > tau_chroma for dl, dc in steps)
    assert sharp > 100 and 0 < chromatic < sharp
    assert abs(c[0] - sharp) <= tied and abs(c[1] - chromatic) <= tied
    assert abs(c[1] / c[0] - chromatic_share(log_image, tau, tau_chroma)) <= 2 * tied / sharp + 1e-12


def test_still_stability_is_the_maps_shading_gate_bit_for_bit_where_still(backend):
    """Where nothing moves, Weiss's cue of the step family is ``maps.shading_gate`` (no colour
    test) to the bit: the same changes along the flow, computed once per pixel instead of once
    per neighbour, then the same operations."""
    rng = np.random.default_rng(4)
    T, h, w = 3, 11, 14
    log_image = rng.normal(-1.0, 0.5, (T, h, w, 3)).astype(np.float32)
    flow = rng.uniform(-0.17, 0.17, (T - 1, h, w, 2)).astype(np.float32)     # still: under STATIC_FLOW
    flow[:, :, :2] = (-0.2, 0.0)                                              # samples leaving the image
    I, F = backend.asarray(log_image), backend.asarray(flow)
    weight, gate = backend.empty((T, h, w)), backend.empty((T, h, w))
    backend.step_evidence.still_stability(I, F, weight, 0.3, STATIC_FLOW)
    backend.maps.shading_gate(I, F, gate, 0.3)
    np.testing.assert_array_equal(backend.numpy(weight), backend.numpy(gate))
    assert (backend.numpy(weight) < 1).mean() > 0.5


@pytest.mark.parametrize("size", [(2, 9, 13), (1, 6, 1)], ids=["two-frames", "one-column"])
def test_the_share_read_around_each_pixel_enters_the_backend_gate(any_backend, size):
    """``share_radius`` > 0: ``gate *= 1 + gain (1 - s(x))^2 w evidence`` with ``s(x)`` the
    local share (tested pixel by pixel in tests/test_step_share.py)."""
    be = any_backend
    log_image, flow = scene(*size, seed=3)
    gain, tau, tau_chroma, radius = 8.0, 0.1, 0.05, 0.3
    _, weight, evidence = host_parts(log_image, flow, tau, tau_chroma, 0.3)
    local = local_chromatic_share(log_image, tau, tau_chroma, radius)
    assert local.min() < local.max()
    want = 1.0 + gain * (1.0 - local) ** 2 * weight * evidence
    gate = be.asarray(np.ones(size, np.float32))
    multiply_step_gate(be, be.asarray(log_image), gate, gain, tau, tau_chroma, flow=be.asarray(flow),
                       stability=0.3, share_radius=radius)
    np.testing.assert_allclose(be.numpy(gate), want, rtol=1e-5, atol=5e-5)


def host_share_step_gate(be, log_image, gate, gain, tau, tau_chroma, flow, stability, share_radius):
    """``multiply_step_gate`` with the share read around each pixel on the host, as it was built before
    the kernels ``pixel_counts`` and ``share_weight``: Weiss's cue (or 1) from the kernels, times
    ``(1 - local_chromatic_share)^2`` on host NumPy, into ``step_gate`` with the gain unscaled."""
    T, h, w, _ = log_image.shape
    k = be.step_evidence
    offset = be.empty((T, h, w, 3))
    k.offset_log(log_image, offset, DARK_OFFSET)
    weight = be.empty((T, h, w))
    if flow is not None and T > 1 and stability > 0:
        k.still_stability(log_image, flow, weight, stability, STATIC_FLOW)
    else:
        weight = be.asarray(np.ones((T, h, w), np.float32))
    keep = (1.0 - local_chromatic_share(be.numpy(log_image), tau, tau_chroma, share_radius)) ** 2
    weight = be.asarray(be.numpy(weight) * keep)
    k.step_gate(offset, be.zeros((T * h, 2), np.int32), weight, gate, gain, tau, tau_chroma)


def rendered(T, h, w):
    """A rendered video's log input and flow: coloured objects, grey and dark parts, many pairs near the thresholds."""
    seq = synthetic.render_sequence("objects_camera", n_frames=T, size=(h, w), seed=1)
    return np.log(np.maximum(seq.frames, 1e-4)).astype(np.float32), seq.flow.astype(np.float32)


#: (size, share_radius, what): windows inside the frame, a window that covers the frame, frames
#: smaller than the smallest window (3 x 3), a flat frame in a coloured video (no sharp step of its
#: own: its share is the video's) and a flat video (no sharp step at all: s = 0).
SHARE_SCENES = {
    "rendered": ((3, 30, 40), 0.3, "rendered"),
    "window-covers-the-frame": ((2, 9, 13), 5.0, "scene"),
    "frames-smaller-than-the-window": ((3, 2, 2), 0.3, "scene"),
    "one-column": ((2, 7, 1), 0.3, "scene"),
    "flat-frame": ((3, 9, 13), 0.2, "flat-frame"),
    "flat-video": ((2, 6, 5), 0.3, "flat-video"),
}


def share_scene(size, what):
    if what == "rendered":
        return rendered(*size)
    log_image, flow = scene(*size, seed=5)
    if what == "flat-frame":
        log_image[1] = -0.7
    elif what == "flat-video":
        log_image[:] = -0.7
    return log_image, flow


@pytest.mark.parametrize("stability", [0.3, 0.0])
@pytest.mark.parametrize("key", SHARE_SCENES)
def test_the_local_share_on_the_backend_is_the_host_computation_bit_for_bit(any_backend, key, stability):
    """The share read around each pixel by the kernels (per-pixel counts in float64, integer window
    sums, the float64 division rounded to float32, then float32) equals the host NumPy computation
    from ``local_chromatic_share``, in the weight and in the whole gate, to the bit."""
    be = any_backend
    size, radius, what = SHARE_SCENES[key]
    log_image, flow = share_scene(size, what)
    T, h, w = size
    gain, tau, tau_chroma = 8.0, 0.1, 0.05
    local = local_chromatic_share(log_image, tau, tau_chroma, radius)
    if what == "flat-video":
        assert (local == 0).all()
    elif what == "flat-frame":
        assert np.ptp(local[1]) == 0 and 0 < local[1, 0, 0] < 1
    weight = be.asarray(np.ones(size, np.float32))
    counts = be.empty((T, h, w, 2), np.int32)
    be.step_evidence.pixel_counts(be.asarray(log_image), counts, DARK_OFFSET, tau, tau_chroma)
    be.step_evidence.share_weight(counts, weight, share_radius_pixels(radius, h, w), SHARE_PRIOR_STEPS)
    np.testing.assert_array_equal(be.numpy(weight), np.ones(size, np.float32) * (1.0 - local) ** 2)

    start = np.random.default_rng(2).uniform(0.5, 1.0, size).astype(np.float32)
    gates = []
    for multiply in (multiply_step_gate, host_share_step_gate):
        gate = be.asarray(start.copy())
        multiply(be, be.asarray(log_image), gate, gain, tau, tau_chroma, flow=be.asarray(flow), stability=stability,
                 share_radius=radius)
        gates.append(be.numpy(gate))
    np.testing.assert_array_equal(gates[0], gates[1])
