"""Tests a lab can keep when it copies this plugin: the atlas loads, fits the template and renders."""

from __future__ import annotations

from brainpainter.atlas import registry
from brainpainter.rendering.run import render
from brainpainter.testing import check_atlas


def test_atlas_is_registered_by_this_distribution(brainpainter_home):
    entry = next(e for e in registry.atlases.entries() if e.name == "yeo7")
    assert entry.distribution == "brainpainter-atlas-yeo7"


def test_atlas_fits_the_template_and_renders(brainpainter_home):
    report = check_atlas("yeo7")
    assert report["n_cortical"] == {"lh": 7, "rh": 7}
    assert report["unmatched_columns"] == []


def test_network_names_are_accepted_as_columns(brainpainter_home, stand_in_renderer):
    values = {"Left-Visual": 1.0, "lh_Default": 2.0, "Right-7Networks_3": 0.5}
    result = render(values, "yeo7", renderer=stand_in_renderer, views="lateral-left", width=32, height=24,
                    progress=False)
    summary = result.manifest["input"]
    assert summary["n_regions_matched"] == 3 and summary["unmatched_columns"] == []
