"""Taichi mirror of :mod:`ivkernels.kernels.warp.colour`: sRGB transfer curve,
CIE L*a*b*, luminance and floored log, same host functions and signatures,
NumPy arrays passed as ``ti.types.ndarray()``.

Element-wise functions run a parallel loop over the flat buffer; the image
functions run a parallel loop over the ``T * H`` rows.
"""
import taichi as ti
from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.colour import FAMILY

host = implements(FAMILY, FRONT)


nd1 = ti.types.ndarray(dtype=ti.f32, ndim=1)
nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


# ----------------------------------------------------------------------------
# Device helpers
# ----------------------------------------------------------------------------

@ti.func
def srgb_decode(c):
    """sRGB-encoded value -> linear (IEC 61966-2-1)."""
    v = c / 12.92
    if c > 0.04045:
        v = ti.pow((c + 0.055) / 1.055, 2.4)
    return v


@ti.func
def srgb_encode(c):
    """Linear value -> sRGB-encoded (IEC 61966-2-1)."""
    v = 12.92 * c
    if c > 0.0031308:
        v = 1.055 * ti.pow(c, 1.0 / 2.4) - 0.055
    return v


@ti.func
def lab_f(t):
    """The CIE L*a*b* companding function: cube root above (6/29)^3, linear below."""
    delta = 6.0 / 29.0
    v = t / (3.0 * delta * delta) + 4.0 / 29.0
    if t > delta * delta * delta:
        v = ti.pow(t, 1.0 / 3.0)
    return v


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------

@ti.kernel
def srgb_to_linear_flat(src: nd1, out: nd1):
    for i in range(src.shape[0]):
        out[i] = srgb_decode(src[i])


@ti.kernel
def linear_to_srgb_flat(src: nd1, out: nd1):
    for i in range(src.shape[0]):
        out[i] = srgb_encode(src[i])


@ti.kernel
def log_floor_flat(src: nd1, out: nd1, floor: ti.f32):
    for i in range(src.shape[0]):
        out[i] = ti.log(ti.max(src[i], floor))


@ti.kernel
def lab_rows(rgb: nd4, out: nd4):
    height = rgb.shape[1]
    for r in range(rgb.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(rgb.shape[2]):
            red = rgb[t, y, x, 0]
            green = rgb[t, y, x, 1]
            blue = rgb[t, y, x, 2]
            fx = lab_f((0.4124564 * red + 0.3575761 * green + 0.1804375 * blue) / 0.95047)
            fy = lab_f(0.2126729 * red + 0.7151522 * green + 0.0721750 * blue)
            fz = lab_f((0.0193339 * red + 0.1191920 * green + 0.9503041 * blue) / 1.08883)
            out[t, y, x, 0] = 116.0 * fy - 16.0
            out[t, y, x, 1] = 500.0 * (fx - fy)
            out[t, y, x, 2] = 200.0 * (fy - fz)


@ti.kernel
def luminance_rows(rgb: nd4, out: nd3):
    height = rgb.shape[1]
    for r in range(rgb.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(rgb.shape[2]):
            out[t, y, x] = 0.2126 * rgb[t, y, x, 0] + 0.7152 * rgb[t, y, x, 1] + 0.0722 * rgb[t, y, x, 2]


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

def _run_flat(kernel, src, out, *extra) -> None:
    if src.size:
        kernel(src.reshape(-1), out.reshape(-1), *extra)


@host("srgb_to_linear")
def srgb_to_linear(src, out) -> None:
    """sRGB-encoded -> linear (IEC 61966-2-1), any shape; see
    :func:`ivkernels.kernels.warp.colour.srgb_to_linear` (NumPy arrays here)."""
    _run_flat(srgb_to_linear_flat, src, out)


@host("linear_to_srgb")
def linear_to_srgb(src, out) -> None:
    """Linear -> sRGB-encoded, any shape; see :func:`ivkernels.kernels.warp.colour.linear_to_srgb`."""
    _run_flat(linear_to_srgb_flat, src, out)


@host("log_floor")
def log_floor(src, out, floor: float) -> None:
    """``out = log(max(src, floor))``, any shape, ``floor > 0``; see
    :func:`ivkernels.kernels.warp.colour.log_floor`."""
    _run_flat(log_floor_flat, src, out, floor)


@host("linear_rgb_to_lab")
def linear_rgb_to_lab(rgb, out) -> None:
    """Linear sRGB (T, H, W, 3) -> CIE L*a*b* (D65, L in [0, 100]); see
    :func:`ivkernels.kernels.warp.colour.linear_rgb_to_lab`."""
    if rgb.size:
        lab_rows(rgb, out)


@host("luminance")
def luminance(rgb, out) -> None:
    """Rec. 709 luminance (T, H, W, 3) -> (T, H, W) of linear RGB; see
    :func:`ivkernels.kernels.warp.colour.luminance`."""
    if rgb.size:
        luminance_rows(rgb, out)
