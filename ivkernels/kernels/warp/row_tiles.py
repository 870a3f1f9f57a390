"""Rows cut into tiles, for the GPU's launch layout (:func:`ivkernels.kernels.launch.row_tiles`).

A kernel launched over ``rows * tiles`` threads finds its row and its span of
columns with :func:`row_span`; with one tile per row (the CPU) thread ``k``
is row ``k`` and spans the whole row, as before tiles existed.  Energies of a
row then come from several threads: they are added with ``wp.atomic_add``
(one add per thread and row; with one tile per row the same sum as a plain
add).
"""
from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})


@wp.func
def row_span(k: int, tiles: int, width: int):
    """Row ``r`` and columns ``[x0, x1)`` of thread ``k`` when each row is cut into
    ``tiles`` tiles of (as near as possible) equal width."""
    if tiles == 1:
        return k, 0, width
    r = k // tiles
    j = k - r * tiles
    return r, (j * width) // tiles, ((j + 1) * width) // tiles


@wp.func
def frame_row(r: int, height: int):
    """Frame ``t`` and row ``y`` of row ``r = t * height + y`` of a frame stack."""
    t = r // height
    return t, r - t * height
