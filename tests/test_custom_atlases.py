"""Custom atlases: label maps on a template (atlas add --annot), region groups (TOML), user storage."""

from __future__ import annotations

import contextlib
import io
import json
import textwrap
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas import user as user_atlases
from brainpainter.atlas.registry import load_atlas_config
from brainpainter.atlas.template import load_template
from brainpainter.cli.main import cli, main
from brainpainter.errors import BrainPainterError
from brainpainter.layers.regions import region_colors
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.run import render
from brainpainter.testing import StandInRenderer, check_atlas, fake_distribution, installed, stand_in
from brainpainter.testing import write_tiny_template as _tiny

FREESURFER = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "freesurfer"
FSAVERAGE = FREESURFER / "subjects" / "fsaverage"
YEO7 = {h: FSAVERAGE / "label" / f"{h}.Yeo2011_7Networks_N1000.annot" for h in ("lh", "rh")}
NETWORKS = [f"7Networks_{i}" for i in range(1, 8)]
LOBES = textwrap.dedent(
    """
    [atlas]
    base = "dk"
    title = "Lobes"

    [groups]
    frontal = ["superiorfrontal", "rostralmiddlefrontal", "caudalmiddlefrontal", "parsopercularis",
               "parstriangularis", "parsorbitalis", "lateralorbitofrontal", "medialorbitofrontal",
               "precentral", "paracentral", "frontalpole"]
    parietal = ["superiorparietal", "inferiorparietal", "supramarginal", "postcentral", "precuneus"]
    temporal = ["superiortemporal", "middletemporal", "inferiortemporal", "bankssts", "fusiform",
                "transversetemporal", "entorhinal", "temporalpole", "parahippocampal"]
    occipital = ["lateraloccipital", "lingual", "cuneus", "pericalcarine"]
    cingulate = ["rostralanteriorcingulate", "caudalanteriorcingulate", "posteriorcingulate",
                 "isthmuscingulate"]
    insula = ["insula"]
    """
)
LOBE_NAMES = ["frontal", "parietal", "temporal", "occipital", "cingulate", "insula"]


