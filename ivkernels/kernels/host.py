"""Backend-neutral host code of the kernel families: tables, constants, shapes.

Everything here is plain NumPy and Python, computed on the host and handed to
the kernels of any backend (Warp, Taichi, NumPy); the family modules of each
backend re-export what is part of their public face (``gaussian_kernel``,
``shading_scratch_shape``, ``flow_scratch_shape``, ``GREY_WEIGHTS``), so that
one definition serves every backend.  Nothing here imports a backend.

Contents
--------
* ``flow_classic``: :data:`GREY_WEIGHTS`.
* ``pyramid``: :func:`gaussian_kernel`.
* ``energy_albedo_entropy``: :class:`EntropyScratch`, :func:`allocate_entropy_scratch_with`,
  :func:`run_entropy_steps`.
* ``median``: :data:`KMEANS_ITERATIONS`, :data:`MIN_SEPARATION`,
  :func:`median_network`, :func:`spatial_weights`,
  :func:`shading_scratch_shape`, :func:`flow_scratch_shape`.
* ``coarse_basis``: :func:`grid_shape`, :data:`MAX_EXPONENT`.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ivkernels.kernels.checks import check_int

# ----------------------------------------------------------------------------
# flow_classic
# ----------------------------------------------------------------------------

#: Grey level of Classic+NL's input (MATLAB ``rgb2gray``): weights of R, G, B.
GREY_WEIGHTS = (0.2989, 0.5870, 0.1140)


# ----------------------------------------------------------------------------
# pyramid
# ----------------------------------------------------------------------------

def gaussian_kernel(sigma: float) -> np.ndarray:
    """Normalised 1-D Gaussian taps ``exp(-k^2 / 2 sigma^2)``, k = -r..r, r = max(1, ceil(3 sigma)).

    sigma : standard deviation in pixels, > 0.  Returns float32 ``(2r + 1,)``
    summing to 1.
    """
    radius = max(1, math.ceil(3.0 * sigma))
    k = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-0.5 * (k / sigma) ** 2)
    return (w / w.sum()).astype(np.float32)


# ----------------------------------------------------------------------------
# energy_albedo_entropy
# ----------------------------------------------------------------------------

class EntropyScratch(NamedTuple):
    """Preallocated backend arrays of ``entropy_term``, laid out by :func:`entropy_scratch_layout`.

    hist, tmp, blurred : float32 (T, B, B, B); row_flags : int32 (2, T, B, B);
    dots : float64 (T,).
    """

    hist: Any
    row_flags: Any
    tmp: Any
    blurred: Any
    dots: Any


def allocate_entropy_scratch_with(empty, n_frames: int, bins: int) -> EntropyScratch:
    """:class:`EntropyScratch` for ``n_frames`` frames and a ``bins^3`` cube, each field made by
    ``empty(shape, numpy_dtype)`` (a backend's allocator); ``n_frames >= 1``, ``bins >= 2``."""
    n_frames = check_int("n_frames", n_frames, 1)
    bins = check_int("bins", bins, 2)
    cube = (n_frames, bins, bins, bins)
    return EntropyScratch(hist=empty(cube, np.float32), row_flags=empty((2, n_frames, bins, bins), np.int32),
                          tmp=empty(cube, np.float32), blurred=empty(cube, np.float32),
                          dots=empty((n_frames,), np.float64))


def run_entropy_steps(family, A, whiten, lo: float, h: float, taps, sigma_p: float, scratch,
                      gA, energy_rows, lam: float) -> None:
    """Eq. 12's energy and gradient by the five host functions of a backend's ``energy_albedo_entropy``
    module ``family``: histogram, blur, dot, sliced gradient, energy (``entropy_term`` of every backend).

    ``A`` (T, H, W, 3) has been checked by the caller; ``scratch`` must be an
    :class:`EntropyScratch` (TypeError otherwise).
    """
    if not isinstance(scratch, EntropyScratch):
        raise TypeError(f"scratch must be an EntropyScratch (allocate_entropy_scratch), "
                        f"got {type(scratch).__name__}")
    family.entropy_histogram(A, whiten, lo, h, scratch.hist, scratch.row_flags)
    family.entropy_blur(scratch.hist, taps, scratch.row_flags, scratch.tmp, scratch.blurred)
    family.entropy_dot(scratch.hist, scratch.blurred, scratch.dots)
    family.entropy_slice_gradient(A, whiten, lo, h, scratch.blurred, scratch.dots, gA, lam)
    family.entropy_energy(scratch.dots, sigma_p, A.shape[1] * A.shape[2], energy_rows, lam)


# ----------------------------------------------------------------------------
# median
# ----------------------------------------------------------------------------

#: Lloyd iterations of the 2-means split of a window's flow vectors (surf of Eq. 10).
KMEANS_ITERATIONS = 8
#: Final cluster centres closer than this (pixels) mean "no motion boundary in the window".
MIN_SEPARATION = 0.5


def median_network(n: int = 25) -> list:
    """Compare-exchange pairs ``(i, j)``, ``i < j``, after which wire ``n // 2``
    holds the median of ``n`` (odd) inputs.

    Batcher's odd-even merge sort on the next power of two, with the padding
    wires taken as +inf (their comparators are no-ops and dropped) and every
    comparator that cannot reach the middle wire pruned: 113 pairs for n = 25.
    Branch-free, so much faster than a selection loop on random data.
    """
    size = 1
    while size < n:
        size *= 2
    pairs = []
    p = 1
    while p < size:
        k = p
        while k >= 1:
            for j in range(k % p, size - k, 2 * k):
                for i in range(min(k, size - j - k)):
                    if (i + j) // (2 * p) == (i + j + k) // (2 * p) and i + j + k < n:
                        pairs.append((i + j, i + j + k))
            k //= 2
        p *= 2
    needed = {n // 2}
    kept = []
    for i, j in reversed(pairs):
        if i in needed or j in needed:
            kept.append((i, j))
            needed |= {i, j}
    return kept[::-1]


def spatial_weights(radius: int, sigma: float) -> np.ndarray:
    """``exp(-|d|^2 / (2 sigma^2))`` over the (2r+1)^2 window offsets ``d``, row-major.

    The spatial factor of the shading median's weights (Eq. 10); float32
    ``((2r+1)^2,)``, 1 at the centre.
    """
    d = np.arange(-radius, radius + 1, dtype=np.float64)
    return np.exp(-(d[:, None] ** 2 + d[None, :] ** 2) / (2.0 * sigma * sigma)).astype(np.float32).ravel()


def shading_scratch_shape(S_shape: tuple, radius: int) -> tuple:
    """Shape of the float32 scratch of ``weighted_median_shading``: ``(T*H, 2*(2r+1)^2)``."""
    return (S_shape[0] * S_shape[1], 2 * (2 * radius + 1) ** 2)


def flow_scratch_shape(flow_shape: tuple, radius: int) -> tuple:
    """Shape of the float32 scratch of ``weighted_median_flow``: ``(T*H, 3*(2r+1)^2)``."""
    return (flow_shape[0] * flow_shape[1], 3 * (2 * radius + 1) ** 2)


# ----------------------------------------------------------------------------
# coarse_basis
# ----------------------------------------------------------------------------

#: The affinity's exponent is clamped here, so no weight underflows in float32.
MAX_EXPONENT = 30.0


def grid_shape(h: int, w: int, spacing: int) -> tuple[int, int]:
    """Nodes ``(Hc, Wc)`` of an ``h x w`` frame with nodes every ``spacing`` pixels: node
    ``j`` sits on pixel row ``min(j * spacing, h - 1)``, and the grid reaches one node past
    the last pixel, so every pixel has nodes on both sides."""
    return (h - 1) // spacing + 2, (w - 1) // spacing + 2
