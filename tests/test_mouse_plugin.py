"""The mouse atlas distribution (brainpainter-atlas-mouse): pip-installed into a throw-away folder, the
original's mouse_template.csv renders with 0 unmatched columns in the original's three views, the dorsal
view is the right way round and framed, and the shipped data is what the build script derives."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.cli.main import cli
from brainpainter.testing import StandInRenderer, installed, stand_in

REPO = Path(__file__).resolve().parents[1]
PLUGIN = REPO / "plugins" / "atlases" / "brainpainter-atlas-mouse"
DATA = PLUGIN / "bp_atlas_mouse" / "data" / "mouse"
# ../shared/data beside the repository (BRAINPAINTER_MOUSE_DATA names another copy, e.g. from a worktree)
SOURCE = Path(os.environ.get("BRAINPAINTER_MOUSE_DATA",
                             REPO.parent / "shared" / "data" / "mouse" / "brainpainter2021"))
TEMPLATE_CSV = SOURCE / "mouse_template.csv"
DIST = "brainpainter-atlas-mouse"
needs_source = pytest.mark.skipif(not TEMPLATE_CSV.is_file(), reason="needs ../shared/data/mouse")


pytestmark = pytest.mark.usefixtures("fresh_registry")


def test_installed_atlas_is_listed_with_its_own_brain_and_attribution(site):
    assert "mouse" not in registry.atlases.names()
    with installed(site):
        rows = {r["name"]: r for r in json.loads(CliRunner().invoke(cli, ["atlas", "list", "--json"]).output)}
        assert rows["mouse"]["distribution"] == DIST and rows["mouse"]["error"] is None
        atlas = registry.atlases.get("mouse")
        assert len(atlas.cortical("lh")) == len(atlas.cortical("rh")) == 20 and len(atlas.subcortical()) == 14
        assert {"Left-Auditory", "Right-Hippocampus", "Left-Cerebellum"} <= set(atlas.keys)
        assert atlas.template_dir is not None and Path(site) in atlas.template_dir.parents
        text = (atlas.template_dir.parent / "ATTRIBUTION.txt").read_text()
        assert "Marinescu et al. (2019)" in text and "CC-BY 3.0" in text and "modified" in text
        result = CliRunner().invoke(cli, ["atlas", "show", "mouse"])
        assert result.exit_code == 0 and "Left-Olfactory" in result.output


@needs_source
def test_original_template_renders_every_row_with_0_unmatched_in_the_three_views(site, tmp_path):
    with installed(site), stand_in() as renderer:
        result = CliRunner().invoke(cli, [
            "render", str(TEMPLATE_CSV), "--atlas", "mouse", "--out", str(tmp_path / "out"), "--renderer",
            renderer, "--views", "top,cortical-outer,subcortical", "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        assert "54/54 regions matched, 0 unmatched column(s)" in result.output
        assert len(StandInRenderer.calls) >= 2
        colors, _ = StandInRenderer.calls[-1]
        assert len(colors) == 54


@needs_source
@pytest.mark.integration
def test_shipped_data_is_what_the_build_script_derives(tmp_path):
    spec = importlib.util.spec_from_file_location("mouse_build", PLUGIN / "build_data.py")
    assert spec and spec.loader
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    out = build.main(SOURCE, tmp_path / "mouse")
    for name in ("regions.tsv", "atlas.json", "ATTRIBUTION.txt", "template/manifest.json"):
        assert (out / name).read_bytes() == (DATA / name).read_bytes(), name
    for npz in ("template/cortex-lh.npz", "template/cortex-rh.npz", "template/subcortical.npz"):
        assert (out / npz).read_bytes() == (DATA / npz).read_bytes(), npz
    meta = json.loads((DATA / "atlas.json").read_text())
    assert all(r["n_vertices"] < 0.5 * 3 * r["n_faces"] for r in meta["regions"])  # welded soups
    notes = {r["key"]: r["notes"] for r in meta["regions"]}
    assert any("dropped 2 piece(s)" in n for n in notes["Right-Perirhinal"])


def dorsal_layout(img: np.ndarray, colours: dict[str, tuple[int, int, int]]) -> dict[str, np.ndarray]:
    out = {}
    for key, rgb in colours.items():
        rows, cols = np.nonzero(np.abs(img - rgb).max(-1) <= 3)
        assert len(rows) > 100, key
        out[key] = np.array([rows.mean(), cols.mean()])
    return out


@needs_source
@pytest.mark.render
def test_dorsal_view_has_olfactory_anterior_cerebellum_posterior_left_on_the_left(site, tmp_path):
    from PIL import Image

    from brainpainter.rendering.run import render

    values = {"Left-Olfactory": 1.0, "Right-Olfactory": 2.0, "Left-Cerebellum": 3.0, "Right-Cerebellum": 3.0}
    with installed(site):
        render(values, "mouse", out=tmp_path, views="top", gradient=["#ffffff", "#ff0000", "#00c800",
                                                                      "#0000ff"],
               vmin=0, vmax=3, width=500, height=500, shading="flat", quality="fast", progress=False)
    img = np.asarray(Image.open(tmp_path / "1_dorsal.png").convert("RGB")).astype(int)
    at = dorsal_layout(img, {"lh-olf": (255, 0, 0), "rh-olf": (0, 200, 0), "cb": (0, 0, 255)})
    assert at["lh-olf"][0] < 0.3 * img.shape[0] and at["rh-olf"][0] < 0.3 * img.shape[0]  # anterior: top
    assert at["cb"][0] > 0.6 * img.shape[0]  # cerebellum posterior: bottom
    assert at["lh-olf"][1] < img.shape[1] / 2 < at["rh-olf"][1]  # left on the left
    brain = np.nonzero((np.abs(img - 255).max(-1) > 8).any(0))[0]
    width = (brain.max() - brain.min() + 1) / img.shape[1]
    assert 0.6 <= width <= 0.95, width  # framed (a square image: the mouse brain is longer than wide)


@pytest.mark.render
def test_default_views_are_those_it_can_show_framed_to_its_shape(site, tmp_path):
    """No views given: the atlas's own (its hemispheres are open on the medial side: no medial view, whose
    shards of open mesh it drew); no size given: the image takes the shape of what the views show (its
    side views wide, its top view tall), as many pixels as 1200x900. In the square image of before, the
    side views left 47 % of the rows and 63 % of the pixels empty. A size the user gives is kept."""
    from PIL import Image

    from brainpainter.rendering.run import render

    with installed(site):
        result = render({"Left-Olfactory": 1.0}, "mouse", out=tmp_path / "auto", shading="flat",
                        quality="fast", progress=False)
        render({"Left-Olfactory": 1.0}, "mouse", out=tmp_path / "top", views="top", shading="flat",
               quality="fast", progress=False)
        render({"Left-Olfactory": 1.0}, "mouse", out=tmp_path / "given", views="top", width=400, height=300,
               shading="flat", quality="fast", progress=False)
    assert sorted(f.name for f in result.files) == ["1_lateral-left.png", "1_subcortical.png"]
    for png in [*result.files, tmp_path / "top" / "1_dorsal.png"]:
        img = np.asarray(Image.open(png).convert("RGB")).astype(int)
        h, w = img.shape[:2]
        assert abs(w * h - 1200 * 900) < 0.01 * 1200 * 900
        assert (w > 1.5 * h) if "dorsal" not in png.name else (h > 1.15 * w), (png.name, w, h)
        brain = np.abs(img - 255).max(-1) > 8
        cols, rows = np.nonzero(brain.any(0))[0], np.nonzero(brain.any(1))[0]
        fill = ((cols.max() - cols.min() + 1) / w, (rows.max() - rows.min() + 1) / h)
        assert all(0.8 <= f <= 0.95 for f in fill), (png.name, fill)  # framed on both axes
        assert brain.mean() >= 0.55, (png.name, brain.mean())  # at most 45 % of the image empty
    with Image.open(tmp_path / "given" / "1_dorsal.png") as im:
        assert im.size == (400, 300)
