"""Taichi mirror of :mod:`ivkernels.kernels.warp.sampling`: bilinear / bicubic
warping by a flow and the bilinear splat (its adjoint), same host functions and
signatures, NumPy arrays passed as ``ti.types.ndarray()``.

The outermost loop runs over the ``T * H`` rows in parallel, each iteration
looping over ``x``.  The splat scatters with ``+=`` on the output ndarray,
which Taichi makes atomic inside the parallel loop.
"""
import taichi as ti
from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.sampling import FAMILY

host = implements(FAMILY, FRONT)


nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


# ----------------------------------------------------------------------------
# Device helpers (the same as the @wp.func helpers of the Warp module)
# ----------------------------------------------------------------------------

@ti.func
def clamped_corners(p, n):
    """``(i0, i1, f)``: ``floor(p)``, ``floor(p) + 1`` clamped to ``[0, n-1]``, weight of ``i1``."""
    q = ti.math.clamp(p, -2.0, ti.cast(n, ti.f32) + 1.0)
    f = ti.floor(q)
    i0 = ti.cast(f, ti.i32)
    return ti.math.clamp(i0, 0, n - 1), ti.math.clamp(i0 + 1, 0, n - 1), q - f


@ti.func
def bilinear_at(src: ti.template(), t, c, x0, x1, fx, y0, y1, fy):
    """Bilinear mix of channel ``c`` of ``src[t]`` at corners from :func:`clamped_corners`."""
    top = (1.0 - fx) * src[t, y0, x0, c] + fx * src[t, y0, x1, c]
    bottom = (1.0 - fx) * src[t, y1, x0, c] + fx * src[t, y1, x1, c]
    return (1.0 - fy) * top + fy * bottom


@ti.func
def inside_image(px, py, height, width):
    """1.0 if ``(px, py)`` lies in ``[0, width-1] x [0, height-1]``, else 0.0."""
    result = 0.0
    if px >= 0.0 and px <= ti.cast(width - 1, ti.f32) and py >= 0.0 and py <= ti.cast(height - 1, ti.f32):
        result = 1.0
    return result


@ti.func
def keys_cubic(s):
    """Keys' cubic convolution kernel with a = -0.5 at distance ``s``."""
    a = -0.5
    s = ti.abs(s)
    w = 0.0
    if s <= 1.0:
        w = ((a + 2.0) * s - (a + 3.0)) * s * s + 1.0
    elif s < 2.0:
        w = ((a * s - 5.0 * a) * s + 8.0 * a) * s - 4.0 * a
    return w


@ti.func
def bicubic_at(src: ti.template(), t, c, px, py):
    """Bicubic (Keys, a = -0.5) sample of channel ``c`` of ``src[t]``, tap indices clamped."""
    height = src.shape[1]
    width = src.shape[2]
    qx = ti.math.clamp(px, -2.0, ti.cast(width, ti.f32) + 1.0)
    qy = ti.math.clamp(py, -2.0, ti.cast(height, ti.f32) + 1.0)
    bx = ti.floor(qx)
    by = ti.floor(qy)
    fx = qx - bx
    fy = qy - by
    ix = ti.cast(bx, ti.i32)
    iy = ti.cast(by, ti.i32)
    acc = 0.0
    for j in ti.static(range(4)):
        yj = ti.math.clamp(iy + j - 1, 0, height - 1)
        wy = keys_cubic(fy - (j - 1))
        row = 0.0
        for i in ti.static(range(4)):
            xi = ti.math.clamp(ix + i - 1, 0, width - 1)
            row += keys_cubic(fx - (i - 1)) * src[t, yj, xi, c]
        acc += wy * row
    return acc


# ----------------------------------------------------------------------------
# Kernels (parallel over rows = t * H + y)
# ----------------------------------------------------------------------------

@ti.kernel
def bilinear_warp_rows(src: nd4, flow: nd4, out: nd4, inside: nd3):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            px = ti.cast(x, ti.f32) + flow[t, y, x, 0]
            py = ti.cast(y, ti.f32) + flow[t, y, x, 1]
            x0, x1, fx = clamped_corners(px, width)
            y0, y1, fy = clamped_corners(py, height)
            for c in range(src.shape[3]):
                out[t, y, x, c] = bilinear_at(src, t, c, x0, x1, fx, y0, y1, fy)
            inside[t, y, x] = inside_image(px, py, height, width)


@ti.kernel
def bilinear_splat_rows(values: nd4, flow: nd4, out: nd4):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            px = ti.cast(x, ti.f32) + flow[t, y, x, 0]
            py = ti.cast(y, ti.f32) + flow[t, y, x, 1]
            x0, x1, fx = clamped_corners(px, width)
            y0, y1, fy = clamped_corners(py, height)
            w00 = (1.0 - fx) * (1.0 - fy)
            w01 = fx * (1.0 - fy)
            w10 = (1.0 - fx) * fy
            w11 = fx * fy
            for c in range(values.shape[3]):
                v = values[t, y, x, c]
                out[t, y0, x0, c] += w00 * v
                out[t, y0, x1, c] += w01 * v
                out[t, y1, x0, c] += w10 * v
                out[t, y1, x1, c] += w11 * v


@ti.kernel
def bicubic_warp_rows(src: nd4, flow: nd4, out: nd4, inside: nd3):
    height = flow.shape[1]
    width = flow.shape[2]
    for r in range(flow.shape[0] * height):
        t = r // height
        y = r - t * height
        for x in range(width):
            px = ti.cast(x, ti.f32) + flow[t, y, x, 0]
            py = ti.cast(y, ti.f32) + flow[t, y, x, 1]
            for c in range(src.shape[3]):
                out[t, y, x, c] = bicubic_at(src, t, c, px, py)
            inside[t, y, x] = inside_image(px, py, height, width)


# ----------------------------------------------------------------------------
# Host functions
# ----------------------------------------------------------------------------

@host("warp_bilinear")
def warp_bilinear(src, flow, out, inside) -> None:
    """Bilinear warp ``out = src[t](x + u)`` and the inside-the-image map; see
    :func:`ivkernels.kernels.warp.sampling.warp_bilinear` (NumPy arrays here)."""
    if src.size:
        bilinear_warp_rows(src, flow, out, inside)


@host("splat_bilinear")
def splat_bilinear(values, flow, out) -> None:
    """``out +=`` the transpose of :func:`warp_bilinear` applied to ``values`` (atomic
    adds); see :func:`ivkernels.kernels.warp.sampling.splat_bilinear`."""
    if values.size:
        bilinear_splat_rows(values, flow, out)


@host("warp_bicubic")
def warp_bicubic(src, flow, out, inside) -> None:
    """Bicubic (Keys, a = -0.5) warp with clamped taps and the inside map; see
    :func:`ivkernels.kernels.warp.sampling.warp_bicubic`."""
    if src.size:
        bicubic_warp_rows(src, flow, out, inside)
