"""``energy_albedo_entropy`` on the NumPy backend: the steps of
:mod:`ivkernels.kernels.reference.energy_albedo_entropy` written into the scratch and outputs.

``row_flags`` plane 0 marks every histogram row that received mass, as on
the other backends; the blur here reads the whole cube and leaves plane 1 at 0.
"""
from __future__ import annotations

import sys

import numpy as np

from ivkernels.kernels.checks import check_float, check_int
from ivkernels.kernels.host import EntropyScratch, allocate_entropy_scratch_with, run_entropy_steps
from ivkernels.kernels.numpy._adapt import add, arrays, check_disjoint, write
from ivkernels.kernels.reference import energy_albedo_entropy as ref


def allocate_entropy_scratch(n_frames: int, bins: int, device="cpu") -> EntropyScratch:
    """:class:`~ivkernels.kernels.host.EntropyScratch` of NumPy arrays for ``n_frames`` frames, ``bins^3`` bins."""
    if device != "cpu":
        raise ValueError(f"the numpy backend runs on device='cpu' only, got {device!r}")
    return allocate_entropy_scratch_with(np.empty, n_frames, bins)


def _cube(name: str, a) -> int:
    arrays(**{name: a})
    if a.ndim != 4 or not a.shape[1] == a.shape[2] == a.shape[3] >= 2:
        raise ValueError(f"{name} must have shape (T, B, B, B) with B >= 2, got {a.shape}")
    return a.shape[1]


def entropy_histogram(A, whiten, lo: float, h: float, hist, row_flags) -> None:
    """Overwrite ``hist`` (T, B, B, B) with the splat of ``W A`` (A (T, H, W, 3)); flag rows in ``row_flags``."""
    arrays(A=A, whiten=whiten)
    bins = _cube("hist", hist)
    cube = ref.entropy_histogram(A, whiten, check_float("lo", lo), check_float("h", h, positive=True), bins)
    write("hist", hist, cube)
    arrays(np.int32, row_flags=row_flags)
    write("row_flags", row_flags, np.stack([(cube > 0).any(axis=-1), np.zeros(cube.shape[:3], bool)]))


def entropy_blur(hist, taps, row_flags, tmp, blurred) -> None:
    """``blurred = G * hist`` per frame (T, B, B, B), ``G`` separable with the odd-length ``taps``."""
    _cube("hist", hist)
    arrays(taps=taps, tmp=tmp)
    check_disjoint("tmp", tmp, "hist", hist, "the blur reads neighbours of hist while writing tmp")
    check_disjoint("blurred", blurred, "hist", hist, "the blur reads neighbours of hist while writing blurred")
    if taps.ndim != 1 or taps.shape[0] % 2 != 1:
        raise ValueError(f"taps must have an odd length 2r+1, got shape {taps.shape}")
    arrays(np.int32, row_flags=row_flags)
    row_flags[1] = 0
    write("blurred", blurred, ref.entropy_blur(hist, taps))


def entropy_dot(hist, blurred, dots) -> None:
    """Overwrite ``dots`` float64 (T,) with ``<hist_t, blurred_t>``."""
    _cube("hist", hist)
    arrays(blurred=blurred)
    arrays(np.float64, dots=dots)
    write("dots", dots, ref.entropy_dot(hist, blurred))


def entropy_slice_gradient(A, whiten, lo: float, h: float, blurred, dots, gA, lam: float) -> None:
    """Add Eq. 12's gradient into ``gA`` (T, H, W, 3)."""
    arrays(A=A, whiten=whiten)
    _cube("blurred", blurred)
    arrays(np.float64, dots=dots)
    check_disjoint("gA", gA, "A", A, "the gradient is scattered into gA while A is read")
    add("gA", gA, ref.entropy_slice_gradient(A, whiten, check_float("lo", lo), check_float("h", h, positive=True),
                                             blurred, dots, check_float("lam", lam)))


def entropy_energy(dots, sigma_p: float, n_pixels: int, energy_rows, lam: float) -> None:
    """Add ``E_t`` into ``energy_rows[t * (len(energy_rows) // T)]``."""
    arrays(np.float64, dots=dots, energy_rows=energy_rows)
    T = dots.shape[0]
    if T == 0 or energy_rows.ndim != 1 or energy_rows.shape[0] % T:
        raise ValueError(f"energy_rows length {energy_rows.shape} is not a multiple of T = {T}")
    add("energy_rows", energy_rows,
        ref.entropy_energy(dots, check_float("sigma_p", sigma_p, positive=True), check_int("n_pixels", n_pixels, 1),
                           check_float("lam", lam), energy_rows.shape[0] // T))


def entropy_term(A, whiten, lo: float, h: float, taps, sigma_p: float, scratch: EntropyScratch,
                 gA, energy_rows, lam: float) -> None:
    """Add Eq. 12's energy and gradient for every frame of ``A`` (T, H, W, 3); ``scratch`` is overwritten."""
    arrays(A=A)
    if A.ndim != 4:
        raise ValueError(f"A must have shape (T, H, W, 3), got {A.shape}")
    check_disjoint("gA", gA, "A", A, "the gradient is scattered into gA while A is read")
    run_entropy_steps(sys.modules[__name__], A, whiten, lo, h, taps, sigma_p, scratch, gA, energy_rows, lam)


