"""Occlusion and motion-boundary maps computed from the flow (Sections 3.2, 3.3).

* :func:`occlusion_soft`: the occlusion likelihood ``o(x)`` of Eq. 7 (times
  the inside-the-image indicator),
* :func:`occlusion_binary`: ``w_occ`` of Eq. 6, 1 = visible in frame t+1,
* :func:`motion_boundary`: ``w_bnd`` of Eq. 9, 1 = near a motion boundary
  (thresholded Sobel magnitude of the flow, dilated),
* :func:`warp_reliability`: clears ``w_occ`` where the bilinear warp of the
  next frame is not trustworthy (a sub-pixel sample across an edge),
* :func:`chroma_consistency`: clears ``w_occ`` where the input's chromaticity
  changes along the flow (a flow that joins two different surfaces),
* :func:`round_trip_consistency`: clears ``w_occ`` where the forward flow and
  the backward flow disagree (the forward-backward check),
* :func:`shading_gate`: the per-pixel weight of the local shading smoothness
  (Eq. 9), low where the input's log gradient changes along the flow,
* :func:`still_surface`: 1 where a window's frames show the same surface at
  the same pixel (Weiss's median of the log gradients), whatever the light does.

The next frame's Lab colour at ``x + u`` is sampled inside the kernels with the
bilinear helpers of :mod:`ivkernels.kernels.warp.sampling` (clamped corners).
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows, row_tiles
from ivkernels.kernels.reference.maps import FAMILY
from ivkernels.kernels.warp._checks import FRONT
from ivkernels.kernels.warp.row_tiles import row_span
from ivkernels.kernels.warp.sampling import bilinear_at, clamped_corners, inside_image
from ivkernels.kernels.workspace import scratch_buffer

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def occlusion_likelihood(lab: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                         div_neg: wp.array3d(dtype=float), t: int, y: int, x: int,
                         sigma_e: float, sigma_d: float):
    """Eq. 7 at pixel (t, y, x): returns ``(o, inside)``.

    ``o = exp(-|lab_t(x) - lab_{t+1}(x + u)|^2 / (2 sigma_e^2) - d^2 / (2 sigma_d^2))``
    with the squared Euclidean Lab distance and ``lab_{t+1}`` sampled
    bilinearly; ``inside`` is 1.0 if ``x + u`` lies in the image, else 0.0.
    """
    height = flow.shape[1]
    width = flow.shape[2]
    px = float(x) + flow[t, y, x, 0]
    py = float(y) + flow[t, y, x, 1]
    x0, x1, fx = clamped_corners(px, width)
    y0, y1, fy = clamped_corners(py, height)
    dist2 = float(0.0)
    for c in range(3):
        diff = lab[t, y, x, c] - bilinear_at(lab, t + 1, c, x0, x1, fx, y0, y1, fy)
        dist2 += diff * diff
    d = div_neg[t, y, x]
    o = wp.exp(-dist2 / (2.0 * sigma_e * sigma_e) - d * d / (2.0 * sigma_d * sigma_d))
    return o, inside_image(px, py, height, width)


# ----------------------------------------------------------------------------
# Kernels (one thread per tile of a row = t * H + y: one tile per row on the
# CPU, one pixel per tile on a GPU)
# ----------------------------------------------------------------------------

@wp.kernel
def occlusion_soft_rows(row_begin: int, tiles: int, lab: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                        div_neg: wp.array3d(dtype=float), out: wp.array3d(dtype=float),
                        sigma_e: float, sigma_d: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        o, inside = occlusion_likelihood(lab, flow, div_neg, t, y, x, sigma_e, sigma_d)
        out[t, y, x] = o * inside


@wp.kernel
def occlusion_binary_rows(row_begin: int, tiles: int, lab: wp.array4d(dtype=float),
                          flow: wp.array4d(dtype=float), div_neg: wp.array3d(dtype=float),
                          out: wp.array3d(dtype=float), sigma_e: float, sigma_d: float, threshold: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        o, inside = occlusion_likelihood(lab, flow, div_neg, t, y, x, sigma_e, sigma_d)
        w = 0.0
        if o >= threshold and inside > 0.0:
            w = 1.0
        out[t, y, x] = w


@wp.func
def corner_spread(img: wp.array4d(dtype=float), t: int, x0: int, x1: int, fx: float,
                  y0: int, y1: int, fy: float):
    """Mean over channels of ``sum_k w_k |img(corner_k) - img(sample)|``: how far the
    four bilinear corners of a sample lie from the value interpolated between them."""
    spread = float(0.0)
    for c in range(3):
        v = bilinear_at(img, t, c, x0, x1, fx, y0, y1, fy)
        spread += ((1.0 - fx) * (1.0 - fy) * wp.abs(img[t, y0, x0, c] - v)
                   + fx * (1.0 - fy) * wp.abs(img[t, y0, x1, c] - v)
                   + (1.0 - fx) * fy * wp.abs(img[t, y1, x0, c] - v)
                   + fx * fy * wp.abs(img[t, y1, x1, c] - v))
    return spread / 3.0


@wp.kernel
def warp_reliability_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float),
                          flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float), max_spread: float):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], width)
        y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], height)
        if corner_spread(img, t + 1, x0, x1, fx, y0, y1, fy) >= max_spread:
            occ[t, y, x] = 0.0


@wp.func
def chroma_change_at(img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float), t: int, y: int, x: int):
    """``max_c |C_{t+1}(x + u)_c - C_t(x)_c|`` with ``C = img - mean over channels`` (the log
    chromaticity of a log image), ``C_{t+1}`` sampled bilinearly (clamped corners)."""
    x0, x1, fx = clamped_corners(float(x) + flow[t, y, x, 0], img.shape[2])
    y0, y1, fy = clamped_corners(float(y) + flow[t, y, x, 1], img.shape[1])
    d0 = bilinear_at(img, t + 1, 0, x0, x1, fx, y0, y1, fy) - img[t, y, x, 0]
    d1 = bilinear_at(img, t + 1, 1, x0, x1, fx, y0, y1, fy) - img[t, y, x, 1]
    d2 = bilinear_at(img, t + 1, 2, x0, x1, fx, y0, y1, fy) - img[t, y, x, 2]
    mean = (d0 + d1 + d2) / 3.0
    return wp.max(wp.abs(d0 - mean), wp.max(wp.abs(d1 - mean), wp.abs(d2 - mean)))


@wp.kernel
def chroma_consistency_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float),
                            flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float), max_change: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if chroma_change_at(img, flow, t, y, x) >= max_change:
            occ[t, y, x] = 0.0


@wp.func
def log_change_at(img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float), p: int, y: int, x: int):
    """``(L_{p+1}(x + u) - L_p(x), inside)``, ``L`` the mean over channels of ``img``."""
    height = img.shape[1]
    width = img.shape[2]
    px = float(x) + flow[p, y, x, 0]
    py = float(y) + flow[p, y, x, 1]
    x0, x1, fx = clamped_corners(px, width)
    y0, y1, fy = clamped_corners(py, height)
    d = float(0.0)
    for c in range(3):
        d += bilinear_at(img, p + 1, c, x0, x1, fx, y0, y1, fy) - img[p, y, x, c]
    return d / 3.0, inside_image(px, py, height, width)


@wp.kernel
def luminance_consistency_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float),
                               flow: wp.array4d(dtype=float), near: wp.array3d(dtype=float),
                               offsets: wp.array1d(dtype=float), occ: wp.array3d(dtype=float), max_change: float):
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, flow.shape[2])
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        if near[t, y, x] >= 0.5:
            d, inside = log_change_at(img, flow, t, y, x)
            if wp.abs(d - offsets[t]) >= max_change:
                occ[t, y, x] = 0.0


@wp.kernel
def round_trip_consistency_rows(row_begin: int, tiles: int, flow: wp.array4d(dtype=float),
                                back_flow: wp.array4d(dtype=float), occ: wp.array3d(dtype=float),
                                max_distance: float):
    height = flow.shape[1]
    width = flow.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        u = flow[t, y, x, 0]
        v = flow[t, y, x, 1]
        x0, x1, fx = clamped_corners(float(x) + u, width)
        y0, y1, fy = clamped_corners(float(y) + v, height)
        du = u + bilinear_at(back_flow, t, 0, x0, x1, fx, y0, y1, fy)
        dv = v + bilinear_at(back_flow, t, 1, x0, x1, fx, y0, y1, fy)
        if wp.sqrt(du * du + dv * dv) >= max_distance:
            occ[t, y, x] = 0.0


@wp.func
def chroma_distance(img: wp.array4d(dtype=float), t: int, y: int, x: int, yy: int, xx: int):
    """``|C(x) - C(y)|`` (Euclidean), ``C`` the log chromaticity (log image minus its channel mean)."""
    d0 = img[t, y, x, 0] - img[t, yy, xx, 0]
    d1 = img[t, y, x, 1] - img[t, yy, xx, 1]
    d2 = img[t, y, x, 2] - img[t, yy, xx, 2]
    m = (d0 + d1 + d2) / 3.0
    return wp.sqrt((d0 - m) * (d0 - m) + (d1 - m) * (d1 - m) + (d2 - m) * (d2 - m))


@wp.kernel
def shading_gate_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float), flow: wp.array4d(dtype=float),
                      gate: wp.array3d(dtype=float), tau: float, tau_chroma: float):
    height = img.shape[1]
    width = img.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    p = wp.min(t, img.shape[0] - 2)          # the frame's pair with the next frame; the last uses the one before
    for x in range(x_begin, x_end):
        d, valid = log_change_at(img, flow, p, y, x)
        e = float(0.0)
        if valid > 0.0:
            for j in range(3):
                yy = y + j - 1
                if yy >= 0 and yy < height:
                    for i in range(3):
                        xx = x + i - 1
                        if xx >= 0 and xx < width and (i != 1 or j != 1):
                            dn, valid_n = log_change_at(img, flow, p, yy, xx)
                            if valid_n > 0.0:
                                e = wp.max(e, wp.abs(d - dn))
        if tau_chroma > 0.0:
            c = float(0.0)
            for j in range(3):
                yy = y + j - 1
                if yy >= 0 and yy < height:
                    for i in range(3):
                        xx = x + i - 1
                        if xx >= 0 and xx < width and (i != 1 or j != 1):
                            c = wp.max(c, chroma_distance(img, t, y, x, yy, xx))
            qc = c / tau_chroma
            e = e * wp.exp(-qc * qc)
        q = e / tau
        gate[t, y, x] = wp.exp(-q * q)


@wp.func
def luminance_gradient(img: wp.array4d(dtype=float), t: int, y: int, x: int, axis: int):
    """``L(x + e) - L(x)`` along ``axis`` (0: x, 1: y), ``L`` the channel mean of ``img``;
    0 on the last column (axis 0) or row (axis 1)."""
    y1 = y
    x1 = x
    if axis == 0:
        x1 = x + 1
    else:
        y1 = y + 1
    if x1 >= img.shape[2] or y1 >= img.shape[1]:
        return 0.0
    here = (img[t, y, x, 0] + img[t, y, x, 1] + img[t, y, x, 2]) / 3.0
    there = (img[t, y1, x1, 0] + img[t, y1, x1, 1] + img[t, y1, x1, 2]) / 3.0
    return there - here


@wp.kernel
def luminance_gradients_rows(row_begin: int, tiles: int, img: wp.array4d(dtype=float),
                             gradients: wp.array4d(dtype=float)):
    height = img.shape[1]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, img.shape[2])
    t = r // height
    y = r - t * height
    for x in range(x_begin, x_end):
        gradients[t, y, x, 0] = luminance_gradient(img, t, y, x, 0)
        gradients[t, y, x, 1] = luminance_gradient(img, t, y, x, 1)


@wp.func
def frame_median(gradients: wp.array4d(dtype=float), y: int, x: int, axis: int):
    """The median over the frames of ``gradients[:, y, x, axis]`` (the mean of the two
    middle values for an even count), without storage: each value's rank is counted."""
    frames = gradients.shape[0]
    lower_at = (frames - 1) // 2
    upper_at = frames // 2
    lower = float(0.0)
    upper = float(0.0)
    for k in range(frames):
        v = gradients[k, y, x, axis]
        below = int(0)
        equal = int(0)
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


