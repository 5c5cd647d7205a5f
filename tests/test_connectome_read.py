"""Connectome inputs: matrix files (CSV/TSV/.txt/.edge/.npy/.mat/.pconn), node order and names, centroids,
nodes files (coordinates, BrainNet Viewer .node), vectors per node, and the bad inputs of each."""

from __future__ import annotations

import importlib.metadata
import tracemalloc
import warnings
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
import scipy.io

from brainpainter.atlas.model import load_atlas_dir
from brainpainter.atlas.registry import get_atlas
from brainpainter.atlas.volumes import space_transform
from brainpainter.connectome.centroids import atlas_template, centroid, region_centroids
from brainpainter.connectome.matrix import read_matrix
from brainpainter.connectome.order import describe_order, node_order
from brainpainter.connectome.read import read_connectome
from brainpainter.errors import BrainPainterError

REPO = Path(__file__).resolve().parents[1]
SCHAEFER400 = (REPO / "plugins" / "atlases" / "brainpainter-atlas-schaefer-yeo" / "bp_atlas_schaefer_yeo"
               / "data" / "schaefer400_7n")
MOUSE = REPO / "plugins" / "atlases" / "brainpainter-atlas-mouse" / "bp_atlas_mouse" / "data" / "mouse"
W3 = np.array([[0.0, 0.5, -0.2], [0.5, 0.0, 0.0], [-0.2, 0.0, 0.0]])
DK3 = ["Left-precentral", "Right-precentral", "Left-insula"]


@pytest.fixture(scope="module")
def dk():
    return get_atlas("dk")


def write_csv(path: Path, weights: np.ndarray, names: list[str] | None = None, rows: bool = True,
              columns: bool = True, sep: str = ",") -> Path:
    lines = []
    if names is not None and columns:
        lines.append(sep.join(([""] if rows else []) + names))
    for i, row in enumerate(weights):
        cells = ["NaN" if np.isnan(v) else repr(float(v)) for v in row]
        lines.append(sep.join(([names[i]] if names is not None and rows else []) + cells))
    path.write_text("\n".join(lines) + "\n")
    return path


# -- matrix files -------------------------------------------------------------------------------
@pytest.mark.parametrize("rows,columns,sep", [(True, True, ","), (False, True, "\t"), (True, False, ","),
                                              (True, True, "\t")])
def test_text_matrix_names_in_first_row_and_or_column(tmp_path, rows, columns, sep):
    path = write_csv(tmp_path / "m.csv", W3, ["ctx-lh-precentral", "Right-precentral", "lh_insula"], rows,
                     columns, sep)
    m = read_matrix(path)
    assert m.names == ("ctx-lh-precentral", "Right-precentral", "lh_insula")
    np.testing.assert_array_equal(m.weights, W3)


def test_text_matrix_without_names_and_pandas_numbered_index(tmp_path):
    import pandas as pd

    np.savetxt(tmp_path / "m.txt", W3)
    assert read_matrix(tmp_path / "m.txt").names is None
    np.testing.assert_array_equal(read_matrix(tmp_path / "m.txt").weights, W3)
    pd.DataFrame(W3).to_csv(tmp_path / "pd.csv")  # header ",0,1,2" and an index column 0..2
    m = read_matrix(tmp_path / "pd.csv")
    assert m.names is None and m.weights.shape == (3, 3)
    np.testing.assert_allclose(m.weights, W3)


