"""Issue 44, items 1-9: a connectome's layers true to their own bars beside other layers, and dense
graphs that read (one hemisphere per lateral view, Yeo's network colours, labels that can be read)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import brainpainter
from brainpainter.connectome.model import Connectome
from brainpainter.rendering.connectome_layers import ConnectomeLayer
from brainpainter.rendering.run import prepare_run
from brainpainter.testing.connectome_check import tiny_connectome


def test_a_label_never_moves_the_plain_scale_onto_the_edges(tiny):
    """Item 3: ``--cmap viridis --edges-label FC`` keeps viridis on the regions; the edges RdBu_r about 0."""
    table = {"Left-insula": 1.0, "Right-insula": 2.0}
    plain = prepare_run(table, "dk", template=str(tiny), connectome=tiny_connectome(), cmap="viridis")
    labelled = prepare_run(table, "dk", template=str(tiny), connectome=tiny_connectome(), cmap="viridis",
                           edges_label="FC", nodes_label="strength")
    for run in (plain, labelled):
        layers = {layer.kind: layer.scale for layer in run.layers}
        assert layers["regions"].name == "viridis"
        assert (layers["edges"].name, layers["edges"].center) == ("RdBu_r", 0.0)
        assert layers["edges"].vmin == -layers["edges"].vmax
        assert layers["nodes"].to_dict() == {k.kind: k.scale for k in plain.layers}["nodes"].to_dict()
    assert [layer.label for layer in labelled.layers][1:] == ["FC", "strength"]


def _rgb255(rgb) -> np.ndarray:
    return np.round(np.asarray(rgb, float)[:3] * 255)


def ladder(weight: float = 0.6) -> Connectome:
    """Eight nodes on fsaverage, four a hemisphere (x = -/+40 mm), each joined to its mirror image across the
    midline and to the next node of its hemisphere (the right ones 10 mm further forward and 15 mm lower, so
    that no lateral view hides one hemisphere's behind the other's), every edge of weight `weight`."""
    ys = (-50.0, -15.0, 15.0, 45.0)
    positions = np.array([[-40.0, y, 45.0] for y in ys] + [[40.0, y + 10.0, 30.0] for y in ys])
    w = np.full((8, 8), np.nan)
    for i in range(4):
        w[i, i + 4] = w[i + 4, i] = weight
        if i < 3:
            w[i, i + 1] = w[i + 1, i] = w[i + 4, i + 5] = w[i + 5, i + 4] = weight
    names = tuple(f"{h}{i}" for h in "LR" for i in range(4))
    return Connectome(names, positions, w, node_categories=tuple("left" if h == "L" else "right"
                                                                 for h in "LR" for _ in range(4)))


FLAT = {"shading": "flat", "quality": "fast", "background": "white", "width": 480, "height": 400,
        "progress": False}


@pytest.mark.render
@pytest.mark.integration
def test_an_edge_has_its_bar_s_colour_under_the_glass_and_in_the_midline_gap(tmp_path):
    """Item 1: every edge pixel reads back as the edge scale's colour of its weight, under the glass
    (dorsal, the default glass brain) and between the hemispheres alike: no "spine" along the midline."""
    from PIL import Image

    c = ladder()
    bare = Connectome(c.names, c.positions, np.full((8, 8), np.nan), node_categories=c.node_categories)
    result = brainpainter.render(None, "dk", connectome=c, views="dorsal", **FLAT)
    img = next(iter(result.images.values()))
    Image.fromarray(img).save(tmp_path / "ladder_dorsal.png")
    nodes_only = next(iter(brainpainter.render(None, "dk", connectome=bare, views="dorsal",
                                               **FLAT).images.values()))
    rgb = img[..., :3].astype(float)
    edges = np.abs(rgb - nodes_only[..., :3]).max(axis=-1) > 30  # where the edges are drawn
    bar = _rgb255(result.layers[0].scale(np.array([0.6]))[0])
    assert edges.sum() > 2000
    err = np.abs(rgb[edges] - bar).max(axis=-1)
    assert np.median(err) <= 10 and np.percentile(err, 90) <= 10  # was 84 and 97: paled by the glass
    xs = np.nonzero(edges)[1]
    middle = np.abs(xs - img.shape[1] / 2) < 12
    assert middle.sum() > 100
    for band in (middle, ~middle):  # as bright under the glass as in the gap, each within 10 of the bar
        assert np.abs(np.median(rgb[edges][band], axis=0) - bar).max() <= 10


@pytest.mark.render
@pytest.mark.integration
@pytest.mark.parametrize("kind", ["map", "regions"])
def test_values_under_a_connectome_read_true_to_their_bar(tmp_path, kind):
    """Item 2: a map or region values under a connectome are drawn in their bar's colours (the cortex
    opaque, the nodes and edges over it), not pale on the glass."""
    from PIL import Image

    c = ladder()
    if kind == "map":
        maps = {"lh": np.full(10242, 2.0), "rh": np.full(10242, 3.0)}
        result = brainpainter.render(None, connectome=c, lh=maps["lh"], rh=maps["rh"], map_cmap="viridis",
                                     map_vmin=1, map_vmax=4, views="dorsal", **FLAT)
    else:
        table = {f"{side}-{r}": v for side, v in (("Left", 2.0), ("Right", 3.0))
                 for r in ("superiorfrontal", "precentral", "postcentral", "superiorparietal",
                           "caudalmiddlefrontal", "rostralmiddlefrontal", "supramarginal", "paracentral",
                           "inferiorparietal", "lateraloccipital", "parsopercularis", "parstriangularis")}
        result = brainpainter.render(table, "dk", connectome=c, cmap="viridis", vmin=1, vmax=4,
                                     views="dorsal", **FLAT)
    img = next(iter(result.images.values()))
    Image.fromarray(img).save(tmp_path / f"{kind}_dorsal.png")
    scale = result.layers[0].scale
    rgb = img[..., :3].astype(float)
    h, w = rgb.shape[:2]
    for value, cols in ((2.0, slice(int(0.2 * w), int(0.4 * w))), (3.0, slice(int(0.6 * w), int(0.8 * w)))):
        bar = _rgb255(scale(np.array([value]))[0])
        patch = rgb[int(0.3 * h):int(0.7 * h), cols].reshape(-1, 3)
        err = np.abs(patch - bar).max(axis=-1)
        assert np.median(err) <= 10, (value, np.median(patch, axis=0), bar)
    nodes = {name: _rgb255(v) for name, v in result.layers[-1].scale.categories}
    for v in nodes.values():  # the nodes drawn over the cortex, in their colours
        assert (np.abs(rgb - v).max(axis=-1) <= 3).sum() > 50


@pytest.mark.render
@pytest.mark.integration
def test_a_lateral_view_shows_its_hemisphere_s_nodes_and_edges_dorsal_both(tmp_path):
    """Item 7: lateral-left draws the left nodes and the edges between them, not the right ones nor the
    edges across the midline (nilearn's ``l`` display mode); dorsal draws all."""
    c = ladder()
    result = brainpainter.render(None, "dk", connectome=c, views="dorsal,lateral-left,lateral-right", **FLAT)
    colours = dict(result.layers[1].scale.categories)
    seen = {}
    for (_, view), img in result.images.items():
        rgb = img[..., :3].astype(float)
        seen[view] = {name: int((np.abs(rgb - _rgb255(v)).max(axis=-1) <= 3).sum())
                      for name, v in colours.items()}
    assert seen["lateral-left"]["left"] > 100 and seen["lateral-right"]["right"] > 100
    assert seen["dorsal"]["left"] > 100 and seen["dorsal"]["right"] > 100
    # each lateral view is the picture of its hemisphere's nodes and edges alone (nothing of the other's
    # shows through the glass): it differs from that picture only where its nodes take their category's
    # colour (alone, a half's one category takes the first colour)
    for side, keep in (("left", slice(0, 4)), ("right", slice(4, 8))):
        half = Connectome(c.names[keep], c.positions[keep], c.weights[keep, keep],
                          node_categories=c.node_categories[keep])
        alone = brainpainter.render(None, "dk", connectome=half, views=f"lateral-{side}", **FLAT,
                                    edges_vmin=-0.6, edges_vmax=0.6, edges_cmap="RdBu_r")
        img = result.images[(next(iter(result.images))[0], f"lateral-{side}")][..., :3].astype(float)
        other = next(iter(alone.images.values()))[..., :3].astype(float)
        differ = np.abs(img - other).max(axis=-1) > 3
        recoloured = np.abs(img[differ] - _rgb255(colours[side])).max(axis=-1) <= 3
        assert not differ.any() or recoloured.mean() > 0.97


def test_connectome_parts_split_by_hemisphere_and_the_views_that_draw_them(tiny):
    """Item 7: nodes and edges are parts of their hemisphere; the edges between hemispheres belong to none
    and only views of both hemispheres draw them."""
    from brainpainter.atlas.template import load_template
    from brainpainter.rendering.scene import Scene
    from brainpainter.rendering.views import get_view

    scene = Scene(load_template(tiny), "dk", layers=(ConnectomeLayer(ladder()),))
    parts = {p.name: p.hemi for p in scene.geometry.parts if p.kind in ("node", "edge")}
    assert parts == {"nodes-lh": "lh", "nodes-rh": "rh", "edges-lh": "lh", "edges-rh": "rh", "edges": None}
    drawn = {view: {p.name for p in scene.geometry.visible(get_view(view)) if p.kind in ("node", "edge")}
             for view in ("dorsal", "lateral-left", "medial-right")}
    assert drawn["dorsal"] == set(parts)
    assert drawn["lateral-left"] == {"nodes-lh", "edges-lh"}
    assert drawn["medial-right"] == {"nodes-rh", "edges-rh"}


def test_yeo_network_categories_take_yeo_s_published_colours():
    """Item 8: Schaefer/Yeo network names as node categories take Yeo's colours (tab10 gave salience red)."""
    import matplotlib

    from brainpainter.color.scale import ScaleOptions
    from brainpainter.rendering.connectome_layers import category_scale

    seven = ("Vis", "SomMot", "DorsAttn", "SalVentAttn", "Limbic", "Cont", "Default")
    scale = category_scale(seven, ScaleOptions())
    got = {name: tuple(round(255 * c) for c in rgb) for name, rgb in scale.categories}
    assert got == {"Vis": (120, 18, 134), "SomMot": (70, 130, 180), "DorsAttn": (0, 118, 14),
                   "SalVentAttn": (196, 58, 250), "Limbic": (220, 248, 164), "Cont": (230, 148, 34),
                   "Default": (205, 62, 78)}
    assert dict(category_scale(("DefaultB", "TempPar"), ScaleOptions()).categories)["TempPar"] == \
        pytest.approx((12 / 255, 48 / 255, 1.0))
    assert dict(category_scale(("DMN", "Visual"), ScaleOptions()).categories)["DMN"] == \
        pytest.approx((205 / 255, 62 / 255, 78 / 255))
    # categories that are not all networks keep the categorical colour map
    other = category_scale(("Default", "module 3"), ScaleOptions())
    tab10 = matplotlib.colormaps["tab10"].colors[:2]  # type: ignore[attr-defined]
    assert [tuple(rgb) for _, rgb in other.categories] == [tuple(c) for c in tab10]


def test_a_connectome_figure_s_bars_are_named_by_layer_and_their_tick_labels_never_overprint(tiny, tmp_path):
    """Item 6: a figure of one narrow view has an edge bar (ticks -0.75 ... 0.75 at 0.25 steps) and a
    network key: no two tick labels shown overlap, and the bars are named by their layer, not by files."""
    from brainpainter.media.colorbar import agg_canvas
    from brainpainter.testing import stand_in

    rng = np.random.default_rng(0)
    n = 6
    w = rng.uniform(-0.91, 0.91, (n, n))
    w = (w + w.T) / 2
    w[0, 1] = w[1, 0] = 0.91
    matrix = tmp_path / "schaefer_400_mean_connectivity_matrix.csv"
    np.savetxt(matrix, w, delimiter=",")
    nodes = tmp_path / "nodes.csv"
    nodes.write_text("name,x,y,z\n" + "".join(f"n{i},{(-1) ** i * 30},{10 * i - 25},20\n" for i in range(n)))
    categories = tmp_path / "net400.txt"
    categories.write_text("\n".join(["Vis", "Default"] * (n // 2)) + "\n")
    kw = {"connectome": str(matrix), "nodes": str(nodes), "node_categories": str(categories),
          "template": str(tiny), "views": "dorsal", "width": 300, "height": 400, "progress": False}
    with stand_in() as renderer:
        fig = brainpainter.figure(None, renderer=renderer, **kw)
        # a long label of one's own: a narrow bar, the four tick labels too wide for it
        long = brainpainter.figure(None, renderer=renderer, edges_label="functional connectivity (Fisher z)",
                                   **kw)
    edges_ax, nodes_ax = fig.colorbar_axes
    assert edges_ax.xaxis.get_label().get_text() == "edge weight"
    assert nodes_ax.xaxis.get_label().get_text() == "network"
    for result in (fig, long):
        ax, renderer_ = result.colorbar_axes[0], agg_canvas(result.figure).get_renderer()
        shown = [t for t in ax.xaxis.get_ticklabels() if t.get_visible() and t.get_text()]
        boxes = sorted((b.x0, b.x1) for b in (t.get_window_extent(renderer_) for t in shown))
        space = renderer_.points_to_pixels(0.4 * shown[0].get_fontsize())  # a space between: 0.4 em
        assert len(boxes) >= 2  # was "-0.75-0.25 0.25 0.75": 0.2 em between the first two
        assert all(b[0] - a[1] >= space for a, b in itertools.pairwise(boxes)), \
            [t.get_text() for t in shown]


def test_node_labels_top_can_rank_within_each_category():
    """Item 9: ``--node-labels-top 1 --node-labels-per-category`` names each network's strongest."""
    from brainpainter.connectome.labels import labelled_nodes
    from brainpainter.errors import BrainPainterError

    c = Connectome(tuple("abcdef"), np.zeros((6, 3)), np.full((6, 6), np.nan),
                   node_values=np.array([9.0, 8.0, 7.0, 1.0, 2.0, 0.5]),
                   node_categories=("Vis", "Vis", "Vis", "Default", "Default", "Limbic"))
    assert labelled_nodes(c, 2) == (0, 1)  # all visual
    assert labelled_nodes(c, 1, per_category=True) == (0, 4, 5)
    assert labelled_nodes(c, 2, per_category=True) == (0, 1, 3, 4, 5)
    with pytest.raises(BrainPainterError, match="give --node-categories"):
        labelled_nodes(Connectome(c.names, c.positions, c.weights), 1, per_category=True)


def test_node_labels_print_at_least_7_points_in_a_figure(tiny, monkeypatch):
    """Item 9: in a three-view figure 7.2 in wide, the labels' text is at least 7 pt tall as printed (it was
    9 px of a 300 px render shown 1.6 in tall: 3.5 pt); a lateral view labels only its hemisphere's nodes."""
    from brainpainter.rendering import node_labels
    from brainpainter.testing import stand_in

    drawn: list[tuple[int, int]] = []
    height_of = node_labels.text_height
    monkeypatch.setattr(node_labels, "text_height",
                        lambda h, *a: drawn.append((h, height_of(h, *a))) or drawn[-1][1])
    labelled = []
    draw = node_labels.draw_node_labels
    monkeypatch.setattr(node_labels, "draw_node_labels",
                        lambda p, c, pose: labelled.append(c.labelled) or draw(p, c, pose))
    with stand_in() as renderer:
        fig = brainpainter.figure(None, connectome=ladder(), template=str(tiny), renderer=renderer,
                                  views="lateral-left,dorsal,lateral-right", width=400, height=300,
                                  node_labels=True, progress=False)
    assert len(drawn) == 3
    for ax in fig.image_axes.values():
        inches = ax.get_position().height * fig.figure.get_figheight()
        rows = ax.get_images()[0].get_array().shape[0]  # the render as shown (cropped)
        for _, px in drawn:
            assert px * inches * 72 / rows >= 7.0
    assert sorted(labelled, key=len) == [(0, 1, 2, 3), (4, 5, 6, 7), tuple(range(8))]


@pytest.mark.render
@pytest.mark.integration
def test_edges_labelled_keep_their_bar_s_colours_beside_regions_in_viridis(tmp_path):
    """Item 3, read back: with region values in viridis and ``edges_label="FC"`` the edge pixels are the
    colour of their weight on RdBu_r about 0 (they were viridis over 0.6..0.6)."""
    c = ladder()
    bare = Connectome(c.names, c.positions, np.full((8, 8), np.nan), node_categories=c.node_categories)
    table = {"Left-superiorfrontal": 1.0, "Right-superiorfrontal": 2.0}
    kw = {"cmap": "viridis", "edges_label": "FC", "views": "dorsal", **FLAT}
    result = brainpainter.render(table, "dk", connectome=c, **kw)
    img = next(iter(result.images.values()))[..., :3].astype(float)
    nodes_only = next(iter(brainpainter.render(table, "dk", connectome=bare, **{**kw, "edges_label": None})
                           .images.values()))[..., :3]
    edges = np.abs(img - nodes_only).max(axis=-1) > 30
    bar = _rgb255({la.kind: la.scale for la in result.layers}["edges"](np.array([0.6]))[0])
    assert np.allclose(bar, [103, 0, 31], atol=2)  # RdBu_r's darkest red: 0.6 is the largest |weight|
    assert edges.sum() > 1000 and np.median(np.abs(img[edges] - bar).max(axis=-1)) <= 10
