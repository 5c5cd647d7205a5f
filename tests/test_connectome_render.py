"""A connectome rendered through the run: its two layers, the manifest, the pixels (issue 36's bars)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import brainpainter
from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError
from brainpainter.testing.connectome_check import tiny_connectome

FLAT = {"shading": "flat", "quality": "fast", "glass_opacity": 0.0, "background": "white"}


def _near(img: np.ndarray, rgb, tol: float = 2) -> np.ndarray:
    return np.abs(img[..., :3].astype(float) - np.round(np.asarray(rgb, float)[:3] * 255)).max(axis=-1) <= tol


def precentral_pair(values=(1.0, 4.0), weight: float = 0.6) -> Connectome:
    """Left- and Right-precentral of DK at their centroids on fsaverage's pial surface, one edge."""
    from brainpainter.atlas.template import load_template

    template = load_template("fsaverage")
    centres = []
    for hemi in ("lh", "rh"):
        cm = template.cortex("dk", hemi)
        faces = np.asarray(cm.faces)[np.asarray(cm.face_label) == list(cm.label_names).index("precentral")]
        centres.append(np.asarray(cm.vertices["pial"])[np.unique(faces)].mean(axis=0))
    weights = np.array([[np.nan, weight], [weight, np.nan]])
    return Connectome(("Left-precentral", "Right-precentral"), np.array(centres), weights,
                      node_values=np.array(values, float))


def test_a_connectome_alone_draws_its_edges_and_nodes_on_their_own_scales(tiny, tmp_path):
    result = brainpainter.render(None, connectome=tiny_connectome(), template=str(tiny), out=tmp_path / "out",
                                 width=320, height=240, progress=False, edges_label="FC (r)")
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert [f["view"] for f in manifest["files"]] == ["dorsal", "lateral-left"]
    assert manifest["connectome"]["n_edges"] == 1 and manifest["connectome"]["n_nodes"] == 2
    assert [n["name"] for n in manifest["connectome"]["nodes"]] == ["left", "right"]
    layers = {layer["kind"]: layer for layer in manifest["settings"]["layers"]}
    # the edges: diverging about 0 over the largest |weight|; the nodes: their values' own scale
    assert layers["edges"]["scale"]["name"] == "RdBu_r" and layers["edges"]["scale"]["center"] == 0.0
    assert (layers["edges"]["scale"]["vmin"], layers["edges"]["scale"]["vmax"]) == (-0.8, 0.8)
    assert layers["edges"]["label"] == "FC (r)"
    assert layers["nodes"]["scale"]["name"] == "viridis" and layers["nodes"]["scale"]["vmax"] == 4.0
    assert [layer.kind for layer in result.layers] == ["edges", "nodes"]


def test_edge_and_node_options_colour_their_own_layer(tiny):
    result = brainpainter.render(None, connectome=tiny_connectome(), template=str(tiny), views="dorsal",
                                 edges_cmap="magma", edges_vmin=0, edges_vmax=1, nodes_cmap="cividis",
                                 width=320, height=240, progress=False, **FLAT)
    edges, nodes = result.layers
    assert (edges.scale.name, edges.scale.vmin, edges.scale.vmax, edges.scale.center) == ("magma", 0, 1, None)
    assert nodes.scale.name == "cividis"
    img = result.images[("connectome", "dorsal")]
    for rgb in (edges.scale(np.array([0.8]))[0], nodes.scale(np.array([1.0]))[0],
                nodes.scale(np.array([4.0]))[0]):
        assert _near(img, rgb).sum() > 10


def test_node_categories_are_a_categorical_layer_with_a_key(tiny):
    c = tiny_connectome()
    c = Connectome(c.names, c.positions, c.weights, node_categories=("DMN", "Visual"))
    result = brainpainter.render(None, connectome=c, template=str(tiny), views="dorsal", width=320,
                                 height=240, progress=False, **FLAT)
    nodes = result.layers[1]
    assert [name for name, _ in nodes.scale.categories] == ["DMN", "Visual"]
    img = result.images[("connectome", "dorsal")]
    left, right = (np.nonzero(_near(img, rgb))[1].mean() for _, rgb in nodes.scale.categories)
    assert left < img.shape[1] / 2 < right


@pytest.mark.parametrize(("options", "pattern"), [
    ({"nodes_cmap": "viridis", "connectome": Connectome(("a", "b"), np.zeros((2, 3)), np.ones((2, 2)))},
     "--nodes-cmap colours node values, but this run draws none"),
    ({"edges_cmap": "viridis"}, "--edges-cmap colours edge weights, but this run draws none"),
    ({"top_edges": 3}, "--top-edges describes a connectome's nodes or edges, but no --connectome"),
])
def test_options_of_a_layer_not_drawn_are_refused(tiny, options, pattern):
    with pytest.raises(BrainPainterError, match=pattern):
        brainpainter.render({"Left-insula": 1.0} if "connectome" not in options else None,
                            template=str(tiny), progress=False, **options)


@pytest.mark.render
@pytest.mark.integration
def test_bar_two_precentral_nodes_one_edge_seen_from_above(tmp_path):
    """Issue 36's first bar: from above the left node is on the left, the edge has its weight's
    colour on the edge scale, and the larger node value draws more pixels."""
    from PIL import Image

    result = brainpainter.render(None, connectome=precentral_pair(), views="dorsal", width=480, height=400,
                                 progress=False, **FLAT)
    img = result.images[("connectome", "dorsal")]
    Image.fromarray(img).save(tmp_path / "precentral.png")
    edges, nodes = result.layers
    small, large = (_near(img, nodes.scale(np.array([v]))[0]) for v in (1.0, 4.0))
    edge = _near(img, edges.scale(np.array([0.6]))[0])
    assert small.sum() > 20 and large.sum() > 3 * small.sum()
    # dorsal: anterior up, the subject's left on the image's left
    assert np.nonzero(small)[1].mean() < img.shape[1] / 2 < np.nonzero(large)[1].mean()
    assert edge.sum() > 100
    cols = np.nonzero(edge)[1]
    assert cols.min() < img.shape[1] / 2 < cols.max()  # it runs across the midline