def test_xlsx_matrix_with_names_reads_as_region_tables_do(tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("openpyxl")
    names = ["Left-insula", "Right-insula"]
    pd.DataFrame([[0, 0.5], [0.5, 0]], index=names, columns=names).to_excel(tmp_path / "m.xlsx")
    m = read_matrix(tmp_path / "m.xlsx")
    assert m.names == tuple(names) and m.weights[0, 1] == 0.5


def test_text_matrix_takes_a_small_multiple_of_its_size_in_memory(tmp_path):
    path = tmp_path / "m.csv"
    np.savetxt(path, np.random.default_rng(0).uniform(-1, 1, (400, 400)), fmt="%.4f", delimiter=",")
    tracemalloc.start()
    try:
        assert read_matrix(path).weights.shape == (400, 400)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5 * path.stat().st_size  # a Python string per cell took 11.5x


@pytest.mark.parametrize("sep", [",", " "])
def test_one_long_line_is_refused_before_it_is_split(tmp_path, sep):
    path = tmp_path / "m.txt"
    path.write_text(sep.join(["0.5"] * 1_000_000) + f"\n0{sep}1\n1{sep}0\n")
    message, peak = refused(path)
    assert "line 1 has more than 5 fields but the file has 3 lines" in message
    assert peak < 4 * path.stat().st_size  # splitting it made a string per field: 20 times its size


@pytest.mark.parametrize("end", ["\n", "\r\n", "\r"])
def test_spreadsheet_exports_with_a_separator_at_every_line_end(tmp_path, end):
    (tmp_path / "m.csv").write_bytes(end.join([",A,B,", "A,,0.5,", "B,0.5,,", ""]).encode())
    m = read_matrix(tmp_path / "m.csv")
    assert m.names == ("A", "B") and m.weights[0, 1] == 0.5 and m.weights[1, 1] == 0  # empty: no edge


def test_npy_mat_edge_and_array_read_alike(tmp_path):
    np.save(tmp_path / "m.npy", W3)
    scipy.io.savemat(tmp_path / "m.mat", {"W": W3, "label": "dk", "n": np.array([3])})
    np.savetxt(tmp_path / "m.edge", W3, delimiter="\t")
    for given in (tmp_path / "m.npy", tmp_path / "m.mat", tmp_path / "m.edge", W3, W3.tolist()):
        np.testing.assert_array_equal(read_matrix(given).weights, W3)


def write_pconn(path: Path, weights: np.ndarray = W3) -> Path:
    names = ["ctx-lh-precentral", "ctx-rh-precentral", "ctx-lh-insula"]
    parcels = nib.cifti2.cifti2_axes.ParcelsAxis(
        names, [np.zeros((0, 3), int)] * 3,
        [{"CIFTI_STRUCTURE_CORTEX_LEFT": np.array([i])} for i in range(3)],
        nvertices={"CIFTI_STRUCTURE_CORTEX_LEFT": 10})
    header = nib.cifti2.Cifti2Header.from_axes((parcels, parcels))
    nib.save(nib.cifti2.Cifti2Image(weights.astype(np.float32), header), path)
    return path


def test_pconn_names_come_from_its_parcel_axes(tmp_path):
    conn = read_connectome(write_pconn(tmp_path / "m.pconn.nii"), get_atlas("dk"))
    assert conn.names == tuple(DK3)
    np.testing.assert_allclose(conn.weights[0, 1], 0.5)


# -- nodes from the atlas -------------------------------------------------------------------------
def test_named_matrix_on_dk_two_nodes_left_left_right_right(tmp_path, dk):
    path = write_csv(tmp_path / "m.csv", np.array([[0.0, 0.7], [0.7, 0.0]]),
                     ["ctx-lh-precentral", "precentral_R"])
    conn = read_connectome(path, dk)
    assert conn.names == ("Left-precentral", "Right-precentral")
    assert conn.positions[0, 0] < -20 and conn.positions[1, 0] > 20  # left node left of the midline
    source, target, weight = conn.edges()
    assert (source.tolist(), target.tolist(), weight.tolist()) == ([0], [1], [0.7])
    assert np.isnan(conn.weights[0, 0]) and conn.weights[1, 0] == 0.7


def test_unnamed_matrix_follows_the_atlas_node_order(dk):
    cortical, every = node_order(dk)
    assert len(cortical) == 68 and cortical[0].startswith("Left-") and cortical[-1].startswith("Right-")
    assert every[:68] == cortical and len(every) == len(dk.regions)
    assert "68 cortical regions" in describe_order(dk)
    conn = read_connectome(np.eye(68) * 0 + 0.1, dk)
    assert conn.names == cortical and len(conn.edges()[0]) == 68 * 67 // 2


def test_schaefer_order_is_its_label_order():
    atlas = load_atlas_dir(SCHAEFER400)
    cortical, _ = node_order(atlas)
    assert [atlas.region(k).index for k in cortical] == [*range(1001, 1201), *range(2001, 2201)]
    assert cortical[0] == "Left-Vis_1" and cortical[200] == "Right-Vis_1"


def test_atlas_show_prints_the_node_order():
    from click.testing import CliRunner

    from brainpainter.cli.main import cli

    out = CliRunner().invoke(cli, ["atlas", "show", "dk"])
    assert out.exit_code == 0 and "connectome matrix without names" in out.output
    import json

    data = json.loads(CliRunner().invoke(cli, ["atlas", "show", "dk", "--json"]).output)
    assert data["connectome_order"][:2] == ["Left-bankssts", "Left-caudalanteriorcingulate"]


def test_centroid_of_a_curved_sheet_is_pulled_into_it_and_a_closed_box_keeps_its_mean():
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=50.0)
    cap = sphere.faces[sphere.vertices[sphere.faces].mean(axis=1)[:, 2] > 30]  # a cap: its mean is below it
    point = centroid(sphere.vertices, cap)
    region = np.unique(sphere.vertices[cap.ravel()], axis=0)
    assert np.linalg.norm(region - point, axis=1).min() <= 2.0 + 1e-9
    box = trimesh.creation.box(extents=(10, 20, 10))
    np.testing.assert_allclose(centroid(box.vertices, box.faces, closed=True), [0, 0, 0], atol=1e-9)


