"""Shared by the GPU-layout tests: the GPU's launch layouts forced on the CPU.

``FORCE_GPU_LAYOUT_TILES`` (:mod:`ivkernels.kernels.launch`) switches the
kernels' GPU layouts on for the CPU: rows cut into :data:`TILES` uneven tiles,
one thread per (row, chunk) cell of a reduction, the vector operations in the
GPU's chunks.
"""
from ivkernels.kernels import launch

TILES = 3


def both_layouts(monkeypatch, call):
    """``call()`` (NumPy arrays out) with the CPU layout, then with the GPU's (one launch thread)."""
    with launch.threads(1):
        cpu = call()
        monkeypatch.setattr(launch, "FORCE_GPU_LAYOUT_TILES", TILES)
        gpu = call()
        monkeypatch.setattr(launch, "FORCE_GPU_LAYOUT_TILES", None)
    return cpu, gpu
