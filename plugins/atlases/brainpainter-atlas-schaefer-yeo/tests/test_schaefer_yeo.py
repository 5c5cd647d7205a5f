"""Tests a lab can keep with this distribution: every atlas is registered, fits the template, renders."""

from __future__ import annotations

import pytest

from brainpainter.atlas import registry
from brainpainter.rendering.run import render
from brainpainter.testing import check_atlas

NAMES = [f"schaefer{s}_{n}n" for s in range(100, 1001, 100) for n in (7, 17)] + ["yeo17"]


def test_all_atlases_are_registered_by_this_distribution(brainpainter_home):
    dists = {e.name: e.distribution for e in registry.atlases.entries()}
    assert {n: dists.get(n) for n in NAMES} == dict.fromkeys(NAMES, "brainpainter-atlas-schaefer-yeo")


@pytest.mark.parametrize("name, n", [("schaefer100_17n", 50), ("yeo17", 17)])
def test_atlas_fits_the_template_and_renders(brainpainter_home, name, n):
    report = check_atlas(name)
    assert report["n_cortical"] == {"lh": n, "rh": n}
    assert report["unmatched_columns"] == []


def test_annotation_and_short_names_are_accepted(brainpainter_home, stand_in_renderer):
    values = {"7Networks_LH_Vis_1": 1.0, "RH_Default_PFCv_1": 2.0, "lh_SomMot_2": 3.0,
              "Background+FreeSurfer_Defined_Medial_Wall": 0.0}
    result = render(values, "schaefer100_7n", renderer=stand_in_renderer, views="lateral-left",
                    width=32, height=24, progress=False)
    summary = result.manifest["input"]
    assert summary["n_regions_matched"] == 3 and summary["unmatched_columns"] == []