def test_schaefer400_centroids_lie_within_5mm_of_their_regions():
    atlas = load_atlas_dir(SCHAEFER400)
    keys, _ = node_order(atlas)
    points = region_centroids(atlas, keys)
    tpl = atlas_template(atlas)
    worst = 0.0
    for hemi, prefix in (("lh", "Left-"), ("rh", "Right-")):
        mesh = tpl.cortex(atlas.template_labels, hemi)
        pial = np.asarray(mesh.vertices["pial"], dtype=float)
        for i, key in enumerate(keys):
            if key.startswith(prefix):
                label = mesh.label_names.index(key[len(prefix):])
                region = pial[np.unique(mesh.faces[mesh.face_label == label])]
                worst = max(worst, float(np.linalg.norm(region - points[i], axis=1).min()))
    assert worst <= 5.0


def test_volume_structures_centroids_are_inside_them(tiny):
    atlas = get_atlas("dk")
    points = region_centroids(atlas, ["Left-Hippocampus", "Right-Hippocampus", "Left-insula"], str(tiny))
    np.testing.assert_allclose(points[:2], [[-20, 0, 0], [20, 0, 0]], atol=1e-4)  # the boxes' centres
    assert points[2, 0] < -20


@pytest.mark.usefixtures("fresh_registry")
def test_cortex_and_volume_atlas_combined_nodes_in_the_atlas_order_inside_the_volumes(tmp_path):
    from test_volumes import write_volume

    from brainpainter.atlas.volumes import add_volume_atlas

    lut = tmp_path / "lut.csv"
    lut.write_text("1,ball-lh\n2,ball-rh\n7,box\n")
    add_volume_atlas("balls", write_volume(tmp_path / "balls.nii.gz"), lut, space="fsaverage")
    atlas = get_atlas("dk+balls")
    conn = read_connectome(np.ones((71, 71)), atlas)  # 68 cortical regions, then the volume's 3
    assert conn.names[67:] == ("Right-insula", "Left-ball", "Right-ball", "box")
    np.testing.assert_allclose(conn.positions[68:70], [[-20, 0, 0], [20, 0, 0]], atol=0.5)  # ball centres
    assert np.all(np.abs(conn.positions[70] - [0, 18, -6]) < [12, 6, 6])  # inside the box


