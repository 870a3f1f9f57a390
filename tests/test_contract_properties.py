"""Property-based checks of the input contract (hypothesis): Params, frames and flow.

No solve runs here: every call only validates, so each example costs microseconds.
"""
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import ivkernels as iv
from ivkernels import Params
from ivkernels.decompose import _as_flow
from ivkernels.flow import as_linear_rgb
from ivkernels.io import srgb_to_linear, to_linear_float

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
FIELDS = [f.name for f in dataclasses.fields(Params)]
DEFAULTS = Params()

ANY_VALUE = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-10**6, max_value=10**6),
    st.booleans(),
    st.none(),
    st.text(max_size=3),
    st.sampled_from([np.float32(0.5), np.int64(3), np.float64(np.nan), 1e300, -0.0, 2.5]),
)


def _rule(name):
    from ivkernels.params import _RULES
    from ivkernels.validation import Range

    return _RULES.get(name, Range(type(getattr(DEFAULTS, name))))


@SETTINGS
@given(name=st.sampled_from(FIELDS), value=ANY_VALUE)
def test_params_accept_only_values_in_range(name, value):
    """Any value for any field: refused with the field's name, or stored finite and in range."""
    try:
        p = Params(**{name: value})
    except (TypeError, ValueError) as err:
        assert f"Params.{name}" in str(err) or name == "overlap" and "overlap" in str(err)
        return
    stored = getattr(p, name)
    rule = _rule(name)
    assert type(stored) is rule.kind
    if rule.kind is bool:                       # a switch: only True and False get here
        assert isinstance(value, (bool, np.bool_)) and stored == value
        return
    assert math.isfinite(stored) and rule.contains(stored)
    assert stored == value


@st.composite
def valid_value(draw, name):
    rule = _rule(name)
    if rule.kind is bool:
        return draw(st.booleans())
    low = rule.low if rule.low is not None else -1e6
    high = rule.high if rule.high is not None else 1e6
    if rule.kind is int:
        lo, hi = int(math.ceil(low)), int(math.floor(high))
        lo += 1 if rule.low_open and lo == low else 0
        hi -= 1 if rule.high_open and hi == high else 0
        return draw(st.integers(lo, min(hi, lo + 1000)))
    return draw(st.floats(low, high, exclude_min=rule.low_open, exclude_max=rule.high_open,
                          allow_nan=False, allow_infinity=False))


@SETTINGS
@given(data=st.data(), name=st.sampled_from([n for n in FIELDS if n not in ("window", "overlap")]))
def test_params_accept_every_value_in_range(data, name):
    value = data.draw(valid_value(name))
    assert getattr(Params(**{name: value}), name) == value


@SETTINGS
@given(window=st.integers(-3, 50) | st.floats(-3, 50), overlap=st.integers(-3, 50) | st.floats(-3, 50))
def test_params_window_and_overlap(window, overlap):
    integers = isinstance(window, int) and isinstance(overlap, int)
    ok = integers and window >= 2 and 0 <= overlap < window
    try:
        Params(window=window, overlap=overlap)
    except (TypeError, ValueError):
        assert not ok
    else:
        assert ok


@SETTINGS
@given(h=st.integers(8, 5000), w=st.integers(8, 5000), scale=st.floats(0.01, 0.9),
       min_size=st.integers(8, 200))
def test_pyramid_level_count_matches_the_solver(h, w, scale, min_size):
    from ivkernels.solver.pyramid import level_shapes
    from ivkernels.validation import pyramid_levels

    assert pyramid_levels(h, w, scale, min_size) == len(level_shapes(h, w, scale, min_size))


# ----------------------------------------------------------------------------- frames
DTYPES = [np.uint8, np.uint16, np.float32, np.float64, np.float16, np.int32, np.int8, np.bool_]


@st.composite
def frame_arrays(draw):
    dtype = np.dtype(draw(st.sampled_from(DTYPES)))
    shape = draw(st.one_of(
        st.tuples(st.integers(0, 3), st.integers(8, 12), st.integers(8, 12), st.sampled_from([3, 3, 1, 4])),
        hnp.array_shapes(min_dims=2, max_dims=5, min_side=0, max_side=9),
    ))
    if dtype.kind == "f":
        elements = st.one_of(st.floats(0, 1, width=dtype.itemsize * 8),
                             st.floats(-2, 300, width=dtype.itemsize * 8),
                             st.sampled_from([np.nan, np.inf, 1 + 1e-7, -1e-7]))
        base = draw(st.sampled_from(["unit", "unit", "wide"]))
        fill = st.floats(0, 1, width=dtype.itemsize * 8) if base == "unit" else elements
        return draw(hnp.arrays(dtype, shape, elements=fill)) if draw(st.booleans()) else \
            draw(hnp.arrays(dtype, shape, elements=elements))
    return draw(hnp.arrays(dtype, shape))