@wp.kernel
def median_residual_rows(row_begin: int, tiles: int, gradients: wp.array4d(dtype=float),
                         residual: wp.array3d(dtype=float)):
    y, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, gradients.shape[2])
    for x in range(x_begin, x_end):
        mx = frame_median(gradients, y, x, 0)
        my = frame_median(gradients, y, x, 1)
        for t in range(gradients.shape[0]):
            residual[t, y, x] = wp.abs(gradients[t, y, x, 0] - mx) + wp.abs(gradients[t, y, x, 1] - my)


@wp.kernel
def still_surface_rows(row_begin: int, tiles: int, residual: wp.array3d(dtype=float), out: wp.array2d(dtype=float),
                       tau: float, radius: int, share: float):
    frames = residual.shape[0]
    height = residual.shape[1]
    width = residual.shape[2]
    y, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    y0 = wp.max(y - radius, 0)
    y1 = wp.min(y + radius, height - 1)
    for x in range(x_begin, x_end):
        x0 = wp.max(x - radius, 0)
        x1 = wp.min(x + radius, width - 1)
        count = float((y1 - y0 + 1) * (x1 - x0 + 1))
        agree = float(0.0)
        for t in range(frames):
            total = float(0.0)
            for yy in range(y0, y1 + 1):
                for xx in range(x0, x1 + 1):
                    total += residual[t, yy, xx]
            if total / count < tau:
                agree += 1.0
        out[y, x] = wp.where(agree >= share * float(frames), 1.0, 0.0)


