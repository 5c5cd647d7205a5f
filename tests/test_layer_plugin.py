"""The foci layer plugin (plugins/layers/brainpainter-layer-foci, issue 43): pip-installed into a
throw-away folder, listed by ``brainpainter layers``, reached by ``--layer foci:FILE`` and
``Scene.add(path, kind="foci")``, and drawn where its MNI152 points are."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image
from test_bad_inputs_inprocess import invoke

from brainpainter.atlas import registry
from brainpainter.cli.main import cli
from brainpainter.testing import installed
from brainpainter.testing.distributions import pip_install

REPO = Path(__file__).resolve().parents[1]
PLUGIN = REPO / "plugins" / "layers" / "brainpainter-layer-foci"
TABLE = REPO / "examples" / "brainpainter_dk.csv"
MAGENTA = (1.0, 0.0, 1.0)


@pytest.fixture(scope="module")
def foci_site(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("foci")
    return pip_install(PLUGIN, root / "site", root)


@pytest.fixture
def peaks(tmp_path) -> Path:
    path = tmp_path / "peaks.csv"
    path.write_text("x,y,z,name,color,radius\n-40,-20,50,left M1,#ff00ff,6\n")
    return path


def _near(img: np.ndarray, rgb: tuple[float, float, float], tol: int = 40) -> np.ndarray:
    target = np.round(np.asarray(rgb) * 255)
    return (np.abs(img[..., :3].astype(int) - target) <= tol).all(axis=-1)


def test_the_installed_plugin_is_listed_with_its_options(foci_site):
    assert "foci" not in registry.layer_kinds.names()
    with installed(foci_site):
        rows = {r["name"]: r for r in json.loads(CliRunner().invoke(cli, ["layers", "--json"]).output)}
        assert rows["foci"]["distribution"] == "brainpainter-layer-foci"
        assert {"cmap", "vmin", "vmax", "radius", "color", "label"} <= set(rows["foci"]["options"])
        assert rows["foci"]["given_as"] == ["--layer foci:FILE"] and rows["foci"]["files"] == [".foci.csv"]
        assert {"regions", "map", "tracts", "connectome", "contour", "outline"} <= set(rows)
        from brainpainter.layers.readers import identify

        assert identify("peaks.foci.csv").name == "foci-csv"


@pytest.mark.render
@pytest.mark.integration
def test_a_focus_at_mni_left_m1_is_drawn_in_the_left_half_of_a_dorsal_view(foci_site, peaks, tmp_path):
    with installed(foci_site):
        result = CliRunner().invoke(cli, [
            "render", "--layer", f"foci:{peaks}", "--views", "dorsal", "--size", "320x240", "--shading",
            "flat", "--quality", "fast", "--out", str(tmp_path / "out"), "-q"])
        assert result.exit_code == 0, result.output
        (png,) = (tmp_path / "out").glob("*.png")
        img = np.asarray(Image.open(png))
        manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    focus = _near(img, MAGENTA)
    rows, cols = np.nonzero(focus)
    assert focus.sum() > 30, "the focus is drawn"
    assert cols.max() < img.shape[1] / 2, "x = -40 (left) is in the image's left half from above"
    assert rows.mean() < img.shape[0] * 0.6  # y = -20: a little behind the middle, z = 50 near the top
    assert manifest["foci"]["n_foci"] == 1 and manifest["foci"]["foci"][0]["mni"] == [-40.0, -20.0, 50.0]


@pytest.mark.render
@pytest.mark.integration
def test_a_scene_adds_foci_with_their_own_scale_over_a_region_table(foci_site, tmp_path):
    import brainpainter

    path = tmp_path / "peaks.csv"
    path.write_text("x,y,z,value\n-40,-20,50,1\n40,-20,50,3\n")
    with installed(foci_site):
        scene = brainpainter.Scene(atlas="dk", width=320, height=240, shading="flat", quality="fast")
        scene.add({"Left-insula": 1.0}, cmap="Greys").add(path, kind="foci", cmap="magma", vmin=0, vmax=4)
        result = scene.render(views="dorsal", progress=False)
        with pytest.raises(brainpainter.BrainPainterError, match="'size'"):
            scene.add(path, kind="foci", size=3)
    (img,) = result.images.values()
    foci = next(layer for layer in result.layers if layer.kind == "foci")
    assert foci.label == "peaks.csv" and [layer.kind for layer in result.layers] == ["regions", "foci"]
    low, high = foci.scale(np.array([1.0]))[0], foci.scale(np.array([3.0]))[0]
    left, right = _near(img, tuple(low), 30), _near(img, tuple(high), 30)
    assert left.sum() > 30 and right.sum() > 30
    assert np.nonzero(left)[1].mean() < img.shape[1] / 2 < np.nonzero(right)[1].mean()


def test_bad_layer_options_are_one_line_errors(foci_site, peaks, tmp_path):
    with installed(foci_site):
        for args, said in [(["--layer", "foci"], "KIND:FILE"), (["--layer", "dots:x.csv"], "foci"),
                           (["--layer", f"foci:{peaks}", "--layer-opt", "foci.size=3"], "radius"),
                           ([str(TABLE), "--layer-opt", "foci.cmap=magma"], "no --layer foci"),
                           (["--layer", "map:x.mgh"], "--lh")]:
            code, out, err = invoke(["render", *args, "--out", str(tmp_path / "o"), "-q"])
            assert code == 2 and said in err and len(err.strip().splitlines()) == 1, (args, err)
            assert "Traceback" not in out + err and not (tmp_path / "o").exists()


@pytest.mark.render
@pytest.mark.integration
def test_a_movie_over_a_region_table_draws_the_foci_in_their_colours(foci_site, peaks, tmp_path):
    """A movie's frames are coloured in the movie module, not by Run.item: the drawn layers' colours too."""
    with installed(foci_site):
        result = CliRunner().invoke(cli, [
            "movie", str(TABLE), "--rows", "stage-1,stage-2", "--frames-per-step", "4", "--views", "dorsal",
            "--layer", f"foci:{peaks}", "--size", "320x240", "--shading", "flat", "--quality", "fast",
            "-o", str(tmp_path / "m.gif"), "-q"])
        assert result.exit_code == 0, result.output
    with Image.open(tmp_path / "m.gif") as gif:
        frames = []
        for k in range(gif.n_frames):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB")))
    assert all(_near(frame, MAGENTA).sum() > 20 for frame in frames)


def test_check_reports_a_plugin_layer_file_as_render_would_read_it(foci_site, tmp_path):
    peaks = tmp_path / "peaks.foci.csv"
    peaks.write_text("x,y,z,name,value\n-40,-20,50,left M1,2.5\n40,-20,50,right M1,4\n")
    with installed(foci_site):
        code, out, err = invoke(["check", str(peaks)])
        assert code == 0, err
        assert "a foci file" in out and "n_foci  2" in out and f"--layer foci:{peaks}" in out, out
        report = json.loads(CliRunner().invoke(cli, ["check", str(peaks), "--json"]).output)
        assert report["kind"] == "foci" and report["summary"]["foci"][1]["mni"] == [40.0, -20.0, 50.0]
        assert report["scale"].endswith("2.5 .. 4")  # the foci's own scale, over their values
        (tmp_path / "bad.foci.csv").write_text("x,y,name\n1,2,a\n")
        code, out, err = invoke(["check", str(tmp_path / "bad.foci.csv")])
        assert code == 2 and "Traceback" not in out + err and len(err.strip().splitlines()) == 1, err


def test_an_export_holds_the_foci_in_their_colours(foci_site, peaks, tmp_path):
    import trimesh

    with installed(foci_site):
        result = CliRunner().invoke(cli, ["export", str(TABLE), "--row", "stage-3",
                                          "--layer", f"foci:{peaks}",
                                          "-o", str(tmp_path / "b.glb")])
        assert result.exit_code == 0, result.output
    scene = trimesh.load(tmp_path / "b.glb", file_type="glb")
    foci = scene.geometry["foci-lh"]  # x = -40: the left hemisphere's part
    rgb = np.asarray(foci.visual.vertex_colors)[:, :3] / 255  # per vertex; magenta is 1, 0, 1 linear or not
    assert np.abs(rgb - MAGENTA).max() < 0.03 and foci.vertices[:, 0].mean() < 0
    assert "Left-precentral" in scene.geometry  # over the table's regions


@pytest.mark.render
def test_a_map_under_foci_reads_true_to_its_bar(foci_site, peaks):
    """A plugin layer over a map leaves the map opaque, in its bar's colours (before: the map was drawn
    as glass, pale, as a map under a connectome was before issue 44)."""
    import brainpainter

    value = np.full(10242, 2.0, np.float32)  # fsaverage5: the middle of a 0-4 viridis bar everywhere
    with installed(foci_site):
        result = brainpainter.render({"lh": value, "rh": value}, "dk", layer=[f"foci:{peaks}"], vmin=0,
                                     vmax=4, cmap="viridis", views="lateral-left", width=320, height=240,
                                     shading="flat", quality="fast", progress=False)
    (img,) = result.images.values()
    want = np.round(np.asarray(result.scale(np.array([2.0]))[0][:3]) * 255)
    brain = img[..., 3] > 0 if img.shape[-1] == 4 else np.ones(img.shape[:2], bool)
    brain &= np.abs(img[..., :3].astype(int) - 255).max(axis=-1) > 10  # not the white background
    assert brain.sum() > 5000
    on_bar = (np.abs(img[..., :3].astype(int) - want).max(axis=-1) <= 10) & brain
    assert on_bar.sum() > 0.6 * brain.sum(), (on_bar.sum(), brain.sum())  # the cortex in the bar's colour
