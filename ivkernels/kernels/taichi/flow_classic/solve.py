"""Taichi mirror of :mod:`ivkernels.kernels.warp.flow_classic.solve`:
the IRLS step's linear system, its red-black SOR solve and the flow update (same names, same signatures,
NumPy arrays passed as ``ti.types.ndarray()``)."""

import taichi as ti

from ivkernels.kernels.contract import implements
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference.flow_classic import FAMILY

host = implements(FAMILY, FRONT)

__all__ = ["assemble_system", "sor_sweep", "sor_full_sweep", "apply_update", "select_masked"]

nd3 = ti.types.ndarray(dtype=ti.f32, ndim=3)
nd4 = ti.types.ndarray(dtype=ti.f32, ndim=4)


@ti.kernel
def _assemble_system(flow: nd4, data: nd4, smooth: nd4, out: nd4, lam: ti.f32):
    height = flow.shape[1]
    width = flow.shape[2]
    for t, y in ti.ndrange(flow.shape[0], height):
        for x in range(width):
            u = flow[t, y, x, 0]
            v = flow[t, y, x, 1]
            diag_u = 0.0
            diag_v = 0.0
            rhs_u = -data[t, y, x, 3]
            rhs_v = -data[t, y, x, 4]
            if x < width - 1:
                wu = lam * smooth[t, y, x, 0]
                wv = lam * smooth[t, y, x, 2]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y, x + 1, 0] - u)
                rhs_v += wv * (flow[t, y, x + 1, 1] - v)
            if x > 0:
                wu = lam * smooth[t, y, x - 1, 0]
                wv = lam * smooth[t, y, x - 1, 2]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y, x - 1, 0] - u)
                rhs_v += wv * (flow[t, y, x - 1, 1] - v)
            if y < height - 1:
                wu = lam * smooth[t, y, x, 1]
                wv = lam * smooth[t, y, x, 3]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y + 1, x, 0] - u)
                rhs_v += wv * (flow[t, y + 1, x, 1] - v)
            if y > 0:
                wu = lam * smooth[t, y - 1, x, 1]
                wv = lam * smooth[t, y - 1, x, 3]
                diag_u += wu
                diag_v += wv
                rhs_u += wu * (flow[t, y - 1, x, 0] - u)
                rhs_v += wv * (flow[t, y - 1, x, 1] - v)
            out[t, y, x, 0] = data[t, y, x, 0] + diag_u
            out[t, y, x, 1] = data[t, y, x, 1]
            out[t, y, x, 2] = data[t, y, x, 2] + diag_v
            out[t, y, x, 3] = rhs_u
            out[t, y, x, 4] = rhs_v


@ti.kernel
def _sor_sweep(du: nd4, system: nd4, smooth: nd4, lam: ti.f32, omega: ti.f32, parity: ti.i32):
    height = du.shape[1]
    width = du.shape[2]
    for t, y in ti.ndrange(du.shape[0], height):
        x0 = (parity + y) % 2
        for k in range((width - x0 + 1) // 2):
            x = x0 + 2 * k
            rhs_u = system[t, y, x, 3]
            rhs_v = system[t, y, x, 4]
            if x < width - 1:
                rhs_u += lam * smooth[t, y, x, 0] * du[t, y, x + 1, 0]
                rhs_v += lam * smooth[t, y, x, 2] * du[t, y, x + 1, 1]
            if x > 0:
                rhs_u += lam * smooth[t, y, x - 1, 0] * du[t, y, x - 1, 0]
                rhs_v += lam * smooth[t, y, x - 1, 2] * du[t, y, x - 1, 1]
            if y < height - 1:
                rhs_u += lam * smooth[t, y, x, 1] * du[t, y + 1, x, 0]
                rhs_v += lam * smooth[t, y, x, 3] * du[t, y + 1, x, 1]
            if y > 0:
                rhs_u += lam * smooth[t, y - 1, x, 1] * du[t, y - 1, x, 0]
                rhs_v += lam * smooth[t, y - 1, x, 3] * du[t, y - 1, x, 1]
            a11 = system[t, y, x, 0]
            a12 = system[t, y, x, 1]
            a22 = system[t, y, x, 2]
            det = a11 * a22 - a12 * a12
            if det > 1.0e-20 * (a11 * a22 + 1.0e-30):
                new_u = (a22 * rhs_u - a12 * rhs_v) / det
                new_v = (a11 * rhs_v - a12 * rhs_u) / det
                du[t, y, x, 0] = (1.0 - omega) * du[t, y, x, 0] + omega * new_u
                du[t, y, x, 1] = (1.0 - omega) * du[t, y, x, 1] + omega * new_v


@ti.kernel
def _apply_update(flow: nd4, du: nd4, out: nd4, limit: ti.f32):
    for t, y in ti.ndrange(flow.shape[0], flow.shape[1]):
        for x in range(flow.shape[2]):
            for c in ti.static(range(2)):
                d = du[t, y, x, c]
                if limit > 0.0:
                    d = ti.math.clamp(d, -limit, limit)
                out[t, y, x, c] = flow[t, y, x, c] + d


@ti.kernel
def _select_masked(mask: nd3, inside_mask: nd4, outside_mask: nd4, out: nd4):
    for t, y in ti.ndrange(mask.shape[0], mask.shape[1]):
        for x in range(mask.shape[2]):
            for c in range(out.shape[3]):
                if mask[t, y, x] >= 0.5:
                    out[t, y, x, c] = inside_mask[t, y, x, c]
                else:
                    out[t, y, x, c] = outside_mask[t, y, x, c]


@host("assemble_system")
def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.assemble_system`."""
    _assemble_system(flow, data, smooth, out, float(lam))


@host("sor_sweep")
def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.sor_sweep`."""
    _sor_sweep(du, system, smooth, float(lam), float(omega), int(parity))


@host("sor_full_sweep")
def sor_full_sweep(du, system, smooth, lam: float, omega: float) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.sor_full_sweep` (here the two half sweeps in order)."""
    _sor_sweep(du, system, smooth, float(lam), float(omega), 0)
    _sor_sweep(du, system, smooth, float(lam), float(omega), 1)


@host("apply_update")
def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.apply_update`."""
    _apply_update(flow, du, out, float(limit))


@host("select_masked")
def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """See :func:`ivkernels.kernels.warp.flow_classic.select_masked`."""
    _select_masked(mask, inside_mask, outside_mask, out)
