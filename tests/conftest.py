"""Shared fixtures: every kernel battery runs on every backend present."""
import numpy as np
import pytest

from ivkernels.backends import available_backends


def pytest_generate_tests(metafunc):
    if "backend" in metafunc.fixturenames:
        backends = available_backends()
        metafunc.parametrize("backend", backends, ids=[f"{b.name}-{b.device}" for b in backends])


@pytest.fixture
def rng():
    return np.random.default_rng(0)