def test_region_group_node_is_the_centroid_of_its_members_together(tiny):
    from brainpainter.atlas.model import Atlas, Region

    group = Region(1, "front", "lh", "cortical", (1, 2, 3))
    members_of = (("Left-front", ("Left-insula", "Left-superiorfrontal")),)
    atlas = Atlas("g", "g", "dk", (group,), members=members_of)
    point = region_centroids(atlas, ["Left-front"], str(tiny))[0]
    members = region_centroids(get_atlas("dk"), ["Left-insula", "Left-superiorfrontal"], str(tiny))
    mesh = atlas_template(atlas, str(tiny)).cortex("dk", "lh")
    labels = [mesh.label_names.index(n) for n in ("insula", "superiorfrontal")]
    union = mesh.vertices["pial"][np.unique(mesh.faces[np.isin(mesh.face_label, labels)])]
    assert np.linalg.norm(union - point, axis=1).min() <= 2.0 + 1e-6  # in (or just beneath) the group
    assert min(np.linalg.norm(members - point, axis=1)) > 10  # neither member's own node


def test_mouse_atlas_nodes_on_its_own_brain_inside_their_structures():
    from brainpainter.connectome.centroids import _winding

    atlas = load_atlas_dir(MOUSE)
    _, every = node_order(atlas)
    points = region_centroids(atlas, every)  # the atlas's own template, not fsaverage
    sub = atlas_template(atlas).subcortical()
    inside = []
    for key, point in zip(every, points, strict=True):
        if atlas.region(key).kind == "subcortical":
            faces = sub.faces[sub.face_label == sub.label_names.index(key)]
            inside.append(_winding(point, sub.vertices[faces].astype(float)))
    assert len(inside) == 14 and min(inside) > 0.5
    assert np.all(np.abs(points) < 110)  # within the mouse brain's bounds (its own units)


# -- nodes files --------------------------------------------------------------------------------
def test_brainnet_node_edge_equal_csv_with_coordinates(tmp_path):
    xyz = np.array([[-40.0, -10, 50], [40, -10, 50], [-35, 5, 2]])
    node_lines = ["# BrainNet Viewer nodes"] + [
        f"{x:g}\t{y:g}\t{z:g}\t{c}\t{s:g}\t{name}" for (x, y, z), c, s, name
        in zip(xyz, (1, 1, 2), (3.0, 2.0, 1.5), ("PreCG.L", "PreCG.R", "INS.L"), strict=True)]
    (tmp_path / "n.node").write_text("\n".join(node_lines) + "\n")
    np.savetxt(tmp_path / "n.edge", W3, delimiter="\t")
    brainnet = read_connectome(tmp_path / "n.edge", nodes=tmp_path / "n.node")
    (tmp_path / "nodes.csv").write_text("name,x,y,z,module,strength\nPreCG.L,-40,-10,50,1,3\n"
                                        "PreCG.R,40,-10,50,1,2\nINS.L,-35,5,2,2,1.5\n")
    write_csv(tmp_path / "m.csv", W3, ["PreCG.L", "PreCG.R", "INS.L"])
    csv = read_connectome(tmp_path / "m.csv", nodes=tmp_path / "nodes.csv", node_values="strength",
                          node_categories="module", node_labels="name")
    assert brainnet.names == csv.names == ("PreCG.L", "PreCG.R", "INS.L")
    for field in ("positions", "weights", "node_values"):
        np.testing.assert_array_equal(getattr(brainnet, field), getattr(csv, field))
    assert brainnet.node_categories == csv.node_categories == ("1", "1", "2")
    assert brainnet.node_labels == csv.node_labels


def test_node_and_vector_files_written_by_windows_tools(tmp_path):
    nodes = "-40\t-10\t50\t1\t3\tPreCG.L\r\n40\t-10\t50\t2\t2\tPreCG.R\r\n"
    (tmp_path / "n.node").write_bytes(nodes.encode("utf-8-sig"))
    (tmp_path / "v.txt").write_bytes("1.5\r\n2\r\n".encode("utf-16"))
    conn = read_connectome(np.array([[0, 1.0], [1.0, 0]]), nodes=tmp_path / "n.node",
                           node_values=tmp_path / "v.txt")
    assert conn.names == ("PreCG.L", "PreCG.R") and conn.positions[0, 0] == -40
    np.testing.assert_array_equal(conn.node_values, [1.5, 2.0])


