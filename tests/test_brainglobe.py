"""BrainGlobe atlases (brainpainter atlas add NAME --brainglobe ATLAS_NAME): a tiny atlas written in
BrainGlobe's own format by brainglobe-atlasapi's atlas-generation code (wrapup_atlas_from_data) in a
temporary folder, read back without network; a parent's value colours its children."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas.brainglobe import increasing_axes, open_local_atlas, select_structures
from brainpainter.cli.main import cli
from brainpainter.errors import BrainPainterError

STRUCTURES = [
    {"acronym": "root", "id": 997, "name": "root", "structure_id_path": [997],
     "rgb_triplet": [255, 255, 255]},
    {"acronym": "CTX", "id": 10, "name": "Cortex", "structure_id_path": [997, 10],
     "rgb_triplet": [0, 255, 0]},
    {"acronym": "CA", "id": 11, "name": "Cortex area A", "structure_id_path": [997, 10, 11],
     "rgb_triplet": [255, 0, 0]},
    {"acronym": "CB", "id": 12, "name": "Cerebellum B", "structure_id_path": [997, 12],
     "rgb_triplet": [0, 0, 255]},
]


pytestmark = pytest.mark.usefixtures("fresh_registry")


def tiny_volume() -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """A 100 um annotation volume (axes: from anterior, from superior, from right: BrainGlobe's asr) and the
    marching-cubes mesh of every structure (its own voxels and its descendants'), in micrometres, asr."""
    from skimage.measure import marching_cubes

    ann = np.zeros((20, 16, 24), np.uint32)
    ann[2:18, 2:14, 2:22] = 997
    ann[3:9, 3:8, 3:21] = 11  # CA: anterior, dorsal
    ann[11:17, 6:12, 6:18] = 12  # CB: posterior
    meshes = {}
    for s in STRUCTURES:
        mask = np.isin(ann, [x["id"] for x in STRUCTURES if s["id"] in x["structure_id_path"]])
        if mask.any():
            v, f, _, _ = marching_cubes(np.pad(mask, 1).astype(float), 0.5)
            meshes[s["id"]] = ((v - 1) * 100.0, f)
    return ann, meshes


def write_format3_atlas(folder: Path, name: str) -> Path:
    """The tiny atlas in BrainGlobe's format 3 (brainpainter.testing.brainglobe)."""
    from brainpainter.testing.brainglobe import write_format3_atlas as write

    ann, meshes = tiny_volume()
    return write(folder, name, STRUCTURES, meshes, ann)


@pytest.fixture(scope="module", params=["format3", "atlasgen"])
def bg_dir(request, tmp_path_factory) -> Path:
    """A 3-structure mouse atlas (100 um, BrainGlobe orientation asr) named tiny_mouse_100.0um: written in
    BrainGlobe's format 3 here (with brainglobe-atlasapi's own libraries: zarr, DracoPy), or by
    brainglobe-atlasapi's atlas-generation code (its atlasgen extra)."""
    pytest.importorskip("brainglobe_atlasapi")
    work = tmp_path_factory.mktemp("bg")
    if request.param == "format3":
        return write_format3_atlas(work, "tiny_mouse_100.0um")
    wrapup = pytest.importorskip("brainglobe_atlasapi.atlas_generation.wrapup",
                                 reason="brainglobe-atlasapi's atlas generation needs its atlasgen extra")
    import trimesh

    ann, arrays = tiny_volume()
    meshes = {}
    for sid, (v, f) in arrays.items():
        meshes[sid] = work / f"{sid}.obj"
        trimesh.Trimesh(v, f).export(meshes[sid])
    with warnings.catch_warnings():  # the generation code's own dependencies warn about their deprecations
        warnings.simplefilter("ignore")
        wrapup.wrapup_atlas_from_data(
            atlas_name="tiny_mouse", atlas_minor_version=0, citation="unpublished", atlas_link="https://example.org",
            species="Mouse (Mus musculus)", resolution=(100.0, 100.0, 100.0), orientation="asr", root_id=997,
            reference_stack=(ann > 0).astype(np.uint16) * 100, annotation_stack=ann,
            structures_list=STRUCTURES, meshes_dict=meshes, working_dir=work / "brainglobe",
            atlas_packager="test")
    return work / "brainglobe"


def test_orientation_and_selection():
    assert increasing_axes("asr") == "PIL" and increasing_axes("RAS") == "LPI"
    tree = {s["id"]: s for s in STRUCTURES}
    assert [s["acronym"] for s in select_structures(tree, None, None)] == ["CA", "CB"]
    assert [s["acronym"] for s in select_structures(tree, None, 1)] == ["CTX", "CB"]
    assert [s["acronym"] for s in select_structures(tree, ["CTX"], None)] == ["CTX"]
    with pytest.raises(BrainPainterError, match="--structures must be one of"):
        select_structures(tree, ["XX"], None)


def test_without_the_package_one_line_says_how_to_get_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "brainglobe_atlasapi", None)
    with pytest.raises(BrainPainterError, match="brainglobe-atlasapi"):
        open_local_atlas("allen_mouse_25um")


def fails(*args: str) -> str:
    """Run ``brainpainter atlas add ARGS`` as the command line does; assert exit code 2 and one line."""
    from brainpainter.cli.main import main

    runner = CliRunner()
    with runner.isolation() as (out, err, _):
        with pytest.raises(SystemExit) as exc:
            main(["atlas", "add", *args])
    text = (err.getvalue() if err else out.getvalue()).decode()
    assert exc.value.code == 2 and len(text.strip().splitlines()) == 1 and "Traceback" not in text, text
    return text


def test_without_the_package_the_command_fails_with_one_line_and_adds_nothing(monkeypatch, tmp_path):
    """Runs everywhere, with or without brainglobe-atlasapi."""
    from brainpainter.atlas.registry import atlases_dir

    monkeypatch.setitem(sys.modules, "brainglobe_atlasapi", None)
    text = fails("allen", "--brainglobe", "allen_mouse_25um", "--brainglobe-dir", str(tmp_path))
    assert "brainglobe-atlasapi" in text and "pip install" in text, text
    assert not (atlases_dir() / "allen").exists() and "allen" not in registry.atlases.names()


def test_an_atlas_not_on_this_machine_is_not_downloaded(tmp_path):
    pytest.importorskip("brainglobe_atlasapi")
    with pytest.raises(BrainPainterError, match="brainglobe install -a allen_mouse_25um"):
        open_local_atlas("allen_mouse_25um", tmp_path)
    assert not (tmp_path / "brainglobe-atlasapi" / "atlases").exists()


def test_local_atlas_becomes_an_atlas_with_acronyms_names_and_groups(bg_dir, tmp_path):
    result = CliRunner().invoke(cli, ["atlas", "add", "tiny", "--brainglobe", "tiny_mouse_100.0um",
                                      "--brainglobe-dir", str(bg_dir)])
    assert result.exit_code == 0, result.output
    assert "BrainGlobe 'asr'" in result.output and "2 structures drawn, 2 parent structures" in result.output
    atlas = registry.atlases.get("tiny")
    assert atlas.region("CA").aliases == ("Cortex area A",) and "CTX" in atlas.keys
    assert dict(atlas.members) == {"root": ("CA", "CB"), "CTX": ("CA",)}
    # a parent's value colours its children unless they have their own; the nearest ancestor wins
    assert atlas.expand({"CTX": 1, "root": 2}) == {"CTX": 1, "root": 2, "CA": 1, "CB": 2}
    assert atlas.expand({"CTX": 1, "CA": 5}) == {"CTX": 1, "CA": 5}


@pytest.mark.render
def test_a_parent_value_renders_on_its_child(bg_dir, tmp_path):
    from PIL import Image

    from brainpainter.rendering.run import render

    assert CliRunner().invoke(cli, ["atlas", "add", "tiny", "--brainglobe", "tiny_mouse_100.0um",
                                    "--brainglobe-dir", str(bg_dir)]).exit_code == 0
    render({"CTX": 0.0, "CB": 1.0}, "tiny", out=tmp_path, views="dorsal", gradient=["#ff0000", "#0000ff"],
           width=200, height=200, shading="flat", quality="fast", progress=False)
    img = np.asarray(Image.open(tmp_path / "1_dorsal.png").convert("RGB")).astype(int)
    red = np.nonzero(np.abs(img - (255, 0, 0)).max(-1) <= 3)[0]
    blue = np.nonzero(np.abs(img - (0, 0, 255)).max(-1) <= 3)[0]
    assert len(red) > 300 and len(blue) > 300  # CA drawn in CTX's colour
    assert red.mean() < blue.mean()  # CA anterior (top of the dorsal view), CB posterior


def test_a_mesh_not_on_this_machine_is_reported_never_fetched(tmp_path, monkeypatch):
    """brainglobe-atlasapi 3 fetches a structure's mesh from BrainGlobe's server on first use: not here."""
    pytest.importorskip("brainglobe_atlasapi")
    from brainglobe_atlasapi import structure_class

    fetched: list[object] = []
    monkeypatch.setattr(structure_class.Structure, "_download_mesh", lambda self, f: fetched.append(f))
    folder = write_format3_atlas(tmp_path / "bg", "tiny_mouse_100.0um")
    mesh_dir = next(folder.glob("brainglobe-atlasapi/annotation-sets/*/*/annotations.precomputed/mesh"))
    (mesh_dir / "12").unlink()  # CB
    result = CliRunner().invoke(cli, ["atlas", "add", "tiny", "--brainglobe", "tiny_mouse_100.0um",
                                      "--brainglobe-dir", str(folder)])
    assert result.exit_code == 0, result.output
    assert "mesh not on this machine for 1 structure(s), not drawn: CB" in result.output, result.output
    assert "CA" in registry.atlases.get("tiny").keys and "CB" not in registry.atlases.get("tiny").keys
    for sid in ("10", "11", "997"):
        (mesh_dir / sid).unlink()
    text = fails("tiny2", "--brainglobe", "tiny_mouse_100.0um", "--brainglobe-dir", str(folder))
    assert "has its mesh on this machine (2 not fetched: CA, CB)" in text and "mesh_from_structure" in text
    assert fetched == []
