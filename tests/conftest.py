"""Shared fixtures: every kernel battery runs on every registered backend present.

The ``backend`` parameter holds the backends of the registry
(:func:`ivkernels.backends.available_backends`) except the oracles: the
batteries compare each backend with the NumPy references, and the ``numpy``
backend *is* those references.  ``any_backend`` holds them all.
"""
import numpy as np
import pytest

from ivkernels.backends import available_backends


def pytest_generate_tests(metafunc):
    for fixture, oracles in (("backend", False), ("any_backend", True)):
        if fixture in metafunc.fixturenames:
            backends = available_backends(oracles=oracles)
            metafunc.parametrize(fixture, backends, ids=[f"{b.name}-{b.device}" for b in backends])


@pytest.fixture
def rng():
    return np.random.default_rng(0)


@pytest.fixture
def frames8():
    """Three random 16x16 sRGB uint8 frames (the input-contract batteries' input)."""
    return np.random.default_rng(0).integers(0, 256, (3, 16, 16, 3), dtype=np.uint8)


@pytest.fixture
def image_folder(tmp_path, frames8):
    """``frames8`` written as a folder of PNGs (overridden where a test file needs another)."""
    from ivkernels.io import write_png_sequence

    folder = tmp_path / "frames"
    write_png_sequence(folder, frames8)
    return folder