def test_named_matrix_reorders_the_nodes_file_and_mni_is_mapped_as_tracts_are(tmp_path, tiny):
    (tmp_path / "nodes.csv").write_text("label,x,y,z\nB,1,2,3\nA,4,5,6\n")
    write_csv(tmp_path / "m.csv", np.array([[0.0, 1.0], [1.0, 0.0]]), ["A", "B"])
    conn = read_connectome(tmp_path / "m.csv", nodes=tmp_path / "nodes.csv", space="MNI152NLin2009cAsym")
    from brainpainter.atlas.template import load_template

    affine = space_transform("MNI152NLin2009cAsym", load_template("fsaverage"))
    want = np.array([[4, 5, 6], [1, 2, 3]]) @ affine[:3, :3].T + affine[:3, 3]
    assert conn.names == ("A", "B")
    np.testing.assert_allclose(conn.positions, want)
    assert not np.allclose(conn.positions, [[4, 5, 6], [1, 2, 3]])


def test_node_vectors_from_files_and_sequences(tmp_path, dk):
    np.save(tmp_path / "v.npy", np.array([1.0, 2.0]))
    (tmp_path / "c.txt").write_text("visual,motor\n")  # two entries on a line: no node names
    path = write_csv(tmp_path / "m.csv", np.array([[0.0, 1.0], [1.0, 0.0]]), ["Left-insula", "Right-insula"])
    conn = read_connectome(path, dk, node_values=tmp_path / "v.npy", node_categories=tmp_path / "c.txt",
                           node_labels=["L", ""])
    np.testing.assert_array_equal(conn.node_values, [1.0, 2.0])
    assert conn.node_categories == ("visual", "motor") and conn.node_labels == ("L", "")


def test_node_vectors_as_name_entry_lines_are_matched_by_name(tmp_path, dk):
    path = write_csv(tmp_path / "m.csv", W3, DK3)
    (tmp_path / "v.csv").write_text("region,strength\nctx-lh-insula,3\nLeft-precentral,1\n")
    (tmp_path / "c.tsv").write_text("precentral_R\tmotor\nlh_insula\tsalience\nlh_precentral\tmotor\n")
    conn = read_connectome(path, dk, node_values=tmp_path / "v.csv", node_categories=tmp_path / "c.tsv")
    np.testing.assert_array_equal(conn.node_values, [1.0, np.nan, 3.0])  # Right-precentral: none given
    assert conn.node_categories == ("motor", "motor", "salience")
    (tmp_path / "bad.csv").write_text("Left-precentral,1\nLeft-insulaa,3\n")
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(path, dk, node_values=tmp_path / "bad.csv")
    assert "'Left-insulaa', which is no node of the connectome (did you mean 'Left-insula'?)" in one_line(exc)


def test_a_vector_file_of_far_more_entries_than_nodes_is_refused_before_it_is_split(tmp_path, dk):
    path = write_csv(tmp_path / "m.csv", W3, DK3)
    (tmp_path / "v.txt").write_text(",".join(["1"] * 1_000_000))
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(path, dk, node_values=tmp_path / "v.txt")
    assert "has more than 8 entries but the connectome has 3 nodes" in one_line(exc)


# -- weights --------------------------------------------------------------------------------------
def test_nan_on_the_diagonal_is_fine_nan_elsewhere_is_dropped_with_a_warning(tmp_path, dk):
    w = np.array([[np.nan, 0.4], [0.4, np.nan]])
    conn = read_connectome(write_csv(tmp_path / "a.csv", w, ["Left-insula", "Right-insula"]), dk)
    assert len(conn.edges()[0]) == 1
    w = np.array([[0.0, np.nan, 0.3], [np.nan, 0.0, 0.2], [0.3, 0.2, 0.0]])
    with pytest.warns(UserWarning, match=r"2 NaN weight\(s\) off the diagonal were dropped"):
        conn = read_connectome(write_csv(tmp_path / "b.csv", w, DK3), dk)
    assert len(conn.edges()[0]) == 2


