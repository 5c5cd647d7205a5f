"""View presets and aliases."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.views import DEFAULT_VIEWS, PRESETS, get_view, parse_views


def test_default_views_are_brainpainters_three():
    assert [v.name for v in parse_views(None)] == list(DEFAULT_VIEWS)
    assert DEFAULT_VIEWS == ("lateral-left", "medial-left", "subcortical")


@pytest.mark.parametrize(
    ("alias", "name"),
    [
        ("cortical-outer-right-hemisphere", "lateral-right"),
        ("cortical-inner-left-hemisphere", "medial-left"),
        ("top", "dorsal"),
        ("bottom", "ventral"),
        ("SUBCORTICAL", "subcortical"),
    ],
)
def test_original_names_are_aliases(alias, name):
    assert get_view(alias).name == name


def test_free_camera_and_all():
    views = parse_views("camera:135:30:1.5,lateral-left")
    assert (views[0].azimuth, views[0].elevation, views[0].zoom) == (135.0, 30.0, 1.5)
    assert len(parse_views("all")) == len(PRESETS)


@pytest.mark.parametrize(
    ("spec", "message"),
    [("lateral-lef", "Did you mean 'lateral-left'"), ("camera:1", "camera:AZIMUTH"),
     ("camera:0:100", "elevation must be"), (",", "no view")],
)
def test_bad_views(spec, message):
    with pytest.raises(BrainPainterError, match=message):
        parse_views(spec)


def test_views_aspect_is_the_shape_of_what_the_views_show():
    """A box 2 long (y), 1 wide (x), 1 high (z), as a mouse brain: wide from the side, tall from above."""
    from brainpainter.rendering.framing import views_aspect

    box = np.array([[x, y, z] for x in (0, 1) for y in (0, 2) for z in (0, 1)], dtype=float)
    side, top = get_view("lateral-left"), get_view("dorsal")
    assert views_aspect(box, [(side.azimuth, side.elevation)]) == pytest.approx(2.0)
    assert views_aspect(box, [(top.azimuth, top.elevation)]) == pytest.approx(0.75)  # 0.5, at least 3:4
    assert views_aspect(box, [(side.azimuth, side.elevation), (top.azimuth, top.elevation)]) == \
        pytest.approx(1.0)  # the geometric mean of 2 and 0.5