@wp.func
def edge_hit(magnitude: wp.array3d(dtype=float), t: int, y: int, x: int, threshold: float):
    """1 if ``magnitude[t, y, x] > threshold``, else 0."""
    hit = int(0)
    if magnitude[t, y, x] > threshold:
        hit = 1
    return hit


@wp.kernel
def boundary_dilate_x_rows(row_begin: int, tiles: int, magnitude: wp.array3d(dtype=float),
                           hits: wp.array3d(dtype=float), threshold: float, radius: int):
    """Row pass: ``hits = 1`` where a pixel within ``radius`` along x exceeds the
    threshold, from a running count of the edge pixels in the sliding window.

    The count is carried along x, so each tile first counts the whole window of
    its first pixel (``[x_begin - radius, x_begin + radius]``, clipped); the count
    is an integer, so every tiling gives the same ``hits``."""
    height = magnitude.shape[1]
    width = magnitude.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    count = int(0)
    for xx in range(wp.max(x_begin - radius, 0), wp.min(x_begin + radius + 1, width)):
        count += edge_hit(magnitude, t, y, xx, threshold)
    for x in range(x_begin, x_end):
        hit = float(0.0)
        if count > 0:
            hit = 1.0
        hits[t, y, x] = hit
        if x - radius >= 0:
            count -= edge_hit(magnitude, t, y, x - radius, threshold)
        if x + radius + 1 < width:
            count += edge_hit(magnitude, t, y, x + radius + 1, threshold)


