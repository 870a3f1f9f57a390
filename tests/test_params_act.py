"""Every field of :class:`ivkernels.Params` changes the result of a small decompose.

Each field is moved from a small, fast base setting to another valid value
and the albedo and shading compared with the base's (each backend is
bit-identical run to run, so any difference is the field's doing).  Some
fields act only with others (the colour term's sigma_e only with
occlusion_colour on) or only on some inputs (the overlap only with more than
one window, the guide's settings only when the flow is estimated): each is
moved in a context where it acts, stated in :data:`MOVES`.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import ivkernels as iv
from ivkernels.evaluation import synthetic
from ivkernels.params import Params

#: Fast base: two pyramid levels at 24x32, three windows over five frames.
BASE = Params(window=3, overlap=2, pyramid_min_size=12, outer_iterations=2, lbfgs_iterations=6,
              lbfgs_iterations_coarse=30, guide_lbfgs_iterations=4)

#: field -> (new value, extra changes to both runs, flow: "truth" (the ground truth, of
#: objects_camera unless another kind follows the colon) or an estimated method (on
#: objects_camera unless another kind follows the colon))
MOVES = {
    "eps_shading": (0.05, {}, "truth"),
    "lam_temporal_albedo": (5.0, {}, "truth"),
    "lam_temporal_shading": (50.0, {}, "truth"),
    "tukey_alpha": (0.05, {}, "truth"),
    "sigma_e": (2.0, {"occlusion_colour": True}, "truth"),
    "occlusion_colour": (True, {"sigma_e": 2.0}, "truth"),
    "sigma_d": (0.01, {}, "truth"),
    "occlusion_threshold": (0.99, {}, "truth"),
    "warp_spread_max": (0.001, {}, "truth"),
    "chroma_change_max": (0.01, {}, "truth"),
    "luminance_change_max": (0.01, {}, "truth"),
    "luminance_change_radius": (1, {}, "truth"),
    "boundary_threshold": (0.01, {}, "truth"),
    "boundary_radius": (0, {}, "truth"),
    "lam_shading_local": (1.0, {}, "truth"),
    "shading_cut_threshold": (0.05, {}, "truth"),
    "shading_step_stability_changing_light": (False, {}, "truth"),
    "shading_gate_tau": (0.2, {}, "truth"),
    "shading_gate_chroma": (0.05, {"shading_gate_tau": 0.2}, "truth"),
    "shading_step_gain": (0.0, {}, "truth"),
    "shading_step_tau": (0.02, {}, "truth"),
    "shading_step_chroma": (0.0, {}, "truth"),
    "shading_step_share_radius": (0.0, {}, "truth"),
    "shading_step_noise": (0.0, {}, "truth"),
    "shading_step_noise_cap": (0.5, {}, "truth"),
    # Weiss's cue is read where the scene holds still: a static scene under a moving light
    "shading_step_stability": (0.0, {"shading_step_stability_changing_light": False}, "truth:static_moving_light"),
    "shading_step_static_flow": (0.01, {"shading_step_stability_changing_light": False}, "truth:objects_camera"),
    # the stable steps' pairs act where the light changes over a still scene
    "shading_stable_gain": (0.0, {}, "truth:relit"),
    "shading_stable_spread": (0.5, {}, "truth:relit"),
    "shading_stable_floor": (0.0, {}, "truth:relit"),
    "shading_light_edge_tau": (0.0, {}, "truth:relit"),
    "shading_light_edge_spread": (0.5, {}, "truth:relit"),
    # ... and the switches that read them under a still light too (objects turning over a still floor)
    "shading_stable_changing_light": (False, {}, "truth:rotating_shadows"),
    "shading_light_edge_changing_light": (True, {}, "truth:rotating_shadows"),
    "shading_light_edge_spread_changing_light": (False, {"shading_light_edge_spread": 2.0},
                                                 "truth:rotating_shadows"),
    "lam_shading_nonlocal": (10.0, {}, "truth"),
    "lam_coupling": (1000.0, {}, "truth"),
    "sigma_s": (1.0, {}, "truth"),
    "nonlocal_radius": (2, {}, "truth"),
    "lam_albedo_smooth": (10.0, {}, "truth"),
    # the entropy term costs 3-4x a solve (Params' docstring): a short solve
    "lam_albedo_sparsity": (1.0, {"outer_iterations": 1, "lbfgs_iterations": 2, "lbfgs_iterations_coarse": 2,
                                  "start_from_guide": False, "window": 5}, "truth"),
    # the number of independent shadings grows with the light's change: a relit scene
    "independent_shading_gain": (0.0, {}, "truth:relit"),
    "pyramid_scale": (0.7, {}, "truth"),
    # the coarse levels are solved only without the guide's start (which enters below them)
    "pyramid_min_size": (20, {"start_from_guide": False}, "truth"),
    "outer_iterations": (1, {}, "truth"),
    "lbfgs_iterations": (5, {}, "truth"),
    "lbfgs_iterations_coarse": (5, {"start_from_guide": False}, "truth"),
    "lbfgs_level_growth": (3.0, {"start_from_guide": False}, "truth"),
    "lbfgs_memory": (1, {}, "truth"),
    "coarse_basis_spacing": (0, {}, "truth"),
    "coarse_basis_levels": (1, {"coarse_basis_spacing": 2}, "truth"),
    "coarse_basis_sigma": (0.05, {}, "truth"),
    "init_blur": (0.3, {}, "truth"),
    "log_floor": (0.05, {}, "truth"),
    "flow_guide_scale": (1.0, {}, "truth"),
    "guide_lbfgs_iterations": (1, {}, "truth"),
    "start_from_guide": (False, {}, "truth"),
    "first_flow_at_guide_size": (False, {}, "classic_nl_fast"),
    "flow_refine_warps": (1, {}, "classic_nl_fast"),
    "flow_refine_guide_min_side": (1, {}, "classic_nl_fast"),
    "flow_round_trip_max": (0.5, {}, "classic_nl_fast"),
    "flow_round_trip_scale": (1.0, {"flow_round_trip_max": 0.5}, "classic_nl_fast"),
    "flow_still_surface_tau": (0.0, {}, "classic_nl_fast:rotating_shadows"),
    "flow_still_surface_share": (1.0, {"flow_still_small": 0.0}, "classic_nl_fast:rotating_shadows"),
    "flow_still_small": (0.0, {}, "classic_nl_fast:rotating_shadows"),
    "window": (4, {}, "truth"),
    "overlap": (1, {}, "truth"),
    # the layers are smoothed only where the frames are noisy
    "layer_denoise": (0.0, {}, "truth:noisy"),
}

#: Fields that change no result, and why.  The data term (Eq. 3) is a hard
#: constraint, A = I - S (ivkernels.solver.energy.ConstrainedEnergy): its
#: Charbonnier eps and the luminance weight's eps only set the data term's
#: energy reported in diagnostics["terms"]["data"].
INERT = {"eps_data": 0.01, "lum_eps": 0.01}


_sequences: dict = {}
_cache: dict = {}


def _sequence(kind: str):
    """``(frames, true flow)`` of a synthetic kind, "relit": a static scene whose light
    pattern changes strongly from frame to frame, or "noisy": objects_camera with noise."""
    if kind not in _sequences:
        seq = synthetic.render_sequence("objects_camera" if kind in ("relit", "noisy") else kind, n_frames=5,
                                        size=(24, 32), seed=4, noise=("gaussian", 0.03) if kind == "noisy" else None)
        frames, flow = seq.frames, seq.flow
        if kind == "relit":
            T, H, W, _ = frames.shape
            y, x = np.mgrid[0:H, 0:W] / max(H, W)
            light = np.stack([0.25 + 0.75 * (0.5 + 0.5 * np.sin(6 * (x * np.cos(a) + y * np.sin(a))))
                              for a in np.linspace(0, np.pi, T)])
            frames = (np.repeat(frames[:1], T, axis=0) * light[..., None]).astype(np.float32)
            flow = np.zeros_like(flow)
        _sequences[kind] = (frames, flow)
    return _sequences[kind]


def _run(params: Params, flow: str):
    key = (params, flow)
    if key not in _cache:
        if flow.startswith("truth"):
            frames, true_flow = _sequence(flow.partition(":")[2] or "objects_camera")
            out = iv.decompose(frames, flow=true_flow, params=params)
        else:
            method, _, kind = flow.partition(":")
            out = iv.decompose(_sequence(kind or "objects_camera")[0], flow=method, flow_passes=2, params=params)
        _cache[key] = out
    return _cache[key]


def _differs(a, b) -> float:
    return max(float(np.abs(a.albedo - b.albedo).max()), float(np.abs(a.shading - b.shading).max()))


def test_every_field_is_moved_or_named_inert():
    names = {f.name for f in dataclasses.fields(Params)}
    assert set(MOVES) | set(INERT) == names, sorted(names ^ (set(MOVES) | set(INERT)))
    assert not hasattr(Params(), "__dataclass_fields__") or "lam_data" not in Params.__dataclass_fields__


def test_lam_data_is_no_setting():
    with pytest.raises(TypeError):
        Params(lam_data=1.0)
    with pytest.raises(TypeError, match="unknown parameter"):
        Params().replace(lam_data=1.0)
    assert Params().lam_data == 10.0          # the paper's weight, read by the reported energy


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(MOVES))
def test_field_changes_the_result(name):
    value, context, flow = MOVES[name]
    base = BASE.replace(**context)
    assert getattr(base, name) != value
    moved = base.replace(**{name: value})
    before, after = _run(base, flow), _run(moved, flow)
    if name == "independent_shading_gain":
        assert max(before.diagnostics["independent_shadings"]) > 1.5      # the input is relit
    diff = _differs(before, after)
    assert diff > 1e-5, f"Params.{name} = {value} changes nothing (max difference {diff})"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(INERT))
def test_inert_fields_change_only_the_reported_data_energy(name):
    base = _run(BASE, "truth")
    moved = _run(BASE.replace(**{name: INERT[name]}), "truth")
    assert _differs(base, moved) == 0.0
