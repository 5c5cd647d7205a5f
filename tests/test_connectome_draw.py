"""A connectome drawn: node spheres and edge cylinders as scene parts, coloured and sized (issue 36)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from brainpainter.atlas.template import load_template
from brainpainter.connectome.model import Connectome
from brainpainter.rendering import framing
from brainpainter.rendering.connectome_layers import ConnectomeLayer
from brainpainter.rendering.connectome_parts import (
    EDGE_RADIUS,
    NODE_RADIUS,
    PLAIN_NODE_RADIUS,
    cylinder_mesh,
    edge_radii,
    node_radii,
)
from brainpainter.rendering.scene import Scene
from brainpainter.rendering.views import get_view
from brainpainter.testing.connectome_check import tiny_connectome


def random_connectome(n: int, n_edges: int, seed: int = 0) -> Connectome:
    """`n` nodes inside the tiny template's hemispheres and `n_edges` edges of both signs."""
    rng = np.random.default_rng(seed)
    positions = np.column_stack([rng.choice([-60.0, 60.0], n) + rng.uniform(-30, 30, n),
                                 rng.uniform(-30, 30, n), rng.uniform(-30, 30, n)])
    weights = np.full((n, n), np.nan)
    upper = np.transpose(np.triu_indices(n, 1))
    for i, j in upper[rng.choice(len(upper), n_edges, replace=False)]:
        weights[i, j] = weights[j, i] = rng.uniform(-1, 1)
    return Connectome(tuple(f"n{i}" for i in range(n)), positions, weights, node_values=rng.uniform(0, 1, n))


def test_node_radius_follows_the_value_within_the_clamped_range():
    r = node_radii(np.array([1.0, 2.5, 4.0, np.nan]), 4)
    np.testing.assert_allclose(r, [NODE_RADIUS[0], np.mean(NODE_RADIUS), NODE_RADIUS[1], NODE_RADIUS[0]])
    np.testing.assert_allclose(node_radii(None, 3), PLAIN_NODE_RADIUS)
    np.testing.assert_allclose(node_radii(np.array([7.0, 7.0]), 2), np.mean(NODE_RADIUS))


def test_edge_radius_follows_the_absolute_weight():
    np.testing.assert_allclose(edge_radii(np.array([-1.0, 0.5, 0.0])),
                               [EDGE_RADIUS[1], np.mean(EDGE_RADIUS), EDGE_RADIUS[0]])


def test_a_cylinder_runs_from_node_to_node_at_its_radius_with_outward_normals():
    a, b = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]), np.array([[10.0, 0.0, 0.0], [1.0, 2.0, -7.0]])
    verts, normals, tris, pal = cylinder_mesh(a, b, np.array([0.5, 2.0]), np.array([7, 9]))
    verts = verts.reshape(2, -1, 3)
    for k, r in enumerate((0.5, 2.0)):
        axis = (b[k] - a[k]) / np.linalg.norm(b[k] - a[k])
        rel = verts[k] - a[k]
        along = rel @ axis
        assert set(np.round(along, 4)) == {0.0, 10.0}  # both rings, at the ends
        np.testing.assert_allclose(np.linalg.norm(rel - along[:, None] * axis, axis=1), r, rtol=1e-5)
    assert set(pal.tolist()) == {7, 9}
    v = verts.reshape(-1, 3).astype(float)
    face_n = np.cross(v[tris[:, 1]] - v[tris[:, 0]], v[tris[:, 2]] - v[tris[:, 0]])
    # counter-clockwise seen from outside: each face's normal agrees with its vertices' normals
    assert (np.einsum("ij,ij->i", face_n, normals[tris[:, 0]]) > 0).all()


def test_a_cylinder_seen_from_any_side_is_nearly_as_wide_as_a_round_tube():
    # its width across the image is what tells a weight from another (8 sides: >= cos(22.5 degrees))
    ring = cylinder_mesh(np.zeros((1, 3)), np.array([[0.0, 0.0, 10.0]]), np.array([1.0]), np.array([0]))[0]
    for angle in np.linspace(0.0, np.pi, 37):
        across = ring[:, :2] @ np.array([np.cos(angle), np.sin(angle)])
        assert 2.0 * np.cos(np.pi / 8) - 1e-5 <= np.ptp(across) <= 2.0 + 1e-5


