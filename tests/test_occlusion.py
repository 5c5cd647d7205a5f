"""Baked ambient occlusion (issue 25): the bake, the template arrays, and the relief it gives a render."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from brainpainter.atlas import mesh, occlusion
from brainpainter.atlas.template import load_template
from brainpainter.media.imagemetrics import lightness_spread
from brainpainter.rendering import geometry


def test_one_vertex_normals_function():
    import brainpainter.atlas.meshing as meshing
    import brainpainter.media.export as export

    assert geometry.vertex_normals is mesh.vertex_normals
    assert meshing.vertex_normals is mesh.vertex_normals
    assert export.vertex_normals is mesh.vertex_normals


def test_vertex_normals_sum_corner_by_corner():
    """The builder's meshing summed face normals corner by corner; rebuilt templates need the same bits."""
    m = trimesh.creation.icosphere(subdivisions=3)
    v = m.vertices + np.random.default_rng(0).normal(0.0, 0.05, m.vertices.shape)
    fn = np.cross(v[m.faces[:, 1]] - v[m.faces[:, 0]], v[m.faces[:, 2]] - v[m.faces[:, 0]])
    summed = np.zeros_like(v)
    for k in range(3):
        np.add.at(summed, m.faces[:, k], fn)
    expected = summed / np.linalg.norm(summed, axis=1, keepdims=True)
    assert np.array_equal(mesh.vertex_normals(v, m.faces, np.float64), expected)


def _nested_spheres() -> tuple[np.ndarray, np.ndarray, int, int]:
    """A sphere of radius 5 mm inside one of 20 mm: vertices, faces, the outer one's vertices and faces."""
    outer = trimesh.creation.icosphere(subdivisions=3, radius=20.0)
    inner = trimesh.creation.icosphere(subdivisions=3, radius=5.0)
    v = np.vstack([outer.vertices, inner.vertices])
    f = np.vstack([outer.faces, inner.faces + len(outer.vertices)])
    return v, f, len(outer.vertices), len(outer.faces)


def test_an_enclosed_surface_is_occluded_and_an_open_one_is_not():
    v, f, n, _ = _nested_spheres()
    ao = occlusion.ambient_occlusion(v, f, n_directions=64)
    assert ao.dtype == np.float32 and ao.shape == (len(v),)
    assert np.percentile(ao[:n], 5) > 0.95  # a sphere sees the whole sky
    assert ao[n:].max() < 0.05  # inside another sphere: no sky at all


def test_a_fold_is_darker_at_its_bottom():
    # two walls standing on a plate, 2 mm apart and 9 mm high: a deep narrow trench between them
    box = trimesh.creation.box(extents=(40.0, 40.0, 10.0))
    walls = [trimesh.creation.box(extents=(4.0, 30.0, 9.0),
                                  transform=trimesh.transformations.translation_matrix((x, 0.0, 9.5)))
             for x in (-3.0, 3.0)]
    plate = trimesh.util.concatenate([box, *walls])
    plate = plate.subdivide_to_size(1.0)
    ao = occlusion.ambient_occlusion(plate.vertices, plate.faces, n_directions=96)
    v = plate.vertices
    floor = (np.abs(v[:, 0]) < 0.9) & (np.abs(v[:, 1]) < 10) & (np.abs(v[:, 2] - 5.0) < 0.1)
    top = (np.abs(v[:, 0]) > 12) & (np.abs(v[:, 2] - 5.0) < 0.1)
    assert floor.any() and top.any()
    assert ao[floor].mean() < 0.5 < 0.9 < ao[top].mean()


def test_a_hidden_surface_shades_nothing():
    v, f, n, n_faces = _nested_spheres()
    baked = occlusion.ambient_occlusion(v, f, n_directions=64)
    shown = np.arange(len(f)) >= n_faces  # the outer sphere hidden
    ao = occlusion.occlusion_of_shown(v, f, shown, baked)
    assert np.percentile(ao[n:], 5) > 0.95  # the inner sphere alone sees the whole sky
    assert np.array_equal(ao[:n], baked[:n])  # the hidden one keeps what it had (never drawn)
    assert np.array_equal(occlusion.occlusion_of_shown(v, f, np.ones(len(f), bool), baked), baked)


def test_stored_as_uint8():
    a = np.array([0.0, 0.5, 1.0, 1.2], np.float32)
    s = occlusion.to_uint8(a)
    assert s.dtype == np.uint8 and s.tolist() == [0, 128, 255, 255]
    assert np.allclose(occlusion.from_stored(s), [0, 128 / 255, 1, 1])


