"""Taichi mirror of :mod:`ivkernels.kernels.warp.maps`: occlusion maps (Eq. 6, 7)
the motion-boundary map (Sec. 3.3), the gate of the local shading
smoothness (Eq. 9) and the still-surface map, same host functions and signatures,
NumPy arrays passed as ``ti.types.ndarray()``.

The next frame's Lab colour at ``x + u`` is sampled with the bilinear helpers
of :mod:`ivkernels.kernels.taichi.sampling`.  Parallel over the ``T * H`` rows.
"""
import numpy as np
import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.maps import FAMILY
from ivkernels.kernels.taichi.sampling import bilinear_at, clamped_corners, inside_image
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd2 = ti.types.ndarray(dtype=ti.f32, ndim=2)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.func
def occlusion_likelihood(lab: ti.template(), flow: ti.template(), div_neg: ti.template(), t, y, x,
                         sigma_e, sigma_d):
    """Eq. 7 at pixel (t, y, x): returns ``(o, inside)`` (see the Warp module)."""
    height = flow.shape[1]
    width = flow.shape[2]
    px = ti.cast(x, ti.f32) + flow[t, y, x, 0]
    py = ti.cast(y, ti.f32) + flow[t, y, x, 1]
    x0, x1, fx = clamped_corners(px, width)
    y0, y1, fy = clamped_corners(py, height)
    dist2 = 0.0
    for c in ti.static(range(3)):
        diff = lab[t, y, x, c] - bilinear_at(lab, t + 1, c, x0, x1, fx, y0, y1, fy)
        dist2 += diff * diff
    d = div_neg[t, y, x]
    o = ti.exp(-dist2 / (2.0 * sigma_e * sigma_e) - d * d / (2.0 * sigma_d * sigma_d))
    return o, inside_image(px, py, height, width)


@ti.kernel
def occlusion_soft_rows(lab: nd4, flow: nd4, div_neg: nd3, out: nd3, sigma_e: ti.f32, sigma_d: ti.f32):
    height = flow.shape[1]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(flow.shape[2]):
            o, inside = occlusion_likelihood(lab, flow, div_neg, t, y, x, sigma_e, sigma_d)
            out[t, y, x] = o * inside


@ti.kernel
def occlusion_binary_rows(lab: nd4, flow: nd4, div_neg: nd3, out: nd3, sigma_e: ti.f32, sigma_d: ti.f32,
                          threshold: ti.f32):
    height = flow.shape[1]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(flow.shape[2]):
            o, inside = occlusion_likelihood(lab, flow, div_neg, t, y, x, sigma_e, sigma_d)
            w = 0.0
            if o >= threshold and inside > 0.0:
                w = 1.0
            out[t, y, x] = w


@ti.func
def corner_spread(img: ti.template(), t, x0, x1, fx, y0, y1, fy):
    """Mean over channels of ``sum_k w_k |img(corner_k) - img(sample)|`` (see the Warp module)."""
    spread = 0.0
    for c in ti.static(range(3)):
        v = bilinear_at(img, t, c, x0, x1, fx, y0, y1, fy)
        spread += ((1.0 - fx) * (1.0 - fy) * ti.abs(img[t, y0, x0, c] - v)
                   + fx * (1.0 - fy) * ti.abs(img[t, y0, x1, c] - v)
                   + (1.0 - fx) * fy * ti.abs(img[t, y1, x0, c] - v)
                   + fx * fy * ti.abs(img[t, y1, x1, c] - v))
    return spread / 3.0