def test_nodes_and_edges_are_parts_with_a_slot_each_drawn_inside_the_glass(tiny):
    scene = Scene(load_template(tiny), "dk", layers=(ConnectomeLayer(tiny_connectome()),))
    g = scene.geometry
    parts = {p.name: p for p in g.parts}
    # one node a hemisphere, the edge between them: of neither (issue 44: views of one hemisphere skip it)
    assert (parts["nodes-lh"].kind, parts["nodes-rh"].kind, parts["edges"].kind) == ("node", "node", "edge")
    assert (parts["nodes-lh"].hemi, parts["nodes-rh"].hemi, parts["edges"].hemi) == ("lh", "rh", None)
    assert {"node:0", "node:1", "edge:0"} <= set(g.slot_of)
    # the larger node value, the larger sphere
    spread = [np.ptp(p.vertices[p.palette_index == g.slot_of[f"node:{i}"]][:, 0])
              for i, p in ((0, parts["nodes-lh"]), (1, parts["nodes-rh"]))]
    np.testing.assert_allclose(spread, [2 * NODE_RADIUS[0], 2 * NODE_RADIUS[1]], rtol=0.01)
    assert g.cortex == "glass"  # a connectome alone shows the cortex as glass
    for view in ("dorsal", "subcortical"):
        assert {"nodes-lh", "nodes-rh", "edges"} <= {p.name for p in g.visible(get_view(view))}
    assert {p.name for p in g.visible(get_view("lateral-left")) if p.kind in ("node", "edge")} == {"nodes-lh"}
    # drawn over an opaque cortex too (on top of it: issue 44), the edges between hemispheres in views of both
    assert framing.shows(get_view("dorsal"), "node", "lh", "opaque") is True
    assert framing.shows(get_view("dorsal"), "edge", None, "opaque") is True
    assert framing.shows(get_view("lateral-left"), "edge", None, "glass") is False


def test_four_hundred_nodes_and_eight_hundred_edges_are_cheap(tiny):
    template = load_template(tiny)
    connectome = random_connectome(400, 800)
    assert Scene(template, "dk").geometry.parts  # warm: the template's meshes read once
    t0 = time.perf_counter()
    plain = Scene(template, "dk").geometry
    t1 = time.perf_counter()
    g = Scene(template, "dk", layers=(ConnectomeLayer(connectome),)).geometry
    t2 = time.perf_counter()
    extra = (t2 - t1) - (t1 - t0)
    triangles = {kind: sum(len(p.triangles) for p in g.parts if p.kind == kind) for kind in ("node", "edge")}
    assert triangles == {"node": 400 * 320, "edge": 800 * 16}
    assert len(g.keys) == len(plain.keys) + 1200
    assert extra < 0.5, f"400 nodes and 800 edges cost {extra:.2f} s more to build"


@pytest.mark.render
def test_connectome_check_passes_and_catches_a_mirrored_renderer():
    pytest.importorskip("bpy")
    from test_renderer_conformance import _Mirrored

    from brainpainter.testing import check_renderer

    report = check_renderer("blender", checks=("connectome",))
    assert report["connectome_pixels"]["node:1"] > 3 * report["connectome_pixels"]["node:0"]
    with pytest.raises(AssertionError, match="connectome: dorsal: node:0 is centred"):
        check_renderer(_Mirrored, checks=("connectome",))


def test_a_connectome_over_a_cortex_without_values_is_drawn_in_the_smooth_glass_brain(tiny, tmp_path):
    """``--cortex auto``: a connectome alone draws the template's glass hulls in the cortex views, not
    the pial cortex as glass (~300,000 triangles drawn twice, its folds crowding the nodes); with
    cortical region values the cortex is opaque in their colours, the connectome drawn over it (issue 44);
    without hulls, the cortex."""
    from brainpainter.rendering.run import prepare_run
    from brainpainter.rendering.settings import RenderSettings

    matrix = tmp_path / "m.csv"
    matrix.write_text(",Left-insula,Right-insula\nLeft-insula,0,0.5\nRight-insula,0.5,0\n")
    run = prepare_run(None, "dk", template=str(tiny), connectome=str(matrix))
    assert run.settings.cortex == "hull"
    with_values = prepare_run({"Left-insula": 1.0}, "dk", template=str(tiny), connectome=str(matrix))
    assert with_values.settings.cortex == "opaque"  # the regions' colours true to their bar
    g = Scene(load_template(tiny), "dk", layers=(ConnectomeLayer(tiny_connectome()),),
              settings=RenderSettings(cortex="hull")).geometry
    for view, hulls in (("dorsal", {"glass-lh", "glass-rh"}), ("lateral-left", {"glass-lh"})):
        shown = {p.name: p.kind for p in g.visible(get_view(view))}
        assert {n for n, k in shown.items() if k == "glass"} == hulls and "cortex-lh" not in shown
        assert {"nodes-lh"} <= set(shown) and ("edges" in shown) == (view == "dorsal")
    assert not framing.shows(get_view("dorsal"), "cortex", "lh", "hull")
