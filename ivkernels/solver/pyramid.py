"""Image pyramids on the backend, and the coarse-to-fine loop.

:func:`coarse_to_fine` knows nothing about the energy: it takes the per-level
solver as an argument (as scikit-image's registration code does), so the
intrinsic-video solver (:mod:`ivkernels.solver.window_solver`) and each GNC
stage of Classic+NL (:mod:`ivkernels.flow.classic_nl`) run the same loop.
"""
from __future__ import annotations

import math
from typing import Callable


def level_shapes(height: int, width: int, scale: float, min_size: int) -> list[tuple[int, int]]:
    """(h, w) of every pyramid level, finest first.

    Level ``l`` has size ``round(H * scale**l) x round(W * scale**l)``; levels
    are added while the shorter side stays >= ``min_size`` (the finest level is
    always present, however small the input).
    """
    if height < 1 or width < 1:
        raise ValueError(f"image size must be positive, got {height}x{width}")
    shapes = [(height, width)]
    level = 1
    while True:
        h = int(round(height * scale ** level))
        w = int(round(width * scale ** level))
        if min(h, w) < min_size:
            break
        shapes.append((h, w))
        level += 1
    return shapes


def antialias_sigma(scale: float) -> float:
    """Gaussian sigma (pixels of the finer level) before resampling by ``scale`` < 1.

    ``1 / sqrt(2 * scale)`` as in Classic+NL (sigma = 1 for halving).
    """
    return 1.0 / math.sqrt(2.0 * scale)


def downsample(be, src, shape: tuple[int, int]):
    """Antialiased resize of a (T, h, w, C) backend array to ``shape`` = (h', w')."""
    T, h, w, C = src.shape
    scale = min(shape[0] / h, shape[1] / w)
    blurred = be.empty(src.shape)
    scratch = be.empty(src.shape)
    be.pyramid.gaussian_blur(src, blurred, scratch, antialias_sigma(scale))
    out = be.empty((T, shape[0], shape[1], C))
    be.pyramid.resize_bilinear(blurred, out)
    return out


def resize(be, src, shape: tuple[int, int]):
    """Bilinear resize (no antialiasing) of a (T, h, w, C) backend array."""
    T, _, _, C = src.shape
    out = be.empty((T, shape[0], shape[1], C))
    be.pyramid.resize_bilinear(src, out)
    return out


def resize_flow(be, flow, shape: tuple[int, int]):
    """Resize a (T, h, w, 2) flow to ``shape`` and scale its vectors with it."""
    out = be.empty((flow.shape[0], shape[0], shape[1], 2))
    be.pyramid.resize_flow(flow, out)
    return out


def image_pyramid(be, frames, shapes: list[tuple[int, int]]) -> list:
    """Antialiased pyramid of (T, H, W, C) ``frames``, one array per shape, finest first.

    Each level is made from the next finer one, so each blur stays small.
    """
    levels = [frames]
    for shape in shapes[1:]:
        levels.append(downsample(be, levels[-1], shape))
    return levels


def coarse_to_fine(shapes: list[tuple[int, int]], solve_level: Callable, init: Callable,
                   upsample: Callable, start_level: int | None = None):
    """Run ``solve_level`` from the coarsest shape to the finest; returns the finest state.

    Every callback gets the index ``level`` of the level it works on (0 = the
    finest, ``len(shapes) - 1`` the coarsest), so per-level buffers and
    schedules are looked up by index, never recovered from a shape.

    Parameters
    ----------
    shapes : level shapes (h, w), finest first (:func:`level_shapes`, or any
        other pyramid's sizes).
    solve_level : ``solve_level(level, shape, state) -> state``.
    init : ``init(level, shape) -> state`` at the first level solved.
    upsample : ``upsample(level, shape, state) -> state``: the state solved at
        ``level + 1`` brought to ``level``, of shape ``shape``.
    start_level : the level to start at (default: the coarsest); the levels
        coarser than it are skipped, for a start that is already solved there.
    """
    if not shapes:
        raise ValueError("coarse_to_fine needs at least one level shape")
    first = len(shapes) - 1 if start_level is None else int(start_level)
    if not 0 <= first < len(shapes):
        raise ValueError(f"start_level must be in [0, {len(shapes) - 1}], got {start_level}")
    state = None
    for level in range(first, -1, -1):
        shape = shapes[level]
        state = init(level, shape) if level == first else upsample(level, shape, state)
        state = solve_level(level, shape, state)
    return state