@wp.kernel
def boundary_dilate_y_rows(row_begin: int, tiles: int, hits: wp.array3d(dtype=float),
                           out: wp.array3d(dtype=float), radius: int):
    """Column pass: ``out`` = max of ``hits`` over the rows within ``radius``."""
    height = hits.shape[1]
    width = hits.shape[2]
    r, x_begin, x_end = row_span(row_begin + wp.tid(), tiles, width)
    t = r // height
    y = r - t * height
    y_lo = wp.max(y - radius, 0)
    y_hi = wp.min(y + radius, height - 1)
    for x in range(x_begin, x_end):
        m = hits[t, y_lo, x]
        for yy in range(y_lo + 1, y_hi + 1):
            m = wp.max(m, hits[t, yy, x])
        out[t, y, x] = m


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("occlusion_soft")
def occlusion_soft(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3) -> None:
    """Occlusion likelihood ``o(x)`` of Eq. 7, times the inside-the-image indicator.

    ``out[t] = exp(-|lab[t](x) - lab[t+1](x + u_t)|^2 / (2 sigma_e^2) - d_t^2 / (2 sigma_d^2))``
    where ``x + u_t`` stays inside ``[0, W-1] x [0, H-1]``, and 0 elsewhere.

    Parameters
    ----------
    lab : wp.array float32 (T+1, H, W, 3), CIE Lab (L in [0, 100]) of frames 0..T
        (:func:`ivkernels.kernels.warp.colour.linear_rgb_to_lab`).
    flow : wp.array float32 (T, H, W, 2), forward flow t -> t+1, pixels.
    div_neg : wp.array float32 (T, H, W), one-sided divergence ``d <= 0``
        (:func:`ivkernels.kernels.warp.derivatives.divergence_negative`).
    out : wp.array float32 (T, H, W), written, in [0, 1].
    sigma_e : Lab distance scale (paper: 20).
    sigma_d : divergence scale, pixels per pixel (paper: 0.3).

    On a GPU one pixel per thread (row tiles).
    """
    tiles = row_tiles(flow.shape[2], lab.device)
    launch_rows(occlusion_soft_rows, flow.shape[0] * flow.shape[1] * tiles,
                [tiles, lab, flow, div_neg, out, sigma_e, sigma_d], device=lab.device)


