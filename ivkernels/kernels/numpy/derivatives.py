"""``derivatives`` on the NumPy backend: :mod:`ivkernels.kernels.reference.derivatives` written into the outputs."""
from __future__ import annotations

from ivkernels.kernels.numpy._adapt import arrays, check_disjoint, write
from ivkernels.kernels.reference import derivatives as ref


def image_gradient(src, gx, gy) -> None:
    """5-point x and y derivatives of ``src`` (T, H, W, C)."""
    arrays(src=src)
    check_disjoint("gx", gx, "src", src, "the stencil reads neighbours of src while writing gx")
    check_disjoint("gy", gy, "src", src, "the stencil reads neighbours of src while writing gy")
    dx, dy = ref.image_gradient(src)
    write("gx", gx, dx)
    write("gy", gy, dy)


def flow_sobel_magnitude(flow, out) -> None:
    """Sobel magnitude (T, H, W) of ``flow`` (T, H, W, 2)."""
    arrays(flow=flow)
    write("out", out, ref.flow_sobel_magnitude(flow))


def divergence_negative(flow, out) -> None:
    """``min(div u, 0)`` (T, H, W) of ``flow`` (T, H, W, 2)."""
    arrays(flow=flow)
    write("out", out, ref.divergence_negative(flow))
