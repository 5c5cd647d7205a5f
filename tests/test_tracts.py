"""White-matter tracts: reading, resampling, orienting, tubes, bundle values, the scene's tract parts."""

from __future__ import annotations

from pathlib import Path

import nibabel as nib
import numpy as np
import pandas as pd
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.framing import shows
from brainpainter.rendering.tract_parts import TractLayer
from brainpainter.rendering.views import get_view
from brainpainter.tracts.model import TractSpec, bundle_files, read_affine
from brainpainter.tracts.names import canonical, hemisphere
from brainpainter.tracts.read import read_bundles
from brainpainter.tracts.streamlines import direction_bins, orient, resample
from brainpainter.tracts.tubes import SIDES, TRIANGLE_BUDGET, auto_radius, points_for, tube_mesh
from brainpainter.tracts.values import read_tract_values


def bundle(x: float, n: int = 20, seed: int = 0, z: float = 10.0, length: float = 40.0) -> list[np.ndarray]:
    """`n` gently curved streamlines along y at x, of 5-9 points, half of them reversed."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        k = int(rng.integers(5, 10))
        y = np.linspace(-length / 2, length / 2, k)
        pts = np.column_stack([np.full(k, x) + rng.normal(0, 1), y, z + 3 * np.sin(y / length * np.pi)
                               + rng.normal(0, 1)]).astype(np.float32)
        out.append(pts[::-1] if i % 2 else pts)
    return out


def write(path: Path, streamlines: list[np.ndarray]) -> Path:
    """A tractogram written by nibabel (format from the suffix)."""
    nib.streamlines.save(nib.streamlines.Tractogram(streamlines, affine_to_rasmm=np.eye(4)), str(path))
    return path


@pytest.fixture
def bundles(tmp_path) -> Path:
    folder = tmp_path / "bundles"
    folder.mkdir()
    write(folder / "AF_L.trk", bundle(-25.0))
    write(folder / "CST_R.tck", bundle(25.0, seed=1))
    return folder


# -- names ----------------------------------------------------------------------------------
@pytest.mark.parametrize(("given", "name"), [
    ("AF_left", "AF_left"), ("AF_L", "AF_left"), ("ARC_L", "AF_left"), ("Left Arcuate", "AF_left"),
    ("CST_R", "CST_right"), ("Right Corticospinal", "CST_right"), ("UNC_L", "UF_left"),
    ("CC_ForcepsMajor", "CC_ForcepsMajor"), ("Forceps Major", "CC_ForcepsMajor"), ("FP", "CC_ForcepsMajor"),
    ("IFOF_R", "IFO_right"), ("SLF_III_left", "SLF_III_left"), ("my bundle", "my_bundle"),
])
def test_bundle_names_of_tractseg_pyafq_and_buan_are_one_name(given, name):
    assert canonical(given) == name


def test_hemisphere_of_a_bundle():
    names = ("AF_left", "CST_right", "CC_ForcepsMajor")
    assert [hemisphere(n) for n in names] == ["lh", "rh", None]


# -- streamlines ----------------------------------------------------------------------------
def test_resample_gives_equally_spaced_points_and_keeps_the_ends():
    lines = [np.array([[0, 0, 0], [1, 0, 0], [4, 0, 0]], float), np.array([[0, 0, 0], [0, 0, 10]], float)]
    pts = np.concatenate(lines)
    out = resample(pts, np.array([0, 3]), np.array([3, 2]), 5)
    assert out.shape == (2, 5, 3)
    np.testing.assert_allclose(out[0, :, 0], [0, 1, 2, 3, 4], atol=1e-6)
    np.testing.assert_allclose(out[1, :, 2], [0, 2.5, 5, 7.5, 10], atol=1e-6)


def test_resample_matches_dipy():
    dipy_streamline = pytest.importorskip("dipy.tracking.streamline")
    lines = bundle(0.0, n=7)
    lengths = np.array([len(s) for s in lines])
    out = resample(np.concatenate(lines), np.r_[0, np.cumsum(lengths)[:-1]], lengths, 12)
    np.testing.assert_allclose(out, np.array(dipy_streamline.set_number_of_points(lines, 12)), atol=1e-4)


def test_orient_makes_a_bundle_run_one_way():
    lines = bundle(0.0, n=10)
    lengths = np.array([len(s) for s in lines])
    x = orient(resample(np.concatenate(lines), np.r_[0, np.cumsum(lengths)[:-1]], lengths, 8))
    assert np.all(x[:, -1, 1] > x[:, 0, 1])  # all from posterior to anterior (+y)


def test_direction_colours_are_red_for_left_right():
    line = np.stack([np.linspace(-10, 10, 5), np.zeros(5), np.zeros(5)], 1)[None]
    bins, colors = direction_bins(line)
    np.testing.assert_allclose(colors[bins[0]], np.tile([1, 0, 0], (5, 1)))


# -- reading --------------------------------------------------------------------------------
def test_trk_and_tck_written_by_nibabel_are_read_as_named_bundles(bundles):
    t = read_bundles(bundle_files([str(bundles)]), np.eye(4), 1000, 16)
    assert t.names == ("AF_left", "CST_right") and t.counts == (20, 20) and not t.notes
    assert t.lines.shape == (40, 16, 3) and t.lines.dtype == np.float32
    af = t.lines[t.bundle == 0]
    assert np.allclose(af[..., 0].mean(), -25.0, atol=1.0)
    assert np.all(af[:, -1, 1] > af[:, 0, 1])  # oriented


def test_above_the_budget_a_subsample_is_drawn_and_said(tmp_path):
    path = write(tmp_path / "whole_brain.tck", bundle(0.0, n=500))
    t = read_bundles([path], np.eye(4), 50, 8)
    assert t.lines.shape == (50, 8, 3) and t.counts == (500,)
    assert "50 of 500 streamlines drawn" in t.notes[0]
    again = read_bundles([path], np.eye(4), 50, 8)
    np.testing.assert_array_equal(t.lines, again.lines)  # every worker draws the same


def test_streaming_keeps_memory_bounded(tmp_path, monkeypatch):
    import brainpainter.tracts.read as read

    monkeypatch.setattr(read, "CHUNK", 7)  # many chunks
    path = write(tmp_path / "x.trk", bundle(0.0, n=60))
    t = read_bundles([path], np.eye(4), 1000, 8)
    whole = read_bundles([path], np.eye(4), 1000, 8)
    assert t.lines.shape == (60, 8, 3)
    np.testing.assert_allclose(t.lines, whole.lines)


def test_affine_and_space_place_the_streamlines(bundles, tmp_path, tiny):
    from brainpainter.atlas.template import load_template

    np.savetxt(tmp_path / "shift.txt", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 40], [0, 0, 0, 1]])
    spec = TractSpec((str(bundles),), space="template", affine=str(tmp_path / "shift.txt"))
    t = spec.load(load_template(str(tiny)))
    assert np.allclose(t.lines[..., 2].mean(), 50.0, atol=2.0)


def test_mni152_bundles_are_mapped_to_the_fsaverage_template(bundles):
    from brainpainter.atlas.template import load_template
    from brainpainter.atlas.volumes import MNI152_TO_MNI305

    t = TractSpec((str(bundles),)).load(load_template("fsaverage"))
    raw = read_bundles(bundle_files([str(bundles)]), np.eye(4), 1000, 32)
    expected = raw.lines @ MNI152_TO_MNI305[:3, :3].T + MNI152_TO_MNI305[:3, 3]
    np.testing.assert_allclose(np.sort(t.lines.ravel()), np.sort(expected.ravel()), atol=1e-3)


@pytest.mark.parametrize(("paths", "message"), [
    (["missing-folder"], "does not exist"),
    (["table.csv"], "is not a tractogram"),
    (["empty"], "holds no tractogram"),
])
def test_bad_tract_paths_are_one_line_errors(tmp_path, monkeypatch, paths, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "table.csv").write_text("a,b\n1,2\n")
    (tmp_path / "empty").mkdir()
    with pytest.raises(BrainPainterError, match=message):
        TractSpec(tuple(paths))


def test_bad_affine_is_a_one_line_error(tmp_path):
    (tmp_path / "bad.txt").write_text("1 2 3\n4 5 6\n")
    with pytest.raises(BrainPainterError, match="4x4"):
        read_affine(tmp_path / "bad.txt")
    np.savetxt(tmp_path / "fsl.mat", np.eye(4))
    np.testing.assert_array_equal(read_affine(tmp_path / "fsl.mat"), np.eye(4))


def test_a_broken_tractogram_is_a_one_line_error(tmp_path):
    (tmp_path / "AF_L.trk").write_bytes(b"not a trk file at all")
    with pytest.raises(BrainPainterError, match="could not be read"):
        read_bundles([tmp_path / "AF_L.trk"], np.eye(4), 10, 8)


# trx-python's writer (TrxFile.from_tractogram) leaves a temporary folder to the garbage collector
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_trx_groups_are_bundles(tmp_path):
    pytest.importorskip("trx.trx_file_memmap")
    from trx.trx_file_memmap import TrxFile, save

    lines = bundle(-25.0) + bundle(25.0, seed=1)
    ref = nib.Nifti1Image(np.zeros((2, 2, 2), np.uint8), np.eye(4))
    tg = nib.streamlines.Tractogram(lines, affine_to_rasmm=np.eye(4))
    trx = TrxFile.from_tractogram(tg, reference=ref)
    trx.groups = {"AF_L": np.arange(20, dtype=np.uint32), "CST_R": np.arange(20, 40, dtype=np.uint32)}
    save(trx, str(tmp_path / "two.trx"))
    trx.close()
    t = read_bundles([tmp_path / "two.trx"], np.eye(4), 1000, 8)
    assert t.names == ("AF_left", "CST_right")
    x = [float(t.lines[t.bundle == i][..., 0].mean()) for i in (0, 1)]
    assert x[0] < 0 < x[1], x


# -- tubes ----------------------------------------------------------------------------------
def test_tubes_have_outward_faces_and_radial_normals():
    s = np.linspace(0, 1, 10)
    lines = np.stack([np.cos(3 * s), np.sin(3 * s), 5 * s], 1)[None] * 10
    verts, normals, tris = tube_mesh(lines, radius=1.0, sides=6)
    assert verts.shape == (60, 3) and tris.shape == (9 * 6 * 2, 3)
    f = verts[tris]
    face_normal = np.cross(f[:, 1] - f[:, 0], f[:, 2] - f[:, 0])
    assert np.all(np.einsum("ij,ij->i", face_normal, normals[tris[:, 0]]) > 0)
    centre = np.repeat(lines[0], 6, axis=0)
    np.testing.assert_allclose(np.linalg.norm(verts - centre, axis=1), 1.0, atol=1e-5)


def test_many_streamlines_get_fewer_points_to_stay_near_the_triangle_budget():
    assert points_for(1_000, 32) == 32
    assert points_for(3_000, 32) == 14
    assert points_for(1_000_000, 32) == 5  # never fewer than MIN_POINTS
    m = points_for(10_000, 32)
    assert 10_000 * (m - 1) * SIDES * 2 <= TRIANGLE_BUDGET


def test_centrelines_keep_more_points_than_tubes_and_the_same_colours_at_the_ends():
    from brainpainter.rendering.tract_parts import tract_parts
    from brainpainter.tracts.model import Tracts
    from brainpainter.tracts.tubes import LINE_SEGMENT_BUDGET, line_points_for

    assert line_points_for(10_000, 32) == 11 and line_points_for(3_000, 32) == 32
    assert 10_000 * (line_points_for(10_000, 32) - 1) <= LINE_SEGMENT_BUDGET
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, 32)[:, None]
    start = np.array([-30.0, -40.0, 0.0])
    lines = np.array([start + t * [0.0, 80.0, 10.0] + rng.normal(0, 1, 3) for _ in range(3_000)])
    tracts = Tracts(("AF_left",), lines.astype(np.float32), np.zeros(3_000, np.int32), (3_000,))
    slots: dict[str, int] = {}

    def slots_for(keys, default, hidden):
        return np.array([slots.setdefault(k, len(slots) + 10) for k in keys])

    (part,) = tract_parts(tracts, {"AF_left": 4}, slots_for)
    c = part.centrelines
    assert c is not None and c.points.shape == (3_000, 32, 3) and c.slots.shape == (3_000, 32)
    assert len(part.hull) == 3_000 * 14  # the tubes' points
    # node 0 at one end, node 3 at the other, in both
    tube_slots = part.palette_index.reshape(3_000, 14, SIDES)[:, :, 0]
    for end in (0, -1):
        assert np.array_equal(c.slots[:, end], tube_slots[:, end])
    np.testing.assert_allclose(c.points[:, [0, -1]], lines[:, [0, -1]], atol=1e-3)
    assert c.radius == pytest.approx(auto_radius(3_000))


# -- values ---------------------------------------------------------------------------------
def test_bundle_columns_give_one_value_per_bundle():
    df = pd.DataFrame({"subject": ["a", "b"], "AF_L": [1.0, 2.0], "Left Corticospinal": [3, 4]})
    tv = read_tract_values(df)
    assert tv.images == ("a", "b") and tv.nodes == (("AF_left", 1), ("CST_left", 1))
    assert tv.row("b") == {"tract:AF_left": 2.0, "tract:CST_left": 4.0}
    assert all(np.isnan(v) for v in tv.row("zz").values())


def test_long_profiles_give_a_value_per_node(tmp_path):
    rows = [("ARC_L", k, k / 10) for k in range(10)] + [("CST_R", k, 1.0) for k in range(10)]
    path = tmp_path / "profiles.csv"
    pd.DataFrame(rows, columns=["tractID", "nodeID", "dti_fa"]).to_csv(path, index=False)
    tv = read_tract_values(str(path))
    assert tv.images is None and tv.nodes == (("AF_left", 10), ("CST_right", 10))
    assert tv.row("any")["tract:AF_left:7"] == pytest.approx(0.7)


def test_pyafq_profiles_with_several_measures_need_a_value_column():
    df = pd.DataFrame({"tractID": ["UNC_L"] * 3, "nodeID": [0, 1, 2], "dti_fa": [0.1, 0.2, 0.3],
                       "dti_md": [1, 2, 3], "subjectID": ["s1"] * 3})
    with pytest.raises(BrainPainterError, match="tract-value"):
        read_tract_values(df)
    tv = read_tract_values(df, "dti_md")
    assert tv.images == ("s1",) and tv.row("s1")["tract:UF_left:2"] == 3.0
    assert tv.row("stage-3")["tract:UF_left:2"] == 3.0  # one row (a group's profile) colours every image


def test_a_long_table_without_nodes_gives_one_value_per_bundle():
    tv = read_tract_values(pd.DataFrame({"bundle": ["AF_L", "CST_R"], "fa": [0.3, 0.7]}))
    assert tv.images is None and tv.nodes == (("AF_left", 1), ("CST_right", 1))
    assert tv.row("any") == {"tract:AF_left": 0.3, "tract:CST_right": 0.7}
    tv = read_tract_values(pd.DataFrame({"subject": ["a", "a", "b"], "tract": ["AF_L", "CST_R", "AF_L"],
                                         "fa": [0.3, 0.7, 0.5]}))
    assert tv.images == ("a", "b") and tv.row("b")["tract:AF_left"] == 0.5
    assert np.isnan(tv.row("b")["tract:CST_right"])
    with pytest.raises(BrainPainterError, match="names a bundle twice for one image"):
        read_tract_values(pd.DataFrame({"bundle": ["AF_L", "AF_left"], "fa": [0.3, 0.7]}))
    with pytest.raises(BrainPainterError, match="names a bundle twice for one image"):  # image names stripped
        read_tract_values(pd.DataFrame({"subject": ["a", "a "], "bundle": ["AF_L", "AF_L"],
                                        "fa": [0.3, 0.7]}))


def test_wide_profiles_have_a_node_column():
    tv = read_tract_values(pd.DataFrame({"node": [0, 1, 2], "AF_left": [0.0, 1.5, 3.0]}))
    assert tv.nodes == (("AF_left", 3),) and tv.row("x")["tract:AF_left:2"] == 3.0


# -- the scene ------------------------------------------------------------------------------
def test_subcortical_views_show_the_tracts_cortex_views_hide_them():
    for name in ("subcortical", "subcortical-left", "subcortical-dorsal", "subcortical-ventral"):
        assert shows(get_view(name), "tract", None) and shows(get_view(name), "tract", "rh")
    for name in ("lateral-left", "medial-left", "dorsal"):
        assert not shows(get_view(name), "tract", "lh") and not shows(get_view(name), "tract", None)


def test_cortex_views_show_their_hemispheres_tracts_through_a_glass_or_hidden_cortex():
    lateral, dorsal = get_view("lateral-left"), get_view("dorsal")
    for cortex in ("glass", "hidden"):
        assert shows(lateral, "tract", "lh", cortex) and shows(lateral, "tract", None, cortex)
        assert not shows(lateral, "tract", "rh", cortex)  # behind the left hemisphere (medial-left: in front)
        assert shows(dorsal, "tract", "rh", cortex) and shows(dorsal, "tract", "lh", cortex)
    assert shows(lateral, "cortex", "lh", "glass") and not shows(lateral, "cortex", "lh", "hidden")


def _scene(tiny, bundles, nodes=(), **settings):
    from brainpainter.atlas.template import load_template
    from brainpainter.rendering.scene import RenderSettings, Scene

    template = load_template(str(tiny))
    tracts = TractSpec((str(bundles),), space="template").load(template) if bundles else None
    layers = () if tracts is None else (TractLayer(None, tuple(nodes), tracts=tracts),)
    return Scene(template, "dk", layers=layers, settings=RenderSettings(**settings))


@pytest.mark.parametrize(("cortex", "visible"), [
    ("auto", [("tracts-lh", "tract"), ("cortex-lh", "glass")]),  # auto: glass, as there are tracts
    ("glass", [("tracts-lh", "tract"), ("cortex-lh", "glass")]),
    ("opaque", [("cortex-lh", "cortex")]),
    ("hidden", [("tracts-lh", "tract")]),
])
def test_the_cortex_option_decides_what_a_cortex_view_draws(tiny, bundles, cortex, visible):
    g = _scene(tiny, bundles, cortex=cortex).geometry
    assert [(p.name, p.kind) for p in g.visible(get_view("lateral-left"))] == visible
    glass = next((p for p in g.visible(get_view("lateral-left")) if p.kind == "glass"), None)
    if glass is not None:  # the cortex as glass keeps its regions' palette slots
        cortex_lh = next(p for p in g.parts if p.name == "cortex-lh")
        assert glass.palette_index is cortex_lh.palette_index and cortex_lh.kind == "cortex"
    # the subcortical views are unchanged
    assert {p.name for p in g.visible(get_view("subcortical"))} >= {"tracts-lh", "tracts-rh", "glass-rh"}


@pytest.mark.parametrize(("given", "cortex"), [
    ({"table": {"Left-insula": 2.0}}, "opaque"),  # the cortex carries values: drawn in their colours
    ({"table": {"Left-insula": 2.0}, "cortex": "glass"}, "glass"),  # asked for: kept
    ({"table": {"Left-Hippocampus": 2.0}}, "auto"),  # values on structures only: glass (geometry's auto)
    ({"tract_values": "v.csv"}, "auto"),  # bundle values alone: the grey glass cortex
])
def test_with_tracts_a_cortex_carrying_values_is_drawn_opaque(tmp_path, bundles, given, cortex):
    from brainpainter.rendering.run import prepare_run

    (tmp_path / "v.csv").write_text("AF_L,CST_R\n0.3,0.7\n")
    kwargs = {k: v for k, v in given.items() if k != "table"}
    if "tract_values" in kwargs:
        kwargs["tract_values"] = str(tmp_path / kwargs["tract_values"])
    run = prepare_run(given.get("table"), "dk", tracts=[str(bundles)], tracts_space="template", **kwargs)
    assert run.settings.cortex == cortex


def test_tract_values_naming_no_bundle_drawn_are_a_one_line_error(tmp_path, monkeypatch, capsys, bundles):
    from brainpainter.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("Left-insula\n1\n")
    (tmp_path / "fa.csv").write_text("bundle,fa\nSLF_L,0.4\n")  # drawn as direction colours before
    with pytest.raises(SystemExit) as exit_:
        main(["render", "t.csv", "--tracts", str(bundles), "--tract-values", "fa.csv", "--out", "o"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and len(err.strip().splitlines()) == 1
    assert "['SLF_left'] are none of the tracts drawn ['AF_left', 'CST_right']" in err
    assert not (tmp_path / "o").exists()


def test_tract_values_of_a_bundle_not_drawn_are_a_warning(tmp_path, bundles):
    """A value for UF_L with no UF_L tractogram: said, and left out of the values (the input line
    counted it among the bundles drawn, and nothing said it was not)."""
    from brainpainter.rendering.run import prepare_run

    (tmp_path / "fa.csv").write_text("bundle,fa\nAF_L,0.3\nUF_L,0.4\n")
    with pytest.warns(UserWarning, match=r"'fa.csv': 1 bundle\(s\) with a value have no tractogram and "
                                         r"were not drawn: \['UF_left'\]"):
        run = prepare_run({"Left-insula": 1.0}, "dk", tracts=[str(bundles)], tracts_space="template",
                          tract_values=str(tmp_path / "fa.csv"))
    assert run.tract_values is not None and run.tract_values.bundles == ("AF_left",)


def test_without_tracts_the_cortex_stays_opaque_and_hidden_explains_an_empty_view(tiny):
    g = _scene(tiny, None).geometry
    assert g.cortex == "opaque" and [p.kind for p in g.visible(get_view("lateral-left"))] == ["cortex"]
    with pytest.raises(BrainPainterError, match="--cortex hidden draws no cortex"):
        _scene(tiny, None, cortex="hidden").geometry.visible(get_view("lateral-left"))
    with pytest.raises(BrainPainterError, match="cortex must be one of"):
        _scene(tiny, None, cortex="clear")


def test_tracts_are_parts_of_the_scene_geometry(tiny, bundles):
    g = _scene(tiny, bundles).geometry
    parts = {p.name: p for p in g.parts if p.kind == "tract"}
    assert set(parts) == {"tracts-lh", "tracts-rh"} and parts["tracts-lh"].hemi == "lh"
    af = parts["tracts-lh"]
    assert af.vertices.shape == (20 * 32 * SIDES, 3) and af.triangles.max() < len(af.vertices)
    # direction colours: fixed slots with their colours as defaults, mostly green (anterior-posterior)
    rgb = g.default_rgb[af.palette_index]
    assert np.median(rgb[:, 1]) > 0.9 and np.median(rgb[:, 0]) < 0.3
    assert all(k.startswith("tract-direction:") for k in g.keys if k.startswith("tract"))


def test_valued_bundles_get_a_slot_or_a_slot_per_node(tiny, bundles):
    g = _scene(tiny, bundles, [("AF_left", 1), ("CST_right", 5)]).geometry
    assert "tract:AF_left" in g.slot_of
    assert all(f"tract:CST_right:{k}" in g.slot_of for k in range(5))
    cst = next(p for p in g.parts if p.name == "tracts-rh")
    ring = cst.palette_index.reshape(20, 32, SIDES)
    assert ring[0, 0, 0] == g.slot_of["tract:CST_right:0"]
    assert ring[0, -1, 0] == g.slot_of["tract:CST_right:4"]


def test_too_many_slots_are_refused(tiny, bundles, monkeypatch):
    from brainpainter.rendering import parts

    # the real limit (4096 x 16384 slots of a 2-D palette) takes minutes to reach: a small one
    monkeypatch.setattr(parts, "MAX_SLOTS", 1000)
    with pytest.raises(BrainPainterError, match="palette slots"):
        _ = _scene(tiny, bundles, [("AF_left", 2000)]).geometry


def test_a_bundle_table_alone_prepares_a_run(tmp_path, bundles):
    from brainpainter.rendering.run import prepare_run

    (tmp_path / "t.csv").write_text("Image-name-unique,AF_L,CST_R\nctrl,1,2\npat,2,3\n")
    run = prepare_run(str(tmp_path / "t.csv"), tracts=[str(bundles)], tracts_space="template", vmin=0, vmax=3)
    assert run.table.images == ("ctrl", "pat") and run.tract_values is not None
    assert [v.name for v in run.views] == ["subcortical", "subcortical-dorsal"]  # views that show tracts
    colors = run.item(1, get_view("subcortical")).colors
    assert colors["tract:AF_left"] == pytest.approx(run.scale(np.array([2.0]))[0][:3])


def test_tract_values_without_tracts_are_refused(tmp_path):
    from brainpainter.rendering.run import prepare_run

    with pytest.raises(BrainPainterError, match="no --tracts"):
        prepare_run({"Left-Hippocampus": 1.0}, "dk", tract_values=str(tmp_path / "x.csv"))


def test_the_stand_in_renderer_paints_value_coloured_bundles(tiny, bundles):
    from brainpainter.rendering.geometry import Palette
    from brainpainter.testing.stand_in import StandInRenderer

    scene = _scene(tiny, bundles, [("AF_left", 1)])
    r = StandInRenderer(scene)
    colors = {"tract:AF_left": (1.0, 0.0, 0.0)}
    img = r.render(Palette(colors, scene.geometry), get_view("subcortical"))
    assert (img[..., 0] == 255).any() and (img[..., 1] == 0).any()
    lateral = r.render(Palette(colors, scene.geometry), get_view("lateral-right"))
    assert not ((lateral[..., 0] == 255) & (lateral[..., 1] == 0)).any()


def test_glb_export_carries_the_tubes_with_vertex_colours(tmp_path, bundles, tiny):
    import trimesh

    from brainpainter.media.export import export

    (tmp_path / "fa.csv").write_text("Image-name-unique,AF_L,CST_R\nctrl,3,0\n")
    out = export(str(tmp_path / "fa.csv"), tmp_path / "b.glb", tracts=[str(bundles)], tracts_space="template",
                 template=str(tiny), vmin=0, vmax=3, gradient=["blue", "red"])
    scene = trimesh.load(out)
    tubes = [g for name, g in scene.geometry.items() if name.startswith("tracts")]
    assert {name for name in scene.geometry if name.startswith("tracts")} == {"tracts-lh", "tracts-rh"}
    colors = {name: np.asarray(g.visual.vertex_colors)[:, :3].mean(axis=0)
              for name, g in scene.geometry.items() if name.startswith("tracts")}
    assert colors["tracts-lh"][0] > 200 and colors["tracts-lh"][2] < 50  # AF_left = 3: red
    assert colors["tracts-rh"][2] > 200 and colors["tracts-rh"][0] < 50  # CST_right = 0: blue
    assert all(len(g.faces) for g in tubes)


def test_a_movie_interpolates_bundle_values_between_key_frames(tmp_path, bundles, tiny):
    from brainpainter.media.movie import make_movie
    from brainpainter.testing.stand_in import StandInRenderer, stand_in

    (tmp_path / "fa.csv").write_text("Image-name-unique,AF_L\nA,0\nB,3\n")
    with stand_in() as name:
        make_movie(str(tmp_path / "fa.csv"), out=tmp_path / "m.gif", views="subcortical", frames_per_step=4,
                   tracts=[str(bundles)], tracts_space="template", template=str(tiny), renderer=name,
                   width=64, height=48, vmin=0, vmax=3, gradient=["blue", "red"], progress=False)
        reds = [colors["tract:AF_left"][0] for colors, _ in StandInRenderer.calls]
    assert reds[0] == pytest.approx(0.0) and reds[-1] == pytest.approx(1.0)
    assert np.all(np.diff(reds) > 0)


def test_a_worker_builds_the_same_scene_from_the_pickled_spec(tiny, bundles):
    import pickle

    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.parallel import PainterSpec

    spec = TractSpec((str(bundles),), space="template", max_streamlines=30)
    painter = Painter("dk", str(tiny), layers=(TractLayer(spec, (("AF_left", 1),), 0.5),))
    spec = pickle.loads(pickle.dumps(PainterSpec.of(painter, str(tiny))))
    worker = spec.build()
    (layer,) = worker.scene.layers
    assert layer.nodes == (("AF_left", 1),) and layer.radius == 0.5
    np.testing.assert_array_equal(worker.scene.tracts.lines, painter.scene.tracts.lines)


@pytest.mark.parametrize(("args", "message"), [
    (["--tracts", "nowhere"], "--tracts 'nowhere' does not exist"),
    (["--tract-values", "fa.csv"], "no --tracts were given"),
    (["--tracts", "b", "--tracts-affine", "bad.txt"], "--tracts-affine"),
    (["--tracts", "b", "--tract-radius", "50"], "--tract-radius must be"),
])
def test_bad_tract_options_are_one_line_errors_with_exit_code_2(tmp_path, monkeypatch, capsys, bundles, args,
                                                                 message):
    from brainpainter.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("Left-Hippocampus\n1\n")
    (tmp_path / "fa.csv").write_text("AF_L\n1\n")
    (tmp_path / "bad.txt").write_text("1 2\n")
    (tmp_path / "b").symlink_to(bundles)
    with pytest.raises(SystemExit) as exit_:
        main(["render", "t.csv", "--out", "o", *args])
    err = capsys.readouterr().err
    assert exit_.value.code == 2, err
    assert message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_direction_colours_are_within_one_32nd_of_exact():
    d = np.random.default_rng(0).normal(size=(5000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    bins, colors = direction_bins(np.stack([np.zeros_like(d), d], 1))
    exact = np.abs(d) / np.abs(d).max(axis=1, keepdims=True)
    assert np.abs(colors[bins[:, 0]] - exact).max() <= 1 / 32 + 1e-6
    assert len(np.unique(bins)) <= 817


def test_a_table_of_regions_and_bundles_reports_no_bundle_as_unmatched(tmp_path, bundles):
    from brainpainter.rendering.run import prepare_run

    (tmp_path / "t.csv").write_text("Image-name-unique,Left-insula,AF_L,CST_R\nctrl,1,2,3\n")
    run = prepare_run(str(tmp_path / "t.csv"), "dk", tracts=[str(bundles)], tracts_space="template",
                      strict=True)  # a bundle column is no unknown region name
    assert tuple(run.table.regions) == ("Left-insula",) and not run.table.unmatched
    assert run.tract_values is not None and run.tract_values.row("ctrl")["tract:CST_right"] == 3.0


# -- tractometry tables alone (issue 33 item 15) -------------------------------------------------
def _profile(path: Path, bundles=("AF_L", "CST_R"), n: int = 10) -> Path:
    """A pyAFQ ``tract_profiles.csv`` as pandas writes it: unnamed index, two measures, subject, session."""
    rows = [{"tractID": b, "nodeID": k, "dti_fa": 0.3 + 0.02 * k, "dti_md": 0.0007, "subjectID": "s1",
             "sessionID": 1} for b in bundles for k in range(n)]
    pd.DataFrame(rows).to_csv(path)
    return path


def test_a_profile_table_as_input_colours_the_tracts_along_their_nodes(tmp_path, bundles):
    from brainpainter.rendering.run import prepare_run

    table = _profile(tmp_path / "tract_profiles.csv")
    with pytest.raises(BrainPainterError, match=r"2 value columns \['dti_fa', 'dti_md'\].*--tract-value"):
        prepare_run(str(table), tracts=[str(bundles)], tracts_space="template")
    run = prepare_run(str(table), tracts=[str(bundles)], tracts_space="template", tract_value="dti_fa")
    assert run.tract_values is not None and dict(run.tract_values.nodes) == {"AF_left": 10, "CST_right": 10}
    assert (run.scale.vmin, run.scale.vmax) == pytest.approx((0.3, 0.48))  # the measure's range, not 0..3
    colors = run.item(0, get_view("subcortical")).colors
    assert colors["tract:AF_left:0"] == pytest.approx(run.scale(np.array([0.3]))[0][:3])
    assert colors["tract:AF_left:9"] == pytest.approx(run.scale(np.array([0.48]))[0][:3])
    assert colors["tract:AF_left:0"] != colors["tract:AF_left:9"]


@pytest.mark.parametrize("table", ["profile", "bundles"])
def test_tract_values_alone_render_without_a_region_table(tmp_path, monkeypatch, bundles, tiny, table):
    from PIL import Image

    from brainpainter.cli.main import main
    from brainpainter.testing import stand_in

    monkeypatch.chdir(tmp_path)
    if table == "profile":
        (tmp_path / "v.csv").write_text("bundle,node,value\n" + "".join(
            f"{b},{k},{k}\n" for b in ("AF_L", "CST_R") for k in range(4)))
    else:
        (tmp_path / "v.csv").write_text("AF_L,CST_R\n0,3\n")
    with stand_in() as renderer, pytest.raises(SystemExit) as exit_:
        main(["render", "--tract-values", "v.csv", "--tracts", str(bundles), "--tracts-space", "template",
              "--template", str(tiny), "--renderer", renderer, "--views", "subcortical", "--size", "80x60",
              "--out", "o", "-q"])
    assert exit_.value.code in (0, None)
    rgb = np.asarray(Image.open(tmp_path / "o" / "1_subcortical.png").convert("RGB")).reshape(-1, 3)
    red = (rgb[:, 0] > 200) & (rgb[:, 1] < 60) & (rgb[:, 2] < 60)  # value 3: the scale's last colour
    assert red.sum() > 0


@pytest.mark.parametrize(("content", "message"), [
    ("bundle,node,value\nUF_L,0,1\nUF_L,1,2\n", "are none of the tracts drawn ['AF_left', 'CST_right']"),
    ("foo,bar\n1,2\n", "names a region of any installed atlas (dk, destrieux, dkt); the columns: "
                       "'foo', 'bar'. Use names like 'Left-insula' or 'lh_insula_thickness' (see "
                       "'brainpainter atlas show dk'). Nor does any column name a bundle of --tracts "
                       "['AF_left', 'CST_right']."),
])
def test_a_table_matching_no_region_nor_bundle_is_a_one_line_error(tmp_path, monkeypatch, capsys, bundles,
                                                                    content, message):
    from brainpainter.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text(content)
    with pytest.raises(SystemExit) as exit_:
        main(["render", "t.csv", "--tracts", str(bundles), "--out", "o"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
