"""Core geometry handed to renderers: indexed parts, palette slots, framing (no Blender)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from brainpainter.atlas.template import load_template
from brainpainter.errors import BrainPainterError
from brainpainter.rendering import framing
from brainpainter.rendering.geometry import (
    GLASS_SLOT,
    MEDIAL_SLOT,
    NEUTRAL_GREY,
    NEUTRAL_SLOT,
    Palette,
    split_by_label,
    vertex_normals,
)
from brainpainter.rendering.scene import Scene
from brainpainter.rendering.sulc import convexity
from brainpainter.rendering.views import PRESETS, View, get_view
from brainpainter.testing import write_tiny_template


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    tpl = load_template(write_tiny_template(tmp_path_factory.mktemp("t") / "tiny"))
    return Scene(tpl, "dk", hidden=frozenset({"Left-precuneus"}))


def test_split_by_label_duplicates_border_vertices_only():
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    v, tri, pal, (orig,) = split_by_label(verts, faces, np.array([5, 7]), (np.arange(4),))
    assert len(v) == 6  # the shared edge's two vertices exist once per label
    assert (pal[tri] == np.array([[5], [7]])).all()  # each triangle's vertices carry its slot
    np.testing.assert_array_equal(v[tri], verts[faces])
    np.testing.assert_array_equal(orig[tri], faces)


def test_convexity_finds_a_dent():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=50.0)
    v = np.array(sphere.vertices)
    dent = v[:, 2] > 45  # push the top cap inwards: a pit
    v[dent] *= 0.8
    depth = convexity(v, sphere.faces, iterations=20)
    assert depth.shape == (len(v),) and depth.min() >= 0 and depth.max() <= 1
    assert depth[dent].mean() > 0.5 > depth[v[:, 2] < 0].mean()


def test_vertex_normals_point_outwards():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    n = vertex_normals(sphere.vertices, sphere.faces)
    assert (np.einsum("ij,ij->i", n, sphere.vertices) > 0.99).all()


def test_scene_geometry_parts_and_palette(scene):
    g = scene.geometry
    assert [p.name for p in g.parts] == ["cortex-lh", "cortex-rh", "subcortical", "glass-lh", "glass-rh"]
    assert "Left-precuneus" not in g.keys and "Right-precuneus" in g.keys  # hidden: no slot, no faces
    for p in g.parts:
        assert p.vertices.dtype == np.float32 and p.triangles.dtype == np.uint32
        assert p.palette_index.max() < g.n_slots
        assert len(p.normals) == len(p.vertices) == len(p.sulc)
    glass = g.parts[-1]
    assert (glass.palette_index == GLASS_SLOT).all()
    pal = Palette({"Left-insula": (1, 0, 0), "not-a-region": (0, 1, 0)}, g)
    assert dict(pal) == {"Left-insula": (1.0, 0.0, 0.0), "not-a-region": (0.0, 1.0, 0.0)}
    rgb = pal.rgb
    assert rgb.shape == (g.n_slots, 3)
    np.testing.assert_allclose(rgb[g.slot_of["Left-insula"]], (1, 0, 0))
    np.testing.assert_allclose(rgb[g.slot_of["Left-unknown"]], scene.medial_wall_color, atol=1e-6)
    np.testing.assert_allclose(rgb[g.slot_of["Left-Hippocampus"]], NEUTRAL_GREY, atol=1e-6)
    np.testing.assert_allclose(rgb[[MEDIAL_SLOT, NEUTRAL_SLOT]], [scene.medial_wall_color, NEUTRAL_GREY],
                               atol=1e-6)


def test_visible_parts_follow_the_view(scene):
    g = scene.geometry
    assert [p.name for p in g.visible(get_view("lateral-left"))] == ["cortex-lh"]
    assert [p.name for p in g.visible(get_view("subcortical"))] == ["subcortical", "glass-rh"]
    assert [p.name for p in g.visible(get_view("dorsal"))] == ["cortex-lh", "cortex-rh"]
    with pytest.raises(BrainPainterError, match="shows nothing"):
        g.visible(View("none", "cortex", (), 0.0, 0.0))


@pytest.mark.parametrize("name", [n for n, v in PRESETS.items() if v.content != "flat"])  # flat: test_flat.py
def test_camera_projects_the_framed_parts_inside_the_image(scene, name):
    view = PRESETS[name]
    pose = scene.geometry.camera(view, 4 / 3)
    pts = np.vstack([p.vertices for p in scene.geometry.visible(view)])
    px = framing.to_pixels(pts, pose, 400, 300)
    assert px[:, 0].min() >= 0 and px[:, 0].max() <= 400
    assert px[:, 1].min() >= 0 and px[:, 1].max() <= 300
    # tight: the larger extent fills the image less the margin
    fill = max(np.ptp(px[:, 0]) / 400, np.ptp(px[:, 1]) / 300)
    assert fill == pytest.approx(1 / (1 + 2 * framing.MARGIN), rel=1e-3)
    m = framing.view_projection(pose, 4 / 3)
    depth = pts @ m[2, :3] + m[2, 3]
    assert depth.min() > -1 and depth.max() < 1  # nothing clipped


def test_lateral_left_puts_anterior_on_the_left(scene):
    pose = scene.geometry.camera(get_view("lateral-left"), 4 / 3)
    (front, back) = framing.to_pixels(np.array([[-60, 40, 0], [-60, -40, 0.0]]), pose, 400, 300)
    assert front[0] < 200 < back[0]


def test_sulcal_depth_only_when_the_lighting_uses_it(scene):
    from brainpainter.rendering.scene import RenderSettings

    assert not scene.geometry.parts[0].sulc.any()  # studio lighting: not computed
    lit = Scene(scene.template, "dk", settings=RenderSettings(lighting="sulc"))
    sulc = lit.geometry.parts[0].sulc
    assert sulc.dtype == np.float32 and sulc.max() == 1.0 and sulc.min() == 0.0

