"""``sampling`` on the NumPy backend: :mod:`ivkernels.kernels.reference.sampling` written into the outputs."""
from __future__ import annotations

from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint, write
from ivkernels.kernels.reference import sampling as ref


def warp_bilinear(src, flow, out, inside) -> None:
    """``out = src[t](x + u)`` bilinear, ``inside`` 1 where the sample lies in the image."""
    arrays(src=src, flow=flow)
    check_disjoint("out", out, "src", src, "the warp reads neighbours of src while writing out")
    value, ok = ref.warp_bilinear(src, flow)
    write("out", out, value)
    write("inside", inside, ok)


def splat_bilinear(values, flow, out) -> None:
    """Add the transpose of :func:`warp_bilinear` of ``values`` into ``out``."""
    arrays(values=values, flow=flow)
    check_disjoint("out", out, "values", values, "the splat scatters into out while reading values")
    add("out", out, ref.splat_bilinear(values, flow))


def warp_bicubic(src, flow, out, inside) -> None:
    """``out = src[t](x + u)`` bicubic (Keys), ``inside`` as :func:`warp_bilinear`."""
    arrays(src=src, flow=flow)
    check_disjoint("out", out, "src", src, "the warp reads neighbours of src while writing out")
    value, ok = ref.warp_bicubic(src, flow)
    write("out", out, value)
    write("inside", inside, ok)
