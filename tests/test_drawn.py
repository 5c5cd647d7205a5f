"""Which regions a view draws (media/drawn.py): the renderer's rule (SceneGeometry.visible and the faces of
its parts), so colour-bar swatches follow what the images show, for a human brain and for a brain of
structures only (a mesh-folder atlas with no cortex, as a BrainGlobe atlas is)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.cli.main import cli
from brainpainter.media.drawn import drawn_keys, swatches_needed
from brainpainter.rendering.painter import load_scene
from brainpainter.rendering.views import parse_views
from brainpainter.table.region_table import read_table


@pytest.fixture(autouse=True)
def _fresh_registry():
    registry.reset_all()
    yield
    registry.reset_all()


def test_human_views_draw_their_hemisphere_or_the_structures():
    atlas, scene = load_scene("dk", hidden=["Left-insula"])
    g = scene.geometry
    lateral = set(drawn_keys(g, parse_views("lateral-left")))
    # hidden: not drawn; the template's 'unknown' label is drawn (medial-wall colour) but is no region
    assert lateral - {"Left-unknown"} == {r.key for r in atlas.cortical("lh")} - {"Left-insula"}
    assert set(drawn_keys(g, parse_views("subcortical"))) == {r.key for r in atlas.subcortical()}
    both = drawn_keys(g, parse_views("dorsal,subcortical"))
    assert set(both) >= {r.key for r in atlas.regions} - {"Left-insula"}
    t = read_table({"Left-bankssts": 1.0, "Left-insula": float("nan")}, atlas="dk")
    assert swatches_needed(t, [0], parse_views("lateral-left"), g) == (False, True)  # insula hidden: no NaN
    t = read_table({r.key: 1.0 for r in atlas.cortical("lh")}, atlas="dk")
    assert swatches_needed(t, [0], parse_views("lateral-left"), g) == (False, False)  # not Left-unknown
    assert swatches_needed(t, [0], parse_views("lateral-right"), g) == (False, True)


def test_a_structures_only_brain_shows_its_structures_in_surface_views(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    for name, centre in (("CA1", (0, 0, 0)), ("Thalamus", (0, 3, 0)), ("Pons", (0, -3, 0))):
        trimesh.creation.icosphere(subdivisions=2).apply_translation(centre).export(folder / f"{name}.stl")
    assert CliRunner().invoke(cli, ["atlas", "add", "bg", "--subcortical-meshes", str(folder)]).exit_code == 0
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,CA1,Thalamus\nA,1,\n")  # Thalamus NaN, Pons missing
    t = read_table(str(table), atlas="bg")
    _, scene = load_scene("bg")
    dorsal = parse_views("dorsal")  # a cortex view: the brain has no cortex, its structures stand in
    assert set(drawn_keys(scene.geometry, dorsal)) == {"CA1", "Thalamus", "Pons"}
    assert swatches_needed(t, [0], dorsal, scene.geometry) == (True, True)
    _, hidden = load_scene("bg", hidden=["Thalamus", "Pons"])
    assert drawn_keys(hidden.geometry, dorsal) == ["CA1"]
    assert swatches_needed(t, [0], dorsal, hidden.geometry) == (False, False)
    assert np.isnan(t.values).any()