def test_lower_triangle_only_matrix_is_made_symmetric_and_directed_keeps_both():
    w = np.array([[0.0, 0.0], [0.6, 0.0]])
    from brainpainter.connectome.read import edge_weights

    sym = edge_weights(w, False, "w")
    assert sym[0, 1] == sym[1, 0] == 0.6
    directed = edge_weights(np.array([[0.0, 0.2], [0.6, 0.0]]), True, "w")
    assert directed[0, 1] == 0.2 and directed[1, 0] == 0.6
    with pytest.warns(UserWarning, match="not symmetric"):
        asym = edge_weights(np.array([[0.0, 0.2], [0.6, 0.0]]), False, "w")
    assert asym[1, 0] == asym[0, 1] == 0.2


# -- bad input -------------------------------------------------------------------------------------
def one_line(exc: pytest.ExceptionInfo[BrainPainterError]) -> str:
    text = str(exc.value)
    assert "\n" not in text
    return text


def test_non_square_matrix_says_its_shape(tmp_path, dk):
    path = write_csv(tmp_path / "m.csv", np.ones((3, 4)), None)
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(path, dk)
    assert "is 3 x 4" in one_line(exc) and "square" in one_line(exc)
    (tmp_path / "named.csv").write_text(",a,b,c,d\nx,0,1,2,3\ny,1,0,1,2\nz,2,1,0,1\n")
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(tmp_path / "named.csv", dk)
    assert "is 3 x 4; a connectivity matrix is square (N x N): its rows and columns must be the same nodes" \
        in one_line(exc)


def test_names_that_match_no_region_get_suggestions(tmp_path, dk):
    """Each name that matches nothing is listed with its closest region (issue 44 item 15), not the first."""
    path = write_csv(tmp_path / "m.csv", np.ones((4, 4)), ["Left-precentrall", "Right-precentrall", "foo",
                                                           "Left-insula"])
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(path, dk)
    assert ("3 of 4 node name(s) name no single region of atlas 'dk': 'Left-precentrall' (did you mean "
            "'Left-precentral'?), 'Right-precentrall' (did you mean 'Right-precentral'?), 'foo'. Rename them"
            ) in one_line(exc)


@pytest.mark.parametrize(("names", "message"), [
    (["insula", "Left-precentral"],
     "'insula' means both ['Left-insula', 'Right-insula']; give the hemisphere"),
    (["ctx-lh-insula", "Left-insula"],
     "nodes 'ctx-lh-insula' and 'Left-insula' both name region 'Left-insula'"),
])
def test_bare_and_repeated_region_names(tmp_path, dk, names, message):
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(write_csv(tmp_path / "m.csv", np.ones((2, 2)), names), dk)
    assert message in one_line(exc)


def test_unnamed_matrix_of_another_count_than_the_atlas(dk):
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(np.ones((5, 5)), dk)
    assert "5 rows and no names" in one_line(exc) and "68 or 95" in one_line(exc)


def test_nodes_file_with_another_count_than_the_matrix(tmp_path):
    (tmp_path / "n.node").write_text("1 2 3 1 1 A\n4 5 6 1 1 B\n")
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(W3, nodes=tmp_path / "n.node")
    assert "has 2 nodes but" in one_line(exc) and "3 rows" in one_line(exc)


def test_nodes_file_without_coordinates_or_names(tmp_path):
    (tmp_path / "n.csv").write_text("name,x,y\nA,1,2\nB,3,4\n")
    (tmp_path / "bad.csv").write_text("name,x,y,z\nA,1,2,3\nB,3,four,5\n")
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(np.ones((2, 2)), nodes=tmp_path / "n.csv")
    assert "needs a name column (name or label or region or node) and x, y, z" in one_line(exc)
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(np.ones((2, 2)), nodes=tmp_path / "bad.csv")
    assert "node 2 has y = 'four'" in one_line(exc)


def test_empty_matrix_and_a_mat_without_a_2d_variable(tmp_path, dk):
    (tmp_path / "e.csv").write_text("\n \n")
    scipy.io.savemat(tmp_path / "v.mat", {"v": np.arange(3.0).reshape(1, 1, 3), "s": "text"})
    for path, words in ((tmp_path / "e.csv", "is empty"), (tmp_path / "v.mat", "exactly one 2-D numeric")):
        with pytest.raises(BrainPainterError) as exc:
            read_connectome(path, dk)
        assert words in one_line(exc)
    with pytest.raises(BrainPainterError, match="is empty"):
        read_connectome(np.zeros((0, 0)), dk)


