"""Cases of :mod:`ivkernels.kernels.warp.flow_classic` (Classic+NL optical flow: pre-processing,
robust data terms, IRLS system, red-black SOR, edges)."""
from __future__ import annotations

import numpy as np

from ivkernels.kernels.cases import EXACT, Case, Tol
from ivkernels.kernels.cases.inputs import F32, nans, normal, uniform
from ivkernels.kernels.reference import flow_classic as ref

FC = "flow_classic"
ROBUST = ("blend", "a", "eps", "quad_frac", "quad_weight")     # trailing parameters of the data terms


def brightness_system(rng, T, H, W):
    """First image (grey 0-255), its derivatives, the warped second image with its derivatives
    (noisy copies), an inside mask, a flow of a few pixels and an increment ``du``."""
    i1 = uniform(rng, (T, H, W), 0.0, 255.0)
    i1x, i1y = normal(rng, (T, H, W), 0.0, 20.0), normal(rng, (T, H, W), 0.0, 20.0)
    warped = np.stack([i1 + rng.normal(0, 5, (T, H, W)), i1x + rng.normal(0, 3, (T, H, W)),
                       i1y + rng.normal(0, 3, (T, H, W))], -1).astype(F32)
    return {"i1": i1, "i1x": i1x, "i1y": i1y, "warped": warped,
            "inside": (rng.random((T, H, W)) > 0.1).astype(F32), "flow": normal(rng, (T, H, W, 2), 0.0, 2.0),
            "du": normal(rng, (T, H, W, 2), 0.0, 0.3)}


def irls_system(rng, T, H, W, lam=3.0):
    """Data coefficients, smoothness weights and the assembled system of a random problem (float32)."""
    s = brightness_system(rng, T, H, W)
    zero = np.zeros((T, H, W, 2), F32)
    data = ref.data_coefficients(s["i1"], s["i1x"], s["i1y"], s["warped"], s["inside"], zero).astype(F32)
    smooth = ref.smoothness_weights(s["flow"], zero).astype(F32)
    return {"flow": s["flow"], "data": data, "smooth": smooth,
            "system": ref.assemble_system(s["flow"], data, smooth, lam).astype(F32)}


def _simple(function, make, call, outputs, reference, **kw):
    return Case(FC, function, make, call, outputs, reference, **kw)


def _srgb_grey(rng, T, H, W):
    return {"rgb": uniform(rng, (T, H, W, 3), -0.1, 1.1), "out": nans((T, H, W))}


def _log_grey(rng, T, H, W):
    rgb = uniform(rng, (T, H, W, 3))
    rgb[:, :1, :3] = 0.0                                       # below the floor
    return {"rgb": rgb, "out": nans((T, H, W)), "floor": 1e-3}


def _row_min_max(rng, T, H, W):
    return {"src": normal(rng, (T, H, W, 3)), "out": nans((T * H, 3, 2))}


def _scale_shift(rng, T, H, W):
    return {"src": normal(rng, (T, H, W, 3)), "out": nans((T, H, W, 3)),
            "scale": np.array([2.0, -1.0, 0.5], F32), "shift": np.array([1.0, 0.0, -3.0], F32)}


def _rof(rng, T, H, W):
    return {"img": uniform(rng, (T, H, W), -1.0, 1.0), "p_in": uniform(rng, (T, H, W, 2), -0.7, 0.7),
            "p_out": nans((T, H, W, 2)), "theta": 0.125, "delta": 2.0}


def _rof_texture(rng, T, H, W):
    return {"img": uniform(rng, (T, H, W), -1.0, 1.0), "p": uniform(rng, (T, H, W, 2), -0.7, 0.7),
            "out": nans((T, H, W)), "theta": 0.125, "alpha": 0.95}


def _pack_image_gradient(rng, T, H, W):
    return {"img": normal(rng, (T, H, W)), "gx": normal(rng, (T, H, W)), "gy": normal(rng, (T, H, W)),
            "out": nans((T, H, W, 3))}


def _pack_gradient(rng, T, H, W):
    return {"gx": normal(rng, (T, H, W)), "gy": normal(rng, (T, H, W)), "out": nans((T, H, W, 2))}


def _data_coefficients(quad_frac):
    def make(rng, T, H, W):
        s = brightness_system(rng, T, H, W)
        return {**s, "out": nans((T, H, W, 5)), "blend": 0.5, "a": 0.45, "eps": 1e-3, "quad_frac": quad_frac,
                "quad_weight": 2.0}

    return Case(FC, "data_coefficients", make, ("i1", "i1x", "i1y", "warped", "inside", "du", "out", *ROBUST),
                ("out",), lambda v: {"out": ref.data_coefficients(*(v[k] for k in (
                    "i1", "i1x", "i1y", "warped", "inside", "du", *ROBUST)))},
                variant=f"quad_frac={quad_frac:g}", tol=Tol(2e-4, 0.0, 1e-4))