@ti.kernel
def warp_reliability_rows(img: nd4, flow: nd4, occ: nd3, max_spread: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            x0, x1, fx = clamped_corners(ti.cast(x, ti.f32) + flow[t, y, x, 0], width)
            y0, y1, fy = clamped_corners(ti.cast(y, ti.f32) + flow[t, y, x, 1], height)
            if corner_spread(img, t + 1, x0, x1, fx, y0, y1, fy) >= max_spread:
                occ[t, y, x] = 0.0


@ti.func
def chroma_change_at(img: ti.template(), flow: ti.template(), t, y, x):
    """``max_c |C_{t+1}(x + u)_c - C_t(x)_c|``, ``C`` the log chromaticity (see the Warp module)."""
    x0, x1, fx = clamped_corners(ti.cast(x, ti.f32) + flow[t, y, x, 0], img.shape[2])
    y0, y1, fy = clamped_corners(ti.cast(y, ti.f32) + flow[t, y, x, 1], img.shape[1])
    d0 = bilinear_at(img, t + 1, 0, x0, x1, fx, y0, y1, fy) - img[t, y, x, 0]
    d1 = bilinear_at(img, t + 1, 1, x0, x1, fx, y0, y1, fy) - img[t, y, x, 1]
    d2 = bilinear_at(img, t + 1, 2, x0, x1, fx, y0, y1, fy) - img[t, y, x, 2]
    mean = (d0 + d1 + d2) / 3.0
    return ti.max(ti.abs(d0 - mean), ti.abs(d1 - mean), ti.abs(d2 - mean))


@ti.kernel
def chroma_consistency_rows(img: nd4, flow: nd4, occ: nd3, max_change: ti.f32):
    height = flow.shape[1]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(flow.shape[2]):
            if chroma_change_at(img, flow, t, y, x) >= max_change:
                occ[t, y, x] = 0.0


@ti.kernel
def round_trip_consistency_rows(flow: nd4, back_flow: nd4, occ: nd3, max_distance: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            u = flow[t, y, x, 0]
            v = flow[t, y, x, 1]
            x0, x1, fx = clamped_corners(ti.cast(x, ti.f32) + u, width)
            y0, y1, fy = clamped_corners(ti.cast(y, ti.f32) + v, height)
            du = u + bilinear_at(back_flow, t, 0, x0, x1, fx, y0, y1, fy)
            dv = v + bilinear_at(back_flow, t, 1, x0, x1, fx, y0, y1, fy)
            if ti.sqrt(du * du + dv * dv) >= max_distance:
                occ[t, y, x] = 0.0


@ti.func
def log_change_at(img: ti.template(), flow: ti.template(), p, y, x):
    """``(L_{p+1}(x + u) - L_p(x), inside)``, ``L`` the mean over channels of ``img``."""
    height = img.shape[1]
    width = img.shape[2]
    px = ti.cast(x, ti.f32) + flow[p, y, x, 0]
    py = ti.cast(y, ti.f32) + flow[p, y, x, 1]
    x0, x1, fx = clamped_corners(px, width)
    y0, y1, fy = clamped_corners(py, height)
    d = 0.0
    for c in ti.static(range(3)):
        d += bilinear_at(img, p + 1, c, x0, x1, fx, y0, y1, fy) - img[p, y, x, c]
    return d / 3.0, inside_image(px, py, height, width)


@ti.kernel
def luminance_consistency_rows(img: nd4, flow: nd4, near: nd3, offsets: nd1, occ: nd3, max_change: ti.f32):
    height = flow.shape[1]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(flow.shape[2]):
            if near[t, y, x] >= 0.5:
                d, inside = log_change_at(img, flow, t, y, x)
                if ti.abs(d - offsets[t]) >= max_change:
                    occ[t, y, x] = 0.0


@ti.func
def chroma_distance(img: ti.template(), t, y, x, yy, xx):
    """``|C(x) - C(y)|`` (Euclidean), ``C`` the log chromaticity (log image minus its channel mean)."""
    d0 = img[t, y, x, 0] - img[t, yy, xx, 0]
    d1 = img[t, y, x, 1] - img[t, yy, xx, 1]
    d2 = img[t, y, x, 2] - img[t, yy, xx, 2]
    m = (d0 + d1 + d2) / 3.0
    return ti.sqrt((d0 - m) * (d0 - m) + (d1 - m) * (d1 - m) + (d2 - m) * (d2 - m))


@ti.kernel
def shading_gate_rows(img: nd4, flow: nd4, gate: nd3, tau: ti.f32, tau_chroma: ti.f32):
    height = img.shape[1]
    width = img.shape[2]
    for r in range(img.shape[0] * height):
        t = r // height
        y = r - t * height
        p = ti.min(t, img.shape[0] - 2)      # the frame's pair with the next frame; the last uses the one before
        for x in range(width):
            d, valid = log_change_at(img, flow, p, y, x)
            e = 0.0
            if valid > 0.0:
                for j in ti.static(range(3)):
                    yy = y + j - 1
                    if 0 <= yy < height:
                        for i in ti.static(range(3)):
                            xx = x + i - 1
                            if ti.static(i != 1 or j != 1):
                                if 0 <= xx < width:
                                    dn, valid_n = log_change_at(img, flow, p, yy, xx)
                                    if valid_n > 0.0:
                                        e = ti.max(e, ti.abs(d - dn))
            if tau_chroma > 0.0:
                c = 0.0
                for j in ti.static(range(3)):
                    yy = y + j - 1
                    if 0 <= yy < height:
                        for i in ti.static(range(3)):
                            xx = x + i - 1
                            if ti.static(i != 1 or j != 1):
                                if 0 <= xx < width:
                                    c = ti.max(c, chroma_distance(img, t, y, x, yy, xx))
                qc = c / tau_chroma
                e = e * ti.exp(-qc * qc)
            q = e / tau
            gate[t, y, x] = ti.exp(-q * q)


@ti.func
def edge_hit(magnitude: ti.template(), t, y, x, threshold):
    hit = 0
    if magnitude[t, y, x] > threshold:
        hit = 1
    return hit


@ti.func
def luminance_gradient(img: ti.template(), t, y, x, axis):
    """``L(x + e) - L(x)`` along ``axis`` (0: x, 1: y), ``L`` the channel mean; 0 past the edge."""
    y1 = y
    x1 = x
    if axis == 0:
        x1 = x + 1
    else:
        y1 = y + 1
    g = 0.0
    if x1 < img.shape[2] and y1 < img.shape[1]:
        here = (img[t, y, x, 0] + img[t, y, x, 1] + img[t, y, x, 2]) / 3.0
        there = (img[t, y1, x1, 0] + img[t, y1, x1, 1] + img[t, y1, x1, 2]) / 3.0
        g = there - here
    return g


@ti.kernel
def luminance_gradients_rows(img: nd4, gradients: nd4):
    for r in range(img.shape[0] * img.shape[1]):
        t = r // img.shape[1]
        y = r - t * img.shape[1]
        for x in range(img.shape[2]):
            gradients[t, y, x, 0] = luminance_gradient(img, t, y, x, 0)
            gradients[t, y, x, 1] = luminance_gradient(img, t, y, x, 1)


@ti.func
def frame_median(gradients: ti.template(), y, x, axis):
    """The median over the frames of ``gradients[:, y, x, axis]`` (each value's rank counted)."""
    frames = gradients.shape[0]
    lower_at = (frames - 1) // 2
    upper_at = frames // 2
    lower = 0.0
    upper = 0.0
    for k in range(frames):
        v = gradients[k, y, x, axis]
        below = 0
        equal = 0
        for j in range(frames):
            o = gradients[j, y, x, axis]
            if o < v:
                below += 1
            elif o == v:
                equal += 1
        if below <= lower_at and lower_at < below + equal:
            lower = v
        if below <= upper_at and upper_at < below + equal:
            upper = v
    return 0.5 * (lower + upper)


@ti.kernel
def median_residual_rows(gradients: nd4, residual: nd3):
    for y in range(gradients.shape[1]):
        for x in range(gradients.shape[2]):
            mx = frame_median(gradients, y, x, 0)
            my = frame_median(gradients, y, x, 1)
            for t in range(gradients.shape[0]):
                residual[t, y, x] = (ti.abs(gradients[t, y, x, 0] - mx)
                                     + ti.abs(gradients[t, y, x, 1] - my))


@ti.kernel
def still_surface_rows(residual: nd3, out: nd2, tau: ti.f32, radius: ti.i32, share: ti.f32):
    frames = residual.shape[0]
    height = residual.shape[1]
    width = residual.shape[2]
    for y in range(height):
        y0 = ti.max(y - radius, 0)
        y1 = ti.min(y + radius, height - 1)
        for x in range(width):
            x0 = ti.max(x - radius, 0)
            x1 = ti.min(x + radius, width - 1)
            count = ti.cast((y1 - y0 + 1) * (x1 - x0 + 1), ti.f32)
            agree = 0.0
            for t in range(frames):
                total = 0.0
                for yy in range(y0, y1 + 1):
                    for xx in range(x0, x1 + 1):
                        total += residual[t, yy, xx]
                if total / count < tau:
                    agree += 1.0
            still = 0.0
            if agree >= share * ti.cast(frames, ti.f32):
                still = 1.0
            out[y, x] = still


@ti.kernel
def boundary_dilate_x_rows(magnitude: nd3, hits: nd3, threshold: ti.f32, radius: ti.i32):
    """Row pass: running count of edge pixels in the sliding x window."""
    height = magnitude.shape[1]
    width = magnitude.shape[2]
    for r in range(magnitude.shape[0] * height):
        t = r // height
        y = r - t * height
        count = 0
        for xx in range(ti.min(radius + 1, width)):
            count += edge_hit(magnitude, t, y, xx, threshold)
        for x in range(width):
            hit = 0.0
            if count > 0:
                hit = 1.0
            hits[t, y, x] = hit
            if x - radius >= 0:
                count -= edge_hit(magnitude, t, y, x - radius, threshold)
            if x + radius + 1 < width:
                count += edge_hit(magnitude, t, y, x + radius + 1, threshold)


@ti.kernel
def boundary_dilate_y_rows(hits: nd3, out: nd3, radius: ti.i32):
    """Column pass: max of ``hits`` over the rows within ``radius``."""
    height = hits.shape[1]
    width = hits.shape[2]
    for r in range(hits.shape[0] * height):
        t = r // height
        y = r - t * height
        y_lo = ti.max(y - radius, 0)
        y_hi = ti.min(y + radius, height - 1)
        for x in range(width):
            m = hits[t, y_lo, x]
            for yy in range(y_lo + 1, y_hi + 1):
                m = ti.max(m, hits[t, yy, x])
            out[t, y, x] = m


@host("occlusion_soft")
def occlusion_soft(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3) -> None:
    """Occlusion likelihood ``o(x)`` of Eq. 7 times the inside indicator; see
    :func:`ivkernels.kernels.warp.maps.occlusion_soft` (NumPy arrays here)."""
    if out.size:
        occlusion_soft_rows(lab, flow, div_neg, out, sigma_e, sigma_d)


@host("occlusion_binary")
def occlusion_binary(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3,
                     threshold: float = 0.5) -> None:
    """Occlusion map ``w_occ`` of Eq. 6 (1 = visible in t+1); see
    :func:`ivkernels.kernels.warp.maps.occlusion_binary`."""
    if out.size:
        occlusion_binary_rows(lab, flow, div_neg, out, sigma_e, sigma_d, float(threshold))


def _clear_occlusion_where(kernel, log_image, flow, occ, threshold: float, inputs=()) -> None:
    """Run ``kernel``, a test that clears ``occ`` from ``log_image`` sampled along ``flow``,
    with the positive ``threshold``; further ``inputs`` come between ``flow`` and ``occ``
    (see the Warp module)."""
    if occ.size:
        kernel(log_image, flow, *inputs, occ, threshold)


@host("warp_reliability")
def warp_reliability(log_image, flow, occ, max_spread: float) -> None:
    """Clear ``occ`` where the bilinear sample at ``x + u`` straddles an edge; see
    :func:`ivkernels.kernels.warp.maps.warp_reliability`."""
    _clear_occlusion_where(warp_reliability_rows, log_image, flow, occ, max_spread)


@host("chroma_consistency")
def chroma_consistency(log_image, flow, occ, max_change: float) -> None:
    """Clear ``occ`` where the log chromaticity changes along the flow; see
    :func:`ivkernels.kernels.warp.maps.chroma_consistency`."""
    _clear_occlusion_where(chroma_consistency_rows, log_image, flow, occ, max_change)


@host("luminance_consistency")
def luminance_consistency(log_image, flow, near, offsets, occ, max_change: float) -> None:
    """Clear ``occ`` where the brightness changes along the flow near a flow jump; see
    :func:`ivkernels.kernels.warp.maps.luminance_consistency`."""
    _clear_occlusion_where(luminance_consistency_rows, log_image, flow, occ, max_change, (near, offsets))


@host("round_trip_consistency")
def round_trip_consistency(flow, back_flow, occ, max_distance: float) -> None:
    """Clear ``occ`` where the forward and the backward flow disagree; see
    :func:`ivkernels.kernels.warp.maps.round_trip_consistency`."""
    if occ.size:
        round_trip_consistency_rows(flow, back_flow, occ, float(max_distance))


@host("shading_gate")
def shading_gate(log_image, flow, gate, tau: float, tau_chroma: float = 0.0) -> None:
    """The per-pixel gate of the local shading smoothness (Eq. 9) from the input's log
    change along the flow; see :func:`ivkernels.kernels.warp.maps.shading_gate`."""
    t, h, w, _ = log_image.shape
    if t == 1:
        gate[...] = 1.0
    elif gate.size:
        shading_gate_rows(log_image, flow, gate, tau, tau_chroma)


@host("motion_boundary")
def motion_boundary(sobel_mag, out, threshold: float, radius: int, *, workspace=None) -> None:
    """``w_bnd``: 1 where the (2r+1)^2 window holds ``sobel_mag > threshold``; see
    :func:`ivkernels.kernels.warp.maps.motion_boundary` (the (T, H, W) float32
    scratch comes from ``workspace``, or is allocated for this call)."""
    if out.size:
        shape = tuple(sobel_mag.shape)
        hits = scratch_buffer(workspace, f"{__name__}.boundary_hits", shape, np.float32,
                              lambda: np.empty(shape, np.float32))
        boundary_dilate_x_rows(sobel_mag, hits, float(threshold), int(radius))
        boundary_dilate_y_rows(hits, out, int(radius))


@host("still_surface")
def still_surface(log_image, out, tau: float, radius: int, share: float, *, workspace=None) -> None:
    """1 where the frames' log-luminance gradients agree with their median over the frames;
    see :func:`ivkernels.kernels.warp.maps.still_surface` (the float32 gradients and
    residual come from ``workspace``, or are allocated for this call)."""
    if out.size:
        shape = tuple(log_image.shape[:3])
        gradients = scratch_buffer(workspace, f"{__name__}.still_gradients", (*shape, 2), np.float32,
                                   lambda: np.empty((*shape, 2), np.float32))
        residual = scratch_buffer(workspace, f"{__name__}.still_residual", shape, np.float32,
                                  lambda: np.empty(shape, np.float32))
        luminance_gradients_rows(log_image, gradients)
        median_residual_rows(gradients, residual)
        still_surface_rows(residual, out, float(tau), int(radius), float(share))