@host("occlusion_binary")
def occlusion_binary(lab, flow, div_neg, out, sigma_e: float = 20.0, sigma_d: float = 0.3,
                     threshold: float = 0.5) -> None:
    """Occlusion map ``w_occ`` of Eq. 6: 1 = visible in frame t+1, 0 = occluded or leaves the image.

    ``out = 1`` where ``o(x) >= threshold`` (``o`` of Eq. 7, as in
    :func:`occlusion_soft`) and ``x + u`` lies inside ``[0, W-1] x [0, H-1]``;
    0 otherwise.  Same arguments as :func:`occlusion_soft`; ``threshold``: the
    paper's 0.5.  On a GPU one pixel per thread (row tiles).
    """
    tiles = row_tiles(flow.shape[2], lab.device)
    launch_rows(occlusion_binary_rows, flow.shape[0] * flow.shape[1] * tiles,
                [tiles, lab, flow, div_neg, out, sigma_e, sigma_d, float(threshold)], device=lab.device)


def _clear_occlusion_where(kernel, log_image, flow, occ, threshold: float, inputs=()) -> None:
    """Launch ``kernel``, a test that clears ``occ`` (T-1, H, W) from ``log_image``
    (T, H, W, 3) sampled along ``flow`` (T-1, H, W, 2), with the positive ``threshold``;
    the kernel's further ``inputs`` come between ``flow`` and ``occ``.  On a GPU one
    pixel per thread (row tiles)."""
    t, h, w, _ = log_image.shape
    dev = log_image.device
    tiles = row_tiles(w, dev)
    launch_rows(kernel, (t - 1) * h * tiles, [tiles, log_image, flow, *inputs, occ, float(threshold)], device=dev)