def _outcome(call, x):
    try:
        return "ok", call(x)
    except (TypeError, ValueError) as err:
        return type(err).__name__, None


@st.composite
def stacks(draw):
    """(T >= 2, H >= 8, W >= 8, 3) stacks of any dtype: the shape every entry point takes."""
    dtype = np.dtype(draw(st.sampled_from(DTYPES)))
    shape = (draw(st.integers(2, 3)), draw(st.integers(8, 10)), draw(st.integers(8, 10)), 3)
    if dtype.kind == "f":
        width = dtype.itemsize * 8
        unit = st.floats(0, 1, width=width)
        wild = st.one_of(unit, st.floats(-2, 300, width=width),
                         st.sampled_from([np.nan, np.inf, 1 + 1e-7, -1e-7, 255.0]))
        return draw(hnp.arrays(dtype, shape, elements=draw(st.sampled_from([unit, wild]))))
    return draw(hnp.arrays(dtype, shape))


@SETTINGS
@given(x=stacks())
def test_decompose_flow_and_io_take_the_same_frames(x):
    """The same array is accepted by all of decompose, estimate_flow and to_linear_float
    or refused by all with the same exception type."""
    results = {
        "decompose": _outcome(lambda a: iv.iter_decompose(a, flow="dis"), x),
        "estimate_flow": _outcome(as_linear_rgb, x),
        "to_linear_float": _outcome(to_linear_float, x),
    }
    kinds = {name: r[0] for name, r in results.items()}
    assert len(set(kinds.values())) == 1, kinds
    if kinds["to_linear_float"] == "ok":
        np.testing.assert_array_equal(results["estimate_flow"][1], results["to_linear_float"][1])


@SETTINGS
@given(x=stacks() | frame_arrays())
def test_accepted_frames_are_linear_rgb_in_range(x):
    """Whatever decompose's and estimate_flow's checkers accept is linear RGB in [0, 1]."""
    for call in (to_linear_float, as_linear_rgb):
        status, out = _outcome(call, x)
        if status != "ok":
            continue
        assert out.dtype == np.float32 and out.shape == x.shape and out.flags.c_contiguous
        assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1
        if x.dtype.kind == "u":
            expected = srgb_to_linear(x / float(np.iinfo(x.dtype).max))
            np.testing.assert_allclose(out, expected, atol=1e-6)
        else:
            assert x.dtype in (np.float32, np.float64)
            assert np.isfinite(x).all() and x.min() >= -1e-6 and x.max() <= 1 + 1e-6
            np.testing.assert_allclose(out, np.clip(x, 0, 1), atol=1e-7)


def _float_frames(dtype):
    width = np.dtype(dtype).itemsize * 8
    elements = st.one_of(st.floats(0, 1, width=width), st.floats(-2, 300, width=width),
                         st.sampled_from([np.nan, np.inf, -np.inf, 1 + 1e-7, -1e-7, 1 + 1e-5]))
    return hnp.arrays(dtype, st.tuples(st.integers(2, 3), st.integers(4, 6), st.integers(4, 6),
                                       st.just(3)), elements=elements)


@SETTINGS
@given(x=st.sampled_from([np.float32, np.float64]).flatmap(_float_frames))
def test_refused_float_frames_are_out_of_range(x):
    """Float32/64 frames of a valid shape are refused, by decompose's and the flow's
    checkers alike, exactly when some value is non-finite or outside [0, 1] by more
    than the tolerance."""
    bad = not np.isfinite(x).all() or x.min() < -1e-6 or x.max() > 1 + 1e-6
    for call in (to_linear_float, as_linear_rgb):
        status, _ = _outcome(call, x)
        assert (status == "ValueError") == bad, call


# ----------------------------------------------------------------------------- flow
def _flows(dtype):
    width = np.dtype(dtype).itemsize * 8
    return hnp.arrays(dtype, (1, 4, 4, 2), elements=st.floats(-2, 2, width=width) | st.floats(width=width)
                      | st.sampled_from([1e9, -1e39, 1e39, 3e38, 1e6]).filter(
                          lambda v: width == 64 or abs(v) < 3.4e38))


@SETTINGS
@given(flow=st.sampled_from([np.float32, np.float64]).flatmap(_flows))
def test_accepted_flow_is_finite_float32(flow):
    try:
        with np.errstate(over="ignore"):
            out = _as_flow(flow, 2, 4, 4)
    except (TypeError, ValueError):
        assert not np.isfinite(flow).all() or np.abs(flow).max() > 1e6
        return
    assert out.dtype == np.float32 and np.isfinite(out).all()
    np.testing.assert_allclose(out, flow.astype(np.float32))


def test_every_field_has_a_finite_range():
    """Every numeric field, including one added later, refuses NaN and infinity."""
    for name in FIELDS:
        value = getattr(DEFAULTS, name)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            for bad in (math.nan, math.inf):
                with pytest.raises((TypeError, ValueError), match=f"Params.{name} must be"):
                    Params(**{name: bad})
