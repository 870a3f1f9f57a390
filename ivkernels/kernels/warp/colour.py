"""Colour conversions: sRGB transfer curve, CIE L*a*b*, luminance, floored log.

* :func:`srgb_to_linear` / :func:`linear_to_srgb`: the IEC 61966-2-1 piecewise
  transfer curve, element-wise on arrays of any shape (values in [0, 1]).
* :func:`linear_rgb_to_lab`: CIE L*a*b* of linear sRGB (D65 white), L in
  [0, 100]; the ``i^Lab`` of the occlusion detector (Eq. 7, sigma_e = 20 is in
  these units).
* :func:`luminance`: Rec. 709 luminance of linear RGB (the data term's
  ``w_lum = lum(i) + 0.001``, Eq. 3).
* :func:`log_floor`: ``log(max(i, floor))``, the log domain the energy lives in.

Element-wise functions on arrays of any shape run over the flat buffer in
chunks of :data:`CHUNK` elements, one kernel thread per chunk: their output
must be C-contiguous, and an input that is not is copied first.  The image
functions take frame stacks of any strides and run one thread per image row.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.colour import FAMILY
from ivkernels.kernels.warp._checks import FRONT

host = implements(FAMILY, FRONT)

wp.set_module_options({"enable_backward": False})

#: Elements per kernel thread for the element-wise (any shape) functions.
CHUNK = 4096


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@wp.func
def srgb_decode(c: float):
    """sRGB-encoded value -> linear (IEC 61966-2-1)."""
    v = c / 12.92
    if c > 0.04045:
        v = wp.pow((c + 0.055) / 1.055, 2.4)
    return v


@wp.func
def srgb_encode(c: float):
    """Linear value -> sRGB-encoded (IEC 61966-2-1)."""
    v = 12.92 * c
    if c > 0.0031308:
        v = 1.055 * wp.pow(c, 1.0 / 2.4) - 0.055
    return v


@wp.func
def lab_f(t: float):
    """The CIE L*a*b* companding function: cube root above (6/29)^3, linear below."""
    delta = 6.0 / 29.0
    v = t / (3.0 * delta * delta) + 4.0 / 29.0
    if t > delta * delta * delta:
        v = wp.pow(t, 1.0 / 3.0)
    return v


@wp.func
def rgb_to_lab(r: float, g: float, b: float):
    """Linear sRGB -> CIE L*a*b* (D65), L in [0, 100].

    XYZ from the IEC 61966-2-1 matrix, divided by the D65 white
    (0.95047, 1.0, 1.08883), the row sums of that matrix.
    """
    x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047
    y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b
    z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883
    fx = lab_f(x)
    fy = lab_f(y)
    fz = lab_f(z)
    return wp.vec3(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@wp.kernel
def srgb_to_linear_chunks(row_begin: int, src: wp.array(dtype=float), out: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        out[i] = srgb_decode(src[i])


@wp.kernel
def linear_to_srgb_chunks(row_begin: int, src: wp.array(dtype=float), out: wp.array(dtype=float), chunk: int):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        out[i] = srgb_encode(src[i])


@wp.kernel
def log_floor_chunks(row_begin: int, src: wp.array(dtype=float), out: wp.array(dtype=float), chunk: int,
                     floor: float):
    begin = (row_begin + wp.tid()) * chunk
    end = wp.min(begin + chunk, src.shape[0])
    for i in range(begin, end):
        out[i] = wp.log(wp.max(src[i], floor))


@wp.kernel
def lab_rows(row_begin: int, rgb: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = rgb.shape[1]
    t = r // height
    y = r - t * height
    for x in range(rgb.shape[2]):
        lab = rgb_to_lab(rgb[t, y, x, 0], rgb[t, y, x, 1], rgb[t, y, x, 2])
        out[t, y, x, 0] = lab[0]
        out[t, y, x, 1] = lab[1]
        out[t, y, x, 2] = lab[2]


@wp.kernel
def luminance_rows(row_begin: int, rgb: wp.array4d(dtype=float), out: wp.array3d(dtype=float)):
    r = row_begin + wp.tid()
    height = rgb.shape[1]
    t = r // height
    y = r - t * height
    for x in range(rgb.shape[2]):
        out[t, y, x] = 0.2126 * rgb[t, y, x, 0] + 0.7152 * rgb[t, y, x, 1] + 0.0722 * rgb[t, y, x, 2]


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _launch_chunks(kernel, src, out, *extra) -> None:
    """Run an element-wise ``kernel`` on the flat buffers of ``src`` and ``out`` (checked: float32
    arrays of the same shape, ``out`` C-contiguous), ``src`` copied first if it is not contiguous;
    empty: nothing to do."""
    if src.size == 0:
        return
    flat_src, flat_out = src.contiguous().flatten(), out.flatten()
    n = flat_src.shape[0]
    launch_rows(kernel, (n + CHUNK - 1) // CHUNK, [flat_src, flat_out, CHUNK, *extra], device=src.device)


@host("srgb_to_linear")
def srgb_to_linear(src, out) -> None:
    """sRGB-encoded values in [0, 1] -> linear (IEC 61966-2-1 piecewise curve).

    ``out = src / 12.92`` for ``src <= 0.04045``, else ``((src + 0.055) / 1.055) ** 2.4``.
    ``src``, ``out``: float32 wp.arrays of the same, any shape, ``out``
    C-contiguous (``out`` may be ``src``).
    """
    _launch_chunks(srgb_to_linear_chunks, src, out)


@host("linear_to_srgb")
def linear_to_srgb(src, out) -> None:
    """Linear values in [0, 1] -> sRGB-encoded (inverse of :func:`srgb_to_linear`).

    ``out = 12.92 src`` for ``src <= 0.0031308``, else ``1.055 src ** (1/2.4) - 0.055``.
    Any shape, ``out`` C-contiguous and may be ``src``.
    """
    _launch_chunks(linear_to_srgb_chunks, src, out)


@host("log_floor")
def log_floor(src, out, floor: float) -> None:
    """``out = log(max(src, floor))`` element-wise (linear -> log domain), any shape.

    ``floor`` must be > 0 (it bounds the log from below: ``log(floor)``).
    float32, ``out`` C-contiguous and may be ``src``.
    """
    _launch_chunks(log_floor_chunks, src, out, floor)


@host("linear_rgb_to_lab")
def linear_rgb_to_lab(rgb, out) -> None:
    """Linear sRGB -> CIE L*a*b* with the D65 white (``i^Lab`` of Eq. 7).

    Parameters
    ----------
    rgb : wp.array float32 (T, H, W, 3), linear RGB in [0, 1].
    out : wp.array float32 (T, H, W, 3), written: (L*, a*, b*), L* in [0, 100]
        (white (1, 1, 1) -> (100, 0, 0)).  May be ``rgb``.
    """
    launch_rows(lab_rows, rgb.shape[0] * rgb.shape[1], [rgb, out], device=rgb.device)


@host("luminance")
def luminance(rgb, out) -> None:
    """Rec. 709 luminance ``0.2126 R + 0.7152 G + 0.0722 B`` of linear RGB.

    Parameters
    ----------
    rgb : wp.array float32 (T, H, W, 3), linear.
    out : wp.array float32 (T, H, W), written, linear.
    """
    launch_rows(luminance_rows, rgb.shape[0] * rgb.shape[1], [rgb, out], device=rgb.device)