def test_text_cell_inside_the_matrix(tmp_path, dk):
    (tmp_path / "m.csv").write_text("0,1\n1,oops\n")
    with pytest.raises(BrainPainterError) as exc:
        read_connectome(tmp_path / "m.csv", dk)
    assert "line 2, column 2 is 'oops'" in one_line(exc)


def refused(path: Path) -> tuple[str, int]:
    """The error reading `path` gives, and the most memory (bytes) Python allocated meanwhile."""
    tracemalloc.start()
    try:
        with pytest.raises(BrainPainterError) as exc:
            read_matrix(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return one_line(exc), peak


def test_huge_declared_npy_is_refused_before_allocating(tmp_path):
    path = tmp_path / "huge.npy"
    with path.open("wb") as fh:
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (100_000, 100_000)})
        fh.write(b"\0" * 64)
    message, peak = refused(path)
    assert "100000 x 100000" in message and peak < 5 * 2**20
    small = tmp_path / "short.npy"  # within the limit but cut short
    with small.open("wb") as fh:
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (500, 500)})
        fh.write(b"\0" * 64)
    with pytest.raises(BrainPainterError, match="cut short"):
        read_matrix(small)


def test_huge_declared_mat_is_refused_before_allocating(tmp_path):
    path = tmp_path / "huge.mat"
    scipy.io.savemat(path, {"W": np.zeros((3, 5))}, do_compression=False)
    raw = path.read_bytes()
    dims = np.array([3, 5], "<i4").tobytes()
    assert raw.count(dims) == 1
    path.write_bytes(raw.replace(dims, np.array([90_000, 90_000], "<i4").tobytes()))
    message, peak = refused(path)
    assert "90000 x 90000" in message and peak < 5 * 2**20


def mat_with(tmp_path: Path, compress: bool, old: bytes, new: bytes) -> Path:
    """A .mat of a 3 x 3 matrix whose (inflated) bytes have `old` replaced by `new`."""
    path = tmp_path / f"m{int(compress)}.mat"
    scipy.io.savemat(path, {"W": np.arange(9.0).reshape(3, 3)}, do_compression=compress)
    raw = path.read_bytes()
    if not compress:
        assert raw.count(old) == 1
        path.write_bytes(raw.replace(old, new))
        return path
    import struct
    import zlib

    inner = zlib.decompress(raw[136:])
    assert inner.count(old) == 1
    packed = zlib.compress(inner.replace(old, new))
    path.write_bytes(raw[:128] + struct.pack("<II", 15, len(packed)) + packed)
    return path


@pytest.mark.parametrize("compress", [False, True])
def test_mat_element_that_crashed_scipy_is_refused(tmp_path, compress):
    # the data's type tag: miDOUBLE (9), 72 bytes; an unknown type made scipy 1.17's loadmat segfault
    tag = np.array([9, 72], "<u4").tobytes()
    path = mat_with(tmp_path, compress, tag, np.array([216, 72], "<u4").tobytes())
    message, _ = refused(path)
    assert "MATLAB variable 'W' cannot be read safely (its data are of unknown type 216)" in message
    short = mat_with(tmp_path, compress, np.array([3, 3], "<i4").tobytes(), np.array([3, 4], "<i4").tobytes())
    message, _ = refused(short)
    assert "72 bytes of data for a 3 x 4 array" in message


def test_npy_with_a_broken_header_is_one_line_without_warnings(tmp_path):
    path = tmp_path / "b.npy"
    header = b"{'descr': '<f8', 'fortran_order': False, 'shape': (3, 3"
    path.write_bytes(b"\x93NUMPY\x01\x00" + len(header + b"\n").to_bytes(2, "little") + header + b"\n")
    message, _ = refused(path)  # warnings are errors in the tests: none came
    assert "is not a readable .npy file" in message