@host("warp_reliability")
def warp_reliability(log_image, flow, occ, max_spread: float) -> None:
    """Clear ``occ`` where the bilinear sample of the next frame at ``x + u`` straddles an edge.

    The temporal terms (Eq. 4, 8) compare ``X_{t+1}(x + u)``, a bilinear
    sample, with ``X_t(x)``.  Where ``x + u`` falls between pixels on the two
    sides of a crisp albedo edge the sample is a blend that no surface point
    has, so even the true albedo pays there; on the synthetic training
    sequences about 10% of the visible pixels of moving scenes differ by more
    than 0.3 (log) at the truth.  The spread
    ``mean_c sum_k w_k |I_{t+1}(corner_k) - I_{t+1}(x + u)|`` of the image at
    the sample's four corners measures that blend (zero on whole-pixel flow,
    in particular a static scene, and on flat regions); ``occ`` is set to 0
    where it reaches ``max_spread``.

    Parameters
    ----------
    log_image : wp.array float32 (T, H, W, 3), log input image.
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    occ : wp.array float32 (T-1, H, W), ``w_occ``, updated in place.
    max_spread : spread (log units) from which the warp is not trusted, > 0.

    On a GPU one pixel per thread (row tiles).
    """
    _clear_occlusion_where(warp_reliability_rows, log_image, flow, occ, max_spread)


@host("chroma_consistency")
def chroma_consistency(log_image, flow, occ, max_change: float) -> None:
    """Clear ``occ`` where the input's log chromaticity changes along the flow.

    The shading of Eq. 1 is grey, so it scales the three channels of a pixel
    alike and leaves the log chromaticity ``C = log I - mean_c log I`` to the
    albedo.  Where the albedo is constant along the flow (Eq. 4), so is ``C``:
    ``C_{t+1}(x + u) = C_t(x)`` under any change of light.  A pixel where the
    largest channel's change ``max_c |C_{t+1}(x + u)_c - C_t(x)_c|`` reaches
    ``max_change`` is not the same surface in the two frames (the flow is
    wrong there, or the point is hidden in frame t+1), so the temporal terms
    must not join them; ``occ`` is set to 0 there.  Unlike Eq. 7's Lab term
    this test does not see brightness, so a moving shadow does not trigger it.

    Parameters
    ----------
    log_image : wp.array float32 (T, H, W, 3), log input image.
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    occ : wp.array float32 (T-1, H, W), ``w_occ``, updated in place.
    max_change : change of log chromaticity from which the pixels differ, > 0.

    On a GPU one pixel per thread (row tiles).
    """
    _clear_occlusion_where(chroma_consistency_rows, log_image, flow, occ, max_change)


@host("luminance_consistency")
def luminance_consistency(log_image, flow, near, offsets, occ, max_change: float) -> None:
    """Clear ``occ`` where a surface's brightness changes along the flow near a flow jump.

    Where the light holds still, a surface keeps its brightness from frame to
    frame: ``L_{t+1}(x + u) = L_t(x)`` up to the pair's global change of
    exposure, ``L`` the mean over channels of the log image.  Near a motion
    boundary, where parallax hides and uncovers surfaces, a pixel whose
    ``|L_{t+1}(x + u) - L_t(x) - offsets[t]|`` reaches ``max_change`` is
    not the same surface in the two frames; ``occ`` is set to 0 there.  The
    chromaticity test (:func:`chroma_consistency`) misses such a pixel when
    both surfaces are grey.

    Parameters
    ----------
    log_image : wp.array float32 (T, H, W, 3), log input image.
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels.
    near : wp.array float32 (T-1, H, W), 1 where the test applies (0/1).
    offsets : wp.array float32 (T-1,), each pair's global change of the mean log.
    occ : wp.array float32 (T-1, H, W), ``w_occ``, updated in place.
    max_change : change of log brightness from which the pixels differ, > 0.

    On a GPU one pixel per thread (row tiles).
    """
    _clear_occlusion_where(luminance_consistency_rows, log_image, flow, occ, max_change, (near, offsets))


