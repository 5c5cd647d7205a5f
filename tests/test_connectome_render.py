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


# -- the command ---------------------------------------------------------------------------------
TINY_DK = ["Left-insula", "Left-precuneus", "Left-superiorfrontal", "Right-insula", "Right-precuneus",
           "Right-superiorfrontal"]


def write_matrix(path, weights: np.ndarray, names: list[str]) -> str:
    rows = [",".join(["", *names])] + [",".join([n, *("" if np.isnan(v) else repr(float(v)) for v in row)])
                                       for n, row in zip(names, weights, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def six_node_matrix(tmp_path) -> str:
    """The tiny template's six DK regions, every pair an edge of a distinct |weight| (15 edges)."""
    rng = np.random.default_rng(3)
    w = np.zeros((6, 6))
    iu = np.triu_indices(6, 1)
    w[iu] = rng.permutation(np.arange(1, 16)) / 15 * rng.choice([-1, 1], 15)
    return write_matrix(tmp_path / "m.csv", w + w.T, TINY_DK)


@pytest.fixture
def cli(tmp_path, tiny, capsys):
    """``brainpainter render`` with the stand-in on the tiny template: (exit code, stdout and stderr)."""
    from brainpainter.cli.main import main
    from brainpainter.testing import stand_in

    def run(*args: str) -> tuple[int, str]:
        with stand_in() as renderer, pytest.raises(SystemExit) as exit_:
            main(["render", "--atlas", "dk", "--template", str(tiny), "--renderer", renderer, "--size",
                  "80x60", "-q", "--out", str(tmp_path / "out"), *args])
        out = capsys.readouterr()
        return exit_.value.code or 0, out.out + out.err

    run.tiny = tiny  # type: ignore[attr-defined]
    return run


@pytest.mark.parametrize(("args", "n_edges"), [((), 15), (("--top-edges", "4"), 4),
                                               (("--edge-threshold", "80%"), 3),
                                               (("--edge-threshold", "0.5"), 8),
                                               (("--edges-of", "left-insula"), 5),
                                               (("--edges-of", "Left-insula", "--top-edges", "2"), 2)])
def test_the_edges_drawn_are_counted_in_the_manifest(tmp_path, cli, args, n_edges):
    code, output = cli("--connectome", six_node_matrix(tmp_path), *args)
    assert code == 0, output
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["connectome"]["n_edges"] == n_edges
    assert [n["name"] for n in manifest["connectome"]["nodes"]] == TINY_DK
    assert f"connectome: 6 node(s), {n_edges} edge(s) drawn" in output
    assert "input:" not in output and "regions matched" not in output  # no table to report
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["m_dorsal.png", "m_lateral-left.png",
                                                                   "manifest.json"]


def test_node_values_and_categories_files_give_the_node_layer(tmp_path, cli):
    (tmp_path / "values.csv").write_text("".join(f"{k}\n" for k in range(6)))
    nets = "".join(f"{'DMN' if 'precuneus' in n else 'other'}\n" for n in TINY_DK)
    (tmp_path / "nets.csv").write_text(nets)
    code, output = cli("--connectome", six_node_matrix(tmp_path), "--node-values",
                       str(tmp_path / "values.csv"), "--node-categories", str(tmp_path / "nets.csv"),
                       "--nodes-label", "network")
    assert code == 0, output
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    nodes = manifest["connectome"]["nodes"]
    assert [n["value"] for n in nodes] == [0, 1, 2, 3, 4, 5]
    assert [n["category"] for n in nodes][:2] == ["other", "DMN"]
    # each bar named by its layer, not by the matrix's file (issue 44)
    assert [(la["kind"], la["label"]) for la in manifest["settings"]["layers"]] == [("edges", "edge weight"),
                                                                                   ("nodes", "network")]


@pytest.mark.parametrize(("args", "message"), [
    (("--connectome", "{m34}"), "rows and columns must be the same nodes"),
    (("--connectome", "{m6}", "--nodes-cmap", "magma"), "--nodes-cmap colours node values"),
    (("--connectome", "{m6}", "--edge-threshold", "95 percent"), "the edge threshold must be a number"),
    (("--connectome", "{m6}", "--edges-of", "Left-insular"), "did you mean 'Left-insula'"),
    (("{table}", "--top-edges", "3"), "no --connectome was given"),
])
def test_bad_connectome_input_is_one_line_exit_2_nothing_written(tmp_path, cli, args, message):
    m34 = tmp_path / "m34.csv"
    m34.write_text(",a,b,c,d\nx,0,1,2,3\ny,1,0,1,2\nz,2,1,0,1\n")
    (tmp_path / "t.csv").write_text("Left-insula\n1\n")
    subs = {"{m34}": str(m34), "{m6}": six_node_matrix(tmp_path), "{table}": str(tmp_path / "t.csv")}
    code, output = cli(*(subs.get(a, a) for a in args))
    assert code == 2, output
    lines = [line for line in output.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in output, output
    assert not (tmp_path / "out").exists()


@pytest.mark.render
@pytest.mark.integration
def test_bar_the_command_draws_two_precentral_nodes_and_their_edge(tmp_path):
    """The first bar through the command: DK names, centroids from the atlas, node values from a file."""
    from click.testing import CliRunner
    from PIL import Image

    from brainpainter.cli.main import cli as command

    names = ["Left-precentral", "Right-precentral"]
    matrix = write_matrix(tmp_path / "pair.csv", np.array([[0.0, -0.7], [-0.7, 0.0]]), names)
    (tmp_path / "v.csv").write_text("1\n4\n")
    result = CliRunner().invoke(command, [
        "render", "--connectome", matrix, "--atlas", "dk", "--node-values", str(tmp_path / "v.csv"),
        "--views", "dorsal", "--size", "480x400", "--shading", "flat", "--quality", "fast",
        "--glass-opacity", "0", "-q", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    img = np.asarray(Image.open(tmp_path / "out" / "pair_dorsal.png").convert("RGBA"))
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    scales = {la["kind"]: la["scale"] for la in manifest["settings"]["layers"]}
    from brainpainter.color.scale import make_scale

    edge_rgb = make_scale(cmap="RdBu_r", vmin=-0.7, vmax=0.7, center=0.0)(np.array([-0.7]))[0]
    assert (scales["edges"]["vmin"], scales["edges"]["vmax"]) == (-0.7, 0.7)
    node = make_scale(cmap="viridis", vmin=scales["nodes"]["vmin"], vmax=scales["nodes"]["vmax"])
    small, large = (_near(img, node(np.array([v]))[0]) for v in (1.0, 4.0))
    edge = _near(img, edge_rgb)
    assert edge.sum() > 100 and small.sum() > 20 and large.sum() > 3 * small.sum()
    assert np.nonzero(small)[1].mean() < img.shape[1] / 2 < np.nonzero(large)[1].mean()
    positions = [n["position"] for n in manifest["connectome"]["nodes"]]
    assert positions[0][0] < -20 and positions[1][0] > 20  # the atlas's centroids, left and right


def test_a_figure_has_a_bar_per_layer_and_a_node_size_legend(tiny):
    from brainpainter.testing import stand_in

    with stand_in() as renderer:
        fig = brainpainter.figure(None, connectome=tiny_connectome(), template=str(tiny), renderer=renderer,
                                  width=80, height=60, progress=False)
    edges_ax, nodes_ax = fig.colorbar_axes
    assert edges_ax.xaxis.get_label().get_text() == "edge weight"
    assert nodes_ax.xaxis.get_label().get_text() == "node value"
    assert not edges_ax.collections  # the edges' bar has no circles
    (circles,) = nodes_ax.collections
    sizes = circles.get_sizes()
    # the smallest, middle and largest value, their diameters as the spheres' radii (2, 4, 6 mm)
    np.testing.assert_allclose(np.sqrt(sizes) / np.sqrt(sizes[-1]), [2 / 6, 4 / 6, 1.0])


@pytest.mark.render
def test_brainnet_node_and_edge_files_draw_the_same_picture_as_a_csv_with_coordinates(tmp_path, cli):
    """Issue 36's bar: BrainNet Viewer's .node/.edge pair and the same data as a named CSV matrix with
    a coordinates file, node values and categories give the same pixels."""
    from PIL import Image

    from brainpainter.cli.main import main

    xyz = np.array([[-35.0, 10.0, 20.0], [-50.0, -20.0, 0.0], [35.0, 10.0, 20.0], [50.0, -20.0, 0.0]])
    names, sizes, modules = ["a", "b", "c", "d"], [1.0, 2.0, 3.0, 4.0], [1, 1, 2, 2]
    w = np.array([[0, 0.5, -0.3, 0], [0.5, 0, 0, 0.8], [-0.3, 0, 0, 0.2], [0, 0.8, 0.2, 0]])
    (tmp_path / "net.node").write_text("".join(f"{x:g} {y:g} {z:g} {m} {s:g} {n}\n" for (x, y, z), m, s, n
                                               in zip(xyz, modules, sizes, names, strict=True)))
    (tmp_path / "net.edge").write_text("".join(" ".join(f"{v:g}" for v in row) + "\n" for row in w))
    rows = [f"{n},{x:g},{y:g},{z:g}\n" for n, (x, y, z) in zip(names, xyz, strict=True)]
    (tmp_path / "xyz.csv").write_text("name,x,y,z\n" + "".join(rows))
    (tmp_path / "size.txt").write_text("\n".join(f"{s:g}" for s in sizes) + "\n")
    (tmp_path / "module.txt").write_text("\n".join(str(m) for m in modules) + "\n")
    matrix = write_matrix(tmp_path / "net.csv", w, names)
    images = []
    brainnet = ["--connectome", str(tmp_path / "net.edge"), "--nodes", str(tmp_path / "net.node")]
    csv = ["--connectome", matrix, "--nodes", str(tmp_path / "xyz.csv"), "--node-values",
           str(tmp_path / "size.txt"), "--node-categories", str(tmp_path / "module.txt")]
    for k, args in enumerate((brainnet, csv)):
        with pytest.raises(SystemExit) as exit_:
            main(["render", *args, "--template", str(cli.tiny), "--views", "dorsal", "--size", "240x180",
                  "-q", "--out", str(tmp_path / f"out{k}")])
        assert not exit_.value.code
        images.append(np.asarray(Image.open(tmp_path / f"out{k}" / "net_dorsal.png")))
        manifest = json.loads((tmp_path / f"out{k}" / "manifest.json").read_text())
        assert manifest["connectome"]["n_edges"] == 4
    assert (images[0] != 255).any()
    np.testing.assert_array_equal(images[0], images[1])


@pytest.fixture(scope="module")
def cluster():
    """A Dask cluster of two worker processes (as tests/test_parallel.py's)."""
    distributed = pytest.importorskip("distributed")
    from test_parallel import local_cluster

    with local_cluster(distributed) as c, distributed.Client(c, set_as_default=False) as client:
        yield client


def test_a_connectome_travels_to_jobs_and_dask_workers(tmp_path, tiny, cluster):
    """``--jobs`` and Dask: the workers' painters are built from the pickled PainterSpec, the
    connectome in it."""
    from brainpainter.testing import stand_in

    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula,Right-insula\n" + "".join(f"S{i},{i},{3 - i}\n"
                                                                              for i in range(4)))
    kw = {"template": str(tiny), "views": "dorsal", "width": 80, "height": 60, "progress": False}
    with stand_in() as renderer:
        serial = brainpainter.render(table, "dk", out=tmp_path / "serial", renderer=renderer,
                                     connectome=tiny_connectome(), **kw)
        jobs = brainpainter.render(table, "dk", out=tmp_path / "jobs", renderer=renderer, jobs=2,
                                   connectome=tiny_connectome(), **kw)
        dask = brainpainter.render(table, "dk", out=tmp_path / "dask", renderer=renderer, client=cluster,
                                   connectome=tiny_connectome(), **kw)
        plain = brainpainter.render(table, "dk", renderer=renderer, cortex="glass", **kw)
    assert jobs.workers["backend"] == "LocalRunner"
    assert jobs.manifest["connectome"] == serial.manifest["connectome"]
    assert dask.workers["backend"] == "DaskRunner"
    for path in serial.files:
        assert (tmp_path / "jobs" / path.name).read_bytes() == path.read_bytes()
        assert (tmp_path / "dask" / path.name).read_bytes() == path.read_bytes()
    # the workers drew the nodes and the edge (the stand-in: a stripe each in their colours)
    from PIL import Image

    with Image.open(tmp_path / "jobs" / "S1_dorsal.png") as png:
        drawn = np.asarray(png)
    edge = serial.layers[1].scale(np.array([0.8]))[0]
    assert _near(drawn, edge, 1).any() and not _near(plain.images[("S1", "dorsal")], edge, 1).any()


def test_the_export_names_each_node_and_edge_with_its_value_for_the_tooltip(tmp_path, tiny):
    """GLB/HTML: a mesh per node (its name, its value) and per edge ('a – b', its weight), part
    'connectome'; the page draws the cortex as glass over it."""
    import struct

    c = tiny_connectome()
    glb = brainpainter.export(None, tmp_path / "c.glb", connectome=c, template=str(tiny)).read_bytes()
    doc = json.loads(glb[20:20 + struct.unpack("<I", glb[12:16])[0]])
    extras = {node["name"]: node["extras"] for node in doc["nodes"] if node["extras"]["part"] == "connectome"}
    assert {name: (e["name"], e["value"]) for name, e in extras.items()} == {
        "left": ("left", "1"), "right": ("right", "4"), "left \u2013 right": ("left \u2013 right", "0.8")}
    page = brainpainter.export(None, tmp_path / "c.html", connectome=c, template=str(tiny)).read_text()
    tag = 'id="brainpainter-config" type="application/json">'
    config = json.loads(page.split(tag)[1].split("</script>")[0])
    assert config["parts"][-1] == "connectome" and config["glass"] == ["lh", "rh"]
    assert 'data-part="connectome"' in page


@pytest.mark.render
@pytest.mark.integration
def test_a_connectome_inside_a_map_drawn_as_glass(tmp_path):
    """A map (--lh/--rh) with a connectome: the map on the glass cortex, the nodes and edge inside it,
    the map's own scale and opacity kept, the connectome's two layers after it."""
    from PIL import Image

    rng = np.random.default_rng(0)
    maps = {"lh": rng.uniform(1.5, 4, 10242), "rh": rng.uniform(1.5, 4, 10242)}
    kw = {"views": "dorsal", "width": 400, "height": 320, "progress": False}
    with_c = brainpainter.render(maps, connectome=precentral_pair(), map_alpha=1.0, **kw)
    alone = brainpainter.render(maps, cortex="glass", **kw)
    assert [layer.kind for layer in with_c.layers] == ["map", "edges", "nodes"]
    assert with_c.layers[0].scale.to_dict() == alone.layers[0].scale.to_dict()
    assert with_c.manifest["connectome"]["n_edges"] == 1
    (key,) = with_c.images
    img = with_c.images[key]
    Image.fromarray(img).save(tmp_path / "map_connectome.png")
    # the large node: its colour on the nodes' scale, through the glass, where the map alone has none
    node = with_c.layers[2].scale(np.array([4.0]))[0]
    assert _near(img, node, 40).sum() > 50 and _near(alone.images[key], node, 40).sum() < 5


@pytest.mark.render
@pytest.mark.integration
def test_bar_schaefer400_top_1_percent_inside_the_cortex(tmp_path):
    """Issue 36's second bar (the drawing side): a real 400 x 400 resting-state matrix on Schaefer-400,
    top 1 % of its edges: 798 edges drawn, the nodes inside the brain, the edges in the edge scale's
    colours through the glass cortex."""
    import importlib.metadata
    from pathlib import Path

    from PIL import Image

    from brainpainter.atlas.model import load_atlas_dir

    try:
        dist = importlib.metadata.distribution("brainspace")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("brainspace (a test extra) is not installed")
    matrix = dist.locate_file("brainspace/datasets/matrices/holdout_group/"
                              "schaefer_400_mean_connectivity_matrix.csv")
    atlas = load_atlas_dir(Path(__file__).resolve().parents[1] / "plugins" / "atlases"
                           / "brainpainter-atlas-schaefer-yeo" / "bp_atlas_schaefer_yeo" / "data"
                           / "schaefer400_7n")
    with pytest.warns(UserWarning, match="the atlases that take 400 rows: .*schaefer400_17n"):  # no names
        result = brainpainter.render(None, atlas, connectome=str(matrix), edge_threshold="99%",
                                     views="dorsal", width=600, height=500, progress=False, glass_opacity=0.0,
                                     shading="flat", quality="fast")
    c = result.manifest["connectome"]
    assert c["n_nodes"] == 400 and c["n_edges"] == round(0.01 * 400 * 399 / 2)
    positions = np.array([n["position"] for n in c["nodes"]])
    assert (np.sign(positions[:200, 0]) < 0).all() and (np.sign(positions[200:, 0]) > 0).all()
    (key,) = result.images
    img = result.images[key]
    Image.fromarray(img).save(tmp_path / "schaefer400.png")
    edges = result.layers[0].scale
    lo, hi = c["weight_range"]
    drawn = sum(_near(img, edges(np.array([w]))[0], 3) for w in np.linspace(lo, hi, 12)).astype(bool)
    assert drawn.sum() > 2000  # edge pixels in the edge scale's colours
    nodes = _near(img, (0.25, 0.25, 0.30), 2)  # the nodes' grey (no node values)
    xs = np.nonzero(nodes)[1]
    assert nodes.sum() > 2000 and xs.min() > 0.05 * img.shape[1] and xs.max() < 0.95 * img.shape[1]


@pytest.mark.integration
def test_a_map_over_regions_keeps_its_opacity_beside_a_connectome():
    """The map's --map-alpha is its layer's, not the last layer's (a connectome's come after it)."""
    from brainpainter.rendering.run import prepare_run

    kw = {"lh": np.linspace(0, 1, 10242), "rh": np.linspace(1, 0, 10242), "map_alpha": 0.5}
    plain = prepare_run({"Left-insula": 1.0, "Right-insula": 2.0}, "dk", **kw)
    with_c = prepare_run({"Left-insula": 1.0, "Right-insula": 2.0}, "dk", connectome=tiny_connectome(), **kw)
    assert [layer.kind for layer in with_c.layers] == ["regions", "map", "edges", "nodes"]
    for hemi in ("lh", "rh"):
        np.testing.assert_array_equal(with_c.colors(0).vertices[hemi], plain.colors(0).vertices[hemi])
    assert set(with_c.colors(0)) - set(plain.colors(0)) == {"node:0", "node:1", "edge:0"}


@pytest.fixture(scope="module")
def chromium():
    """Headless Chromium (tests/test_export.py's ``browser``)."""
    from test_export import browser

    yield from browser.__wrapped__()  # type: ignore[attr-defined]


def test_hovering_a_node_through_the_glass_names_it_in_headless_chromium(tmp_path, tiny, chromium):
    """The HTML export's tooltip names the node under the mouse (with its value), not the glass cortex
    in front of it, and an edge with its weight."""
    import time

    from test_export import _load

    # seen from the left (the page's first view) the nodes and the edge between them lie apart
    c = Connectome(("left", "right"), np.array([[-35.0, -20.0, 10.0], [35.0, 20.0, 30.0]]),
                   np.array([[np.nan, -0.8], [-0.8, np.nan]]), node_values=np.array([1.0, 4.0]))
    page = brainpainter.export(None, tmp_path / "c.html", connectome=c, template=str(tiny))
    driver = chromium
    _load(driver, page.as_uri())
    for name, expected in (("left", "left: 1"), ("right", "right: 4"),
                           ("left \u2013 right", "left \u2013 right: -0.8")):
        x, y = driver.execute_script("""
            const v = window.brainpainterViewer, T = window.BPTHREE;
            const m = v.meshes.find((o) => o.userData.name === arguments[0]);
            const c = new T.Box3().setFromObject(m).getCenter(new T.Vector3()).project(v.camera);
            const r = v.renderer.domElement.getBoundingClientRect();
            return [r.left + (c.x + 1) / 2 * r.width, r.top + (1 - c.y) / 2 * r.height];""", name)
        driver.execute_script("""
            const e = new PointerEvent("pointermove", {clientX: arguments[0], clientY: arguments[1]});
            window.brainpainterViewer.renderer.domElement.dispatchEvent(e);""", x, y)
        time.sleep(0.2)
        assert driver.execute_script("return document.getElementById('tip').textContent") == expected


def test_a_connectome_alone_turns_in_a_movie(tmp_path, tiny):
    """A movie of one image with --orbit is a rotation (a connectome alone has one image)."""
    from brainpainter.media.movie import make_movie
    from brainpainter.testing.stand_in import StandInRenderer, stand_in

    with stand_in() as renderer:
        result = make_movie(None, connectome=tiny_connectome(), out=tmp_path / "turn.gif", orbit=360,
                            views="camera:180:20", frames_per_step=4, template=str(tiny), renderer=renderer,
                            width=64, height=48, progress=False)
        azimuths = [view.azimuth for _, view in StandInRenderer.calls]
    assert result.n_frames == 5
    assert azimuths == [180.0, 252.0, 324.0, 36.0, 108.0]  # the camera turns a full circle in 5 frames
    edge = result.scale(np.array([0.8]))[0]
    assert all(np.allclose(colors["edge:0"], edge[:3]) for colors, _ in StandInRenderer.calls)


def test_scene_add_a_connectome_draws_as_the_command_line(tmp_path, tiny):
    """``Scene.add``: a Connectome is inferred, a matrix file given kind="connectome"; its keywords
    become the command line's options and the same pixels."""
    from brainpainter import Scene
    from brainpainter.testing import stand_in

    with stand_in() as renderer:
        kw = {"template": str(tiny), "renderer": renderer, "width": 80, "height": 60}
        scene = Scene("dk", **kw).add({"Left-insula": 1.0}).add(tiny_connectome(), cmap="magma", label="FC")
        assert scene.layers[1].kind == "connectome"
        assert scene.run_options()[1]["edges_cmap"] == "magma"
        drawn = scene.render(views="dorsal", progress=False)
        cli = brainpainter.render({"Left-insula": 1.0}, "dk", connectome=tiny_connectome(),
                                  edges_cmap="magma", edges_label="FC", views="dorsal", progress=False, **kw)
        matrix = six_node_matrix(tmp_path)
        from_file = Scene("dk", **kw).add(matrix, kind="connectome", top_edges=2).render(views="dorsal",
                                                                                          progress=False)
    assert [la.kind for la in drawn.layers] == ["regions", "edges", "nodes"] and drawn.layers[1].label == "FC"
    np.testing.assert_array_equal(drawn.images[("1", "dorsal")], cli.images[("1", "dorsal")])
    assert from_file.manifest["connectome"]["n_edges"] == 2
