"""View presets and aliases."""

from __future__ import annotations

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
