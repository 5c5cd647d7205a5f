"""Colour mapping: the original BrainPainter rule, colour maps, diverging, NaN."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from brainpainter.color.rgb import to_rgb
from brainpainter.color.scale import ColourScale, make_scale
from brainpainter.errors import BrainPainterError

ORANGE = np.array(to_rgb("orange"))
YELLOW = np.array([1.0, 1.0, 0.0])

colour = st.tuples(*[st.floats(0, 1)] * 3)
gradients = st.lists(colour, min_size=2, max_size=8)


def test_original_example_interpolates_yellow_to_orange():
    scale = make_scale(gradient=["white", "yellow", "orange", "red"])
    np.testing.assert_allclose(scale(1.2), 0.8 * YELLOW + 0.2 * ORANGE)


def test_default_is_brainpainters_gradient_on_0_to_3():
    scale = make_scale()
    assert (scale.vmin, scale.vmax) == (0.0, 3.0)
    np.testing.assert_allclose(scale([0, 3]), [[1, 1, 1], [1, 0, 0]])


def test_nan_gets_nan_colour():
    scale = make_scale(nan_color="#000080")
    np.testing.assert_allclose(scale([np.nan])[0], to_rgb("#000080"))


@settings(max_examples=200, deadline=None)
@given(gradients, st.integers(0, 7))
def test_exact_hits_on_control_points(grad, i):
    i = i % len(grad)
    scale = make_scale(gradient=[list(c) for c in grad])
    np.testing.assert_allclose(scale(float(i)), scale.colors[i], atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(gradients, st.floats(-1e6, 1e6))
def test_values_outside_clamp_to_end_colours(grad, v):
    scale = make_scale(gradient=[list(c) for c in grad])
    n = len(grad) - 1
    if v <= 0:
        np.testing.assert_allclose(scale(v), scale.colors[0], atol=1e-12)
    elif v >= n:
        np.testing.assert_allclose(scale(v), scale.colors[-1], atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(gradients, st.floats(0, 7), st.floats(0, 7))
def test_monotone_between_control_points(grad, a, b):
    """Within one segment each channel moves monotonically from C[k] to C[k+1]."""
    scale = make_scale(gradient=[list(c) for c in grad])
    n = len(grad) - 1
    a, b = sorted((min(a, n), min(b, n)))
    k = min(int(np.floor(a)), n - 1)
    b = min(b, k + 1.0)
    ca, cb = scale(a), scale(b)
    direction = np.sign(scale.colors[k + 1] - scale.colors[k])
    assert np.all(direction * (cb - ca) >= -1e-12)


@settings(max_examples=100, deadline=None)
@given(st.floats(-100, 100), st.floats(0.1, 100), st.floats(-1e3, 1e3))
def test_vmin_vmax_rescale_is_monotone_in_position(vmin, span, v):
    scale = make_scale(gradient="black,white", vmin=vmin, vmax=vmin + span)
    p1, p2 = scale.position(np.array([v, v + 1.0]))
    assert 0.0 <= p1 <= p2 <= 1.0


def test_diverging_centre_maps_to_middle_colour():
    scale = make_scale(gradient="blue,white,red", center=0.0, data=np.array([-1.0, 4.0]))
    np.testing.assert_allclose(scale(0.0), [1, 1, 1])
    assert scale.vmin == -4.0 and scale.vmax == 4.0  # symmetric by default
    np.testing.assert_allclose(scale(4.0), [1, 0, 0])


def test_two_slope_diverging_with_explicit_limits():
    scale = make_scale(gradient="blue,white,red", vmin=-1, vmax=4, center=0)
    np.testing.assert_allclose(scale(-1.0), [0, 0, 1])
    np.testing.assert_allclose(scale(2.0), [1, 0.5, 0.5])


def test_matplotlib_colormap_defaults_to_data_range():
    scale = make_scale(cmap="viridis", data=np.array([[2.0, np.nan], [6.0, 3.0]]))
    assert (scale.vmin, scale.vmax) == (2.0, 6.0)
    import matplotlib

    np.testing.assert_allclose(scale(6.0), matplotlib.colormaps["viridis"](1.0)[:3], atol=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"cmap": "viridiss"}, "Did you mean 'viridis'"),
        ({"gradient": "white,yelow"}, "Did you mean 'yellow'"),
        ({"gradient": "white"}, "at least 2 colours"),
        ({"gradient": "red", "cmap": "viridis"}, "not both"),
        ({"vmin": 3, "vmax": 1}, "vmax must be greater than vmin"),
        ({"vmin": 0, "vmax": 1, "center": 5}, "center must lie strictly between"),
    ],
)
def test_bad_scales_name_the_value(kwargs, message):
    with pytest.raises(BrainPainterError, match=message):
        make_scale(**kwargs)


def test_scale_is_frozen_dataclass():
    scale = make_scale()
    assert isinstance(scale, ColourScale)
    with pytest.raises(AttributeError):
        scale.vmin = 1.0  # type: ignore[misc]
