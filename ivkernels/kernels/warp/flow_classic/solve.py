"""The IRLS step's linear system and its solve: red-black SOR, then the flow update.

:func:`assemble_system` folds the data coefficients, the smoothness weights
and the current flow into each pixel's 2x2 block and right-hand side, so a
sweep of :func:`sor_sweep` reads only ``du``: pixels with
``(x + y) % 2 == parity`` read only neighbours of the other colour, so a
half sweep is race-free and can be split into row bands anywhere.
:func:`apply_update` adds the clipped increment; :func:`select_masked`
chooses between two fields per pixel.  Part of
:mod:`ivkernels.kernels.warp.flow_classic`.
"""
from __future__ import annotations

import warp as wp

from ivkernels.kernels.contract import implements
from ivkernels.kernels.launch import launch_rows
from ivkernels.kernels.reference.flow_classic import FAMILY
from ivkernels.kernels.warp._checks import FRONT

host = implements(FAMILY, FRONT)

__all__ = ["assemble_system", "sor_sweep", "apply_update", "select_masked"]

wp.set_module_options({"enable_backward": False})


@wp.kernel
def assemble_system_rows(row_begin: int, flow: wp.array4d(dtype=float), data: wp.array4d(dtype=float),
                         smooth: wp.array4d(dtype=float), out: wp.array4d(dtype=float), lam: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    width = flow.shape[2]
    t = r // height
    y = r - t * height
    for x in range(width):
        u = flow[t, y, x, 0]
        v = flow[t, y, x, 1]
        diag_u = float(0.0)
        diag_v = float(0.0)
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


@wp.kernel
def sor_sweep_rows(row_begin: int, du: wp.array4d(dtype=float), system: wp.array4d(dtype=float),
                   smooth: wp.array4d(dtype=float), lam: float, omega: float, parity: int):
    r = row_begin + wp.tid()
    height = du.shape[1]
    width = du.shape[2]
    t = r // height
    y = r - t * height
    x = (parity + y) % 2
    while x < width:
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
        x += 2


@wp.kernel
def apply_update_rows(row_begin: int, flow: wp.array4d(dtype=float), du: wp.array4d(dtype=float),
                      out: wp.array4d(dtype=float), limit: float):
    r = row_begin + wp.tid()
    height = flow.shape[1]
    t = r // height
    y = r - t * height
    for x in range(flow.shape[2]):
        for c in range(2):
            d = du[t, y, x, c]
            if limit > 0.0:
                d = wp.clamp(d, -limit, limit)
            out[t, y, x, c] = flow[t, y, x, c] + d


@wp.kernel
def select_masked_rows(row_begin: int, mask: wp.array3d(dtype=float), inside_mask: wp.array4d(dtype=float),
                       outside_mask: wp.array4d(dtype=float), out: wp.array4d(dtype=float)):
    r = row_begin + wp.tid()
    height = mask.shape[1]
    t = r // height
    y = r - t * height
    for x in range(mask.shape[2]):
        for c in range(out.shape[3]):
            if mask[t, y, x] >= 0.5:
                out[t, y, x, c] = inside_mask[t, y, x, c]
            else:
                out[t, y, x, c] = outside_mask[t, y, x, c]


@host("assemble_system")
def assemble_system(flow, data, smooth, lam: float, out) -> None:
    """The 2x2 block and right-hand side of every pixel's IRLS equations.

    ``out = (a11, a12, a22, b_u, b_v)`` with ``a11 = psi_D Ix^2 + lam sum_n w^u_n``,
    ``a12 = psi_D Ix Iy``, ``a22 = psi_D Iy^2 + lam sum_n w^v_n`` and
    ``b_u = -psi_D Ix It + lam sum_n w^u_n (u_n - u)`` (likewise ``b_v``), so
    that the equations read ``A_p du_p - lam sum_n w_n du_n = b_p``.

    flow : (T, H, W, 2) float32, flow ``u`` the increment is added to.
    data : (T, H, W, 5) float32 from :func:`data_coefficients`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights`.
    out : (T, H, W, 5) float32.
    """
    t, h, w, _ = flow.shape
    dev = flow.device
    launch_rows(assemble_system_rows, t * h, [flow, data, smooth, out, float(lam)], dev)


@host("sor_sweep")
def sor_sweep(du, system, smooth, lam: float, omega: float, parity: int) -> None:
    """One half-sweep of red-black block SOR on the IRLS system, in place on ``du``.

    Updates the pixels with ``(x + y) % 2 == parity``: solves their 2x2 block
    ``A_p du_p = b_p + lam sum_n w_n du_n`` with the neighbours fixed, and
    relaxes by ``omega`` (1 = Gauss-Seidel).  Call with parity 0 then 1 for a
    full sweep.

    du : (T, H, W, 2) float32, increment, read and written.
    system : (T, H, W, 5) float32 from :func:`assemble_system`.
    smooth : (T, H, W, 4) float32 from :func:`smoothness_weights` (the same
        ``lam`` as given to :func:`assemble_system`).
    """
    t, h, w, _ = du.shape
    dev = du.device
    launch_rows(sor_sweep_rows, t * h, [du, system, smooth, float(lam), float(omega), int(parity)], dev)


@host("apply_update")
def apply_update(flow, du, out, limit: float = 1.0) -> None:
    """``out = flow + clip(du, -limit, limit)`` (no clipping when ``limit <= 0``).

    flow, du, out : (T, H, W, 2) float32; ``out`` may be ``flow``.
    """
    t, h, w, _ = flow.shape
    launch_rows(apply_update_rows, t * h, [flow, du, out, float(limit)], flow.device)


@host("select_masked")
def select_masked(mask, inside_mask, outside_mask, out) -> None:
    """``out = inside_mask`` where ``mask >= 0.5``, else ``outside_mask``.

    mask : (T, H, W) float32; inside_mask, outside_mask, out : (T, H, W, C) float32
    (``out`` may alias either input).
    """
    t, h, w = mask.shape
    launch_rows(select_masked_rows, t * h, [mask, inside_mask, outside_mask, out], mask.device)