def run(*args: str) -> tuple[int, str, str]:
    """Run the real console entry point in-process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), pytest.raises(SystemExit) as exc:
        main(list(args))
    return exc.value.code, out.getvalue(), err.getvalue()


def needs_fsaverage():
    if not YEO7["lh"].is_file():
        pytest.skip(f"shared data not found at {FSAVERAGE}")


pytestmark = pytest.mark.usefixtures("fresh_registry")


@pytest.fixture
def tiny(tmp_path):
    """A tiny template with one label set; its 642-vertex icospheres are 'full resolution'."""
    return _tiny(tmp_path / "tiny")


def tiny_annot(path, n=642, names=("unknown", "front", "back"), template=None):
    """An annotation on the tiny template: y >= 0 -> front, else back (vertex 0 -> unknown)."""
    if template is not None:
        cm = load_template(template).cortex("dk", "lh")
        y = cm.vertices["pial"][:, 1]
        labels = np.where(y >= 0, 1, 2)
        labels[0] = 0
    else:
        labels = np.arange(n) % len(names)
    ctab = np.array([[25, 5, 25, 0, 0], [220, 20, 10, 0, 0], [20, 30, 140, 0, 0]])[: len(names)]
    nib.freesurfer.write_annot(str(path), labels.astype(np.int32), ctab, list(names), fill_ctab=True)
    return path


@pytest.fixture
def tiny_annots(tmp_path, tiny):
    return {h: tiny_annot(tmp_path / f"{h}.toy.annot", template=tiny) for h in ("lh", "rh")}


# -- label maps on a template (fast: tiny template) ------------------------------------------------
def test_add_label_map_registers_a_user_atlas(tiny, tiny_annots):
    folder = user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    assert folder == user_atlases.atlases_dir() / "toy"
    assert sorted(p.name for p in folder.iterdir()) == [
        "atlas.json", "cortex-lh-toy.npz", "cortex-rh-toy.npz", "labels.json", "regions.tsv"]
    entry = next(e for e in registry.atlases.entries() if e.name == "toy")
    assert entry.distribution == "user"
    atlas = registry.atlases.get("toy")
    assert atlas.keys[:4] == ["Left-front", "Left-back", "Right-front", "Right-back"]
    assert atlas.region("Left-front").color == (220, 20, 10)
    assert atlas.label_dir == folder
    # the overlay gives the renderer a label set of the template's own mesh
    tpl = load_template(tiny).with_label_sets(folder)
    cm, base = tpl.cortex("toy", "lh"), tpl.cortex("dk", "lh")
    assert len(cm.faces) > len(base.faces) and cm.label_names == ("unknown", "front", "back")
    assert (cm.source_vertex[: len(base.source_vertex)] == base.source_vertex).all()
    centroid_y = cm.vertices["pial"][cm.faces].mean(axis=1)[:, 1]
    front, back = cm.face_label == 1, cm.face_label == 2
    assert (centroid_y[front] > -5).all() and (centroid_y[back] < 5).all()
    assert (cm.face_label == 0).any()  # vertex 0 is 'unknown': drawn like the medial wall


def test_user_atlas_renders_through_cli(tmp_path, tiny, tiny_annots):
    user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-front,Left-back,Right-front,Right-back\nA,1,2,3,0\n")
    with stand_in() as renderer:
        code, out, err = run("render", str(table), "--atlas", "toy", "--template", str(tiny), "--out",
                             str(tmp_path / "out"), "--renderer", renderer, "--views", "lateral-left",
                             "--size", "40x30", "-q")
        assert code == 0, err
        assert "4/6 regions matched, 0 unmatched column(s)" in out  # + 2 subcortical
        colors, _ = StandInRenderer.calls[-1]
    assert colors["Left-front"] != colors["Left-back"]


def test_annotation_for_another_surface_size_is_one_line(tmp_path, tiny):
    lh = tiny_annot(tmp_path / "lh.small.annot", n=100)
    rh = tiny_annot(tmp_path / "rh.small.annot", n=100)
    code, _, err = run("atlas", "add", "toy", "--annot", f"lh={lh}", "--annot", f"rh={rh}",
                       "--template", str(tiny))
    assert code == 2
    assert err.count("\n") == 1
    assert f"{lh} labels 100 vertices" in err and "needs a lh label map with 642" in err
    assert not user_atlases.atlases_dir().exists() or not any(user_atlases.atlases_dir().iterdir())


def test_name_clashes_are_one_line_errors(tiny, tiny_annots):
    args = ["--annot", f"lh={tiny_annots['lh']}", "--annot", f"rh={tiny_annots['rh']}",
            "--template", str(tiny)]
    code, _, err = run("atlas", "add", "dk", *args)
    assert code == 2 and "an atlas named 'dk' is already installed (from brainpainter)" in err
    code, _, err = run("atlas", "add", "Tourville", *args)  # an alias, other case
    assert code == 2 and "'dkt' is already installed" in err
    assert run("atlas", "add", "toy", *args)[0] == 0
    code, _, err = run("atlas", "add", "toy", *args)
    assert code == 2 and err.count("\n") == 1
    assert "you already have an atlas named 'toy'" in err and "--replace" in err
    assert run("atlas", "add", "toy", *args, "--replace")[0] == 0
    code, _, err = run("atlas", "add", "bad/name", *args)
    assert code == 2 and "atlas name 'bad/name' is not allowed" in err


def test_out_writes_a_plugin_ready_folder_without_adding(tmp_path, tiny, tiny_annots):
    code, out, err = run("atlas", "add", "toy", "--annot", str(tiny_annots["lh"]), "--annot",
                         str(tiny_annots["rh"]), "--template", str(tiny),
                         "--out", str(tmp_path / "pkg" / "toy"))
    assert code == 0, err
    assert "written to" in out and "toy" not in registry.atlases.names()
    from brainpainter.atlas.model import load_atlas_dir

    atlas = load_atlas_dir(tmp_path / "pkg" / "toy")
    assert atlas.label_dir == tmp_path / "pkg" / "toy" and len(atlas.cortical("rh")) == 2


def test_remove_undoes_add(tiny, tiny_annots):
    user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    code, out, _ = run("atlas", "remove", "toy")
    assert code == 0 and "atlas 'toy' removed" in out
    assert "toy" not in registry.atlases.names()
    assert list(user_atlases.atlases_dir().iterdir()) == []
    code, _, err = run("atlas", "remove", "toy")
    assert code == 2 and "'toy' was given" in err
    code, _, err = run("atlas", "remove", "dk")
    assert code == 2 and "installed from brainpainter" in err and "pip uninstall brainpainter" in err


def test_remove_of_a_symlinked_atlas_removes_the_link_only(tmp_path, tiny, tiny_annots):
    """An atlas folder that is a symbolic link (kept elsewhere, linked in): the link goes, the files stay,
    nothing is left in the atlas folder, and the message says so."""
    user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    kept = tmp_path / "elsewhere" / "toy"
    kept.parent.mkdir()
    folder = user_atlases.atlases_dir() / "toy"
    folder.rename(kept)
    folder.symlink_to(kept, target_is_directory=True)
    files = sorted(p.name for p in kept.iterdir())
    registry.atlases.reset()
    assert "toy" in registry.atlases.names()
    code, out, err = run("atlas", "remove", "toy")
    assert code == 0, err
    assert "symbolic link" in out and str(kept) in out and "left as they are" in out and "deleted" not in out
    assert list(user_atlases.atlases_dir().iterdir()) == []  # no link, no hidden leftover
    assert sorted(p.name for p in kept.iterdir()) == files  # the target is untouched
    assert "toy" not in registry.atlases.names()


def test_failed_add_leaves_nothing(monkeypatch, tiny, tiny_annots):
    import brainpainter.atlas.labelset as ls

    def broken(folder, *args, **kwargs):
        (folder / "atlas.json").write_text("{}")
        raise BrainPainterError("disk full")

    monkeypatch.setattr(ls, "write_atlas_folder", broken)
    with pytest.raises(BrainPainterError, match="disk full"):
        user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    assert list(user_atlases.atlases_dir().iterdir()) == []
    assert "toy" not in registry.atlases.names()


def test_gifti_label_file_gives_the_same_atlas(tmp_path, tiny, tiny_annots):
    labels, ctab, names = nib.freesurfer.read_annot(str(tiny_annots["lh"]))
    table = nib.gifti.GiftiLabelTable()
    for i, (n, c) in enumerate(zip(names, ctab, strict=True)):
        lab = nib.gifti.GiftiLabel(key=i, red=c[0] / 255, green=c[1] / 255, blue=c[2] / 255, alpha=1.0)
        lab.label = n.decode()
        table.labels.append(lab)
    img = nib.gifti.GiftiImage(labeltable=table, darrays=[
        nib.gifti.GiftiDataArray(labels.astype(np.int32), intent="NIFTI_INTENT_LABEL",
                                 datatype="NIFTI_TYPE_INT32")])
    gii = tmp_path / "toy.L.label.gii"
    nib.save(img, gii)
    user_atlases.add_label_map("toy", {"lh": gii, "rh": tiny_annots["rh"]}, template=str(tiny))
    a = registry.atlases.get("toy")
    assert a.keys[:2] == ["Left-front", "Left-back"] and a.region("Left-front").color == (220, 20, 10)


def test_annot_option_parsing(tmp_path):
    assert user_atlases.parse_annot_options(["lh.a.annot", "rh=x.annot"]) == {
        "lh": Path("lh.a.annot"), "rh": Path("x.annot")}
    with pytest.raises(BrainPainterError, match=r"cannot tell the hemisphere of 'x\.annot'"):
        user_atlases.parse_annot_options(["x.annot"])
    with pytest.raises(BrainPainterError, match="rh is missing"):
        user_atlases.parse_annot_options(["lh=x.annot"])
    with pytest.raises(BrainPainterError, match="two lh files"):
        user_atlases.parse_annot_options(["lh=x.annot", "left=y.annot"])


def test_plugin_of_the_same_name_wins_over_a_user_atlas(tmp_path, tiny, tiny_annots):
    user_atlases.add_label_map("toy", tiny_annots, template=str(tiny))
    root = fake_distribution(tmp_path / "site", "toy-plugin", {"brainpainter.atlases": {"toy": "toy_p:toy"}},
                             {"toy_p/__init__.py": "from brainpainter.atlas.registry import get_atlas\n"
                                                   "def toy():\n    return get_atlas('dk')\n"})
    with installed(root):
        assert next(e for e in registry.atlases.entries() if e.name == "toy").distribution == "toy-plugin"
        assert "has the name of an installed atlas" in registry.atlases.errors()["toy (user)"]
    assert next(e for e in registry.atlases.entries() if e.name == "toy").distribution == "user"


# -- region groups -----------------------------------------------------------------------------------
def config(tmp_path, text, name="groups.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_lobes_config_groups_dk_regions(tmp_path):
    atlas = load_atlas_config(config(tmp_path, LOBES, "lobes.toml"))
    assert atlas.name == "lobes" and atlas.template_labels == "dk"
    assert [r.key for r in atlas.cortical("lh")] == [f"Left-{n}" for n in LOBE_NAMES]
    assert [r.key for r in atlas.cortical("rh")] == [f"Right-{n}" for n in LOBE_NAMES]
    assert len(atlas.subcortical()) == 27  # ungrouped = "keep"
    assert atlas.member_keys("Left-insula") == ("Left-insula",)
    assert "Right-precuneus" in atlas.member_keys("Right-parietal")
    dk_left = {r.key for r in registry.atlases.get("dk").cortical("lh")}
    grouped = {k for r in atlas.cortical("lh") for k in atlas.member_keys(r.key)}
    assert grouped == dk_left
    assert len({r.color for r in atlas.cortical("lh")}) == 6  # one distinct colour per lobe


def test_lobes_render_from_a_six_column_per_hemisphere_csv(tmp_path):
    cfg = config(tmp_path, LOBES, "lobes.toml")
    cols = [f"{side}-{n}" for side in ("Left", "Right") for n in LOBE_NAMES]
    table = tmp_path / "lobes.csv"
    values = ",".join(str(i / 4) for i in range(12))  # inside the default scale, 0..3
    table.write_text("Image-name-unique," + ",".join(cols) + "\nA," + values + "\n")
    with stand_in() as renderer:
        code, out, err = run("render", str(table), "--atlas-config", str(cfg), "--out", str(tmp_path / "o1"),
                             "--renderer", renderer, "--views", "lateral-left,medial-right",
                             "--size", "40x30", "-q")
        assert code == 0, err
        assert "12/39 regions matched, 0 unmatched column(s)" in out
        colors, _ = StandInRenderer.calls[-1]
        # every DK member of a lobe is drawn in the lobe's colour
        assert colors["Left-superiorfrontal"] == colors["Left-precentral"] == colors["Left-frontal"]
        assert colors["Right-cuneus"] == colors["Right-occipital"] != colors["Right-frontal"]
        # the same atlas registered by name renders the same
        assert run("atlas", "add", "lobes", "--config", str(cfg))[0] == 0
        code, out, err = run("render", str(table), "--atlas", "lobes", "--out", str(tmp_path / "o2"),
                             "--renderer", renderer, "--views", "lateral-left", "--size", "40x30", "-q")
        assert code == 0, err and "0 unmatched" in out
        assert StandInRenderer.calls[-1][0]["Left-superiorfrontal"] == colors["Left-superiorfrontal"]
    listed = {r["name"]: r for r in json.loads(CliRunner().invoke(cli, ["atlas", "list", "--json"]).output)}
    assert listed["lobes"]["distribution"] == "user" and listed["lobes"]["n_cortical_per_hemisphere"] == 6
    shown = json.loads(CliRunner().invoke(cli, ["atlas", "show", "lobes", "--json"]).output)
    assert "Left-superiorfrontal" in shown["groups"]["Left-frontal"]


def test_hide_and_values_of_a_group_reach_its_members(tmp_path):
    atlas = load_atlas_config(config(tmp_path, LOBES, "lobes.toml"))
    with stand_in() as renderer:
        painter = Painter(atlas, "fsaverage", hidden=["Left-insula", "frontal"], renderer=renderer)
        assert {"Left-superiorfrontal", "Right-frontalpole", "Left-insula"} <= painter.scene.hidden
        assert "Right-insula" not in painter.scene.hidden
    from brainpainter.color.scale import make_scale

    colors = region_colors({"Left-temporal": 1.0}, atlas, make_scale(vmin=0, vmax=1))
    assert colors["Left-bankssts"] == colors["Left-temporal"] != colors["Left-frontal"]


def test_hemisphere_specific_groups_colours_and_drop(tmp_path):
    atlas = load_atlas_config(config(tmp_path, """
        [atlas]
        base = "dk"
        ungrouped = "drop"
        [groups]
        "Left-language" = ["parsopercularis", "Left-parstriangularis"]
        visual = { regions = ["pericalcarine", "cuneus"], color = "#ff0000" }
        basal-ganglia = ["Caudate", "Putamen", "Pallidum"]
        stem = ["Brain-Stem"]
        """))
    assert atlas.keys == ["Left-language", "Left-visual", "Right-visual", "Left-basal-ganglia",
                          "Right-basal-ganglia", "stem"]
    assert atlas.member_keys("Left-language") == ("Left-parsopercularis", "Left-parstriangularis")
    assert atlas.region("Right-visual").color == (255, 0, 0)
    assert atlas.region("Left-basal-ganglia").kind == "subcortical"
    assert atlas.region("stem").hemi == "bilateral"


@pytest.mark.parametrize(("text", "message"), [
    ('[atlas]\nbase = "dk"\n[groups]\nfrontal = ["superiorfrontl"]\n',
     r"groups\.toml: group 'frontal' names 'superiorfrontl', which is not a region of atlas 'dk'\. "
     r"Did you mean 'superiorfrontal'"),
    ('[atlas]\nbase = "dk"\n[groups]\na = ["insula", "cuneus"]\nb = ["cuneus"]\n',
     r"region 'Left-cuneus' is in groups 'Left-a' and 'Left-b'; a region can be in one group only"),
    ('[atlas]\nbase = "dkk"\n[groups]\na = ["insula"]\n',
     r"base: 'atlas' must be one of .*Did you mean 'dk'"),
    ('[atlas]\nbase = "dk"\n[groups]\na = ["Left-insula"]\n',
     r"'Left-insula', a region of one hemisphere; a two-sided group takes hemisphere-free names"),
    ('[atlas]\nbase = "dk"\n[groups]\n"Left-a" = ["Right-insula"]\n', r"not in the left hemisphere"),
    ('[atlas]\nbase = "dk"\n[groups]\na = ["Hippocampus", "Brain-Stem"]\n',
     r"mixes structures without a side"),
    ('[atlas]\nbase = "dk"\n[groups]\ninsula = ["cuneus"]\n', r"has the name of the region 'Left-insula'"),
    ('[atlas]\nbase = "dk"\nungroupd = "keep"\n[groups]\na = ["insula"]\n', r"unknown key 'ungroupd'"),
    ('[atlas]\nbase = "dk"\n[groups]\n', r"\[groups\] is empty"),
    ('[atlas]\nbase = "dk"\n[groups]\na = "insula"\n', r"group 'a' must list region names"),
    ('[atlas\nbase = "dk"\n', r"is not valid TOML"),
    ('[groups]\na = ["insula"]\n', r"\[atlas\] needs base"),
])
def test_bad_configs_are_one_line_errors(tmp_path, text, message):
    path = config(tmp_path, text)
    with pytest.raises(BrainPainterError, match=message) as err:
        load_atlas_config(path)
    assert "\n" not in str(err.value)
    code, _, stderr = run("atlas", "add", "g", "--config", str(path))
    assert code == 2 and stderr.count("\n") == 1 and stderr.startswith("error: ")
    assert not (user_atlases.atlases_dir() / "g").exists()


def test_atlas_and_atlas_config_together_are_refused(tmp_path):
    with pytest.raises(BrainPainterError, match="not both"):
        render({"Left-frontal": 1.0}, "dk", atlas_config=config(tmp_path, LOBES), progress=False)


def test_atlas_add_needs_one_source(tmp_path):
    code, _, err = run("atlas", "add", "x")
    assert code == 2 and "give either --annot" in err


# -- the real fsaverage template and the Yeo 2011 annotation -----------------------------------------
@pytest.mark.integration
def test_yeo7_from_the_annotation_renders_with_seven_networks_per_hemisphere(tmp_path):
    needs_fsaverage()
    code, out, err = run("atlas", "add", "yeo7net", "--annot", f"lh={YEO7['lh']}",
                         "--annot", f"rh={YEO7['rh']}")
    assert code == 0, err
    assert "7 left, 7 right cortical regions, 27 subcortical" in out
    atlas = registry.atlases.get("yeo7net")
    assert [r.name for r in atlas.cortical("lh")] == NETWORKS == [r.name for r in atlas.cortical("rh")]
    assert atlas.region("Left-7Networks_1").color == (120, 18, 134)  # from the colour table
    cols = [f"{s}-{n}" for s in ("Left", "Right") for n in NETWORKS]
    table = tmp_path / "yeo.csv"
    values = ",".join(str(i / 5) for i in range(14))
    table.write_text("Image-name-unique," + ",".join(cols) + "\nA," + values + "\n")
    with stand_in() as renderer:
        code, out, err = run("render", str(table), "--atlas", "yeo7net", "--out", str(tmp_path / "out"),
                             "--renderer", renderer, "--views", "lateral-left,medial-right,subcortical",
                             "--size", "40x30", "-q")
        assert code == 0, err
        assert "14/41 regions matched, 0 unmatched column(s)" in out
        manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
        assert manifest["input"]["unmatched_columns"] == []
        assert check_atlas("yeo7net")["n_cortical"] == {"lh": 7, "rh": 7}


@pytest.mark.integration
def test_yeo7_label_set_matches_the_full_resolution_annotation(tmp_path):
    """Each network's pial area on the decimated template is within 1 % of the full-resolution one."""
    needs_fsaverage()
    from brainpainter_builder.cortex import assign_face_labels

    folder = user_atlases.add_label_map("yeo7net", YEO7)
    tpl = load_template("fsaverage").with_label_sets(folder)

    def areas(v, f, lab, n):
        a = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
        return np.bincount(lab, weights=a, minlength=n)[1:n] / a.sum()

    for hemi in ("lh", "rh"):
        labels, _, _ = nib.freesurfer.read_annot(str(YEO7[hemi]))
        v, f = nib.freesurfer.read_geometry(str(FSAVERAGE / "surf" / f"{hemi}.pial"))
        full = areas(v, f, assign_face_labels(f, labels), 8)
        cm = tpl.cortex("yeo7net", hemi)
        ours = areas(cm.vertices["pial"].astype(float), cm.faces, cm.face_label.astype(int), 8)
        assert np.abs(ours / full - 1).max() < 0.01, (hemi, ours / full)


