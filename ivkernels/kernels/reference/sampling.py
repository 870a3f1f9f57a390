"""``sampling``: the declared contract of its host functions, and the NumPy references (float64, vectorised)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.contract import Acc, Family, Out, Rule

FAMILY = Family("sampling", "Warping frames by a flow, and its adjoint.")


def _channels(sizes, args):
    if sizes["C"] < 1:
        raise ValueError(f"src must have at least one channel, got shape {tuple(args['src'].shape)}")


_WARP = dict(src="T H W C", flow="T H W 2", out=Out("T H W C"), inside=Out("T H W"),
             rules=(Rule(_channels, after="src"),),
             separate=(("out", "src", "the warp reads neighbours of src while writing out"),))
FAMILY.declare("warp_bilinear(src, flow, out, inside)",
               "``out = src[t](x + u)`` bilinear, ``inside`` 1 where ``x + u`` lies in the image, else 0.", **_WARP)
FAMILY.declare("splat_bilinear(values, flow, out)", "Add the transpose of :meth:`warp_bilinear` of values into out.",
               values="T H W C", flow="T H W 2", out=Acc("T H W C"),
               separate=(("out", "values", "the splat scatters into out while reading values"),))
FAMILY.declare("warp_bicubic(src, flow, out, inside)", "``out = src[t](x + u)`` bicubic (Keys).", **_WARP)


def _corners(p: np.ndarray, n: int):
    """``floor(p)`` and ``floor(p) + 1`` clamped to ``[0, n-1]``, and the weight of the second."""
    f = np.floor(p)
    i0 = f.astype(np.int64)
    return np.clip(i0, 0, n - 1), np.clip(i0 + 1, 0, n - 1), p - f


def _sample_points(flow: np.ndarray):
    t, h, w, _ = flow.shape
    yy, xx = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64), indexing="ij")
    px = xx[None] + flow[..., 0].astype(np.float64)
    py = yy[None] + flow[..., 1].astype(np.float64)
    return px, py


def _inside(px, py, h, w) -> np.ndarray:
    return ((px >= 0) & (px <= w - 1) & (py >= 0) & (py <= h - 1)).astype(np.float64)


def warp_bilinear(src: np.ndarray, flow: np.ndarray):
    """Return ``(out, inside)``: bilinear samples of ``src[t]`` at ``x + flow`` (clamped corners)
    and the inside-the-image indicator, both float64."""
    src = np.asarray(src, np.float64)
    t, h, w, _ = src.shape
    px, py = _sample_points(flow)
    x0, x1, fx = _corners(px, w)
    y0, y1, fy = _corners(py, h)
    ti = np.arange(t)[:, None, None]
    fx, fy = fx[..., None], fy[..., None]
    out = ((1 - fy) * ((1 - fx) * src[ti, y0, x0] + fx * src[ti, y0, x1])
           + fy * ((1 - fx) * src[ti, y1, x0] + fx * src[ti, y1, x1]))
    return out, _inside(px, py, h, w)


def splat_bilinear(values: np.ndarray, flow: np.ndarray) -> np.ndarray:
    """Return the transpose of :func:`warp_bilinear` applied to ``values`` (float64)."""
    values = np.asarray(values, np.float64)
    t, h, w, c = values.shape
    px, py = _sample_points(flow)
    x0, x1, fx = _corners(px, w)
    y0, y1, fy = _corners(py, h)
    ti = np.broadcast_to(np.arange(t)[:, None, None], (t, h, w))
    out = np.zeros_like(values)
    fx, fy = fx[..., None], fy[..., None]
    for yi, xi, wt in ((y0, x0, (1 - fx) * (1 - fy)), (y0, x1, fx * (1 - fy)),
                       (y1, x0, (1 - fx) * fy), (y1, x1, fx * fy)):
        np.add.at(out, (ti, yi, xi), wt * values)
    return out


def keys_cubic(s: np.ndarray, a: float = -0.5) -> np.ndarray:
    """Keys' cubic convolution kernel."""
    s = np.abs(s)
    inner = (a + 2) * s**3 - (a + 3) * s**2 + 1
    outer = a * s**3 - 5 * a * s**2 + 8 * a * s - 4 * a
    return np.where(s <= 1, inner, np.where(s < 2, outer, 0.0))


def warp_bicubic(src: np.ndarray, flow: np.ndarray):
    """Return ``(out, inside)`` like :func:`warp_bilinear` with Keys bicubic (a = -0.5) taps,
    each tap index clamped to the image."""
    src = np.asarray(src, np.float64)
    t, h, w, _ = src.shape
    px, py = _sample_points(flow)
    bx, by = np.floor(px), np.floor(py)
    fx, fy = px - bx, py - by
    ix, iy = bx.astype(np.int64), by.astype(np.int64)
    ti = np.arange(t)[:, None, None]
    out = np.zeros_like(src)
    for j in range(-1, 3):
        yj = np.clip(iy + j, 0, h - 1)
        wy = keys_cubic(fy - j)[..., None]
        for i in range(-1, 3):
            xi = np.clip(ix + i, 0, w - 1)
            out += wy * keys_cubic(fx - i)[..., None] * src[ti, yj, xi]
    return out, _inside(px, py, h, w)
