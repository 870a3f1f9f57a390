"""The three backends (Warp, Taichi, NumPy) give one result once the solve converges.

With the default budgets every level stops on its iteration budget, and the
default tolerance (:data:`ivkernels.solver.lbfgs.REL_TOL`, a relative energy
change of 1e-6 per step) stops runs in the energy's flat valleys, where the
backends' float32 rounding leaves them percents apart.  Run to convergence
(tolerance 1e-10, budgets that are never reached) they agree.

One alternation (``outer_iterations=1``): the S~ update between alternations
is a weighted median (Eq. 13), a discrete choice that rounding-level
differences in S can tip at ties, so a second alternation starts each
backend from a slightly different problem (measured: 0.06% Warp-Taichi, 0.6%
NumPy-Warp on this input; perf/RESULTS.md, "Backends agree once converged").

Sixty-four L-BFGS pairs (``lbfgs_memory=64``): with fewer the tolerance
stops each backend on a slow mode of the step-evidence-gated energy, above
the minimum and apart (with ``Params.shading_step_static_flow = 1``, four
pairs: energies 255391, 255391 and 255366 against 255191 for all three with
sixteen pairs; with ``Params.shading_step_share_radius = 0.1``, whose share
window is under 2 px on this 16x24 input, sixteen pairs stop at 255718.4-.6
with NumPy 0.59% from the others, thirty-two reach 255717.6 within 0.15%;
with the noise floor capped at the noise level function,
``Params.shading_step_noise_cap = 3``, the floors agree to 3e-7 but thirty-two
pairs stop at 256561.54 / .66 / .63 with NumPy 0.54% from Warp, sixty-four
at 256561.55 / .59 / .58 within 0.41%).
"""
from __future__ import annotations

import numpy as np
import pytest

import ivkernels as iv
from ivkernels.backends import available_backends
from ivkernels.evaluation import synthetic
from ivkernels.params import Params
from ivkernels.solver import lbfgs

CONVERGE = Params(lbfgs_iterations=3000, lbfgs_iterations_coarse=3000, outer_iterations=1,
                  start_from_guide=False, lbfgs_memory=64)


def _relative(a, b) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@pytest.mark.slow
def test_backends_agree_within_half_a_percent_when_converged(monkeypatch):
    names = sorted({be.name for be in available_backends(oracles=True) if be.device == "cpu"})
    assert {"warp", "numpy"} <= set(names)
    seq = synthetic.render_sequence("objects_camera", n_frames=2, size=(16, 24), seed=1)
    monkeypatch.setattr(lbfgs, "REL_TOL", 1e-10)
    out = {}
    for name in names:
        out[name] = iv.decompose(seq.frames, flow=seq.flow, backend=name, params=CONVERGE)
        assert all(level["stop_reasons"] == ["tolerance"] for level in out[name].diagnostics["levels"]), name
    for a in names:
        for b in names:
            if a < b:
                assert _relative(out[a].albedo, out[b].albedo) < 0.005, (a, b)
                assert _relative(out[a].shading, out[b].shading) < 0.005, (a, b)


def test_default_tolerance_is_unchanged():
    """The tolerance of every default solve (results stay bitwise as before)."""
    assert lbfgs.REL_TOL == 1e-6