@host("round_trip_consistency")
def round_trip_consistency(flow, back_flow, occ, max_distance: float) -> None:
    """Clear ``occ`` where the forward flow and the backward flow disagree.

    Following ``u_t`` from ``x`` in frame t and then the backward flow
    ``b_t`` (frame t+1 -> frame t) from where it lands should come back to
    ``x``: ``u_t(x) + b_t(x + u_t(x)) = 0``.  Where the two estimates miss
    each other by ``max_distance`` pixels or more, at least one of them is
    wrong there (or ``x`` is hidden in frame t+1), and ``occ`` is set to 0.
    The other tests of ``w_occ`` compare colours along the flow; a match one
    period away on a periodic grey texture passes them all, but a flow
    estimated from the other end rarely makes the same mistake.

    Parameters
    ----------
    flow : wp.array float32 (T, H, W, 2), forward flow t -> t+1 in pixels.
    back_flow : wp.array float32 (T, H, W, 2), backward flow t+1 -> t in pixels,
        on frame t+1's grid; sampled bilinearly at ``x + u`` (clamped corners).
    occ : wp.array float32 (T, H, W), ``w_occ``, updated in place.
    max_distance : round-trip distance (pixels) from which the flow is not trusted, > 0.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = flow.shape
    dev = flow.device
    tiles = row_tiles(w, dev)
    launch_rows(round_trip_consistency_rows, t * h * tiles, [tiles, flow, back_flow, occ, float(max_distance)],
                device=dev)


@host("shading_gate")
def shading_gate(log_image, flow, gate, tau: float, tau_chroma: float = 0.0) -> None:
    """The per-pixel gate of the local shading smoothness (Eq. 9), from the input.

    Weiss's observation, along the flow: across an albedo edge the input's
    log difference between two neighbours stays the same from frame to frame,
    across a shading edge that moves with the light or the scene it changes.
    With ``L`` the mean over channels of the log image and
    ``D_t(x) = L_{t+1}(x + u_t(x)) - L_t(x)`` its change along the flow
    (bilinear sample), the evidence of a moving shading edge at ``x`` is
    ``e(x) = max_{y in N3(x)} |D_t(x) - D_t(y)|`` over the 8 neighbours whose
    sample lies inside the image (0 where ``x``'s own does not), and
    ``gate = exp(-(e / tau)^2)``: 1 on flat and static-edge regions, towards 0
    across edges whose contrast changes by ``tau`` or more between frames.
    Frame ``t < T-1`` uses the pair ``(t, t+1)``, the last frame the pair
    before it; a single frame gets ``gate = 1``.  With ``tau_chroma > 0`` the
    evidence is multiplied by ``exp(-(c / tau_chroma)^2)``, ``c(x)`` the
    largest change over the 8 neighbours of the frame's log chromaticity
    (log image minus its mean over channels, Euclidean): a change of
    contrast where the colour changes too is not taken for a shading edge
    (a shadow under a white light changes no chromaticity).

    Parameters
    ----------
    log_image : wp.array float32 (T, H, W, 3), log input image.
    flow : wp.array float32 (T-1, H, W, 2), forward flow in pixels (zeros for a static scene).
    gate : wp.array float32 (T, H, W), written; dimensionless, in (0, 1].
    tau : log-contrast change (log units) at which the gate falls to 1/e, > 0.
    tau_chroma : log-chromaticity change (log units) that divides the evidence by e; 0: not used.

    On a GPU one pixel per thread (row tiles).
    """
    t, h, w, _ = log_image.shape
    dev = log_image.device
    if t == 1:
        gate.fill_(1.0)
        return
    tiles = row_tiles(w, dev)
    launch_rows(shading_gate_rows, t * h * tiles, [tiles, log_image, flow, gate, tau, tau_chroma], device=dev)


@host("motion_boundary")
def motion_boundary(sobel_mag, out, threshold: float, radius: int, *, workspace=None) -> None:
    """Motion-boundary map ``w_bnd`` (Sec. 3.3, Eq. 9): threshold, then a square dilation
    as a row pass (running count of edge pixels) and a column pass (max) through
    a float32 (T, H, W) scratch buffer.

    ``out[t, y, x] = 1`` if any pixel of the ``(2 radius + 1)^2`` window around
    ``(y, x)`` (clipped to the image) has ``sobel_mag > threshold``, else 0.

    Parameters
    ----------
    sobel_mag : wp.array float32 (T, H, W), flow edge magnitude
        (:func:`ivkernels.kernels.warp.derivatives.flow_sobel_magnitude`).
    out : wp.array float32 (T, H, W), written, 0 or 1.  Must not overlap sobel_mag
        when ``radius > 0`` (ValueError).
    threshold : edge magnitude, pixels per pixel.
    radius : dilation radius in pixels, int >= 0 (0 = threshold only).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` that
        keeps the scratch buffer between calls; without one it is allocated
        for this call.

    On a GPU one pixel per thread (row tiles; each tile of the row pass starts
    its running count afresh, an exact integer count).
    """
    shape, dev = tuple(sobel_mag.shape), sobel_mag.device
    tiles = row_tiles(shape[2], dev)
    rows = shape[0] * shape[1] * tiles
    hits = scratch_buffer(workspace, f"{__name__}.boundary_hits", shape, wp.float32,
                          lambda: wp.empty(shape, dtype=wp.float32, device=dev), dev)
    launch_rows(boundary_dilate_x_rows, rows, [tiles, sobel_mag, hits, float(threshold), int(radius)], device=dev)
    launch_rows(boundary_dilate_y_rows, rows, [tiles, hits, out, int(radius)], device=dev)


@host("still_surface")
def still_surface(log_image, out, tau: float, radius: int, share: float, *, workspace=None) -> None:
    """Where a window's frames show the same surface at the same pixel: Weiss's cue for a
    still camera.

    A still surface keeps its log-luminance gradients ``g_t(x)`` (a shadow or a
    change of light multiplies the image and leaves them, except along the
    shadow's own edge, which is at a different place in every frame), so they
    agree with their median over the frames, ``m(x)`` (Weiss 2001); where a
    surface moves past the pixel they change from frame to frame.  The
    residual ``|g_t(x) - m(x)|_1`` is averaged over the ``(2 radius + 1)^2``
    window (clipped to the image), and ``out(x) = 1`` where it is under
    ``tau`` in at least ``share`` of the frames, else 0.  A flat region
    agrees whether it moves or not: the cue reads a surface that stays, not
    a flow.

    Parameters
    ----------
    log_image : wp.array float32 (T, H, W, 3), log RGB (``L`` is its channel mean).
    out : wp.array float32 (H, W), written, 0 or 1.
    tau : log units per pixel, > 0.
    radius : the window's radius in pixels, int >= 0.
    share : the share of the T frames that must agree, > 0 (above 1: none).
    workspace : optional :class:`ivkernels.kernels.workspace.Workspace` for the
        (T, H, W, 2) gradients and the (T, H, W) residual; without one they are
        allocated for this call.

    Three row passes (the gradients, the residual, the window means); on a
    GPU one pixel per thread.  The median counts each value's rank (T^2
    reads a pixel and axis), for the few frames of a window.
    """
    shape, dev = tuple(log_image.shape[:3]), log_image.device
    tiles = row_tiles(shape[2], dev)
    gradients = scratch_buffer(workspace, f"{__name__}.still_gradients", (*shape, 2), wp.float32,
                               lambda: wp.empty((*shape, 2), dtype=wp.float32, device=dev), dev)
    residual = scratch_buffer(workspace, f"{__name__}.still_residual", shape, wp.float32,
                              lambda: wp.empty(shape, dtype=wp.float32, device=dev), dev)
    launch_rows(luminance_gradients_rows, shape[0] * shape[1] * tiles, [tiles, log_image, gradients], device=dev)
    launch_rows(median_residual_rows, shape[1] * tiles, [tiles, gradients, residual], device=dev)
    launch_rows(still_surface_rows, shape[1] * tiles,
                [tiles, residual, out, float(tau), int(radius), float(share)], device=dev)