def _soft_census(radius):
    def make(rng, T, H, W):
        c = (2 * radius + 1) ** 2 - 1
        return {"img": uniform(rng, (T, H, W), 0.0, 255.0), "out": nans((T, H, W, c)), "radius": radius,
                "eps": 6.0, "scale": 3.0}

    return Case(FC, "soft_census", make, ("img", "out", "radius", "eps", "scale"), ("out",),
                lambda v: {"out": ref.soft_census(v["img"], v["radius"], v["eps"], v["scale"])},
                variant=f"radius={radius}", tol=Tol(1e-5, 1e-5))


def _pack_channels_gradient(rng, T, H, W):
    return {"feat": normal(rng, (T, H, W, 5)), "gx": normal(rng, (T, H, W, 5)), "gy": normal(rng, (T, H, W, 5)),
            "out": nans((T, H, W, 15))}


def _data_coefficients_channels(channels, quad_frac):
    def make(rng, T, H, W):
        first = normal(rng, (T, H, W, 3 * channels), 0.0, 20.0)
        return {"first": first, "warped": (first + rng.normal(0, 4, first.shape)).astype(F32),
                "inside": (rng.random((T, H, W)) > 0.1).astype(F32), "du": normal(rng, (T, H, W, 2), 0.0, 0.3),
                "weights": uniform(rng, channels, 0.2, 2.0), "out": nans((T, H, W, 5)), "blend": 0.5, "a": 0.45,
                "eps": 1e-3, "quad_frac": quad_frac, "quad_weight": 2.0}

    return Case(FC, "data_coefficients_channels", make, ("first", "warped", "inside", "du", "weights", "out", *ROBUST),
                ("out",), lambda v: {"out": ref.data_coefficients_channels(*(v[k] for k in (
                    "first", "warped", "inside", "du", "weights", *ROBUST)))},
                variant=f"C={channels},quad_frac={quad_frac:g}", tol=Tol(3e-4, 0.0, 1e-4))


