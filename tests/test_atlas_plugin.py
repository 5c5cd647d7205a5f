"""The example atlas plugin (plugins/atlases/brainpainter-atlas-yeo7): pip-installed, listed, rendered,
uninstalled; its shipped data is what its build script derives; label-set overlays are checked."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas.model import load_atlas_dir
from brainpainter.atlas.template import load_template
from brainpainter.cli.main import cli
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.painter import Painter
from brainpainter.testing import (
    StandInRenderer,
    check_atlas,
    installed,
    stand_in,
)

REPO = Path(__file__).resolve().parents[1]
PLUGIN = REPO / "plugins" / "atlases" / "brainpainter-atlas-yeo7"
DATA = PLUGIN / "bp_atlas_yeo7" / "data" / "yeo7"
FSAVERAGE = REPO.parent / "shared" / "data" / "freesurfer" / "subjects" / "fsaverage"
NETWORKS = [f"7Networks_{i}" for i in range(1, 8)]


def test_pip_installed_plugin_is_listed_and_renders(site, tmp_path):
    assert "yeo7" not in registry.atlases.names()
    with installed(site):
        rows = {r["name"]: r for r in json.loads(CliRunner().invoke(cli, ["atlas", "list", "--json"]).output)}
        assert rows["yeo7"]["distribution"] == "brainpainter-atlas-yeo7"
        assert rows["yeo7"]["n_cortical_per_hemisphere"] == 7 and rows["yeo7"]["error"] is None
        atlas = registry.atlases.get("yeo7")
        assert atlas.label_dir is not None and Path(site) in atlas.label_dir.parents
        assert [r.name for r in atlas.cortical("lh")] == NETWORKS
        assert "Yeo" in atlas.citation
        assert check_atlas("yeo7")["n_cortical"] == {"lh": 7, "rh": 7}
        cols = [f"{s}-{n}" for s in ("Left", "Right") for n in NETWORKS]
        table = tmp_path / "yeo.csv"
        table.write_text("Image-name-unique," + ",".join(cols) + "\nA," + ",".join(["1"] * 14) + "\n")
        with stand_in() as renderer:
            result = CliRunner().invoke(cli, [
                "render", str(table), "--atlas", "yeo7", "--out", str(tmp_path / "out"), "--renderer",
                renderer, "--views", "lateral-left,medial-right", "--size", "40x30", "-q"])
            assert result.exit_code == 0, result.output
            assert "14/41 regions matched, 0 unmatched column(s)" in result.output
            colors, _ = StandInRenderer.calls[-1]
            assert all(colors[c] == colors["Left-7Networks_1"] for c in cols)
    assert "yeo7" not in registry.atlases.names()


def test_uninstalling_the_plugin_removes_the_atlas(site, tmp_path):
    copy = tmp_path / "site"
    shutil.copytree(site, copy)
    with installed(copy):
        assert "yeo7" in registry.atlases.names()
        for p in [*copy.glob("brainpainter_atlas_yeo7-*.dist-info"), copy / "bp_atlas_yeo7"]:
            shutil.rmtree(p)  # what 'pip uninstall brainpainter-atlas-yeo7' removes
        registry.reset_all()
        listed = CliRunner().invoke(cli, ["atlas", "list"])
        assert listed.exit_code == 0 and "yeo7" not in listed.output


def test_plugins_own_tests_pass_with_the_brainpainter_fixtures(site, tmp_path):
    """The tests a lab copies with the example (they use brainpainter.testing as a pytest plugin)."""
    tests = tmp_path / "tests"
    shutil.copytree(PLUGIN / "tests", tests)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tests)],
                          cwd=tmp_path, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert "3 passed" in proc.stdout


@pytest.mark.integration
def test_shipped_data_is_what_build_data_derives(tmp_path):
    if not (FSAVERAGE / "label" / "lh.Yeo2011_7Networks_N1000.annot").is_file():
        pytest.skip(f"shared data not found at {FSAVERAGE}")
    spec = importlib.util.spec_from_file_location("yeo7_build_data", PLUGIN / "build_data.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = module.main(FSAVERAGE, out=tmp_path / "yeo7")
    shipped = sorted(p.name for p in DATA.iterdir())
    assert shipped == sorted(p.name for p in out.iterdir())
    for name in shipped:
        assert (out / name).read_bytes() == (DATA / name).read_bytes(), name
    assert not any(p.suffix == ".annot" for p in PLUGIN.rglob("*"))  # derived data only
    assert "PART B" in (DATA / "LICENSE.FreeSurfer.txt").read_text()


def test_main_distribution_does_not_take_the_plugin_package():
    from setuptools import find_namespace_packages

    find = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]["find"]
    found = {p for where in find["where"]
             for p in find_namespace_packages(where=str(REPO / where), include=find["include"])}
    assert "brainpainter" in found and "brainpainter_atlases" in found
    assert not any("yeo7" in p for p in found), sorted(found)


# -- label-set overlays -------------------------------------------------------------------------------
def test_overlay_for_another_template_is_a_one_line_error(tiny):
    atlas = load_atlas_dir(DATA)
    with stand_in() as renderer, pytest.raises(BrainPainterError) as err:
        Painter(atlas, str(tiny), renderer=renderer)
    assert "were made for template 'fsaverage', not 'tiny'" in str(err.value)
    assert "\n" not in str(err.value)


def test_overlay_on_a_changed_template_mesh_is_refused(tmp_path):
    folder = tmp_path / "yeo7"
    shutil.copytree(DATA, folder)
    meta = json.loads((folder / "labels.json").read_text())
    meta["labels"]["yeo7"]["cortex"]["lh"]["base_faces_sha256"] = "0" * 64
    (folder / "labels.json").write_text(json.dumps(meta))
    with stand_in() as renderer, pytest.raises(BrainPainterError, match="that mesh has changed; add the"):
        Painter(load_atlas_dir(folder), "fsaverage", renderer=renderer)


def test_overlay_mesh_is_closed_and_keeps_the_base_vertices():
    from brainpainter_builder.cortex import open_edge_count

    tpl = load_template("fsaverage").with_label_sets(DATA)
    entry = json.loads((DATA / "labels.json").read_text())["labels"]["yeo7"]["cortex"]
    for hemi in ("lh", "rh"):
        cm = tpl.cortex("yeo7", hemi)
        base = tpl.base_cortex(entry[hemi]["base"], hemi)
        n = len(base.source_vertex)
        assert open_edge_count(cm.faces) == 0
        assert np.array_equal(cm.vertices["pial"][:n], base.vertices["pial"])
        assert (cm.source_vertex[n:] == -1).all()
        assert set(np.unique(cm.face_label).tolist()) == set(range(8))  # medial wall + 7 networks
