"""Colour parsing: names, hex, 0-1 and 0-255 triples, and errors."""

from __future__ import annotations

import pytest

from brainpainter.color.rgb import to_hex, to_rgb
from brainpainter.errors import BrainPainterError


@pytest.mark.parametrize(
    ("given", "expected"),
    [
        ("red", (1.0, 0.0, 0.0)),
        ("Orange", (1.0, 165 / 255, 0.0)),
        ("#00ff00", (0.0, 1.0, 0.0)),
        ("00ff00", (0.0, 1.0, 0.0)),
        ((0.5, 0.25, 0.0), (0.5, 0.25, 0.0)),
        ((255, 0, 51), (1.0, 0.0, 0.2)),
        ([1, 1, 1], (1.0, 1.0, 1.0)),
        ("255,128,0", (1.0, 128 / 255, 0.0)),
        ("0.1 0.2 0.3", (0.1, 0.2, 0.3)),
        ("tab:blue", to_rgb("#1f77b4")),
    ],
)
def test_to_rgb(given, expected):
    assert to_rgb(given) == pytest.approx(expected)


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ("redd", "Did you mean 'red'"),
        ((1, 2), "not valid"),
        ((300, 0, 0), "out of range"),
        ((-1, 0, 0), "not valid"),
        ("1,2,x", "not valid"),
    ],
)
def test_bad_colours(given, message):
    with pytest.raises(BrainPainterError, match=message):
        to_rgb(given)


def test_hex_round_trip():
    assert to_hex(to_rgb("#12abef")) == "#12abef"


def test_common_colour_names_are_matplotlibs():
    """The names to_rgb knows without importing matplotlib give matplotlib's colours."""
    from matplotlib import colors as mcolors

    from brainpainter.color.rgb import COMMON_NAMES

    mapping = mcolors.get_named_colors_mapping()
    for name in COMMON_NAMES:
        assert to_rgb(name) == tuple(float(c) for c in mcolors.to_rgb(mapping[name])), name
