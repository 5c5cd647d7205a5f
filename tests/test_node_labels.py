"""Node labels drawn on connectome images (issue 36): which nodes, where the text is, off by default."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_connectome_render import cluster  # noqa: F401  (the Dask cluster fixture)

import brainpainter
from brainpainter.connectome.labels import labelled_nodes, node_strength
from brainpainter.connectome.model import Connectome
from brainpainter.connectome.options import ConnectomeOptions
from brainpainter.errors import BrainPainterError
from brainpainter.testing.connectome_check import tiny_connectome

FLAT = {"shading": "flat", "quality": "fast", "glass_opacity": 0.0, "background": "white"}


def star(values=None, labels=None) -> Connectome:
    """Four nodes; node 2 the hub (strength 1.6), then node 0 (0.9), node 3 (0.6), node 1 (0.1)."""
    w = np.full((4, 4), np.nan)
    for i, j, v in ((0, 2, -0.9), (1, 2, 0.1), (2, 3, 0.6)):
        w[i, j] = w[j, i] = v
    return Connectome(("a", "b", "c", "d"), np.zeros((4, 3)), w,
                      node_values=None if values is None else np.asarray(values, float), node_labels=labels)


def test_top_k_labels_the_largest_values_else_the_strongest_nodes():
    np.testing.assert_allclose(node_strength(star()), [0.9, 0.1, 1.6, 0.6])
    assert labelled_nodes(star(), 2) == (0, 2)  # by strength: |weight| summed, the sign ignored
    assert labelled_nodes(star(values=[5, np.nan, 1, 7]), 2) == (0, 3)  # by value, NaN last
    assert labelled_nodes(star(values=[1, 1, 1, 1]), 2) == (0, 2)  # equal values: by strength
    assert labelled_nodes(star(), None) == (0, 1, 2, 3)
    assert labelled_nodes(star(labels=("A", "", "C", "")), None) == (0, 2)  # "" is no label
    assert labelled_nodes(star(labels=("A", "", "C", "D")), 1) == (2,)
    options = ConnectomeOptions(star(labels=("A", "B", "C", "D")), node_labels_top=1)
    loaded = options.load(None)
    assert loaded is not None and loaded.labelled == (2,) and loaded.label_texts()[2] == "C"
    # the strength of the edges drawn: with only the 0.1 edge kept, b and c are the strongest
    trimmed = ConnectomeOptions(star(), edges_of="b", node_labels_top=2).load(None)
    assert trimmed is not None and trimmed.labelled == (1, 2)
    default = ConnectomeOptions(star(labels=("A", "B", "C", "D"))).load(None)
    assert default is not None and default.labelled == ()


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"node_labels": True}, "--node-labels describes"),
    ({"connectome": "m.csv", "node_labels_top": -1}, "--node-labels-top must be a whole number >= 0; -1"),
    ({"connectome": "m.csv", "node_labels_top": 1.5}, "--node-labels-top must be a whole number"),
])
def test_label_options_without_a_connectome_or_a_count_are_refused(kwargs, message):
    with pytest.raises(BrainPainterError, match=message.replace("(", r"\(")):
        ConnectomeOptions(**kwargs)


def _dark(img: np.ndarray) -> np.ndarray:
    return img[..., :3].max(axis=-1) < 60


def test_the_label_is_drawn_beside_its_node_and_no_other(tiny):
    """Dark text pixels just right of the labelled node's projected centre, none beside the other."""
    from brainpainter.rendering import framing
    from brainpainter.rendering.painter import load_scene
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    width, height = 400, 300
    kw = {"template": str(tiny), "views": "dorsal", "width": width, "height": height, "progress": False,
          **FLAT}
    labelled = brainpainter.render(None, connectome=tiny_connectome(), node_labels_top=1, **kw)
    plain = brainpainter.render(None, connectome=tiny_connectome(), **kw)
    img, before = labelled.images[("connectome", "dorsal")], plain.images[("connectome", "dorsal")]
    assert labelled.manifest["connectome"]["labelled"] == ["right"]  # node 1: value 4 > 1
    assert [n.get("label") for n in labelled.manifest["connectome"]["nodes"]] == [None, "right"]
    _, scene = load_scene("dk", str(tiny), settings=RenderSettings(width=width, height=height))
    pose = scene.geometry.camera(get_view("dorsal"), width / height)
    centres = framing.to_pixels(tiny_connectome().positions, pose, width, height)
    (x0, y0), (x1, y1) = centres.round().astype(int)
    text = _dark(img) & ~_dark(before)
    beside = text[y1 - 8:y1 + 8, x1:x1 + 80]
    assert beside.sum() > 20  # the text "right", just right of its sphere
    assert not text[y0 - 8:y0 + 8, x0:x0 + 80].any()  # the left node: unlabelled
    assert text.sum() == beside.sum()  # nothing drawn anywhere else
    # the same label at 6x the size: text 6x as tall
    big = brainpainter.render(None, connectome=tiny_connectome(), node_labels_top=1,
                              **{**kw, "width": 6 * width, "height": 6 * height})
    rows = np.nonzero(_dark(big.images[("connectome", "dorsal")]).any(axis=1))[0]
    assert 4 * (np.ptp(np.nonzero(text.any(axis=1))[0]) + 1) < np.ptp(rows) + 1