@pytest.mark.integration
def test_the_bundled_template_has_occlusion_for_every_surface():
    tpl = load_template("fsaverage")
    assert tpl.has_occlusion and tpl.notes == []
    for labels in tpl.label_sets:
        for hemi in ("lh", "rh"):
            cm = tpl.cortex(labels, hemi)  # split along region borders: occlusion follows
            assert cm.occlusion is not None and set(cm.occlusion) == set(tpl.surfaces)
            for s, ao in cm.occlusion.items():
                assert ao.shape == (len(cm.vertices[s]),)
                # pial and white folds are deep, the inflated surface is nearly open
                assert np.median(ao) > 0.9 if s == "inflated" else np.median(ao) < 0.8
    sub = tpl.subcortical()
    assert sub.occlusion is not None and sub.occlusion.shape == (len(sub.vertices),)


def test_a_template_without_occlusion_loads_with_a_note(tmp_path):
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.testing import CortexMesh, write_template

    sphere = trimesh.creation.icosphere(subdivisions=2, radius=30.0)
    v, f = sphere.vertices.astype(np.float32), sphere.faces.astype(np.int32)
    cm = CortexMesh(v, f, np.zeros(len(f), np.int16), ("a",), white=v, inflated=v)
    tpl = load_template(write_template(tmp_path / "t", {"x": {"lh": cm, "rh": cm}}, [], {}, name="old"))
    assert not tpl.has_occlusion
    assert "no baked ambient occlusion" in tpl.notes[0]
    assert tpl.cortex("x", "lh").occlusion is None
    parts = Scene(tpl, "x", settings=RenderSettings(64, 48)).geometry.parts
    assert parts and all(p.occlusion is None for p in parts)


def _fill(painter, view, rgb):
    keys = [r.key for r in painter.atlas.regions if r.key.startswith("Left-")]
    return painter.paint_colors(dict.fromkeys(keys, rgb), view)


@pytest.mark.render
@pytest.mark.integration
def test_folds_read_in_saturated_colours_on_the_default_template():
    """Issue 25's bars: lateral-left, default options, all DK regions one colour."""
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.views import get_view

    view = get_view("lateral-left")
    with Painter("dk") as painter:
        red, white, yellow = (_fill(painter, view, c) for c in ((1.0, 0, 0), (1.0, 1.0, 1.0), (1.0, 1.0, 0)))
    assert lightness_spread(red) >= 25
    assert lightness_spread(white) >= 30
    brain = ~np.all(white[..., :3] == 255, axis=-1)
    assert (np.median(white[brain][:, :3], axis=0) >= 215).all()
    r, g, b = np.median(yellow[brain][:, :3], axis=0)
    assert r >= 215 and g >= 215 and b <= 15, (r, g, b)
    # a multiplier keeps the hue: red (blended at most with the grey medial wall and the white
    # background at the outline) never turns orange or magenta, and most of it stays pure
    g, b = red[brain][:, 1].astype(int), red[brain][:, 2].astype(int)
    assert (np.abs(g - b) <= 1).all()
    assert np.mean(g == 0) > 0.8


@pytest.mark.render
@pytest.mark.integration
def test_hidden_ventricles_leave_the_caudate_and_thalamus_lit():
    """Issue 33 item 14: the occlusion baked with the ventricles darkened what hiding them uncovers."""
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    view = get_view("subcortical")
    keys = ["Left-Caudate", "Right-Caudate", "Left-Thalamus", "Right-Thalamus"]
    brightness = {}
    for hidden in ((), ("ventricles",)):
        with Painter("dk", hidden=hidden, settings=RenderSettings(width=400, height=300)) as painter:
            yellow, blue = (painter.paint_colors(dict.fromkeys(keys, c), view)[..., :3].astype(int)
                            for c in ((1.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
        shown = np.abs(yellow - blue).sum(axis=-1) > 0  # the pixels of the four structures
        brightness[hidden] = yellow[shown].max(axis=1)
    lit, uncovered = brightness[()], brightness[("ventricles",)]
    # without the ventricles the structures see more sky, never less (baked with them: 0.87x, 12 % < 80)
    assert uncovered.mean() >= 0.97 * lit.mean(), (uncovered.mean(), lit.mean())
    assert np.mean(uncovered < 80) <= np.mean(lit < 80)
