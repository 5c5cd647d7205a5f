"""`brainpainter render` end to end with the Blender renderer on the bundled template."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from brainpainter.rendering.painter import Painter
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import get_view

pytestmark = pytest.mark.render

RED, GREEN, BLUE, YELLOW = (1.0, 0.0, 0.0), (0.0, 0.8, 0.0), (0.0, 0.0, 1.0), (1.0, 1.0, 0.0)


def run(*args, cwd=None, env=None, prefix=()):
    return subprocess.run([*prefix, sys.executable, "-m", "brainpainter", *args], capture_output=True,
                          text=True, cwd=cwd, env=env)


def test_two_row_original_csv_gives_six_pngs_and_manifest(tmp_path):
    csv = tmp_path / "in.csv"
    csv.write_text("Image-name-unique,Left-entorhinal,Left-Hippocampus,Right-Putamen\n"
                   "early,1.5,2,0\nlate,3,3,1\n")
    out = tmp_path / "out"
    proc = run("render", str(csv), "--atlas", "dk", "--out", str(out), "--quality", "fast", "-q")
    assert proc.returncode == 0, proc.stderr
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == sorted(f"{i}_{v}.png" for i in ("early", "late")
                          for v in ("lateral-left", "medial-left", "subcortical"))
    for name in pngs:
        img = Image.open(out / name)
        assert img.size == (1200, 900) and img.mode == "RGBA"
        assert json.loads(img.text["brainpainter:settings"])["quality"] == "fast"
    manifest = json.loads((out / "manifest.json").read_text())
    assert len(manifest["files"]) == 6 and manifest["settings"]["atlas"] == "dk"
    assert sorted(os.listdir(out)) == sorted([*pngs, "manifest.json"])  # no temporary files left


@pytest.fixture(scope="module")
def painter():
    p = Painter("dk", settings=RenderSettings(width=400, height=300, quality="fast", shading="flat"))
    yield p
    p.close()


def centroid(img, rgb):
    target = np.round(np.asarray(rgb) * 255)
    mask = np.abs(img[..., :3].astype(float) - target).max(axis=-1) <= 1
    assert mask.sum() > 30, f"{rgb} hardly visible"
    ys, xs = np.nonzero(mask)
    return xs.mean(), ys.mean()


@pytest.mark.parametrize(
    ("view", "front", "back", "top", "bottom", "anterior_is"),
    [
        ("lateral-left", "Left-rostralmiddlefrontal", "Left-lateraloccipital",
         "Left-superiorparietal", "Left-inferiortemporal", "left"),
        ("medial-left", "Left-medialorbitofrontal", "Left-cuneus", "Left-paracentral",
         "Left-fusiform", "right"),
        ("lateral-right", "Right-rostralmiddlefrontal", "Right-lateraloccipital",
         "Right-superiorparietal", "Right-inferiortemporal", "right"),
        ("medial-right", "Right-medialorbitofrontal", "Right-cuneus", "Right-paracentral",
         "Right-fusiform", "left"),
    ],
)
def test_anatomical_orientation_on_the_real_brain(painter, view, front, back, top, bottom, anterior_is):
    img = painter.paint_colors({front: RED, back: GREEN, top: BLUE, bottom: YELLOW}, get_view(view))
    (fx, _), (bx, _) = centroid(img, RED), centroid(img, GREEN)
    (_, ty), (_, by) = centroid(img, BLUE), centroid(img, YELLOW)
    assert (fx < bx) if anterior_is == "left" else (fx > bx)
    assert ty < by  # superior at the top (image y grows downwards)


def test_dorsal_and_anterior_views_place_hemispheres(painter):
    colors = {"Left-superiorfrontal": RED, "Right-superiorfrontal": GREEN,
              "Left-superiorparietal": BLUE, "Right-superiorparietal": YELLOW}
    img = painter.paint_colors(colors, get_view("dorsal"))
    (lx, ly), (rx, _), (_, py) = centroid(img, RED), centroid(img, GREEN), centroid(img, BLUE)
    assert rx > lx  # right hemisphere on the right, seen from above
    assert ly < py  # anterior at the top
    img = painter.paint_colors(colors, get_view("anterior"))
    assert centroid(img, GREEN)[0] < centroid(img, RED)[0]  # facing the subject: their right on our left


def test_flat_colours_are_exact_on_the_real_brain(painter):
    from brainpainter.color.scale import make_scale

    scale = make_scale()  # white, yellow, orange, red on 0..3
    img = painter.paint({"Left-superiorfrontal": 1.2}, get_view("lateral-left"), scale)
    expected = np.round(scale(1.2) * 255)
    hits = np.all(np.abs(img[..., :3].astype(int) - expected) <= 1, axis=-1)
    assert hits.sum() > 2000  # the region's interior carries exactly the mapped sRGB colour
    missing = np.round(np.asarray(scale.missing_color) * 255)
    assert np.all(np.abs(img[..., :3].astype(int) - missing) <= 1, axis=-1).sum() > 2000


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--views", "sideways"], "view must be one of"),
        (["--views", "lateral-left", "--template", "/nonexistent"], "is not a directory with a manifest"),
    ],
)
def test_option_errors_are_one_line(tmp_path, args, message):
    csv = tmp_path / "in.csv"
    csv.write_text("Image-name-unique,Left-insula\na,1\n")
    proc = run("render", str(csv), "--out", str(tmp_path / "out"), *args)
    assert proc.returncode == 2 and message in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()


def test_unreadable_input_and_unwritable_output(tmp_path, without_root_powers):
    csv = tmp_path / "in.csv"
    csv.write_text("Image-name-unique,Left-insula\na,1\n")
    csv.chmod(0)
    proc = run("render", str(csv), "--out", str(tmp_path / "out"), prefix=without_root_powers)
    csv.chmod(0o644)
    # root too, without its powers; click's check of INPUT answers before brainpainter's opener
    assert proc.returncode == 2 and str(csv) in proc.stderr, proc.stderr
    assert "is not readable" in proc.stderr or "cannot read" in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    proc = run("render", str(csv), "--out", str(blocker / "out"), "--views", "lateral-left",
               "--quality", "fast")
    assert proc.returncode == 2 and "is a file, not a folder" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_missing_bpy_is_one_line_and_writes_nothing(tmp_path):
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "bpy.py").write_text("raise ImportError('no Blender here')\n")
    csv = tmp_path / "in.csv"
    csv.write_text("Image-name-unique,Left-insula\na,1\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(fake), os.environ.get("PYTHONPATH", "")])}
    proc = run("render", str(csv), "--out", str(tmp_path / "out"), env=env)
    assert proc.returncode == 2, proc.stderr
    assert "pip install bpy" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_bpy_that_draws_nothing_is_one_line_and_writes_nothing(tmp_path):
    """A bpy release whose draw calls silently draw nothing (bpy 5.3 before the fix) is an error, not PNGs."""
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "sitecustomize.py").write_text(
        "import numpy as np\n"
        "import brainpainter_blender.gpu_draw as g\n"
        "g.GpuDraw._draw = lambda self, rgb, aim, mark=None: np.zeros(\n"
        "    (self.settings.height, self.settings.width, 4), np.uint8)\n")
    csv = tmp_path / "in.csv"
    csv.write_text("Image-name-unique,Left-insula\na,1\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(fake), os.environ.get("PYTHONPATH", "")])}
    out = tmp_path / "out"
    proc = run("render", str(csv), "--out", str(out), "--views", "lateral-left", "--size", "160x120",
               "--transparent", env=env)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    line = proc.stderr.strip().splitlines()[-1]  # after the progress bar
    assert line.startswith("error: ") and proc.stderr.count("error:") == 1, proc.stderr
    assert "drew nothing" in line and "Blender " in line and "pip install 'bpy" in line
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize(("limits", "noted"), [(["--vmax", "1"], True), ([], False),
                                               (["--vmax", "3"], False)])
def test_values_beyond_a_given_scale_are_a_note(tmp_path, monkeypatch, capsys, tiny, limits, noted):
    """Values past --vmin/--vmax are drawn in the end colours: render says so (only check did)."""
    from brainpainter.cli.main import main
    from brainpainter.testing import stand_in

    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("Left-insula,Left-precuneus\n0,2.5\n")
    with stand_in() as renderer, pytest.raises(SystemExit) as exit_:
        main(["render", "t.csv", "--template", str(tiny), "--renderer", renderer, "--views", "lateral-left",
              "--size", "40x30", "--vmin", "0", *limits, "--out", "o", "-q"])
    assert exit_.value.code in (0, None)
    out = capsys.readouterr().out
    assert ("note: values 0..2.5 reach beyond the colour scale 0..1" in out) == noted, out
    assert ("reach beyond" in out) == noted