def _smoothness_weights(quad_frac):
    def make(rng, T, H, W):
        s = brightness_system(rng, T, H, W)
        flow, du = s["flow"], s["du"]
        flow[:1, H // 2: H // 2 + 1, W // 4: W // 4 + 4] = 1.25    # exact zero differences reach the eps floor
        du[:1, H // 2: H // 2 + 1, W // 4: W // 4 + 4] = 0.0
        return {"flow": flow, "du": du, "out": nans((T, H, W, 4)), "a": 0.45, "eps": 1e-3,
                "quad_frac": quad_frac, "quad_weight": 2.0}

    return Case(FC, "smoothness_weights", make, ("flow", "du", "out", "a", "eps", "quad_frac", "quad_weight"),
                ("out",), lambda v: {"out": ref.smoothness_weights(*(v[k] for k in (
                    "flow", "du", "a", "eps", "quad_frac", "quad_weight")))},
                variant=f"quad_frac={quad_frac:g}", tol=Tol(2e-4, 1e-7))


def _assemble(rng, T, H, W):
    s = irls_system(rng, T, H, W)
    return {"flow": s["flow"], "data": s["data"], "smooth": s["smooth"], "lam": 3.0, "out": nans((T, H, W, 5))}


def _sor(parity):
    def make(rng, T, H, W):
        s = irls_system(rng, T, H, W)
        return {"du": normal(rng, (T, H, W, 2), 0.0, 0.3), "system": s["system"], "smooth": s["smooth"],
                "lam": 3.0, "omega": 1.7, "parity": parity}

    return Case(FC, "sor_sweep", make, ("du", "system", "smooth", "lam", "omega", "parity"), ("du",),
                lambda v: {"du": ref.sor_sweep(v["du"], v["system"], v["smooth"], v["lam"], v["omega"], v["parity"])},
                variant=f"parity={parity}", updates=("du",), tol=Tol(1e-3, 1e-4))


def _sor_full(rng, T, H, W):
    s = irls_system(rng, T, H, W)
    return {"du": normal(rng, (T, H, W, 2), 0.0, 0.3), "system": s["system"], "smooth": s["smooth"],
            "lam": 3.0, "omega": 1.7}


def _apply_update(limit):
    def make(rng, T, H, W):
        return {"flow": normal(rng, (T, H, W, 2), 0.0, 2.0), "du": normal(rng, (T, H, W, 2), 0.0, 3.0),
                "out": nans((T, H, W, 2)), "limit": limit}

    return Case(FC, "apply_update", make, ("flow", "du", "out", "limit"), ("out",),
                lambda v: {"out": ref.apply_update(v["flow"], v["du"], v["limit"])}, variant=f"limit={limit:g}",
                tol=Tol(0.0, 1e-5), in_place=(("flow", "out"),))


def _select_masked(rng, T, H, W):
    return {"mask": (rng.random((T, H, W)) > 0.5).astype(F32), "inside_mask": normal(rng, (T, H, W, 2)),
            "outside_mask": normal(rng, (T, H, W, 2)), "out": nans((T, H, W, 2))}


def _sobel_components(rng, T, H, W):
    return {"flow": normal(rng, (T, H, W, 2), 0.0, 2.0), "out": nans((T, H, W, 4)),
            "row_energy": nans((T * H, 2))}


def _thin_edges(rng, T, H, W):
    f = normal(rng, (T, H, W, 2))
    sobel, energy = ref.flow_sobel_components(f) if f.size else (np.zeros((T, H, W, 4)), np.zeros((T * H, 2)))
    cutoff = (energy.reshape(T, H, 2).sum(1) / max(H * W, 1)).astype(F32)
    return {"sobel": sobel.astype(F32), "cutoff": cutoff, "out": nans((T, H, W))}


def _sobel_reference(v):
    out, energy = ref.flow_sobel_components(v["flow"])
    return {"out": out, "row_energy": energy}


CASES = (
    _simple("srgb_grey", _srgb_grey, ("rgb", "out"), ("out",), lambda v: {"out": ref.srgb_grey(v["rgb"])},
            tol=Tol(1e-5, 1e-3)),
    _simple("log_grey", _log_grey, ("rgb", "out", "floor"), ("out",),
            lambda v: {"out": ref.log_grey(v["rgb"], v["floor"])}, tol=Tol(1e-5, 1e-5)),
    _simple("row_min_max", _row_min_max, ("src", "out"), ("out",), lambda v: {"out": ref.row_min_max(v["src"])},
            tol=EXACT),
    _simple("scale_shift", _scale_shift, ("src", "out", "scale", "shift"), ("out",),
            lambda v: {"out": ref.scale_shift(v["src"], v["scale"], v["shift"])}, tol=Tol(1e-6, 1e-6),
            in_place=(("src", "out"),)),
    _simple("rof_dual_step", _rof, ("img", "p_in", "p_out", "theta", "delta"), ("p_out",),
            lambda v: {"p_out": ref.rof_dual_step(v["img"], v["p_in"], v["theta"], v["delta"])},
            tol=Tol(0.0, 2e-6), no_alias=(("p_in", "p_out"),)),
    _simple("rof_texture", _rof_texture, ("img", "p", "out", "theta", "alpha"), ("out",),
            lambda v: {"out": ref.rof_texture(v["img"], v["p"], v["theta"], v["alpha"])}, tol=Tol(0.0, 2e-6),
            in_place=(("img", "out"),)),
    _simple("pack_image_gradient", _pack_image_gradient, ("img", "gx", "gy", "out"), ("out",),
            lambda v: {"out": ref.pack_image_gradient(v["img"], v["gx"], v["gy"])}, tol=EXACT),
    _simple("pack_gradient", _pack_gradient, ("gx", "gy", "out"), ("out",),
            lambda v: {"out": ref.pack_gradient(v["gx"], v["gy"])}, tol=EXACT),
    *(_data_coefficients(q) for q in (0.0, 0.5, 1.0)),
    _soft_census(1), _soft_census(2),
    _simple("pack_channels_gradient", _pack_channels_gradient, ("feat", "gx", "gy", "out"), ("out",),
            lambda v: {"out": ref.pack_channels_gradient(v["feat"], v["gx"], v["gy"])}, tol=EXACT),
    *(_data_coefficients_channels(c, q) for c in (1, 3, 8) for q in (0.0, 0.5, 1.0)),
    *(_smoothness_weights(q) for q in (0.0, 0.5, 1.0)),
    _simple("assemble_system", _assemble, ("flow", "data", "smooth", "lam", "out"), ("out",),
            lambda v: {"out": ref.assemble_system(v["flow"], v["data"], v["smooth"], v["lam"])},
            tol=Tol(1e-4, 0.0, 1e-5)),
    _sor(0), _sor(1),
    Case(FC, "sor_full_sweep", _sor_full, ("du", "system", "smooth", "lam", "omega"), ("du",),
         lambda v: {"du": ref.sor_full_sweep(v["du"], v["system"], v["smooth"], v["lam"], v["omega"])},
         updates=("du",), tol=Tol(1e-3, 1e-4)),
    _apply_update(1.0), _apply_update(0.0),
    _simple("select_masked", _select_masked, ("mask", "inside_mask", "outside_mask", "out"), ("out",),
            lambda v: {"out": ref.select_masked(v["mask"], v["inside_mask"], v["outside_mask"])}, tol=EXACT,
            in_place=(("inside_mask", "out"), ("outside_mask", "out"))),
    _simple("flow_sobel_components", _sobel_components, ("flow", "out", "row_energy"), ("out", "row_energy"),
            _sobel_reference, tol={"out": Tol(0.0, 1e-5), "row_energy": Tol(1e-4, 1e-6)}),
    _simple("thin_edges", _thin_edges, ("sobel", "cutoff", "out"), ("out",),
            lambda v: {"out": ref.thin_edges(v["sobel"], v["cutoff"])}, tol=EXACT, no_alias=()),
)