@pytest.mark.integration
def test_fsaverage5_annotation_on_fsaverage_is_refused():
    needs_fsaverage()
    small = FREESURFER / "subjects" / "fsaverage5" / "label"
    if not (small / "lh.Yeo2011_7Networks_N1000.annot").is_file():
        pytest.skip("no fsaverage5 Yeo annotation in the shared data")
    code, _, err = run("atlas", "add", "yeo5", "--annot", str(small / "lh.Yeo2011_7Networks_N1000.annot"),
                       "--annot", str(small / "rh.Yeo2011_7Networks_N1000.annot"))
    assert code == 2 and err.count("\n") == 1
    assert "labels 10242 vertices, but template 'fsaverage' needs a lh label map with 163842" in err


def test_reference_image_with_a_stand_in_renderer(tmp_path):
    from PIL import Image

    with stand_in() as renderer:
        code, _, err = run("atlas", "show", "dk", "--image", str(tmp_path / "dk.png"), "--size", "60x40",
                             "--views", "lateral-left,subcortical", "--renderer", renderer)
    assert code == 0, err
    img = Image.open(tmp_path / "dk.png")
    assert img.width == 120 and img.height > 40  # two views side by side, a legend below
    assert img.text["brainpainter:atlas"] == "dk"
    code, _, err = run("atlas", "show", "dk", "--image", str(tmp_path / "nowhere" / "dk.png"))
    assert code == 2 and "does not exist" in err


@pytest.mark.render
@pytest.mark.integration
def test_yeo7_reference_image_with_blender(tmp_path):
    """A real render: every lateral network appears in its colour-table colour."""
    needs_fsaverage()
    pytest.importorskip("bpy")
    from PIL import Image

    user_atlases.add_label_map("yeo7net", YEO7)
    out = tmp_path / "yeo7net.png"
    code, _, err = run("atlas", "show", "yeo7net", "--image", str(out), "--size", "320x240", "--quality",
                       "fast", "--views", "lateral-left,medial-left")
    assert code == 0, err
    pixels = np.asarray(Image.open(out).convert("RGB"))[:240].reshape(-1, 3).astype(int)
    atlas = registry.atlases.get("yeo7net")
    for r in atlas.cortical("lh"):
        # shaded, so compare hue-ish: the pixel colour direction is close to the region colour's
        c = np.array(r.color, float)
        cos = (pixels @ c) / (np.linalg.norm(pixels, axis=1) * np.linalg.norm(c) + 1e-9)
        near = (cos > 0.995) & (np.abs(pixels - c).max(axis=1) < 90)
        assert near.sum() > 200, (r.key, int(near.sum()))
