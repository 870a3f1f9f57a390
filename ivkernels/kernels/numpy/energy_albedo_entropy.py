"""``energy_albedo_entropy`` on the NumPy backend: the steps of
:mod:`ivkernels.kernels.reference.energy_albedo_entropy` written into the scratch and outputs.

Written out rather than derived from the case table (:mod:`ivkernels.kernels.numpy`):
the cases check each step against the whole chain from the albedo, not as a
function of the step's own arguments.

``row_flags`` plane 0 marks every histogram row that received mass, as on
the other backends; the blur here reads the whole cube and leaves plane 1 at 0.
"""
from __future__ import annotations

import sys

import numpy as np

from ivkernels.kernels.contract import implements
from ivkernels.kernels.host import EntropyScratch, allocate_entropy_scratch_with, run_entropy_steps
from ivkernels.kernels.ndarray_checks import FRONT
from ivkernels.kernels.reference import energy_albedo_entropy as ref

host = implements(ref.FAMILY, FRONT)


def allocate_entropy_scratch(n_frames: int, bins: int, device="cpu") -> EntropyScratch:
    """:class:`~ivkernels.kernels.host.EntropyScratch` of NumPy arrays for ``n_frames`` frames, ``bins^3`` bins."""
    if device != "cpu":
        raise ValueError(f"the numpy backend runs on device='cpu' only, got {device!r}")
    return allocate_entropy_scratch_with(np.empty, n_frames, bins)


@host("entropy_histogram")
def entropy_histogram(A, whiten, lo: float, h: float, hist, row_flags) -> None:
    """Overwrite ``hist`` (T, B, B, B) with the splat of ``W A`` (A (T, H, W, 3)); flag rows in ``row_flags``."""
    cube = ref.entropy_histogram(A, whiten, lo, h, hist.shape[1])
    hist[...] = cube
    row_flags[...] = np.stack([(cube > 0).any(axis=-1), np.zeros(cube.shape[:3], bool)])


@host("entropy_blur")
def entropy_blur(hist, taps, row_flags, tmp, blurred) -> None:
    """``blurred = G * hist`` per frame (T, B, B, B), ``G`` separable with the odd-length ``taps``."""
    row_flags[1] = 0
    blurred[...] = ref.entropy_blur(hist, taps)


@host("entropy_dot")
def entropy_dot(hist, blurred, dots) -> None:
    """Overwrite ``dots`` float64 (T,) with ``<hist_t, blurred_t>``."""
    dots[...] = ref.entropy_dot(hist, blurred)


@host("entropy_slice_gradient")
def entropy_slice_gradient(A, whiten, lo: float, h: float, blurred, dots, gA, lam: float) -> None:
    """Add Eq. 12's gradient into ``gA`` (T, H, W, 3)."""
    gA += ref.entropy_slice_gradient(A, whiten, lo, h, blurred, dots, lam).astype(gA.dtype, copy=False)


@host("entropy_energy")
def entropy_energy(dots, sigma_p: float, n_pixels: int, energy_rows, lam: float) -> None:
    """Add ``E_t`` into ``energy_rows[t * (len(energy_rows) // T)]``."""
    energy_rows += np.asarray(ref.entropy_energy(dots, sigma_p, n_pixels, lam, energy_rows.shape[0] // dots.shape[0]))


@host("entropy_term")
def entropy_term(A, whiten, lo: float, h: float, taps, sigma_p: float, scratch: EntropyScratch,
                 gA, energy_rows, lam: float) -> None:
    """Add Eq. 12's energy and gradient for every frame of ``A`` (T, H, W, 3); ``scratch`` is overwritten."""
    run_entropy_steps(sys.modules[__name__], A, whiten, lo, h, taps, sigma_p, scratch, gA, energy_rows, lam)