def test_a_label_whose_node_is_outside_the_image_is_skipped():
    from brainpainter.rendering.framing import CameraPose
    from brainpainter.rendering.node_labels import draw_node_labels

    pose = CameraPose(location=np.array([0.0, 0.0, 100.0]), rotation=np.eye(3), ortho_scale=100.0,
                      clip_start=1.0, clip_end=200.0)
    c = Connectome(("in", "out"), np.array([[0.0, 0.0, 0.0], [80.0, 0.0, 0.0]]), np.full((2, 2), np.nan),
                   labelled=(0, 1))
    blank = np.full((100, 100, 4), 255, np.uint8)
    drawn = draw_node_labels(blank, c, pose)
    dark = _dark(drawn)
    assert dark[40:60, 52:].any() and not dark[:, :50].any()  # "in" right of the centre; "out" left out


NAMES = ("alpha", "beta", "gamma", "delta")


def write_brainnet(tmp_path) -> tuple[str, str]:
    """A BrainNet Viewer pair on the tiny template: four labelled nodes of one size (value), beta the
    strongest, then delta."""
    xyz = [(-35, 10, 20), (-50, -20, 0), (35, 10, 20), (50, -20, 0)]
    (tmp_path / "net.node").write_text("".join(f"{x} {y} {z} 1 1 {n}\n" for (x, y, z), n
                                               in zip(xyz, NAMES, strict=True)))
    w = [[0, 0.5, -0.3, 0], [0.5, 0, 0, 0.8], [-0.3, 0, 0, 0.2], [0, 0.8, 0.2, 0]]
    (tmp_path / "net.edge").write_text("".join(" ".join(map(str, row)) + "\n" for row in w))
    return str(tmp_path / "net.node"), str(tmp_path / "net.edge")


def test_a_node_files_labels_change_no_picture_by_default_and_travel_to_jobs(
        tmp_path, tiny, cluster):  # noqa: F811  (the fixture imported)
    """A .node's label column alone draws nothing (today's pictures); --node-labels-top draws the top
    nodes' labels, the same in one process, with --jobs and on Dask workers, and the manifest names them."""
    from brainpainter.testing import stand_in

    nodes, edges = write_brainnet(tmp_path)
    kw = {"template": str(tiny), "views": "dorsal,lateral-left", "width": 240, "height": 180,
          "progress": False, "connectome": edges, "nodes": nodes,
          "cortex": "glass"}  # the stand-in draws the cortex's stripes (auto: the hull, no cortex)
    with stand_in() as renderer:
        default = brainpainter.render(None, renderer=renderer, **kw)
        # the same nodes without their labels: the labels column changes nothing drawn
        c = ConnectomeOptions(edges, nodes=nodes).load(None, str(tiny))
        assert c is not None and c.node_labels == NAMES
        bare = brainpainter.render(None, renderer=renderer, **{**kw, "connectome": Connectome(
            c.names, c.positions, c.weights), "nodes": None})
        serial = brainpainter.render(None, renderer=renderer, out=tmp_path / "serial", node_labels_top=2,
                                     **kw)
        jobs = brainpainter.render(None, renderer=renderer, out=tmp_path / "jobs", node_labels_top=2,
                                   jobs=2, **kw)
        dask = brainpainter.render(None, renderer=renderer, out=tmp_path / "dask", node_labels_top=2,
                                   client=cluster, **kw)
    image = next(iter(default.images.values()))
    np.testing.assert_array_equal(image, next(iter(bare.images.values())))
    assert "labelled" not in default.manifest["connectome"]
    manifest = json.loads((tmp_path / "serial" / "manifest.json").read_text())
    # equal node values (sizes): the strongest, beta and delta (strengths 1.3 and 1.0; 0.8, 0.5)
    assert manifest["connectome"]["labelled"] == ["beta", "delta"]
    assert jobs.workers["backend"] == "LocalRunner" and dask.workers["backend"] == "DaskRunner"
    assert jobs.manifest["connectome"] == manifest["connectome"]
    for path in serial.files:
        assert (tmp_path / "jobs" / path.name).read_bytes() == path.read_bytes()
        assert (tmp_path / "dask" / path.name).read_bytes() == path.read_bytes()
    from PIL import Image

    with Image.open(serial.files[0]) as png:
        drawn = np.asarray(png)
    assert (_dark(drawn) & ~_dark(image)).sum() > 20