def test_damaged_pconn_headers_are_one_line_and_nibabel_prints_nothing(tmp_path, capfd):
    path = write_pconn(tmp_path / "m.pconn.nii")
    raw = bytearray(path.read_bytes())
    raw[112:120] = np.array([-1.0], "<f8").tobytes()  # pixdim[1] < 0: nibabel logs a fix on stderr
    path.write_bytes(bytes(raw))
    np.testing.assert_allclose(read_matrix(path).weights, W3)
    dims = np.array([3, 3], "<i8").tobytes()  # the NIfTI-2 dim[5], dim[6]: the two axes' lengths
    assert raw[56:72] == dims
    raw[56:72] = np.array([3, 10**9], "<i8").tobytes()
    path.write_bytes(bytes(raw))
    message, _ = refused(path)
    assert "names 3 x 3 parcels but its data are 3 x 1000000000" in message
    assert capfd.readouterr().err == ""


def test_object_npy_is_not_unpickled(tmp_path):
    np.save(tmp_path / "o.npy", np.array([[{"a": 1}]], dtype=object), allow_pickle=True)
    with pytest.raises(BrainPainterError, match="holds object values"):
        read_matrix(tmp_path / "o.npy")


# -- real data -------------------------------------------------------------------------------------
def brainspace_matrix(name: str) -> Path:
    try:
        dist = importlib.metadata.distribution("brainspace")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("brainspace (a test extra) is not installed")
    return Path(str(dist.locate_file(f"brainspace/datasets/matrices/holdout_group/{name}")))


def test_real_schaefer400_group_matrix_top_1_percent():
    from brainpainter.connectome.edges import select_edges

    with pytest.warns(UserWarning, match="the atlases that take 400 rows: .*schaefer400_17n"):  # no names
        conn = read_connectome(brainspace_matrix("schaefer_400_mean_connectivity_matrix.csv"),
                               load_atlas_dir(SCHAEFER400))
    assert conn.n_nodes == 400 and conn.names[0] == "Left-Vis_1" and conn.names[-1].startswith("Right-")
    assert len(conn.edges()[0]) == 400 * 399 // 2
    top = select_edges(conn, threshold="99%")
    assert len(top.edges()[0]) == 798
    assert np.nanmin(np.abs(top.weights)) >= np.nanmax(np.abs(np.where(np.isnan(top.weights), conn.weights,
                                                                         np.nan)))


# -- any text ----------------------------------------------------------------------------------------
def test_any_small_text_file_reads_or_is_one_line(tmp_path):
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    cells = st.sampled_from(["0", "1.5", "-2e-3", "", "NaN", "inf", "x", '"a,b"', '"', "1,5", "ctx-lh-insula",
                             "Left-insula", "Right-insula", " ", "0x1", "1e999"])
    seps = st.sampled_from([",", ";", "\t", " ", "|"])
    rows = st.lists(st.lists(cells, min_size=0, max_size=4), min_size=0, max_size=4)

    @settings(max_examples=300, deadline=None, database=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(rows=rows, sep=seps, suffix=st.sampled_from([".csv", ".tsv", ".txt", ".edge"]))
    def check(rows: list[list[str]], sep: str, suffix: str) -> None:
        path = tmp_path / f"m{suffix}"
        path.write_text("\n".join(sep.join(r) for r in rows))
        try:
            m = read_matrix(path)
        except BrainPainterError as exc:
            assert "\n" not in str(exc)
            return
        assert m.weights.ndim == 2 and m.weights.shape[0] == m.weights.shape[1] > 0
        assert not np.isinf(m.weights).any()
        assert m.names is None or len(m.names) == len(m.weights)

    check()


def test_an_empty_csv_cell_is_no_edge_without_a_warning(tmp_path, dk):
    path = tmp_path / "e.csv"
    path.write_text(",Left-insula,Right-insula,Left-precentral\nLeft-insula,0,,0.3\n"
                    "Right-insula,,0,0.2\nLeft-precentral,0.3,0.2,\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        conn = read_connectome(path, dk)
    assert len(conn.edges()[0]) == 2