def test_scene_add_passes_node_labels_through(tiny):
    from brainpainter import Scene
    from brainpainter.testing import stand_in

    with stand_in() as renderer:
        kw = {"template": str(tiny), "renderer": renderer, "width": 160, "height": 120}
        drawn = Scene("dk", **kw).add(tiny_connectome(), node_labels=True).render(views="dorsal",
                                                                                 progress=False)
        cli = brainpainter.render(None, connectome=tiny_connectome(), node_labels=True, views="dorsal",
                                  progress=False, **kw)
    assert drawn.manifest["connectome"]["labelled"] == ["left", "right"]
    np.testing.assert_array_equal(next(iter(drawn.images.values())), next(iter(cli.images.values())))


def test_labels_of_nodes_that_project_together_are_moved_apart():
    """Two nodes 1 mm apart: each label drawn alone sits right of its node; drawn together, the second
    moves (left of its node) so that no text pixel of either is covered and their boxes do not meet."""
    from brainpainter.rendering.framing import CameraPose, to_pixels
    from brainpainter.rendering.node_labels import draw_node_labels, place_labels

    pose = CameraPose(location=np.array([0.0, 0.0, 100.0]), rotation=np.eye(3), ortho_scale=100.0,
                      clip_start=1.0, clip_end=200.0)
    positions = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    blank = np.full((400, 400, 4), 255, np.uint8)

    def drawn(labelled):
        c = Connectome(("WWWW", "MMMM"), positions, np.full((2, 2), np.nan), labelled=labelled)
        return _dark(draw_node_labels(blank, c, pose))

    alone = [drawn((i,)) for i in (0, 1)]
    assert all(a[:, 200:].sum() > 50 and not a[:, :200].any() for a in alone)  # right of the node
    both = drawn((0, 1))
    assert both.sum() >= 0.97 * (alone[0].sum() + alone[1].sum())  # was ~half: each hid the other
    assert both[:, 200:].sum() > 0.9 * alone[0].sum() and both[:, :200].sum() > 0.9 * alone[1].sum()

    boxes = {}

    def box(i, xy, anchor):  # 40 x 12 px from the anchor point, as PIL anchors it
        x = xy[0] - {"l": 0, "m": 20, "r": 40}[anchor[0]]
        y = xy[1] - {"m": 6, "s": 12, "a": 0}[anchor[1]]
        boxes[i] = (x, y, x + 40, y + 12)
        return boxes[i]

    placed, left_out = place_labels([0, 1], to_pixels(positions, pose, 400, 400), np.array([5.0, 5.0]),
                                    (400, 400), box)
    (a, b) = (boxes[0], boxes[1])
    assert left_out == [] and [p[0] for p in placed] == [0, 1]
    assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]


def test_a_label_that_fits_nowhere_is_left_out():
    from brainpainter.rendering.node_labels import place_labels

    def wide(i, xy, anchor):  # a label wider than half the image fits on one side only
        return (xy[0], xy[1] - 5, xy[0] + 60, xy[1] + 5) if anchor[0] == "l" else (xy[0] - 60, xy[1] - 5,
                                                                                      xy[0], xy[1] + 5)

    placed, left_out = place_labels([3, 5], np.array([[30.0, 50.0], [31.0, 50.0]]), np.array([2.0, 2.0]),
                                    (100, 100), wide)
    assert [p[0] for p in placed] == [3] and left_out == [5]


def test_the_label_of_the_larger_node_value_is_placed_first():
    """Two nodes at one spot: the one of the larger value keeps the place right of the node."""
    from brainpainter.rendering.framing import CameraPose
    from brainpainter.rendering.node_labels import draw_node_labels

    pose = CameraPose(location=np.array([0.0, 0.0, 100.0]), rotation=np.eye(3), ortho_scale=100.0,
                      clip_start=1.0, clip_end=200.0)
    blank = np.full((400, 400, 4), 255, np.uint8)

    def drawn(labelled, values):
        c = Connectome(("WWWW", "MMMM"), np.zeros((2, 3)), np.full((2, 2), np.nan),
                       node_values=np.array(values, float), labelled=labelled)
        return _dark(draw_node_labels(blank, c, pose))

    w, m = drawn((0,), (1.0, 5.0)).sum(), drawn((1,), (1.0, 5.0)).sum()
    assert abs(w - m) > 0.2 * max(w, m)  # the two texts tell apart by their dark pixels
    for values, first in (((1.0, 5.0), m), ((5.0, 1.0), w)):
        both = drawn((0, 1), values)
        assert both[:, 200:].sum() == first  # the larger right of the node, as drawn alone
        assert both.sum() >= 0.95 * (w + m)  # the other left of it, uncovered
