"""brainpainter.Scene (issue 35): layers added one by one, drawn as the command line draws them."""

from __future__ import annotations

import nibabel as nib
import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.media.scene import KINDS, Scene, infer_kind

N5 = 10242


def _mgh(path, values):
    nib.MGHImage(np.asarray(values, np.float32).reshape(-1, 1, 1), np.eye(4)).to_filename(path)
    return path


def test_each_kind_is_inferred_as_the_command_line_reads_it(tmp_path):
    (tmp_path / "bundles").mkdir()
    mask = _mgh(tmp_path / "lh.mask.mgh", np.zeros(N5))
    assert infer_kind(tmp_path / "t.csv") == "regions"
    assert infer_kind({"lh_insula": [1.0]}) == "regions"
    assert infer_kind({"lh": np.zeros(N5), "rh": np.zeros(N5)}) == "map"
    assert infer_kind(mask) == "map"
    assert infer_kind(tmp_path / "bundles") == "tracts"
    assert infer_kind(tmp_path / "AF_L.trk") == "tracts"
    assert infer_kind(tmp_path / "t.csv", values="fa.csv") == "tracts"
    assert infer_kind(mask, outline=True) == "contour"
    assert infer_kind("dk", outline=True) == "outline"
    assert list(KINDS) == ["regions", "map", "tracts", "connectome", "volume-surface", "contour", "outline"]


def test_layers_become_the_command_line_options(tmp_path):
    mask = _mgh(tmp_path / "lh.mask.mgh", np.zeros(N5))
    _mgh(tmp_path / "rh.mask.mgh", np.zeros(N5))
    thickness = _mgh(tmp_path / "lh.thickness.mgh", np.zeros(N5))
    (tmp_path / "bundles").mkdir()
    lines = nib.streamlines.Tractogram([np.zeros((2, 3), np.float32)], affine_to_rasmm=np.eye(4))
    nib.streamlines.save(lines, str(tmp_path / "bundles" / "AF_L.trk"))
    scene = (Scene(atlas="dk", surface="inflated")
             .add(tmp_path / "bundles", values="fa.csv", cmap="magma", vmin=0.3, vmax=0.7, label="FA")
             .add(thickness, cmap="viridis", alpha=0.5, threshold=1.0)
             .add("table.csv", vmin=1.5, vmax=4, label="thickness (mm)")
             .add(mask, outline=True, color="white", levels=[0.05, 0.01])
             .add("dk", outline=True))
    data, options = scene.run_options()
    assert data == "table.csv"  # the region table is INPUT, the map goes beside it as --lh/--rh
    assert options == {
        "surface": "inflated", "regions_vmin": 1.5, "regions_vmax": 4, "regions_label": "thickness (mm)",
        "map_cmap": "viridis", "map_alpha": 0.5, "threshold": 1.0,
        "lh": str(thickness), "tracts": (str(tmp_path / "bundles"),), "tracts_cmap": "magma",
        "tracts_vmin": 0.3, "tracts_vmax": 0.7, "tracts_label": "FA", "tract_values": "fa.csv",
        "contour": mask, "contour_color": "white", "contour_levels": "0.05,0.01", "outline": "dk"}
    alone = Scene().add({"lh": np.zeros(N5)}, cmap="magma")
    assert alone.run_options()[0].keys() == {"lh"}  # a map alone is INPUT
    from types import SimpleNamespace

    surface_image = SimpleNamespace(data=SimpleNamespace(parts={"left": np.zeros(N5), "right": np.ones(N5)}))
    _, under = Scene().add("table.csv").add(surface_image, kind="map").run_options()  # under a table
    assert under.keys() == {"lh", "rh"} and under["rh"].sum() == N5


@pytest.mark.parametrize(("add", "message"), [
    (lambda s: s.add({"lh": np.zeros(N5)}).add({"rh": np.zeros(N5)}),
     r"^the scene has a map layer already \(dict\); a composition draws one of each kind \(regions, map, "
     r"tracts, connectome, volume-surface, contour, outline\), so dict cannot be stacked on it\. "
     r"Draw it in a second Scene\.$"),
    (lambda s: s.add({"lh_insula": [1.0]}, alpha=0.5),
     r"^a regions layer takes \[.*'label'\]; 'alpha' was given\. Leave it out"),
    (lambda s: s.add({"lh_insula": [1.0]}, kind="nodes"), r"kind must be one of .*'nodes' was given"),
    (lambda s: s.add({"lh_insula": [1.0]}, cmap="viridiss"), r"colour map 'viridiss' is not a matplotlib"),
    (lambda s: s.render(), r"^the scene has no layers: add one"),
])
def test_what_a_scene_cannot_draw_is_one_line(add, message):
    with pytest.raises(BrainPainterError, match=message):
        add(Scene())


def test_a_scene_refuses_an_option_that_is_none():
    with pytest.raises(TypeError, match="Scene\\(\\) got an unexpected keyword argument 'colour'"):
        Scene(colour="red")


@pytest.mark.render
def test_a_scene_renders_the_pixels_of_the_command_line(tmp_path):
    """Bar (issue 35): ``Scene`` renders the same pixels as the CLI for the same layers (regions, a map
    over them at alpha 0.5 on its own scale, a contour of a mask)."""
    from click.testing import CliRunner
    from PIL import Image

    from brainpainter.cli.main import cli

    table = tmp_path / "regions.csv"
    table.write_text("Image-name-unique,lh_precentral,lh_superiorfrontal,lh_insula\nctrl,1.5,3,4\n")
    patch = _mgh(tmp_path / "lh.patch.mgh", np.where(np.arange(N5) < N5 // 2, 1.0, 0.0))
    mask = _mgh(tmp_path / "lh.mask.mgh", (np.arange(N5) % 5 == 0))
    image = ["--views", "lateral-left", "--size", "240x180", "--shading", "flat", "--quality", "fast"]
    result = CliRunner().invoke(cli, [
        "render", str(table), "--lh", str(patch), "--cmap", "viridis", "--vmin", "1.5", "--vmax", "4",
        "--map-cmap", "magma", "--map-alpha", "0.5", "--threshold", "0.5", "--contour", str(mask),
        "--outline-color", "white", *image, "--out", str(tmp_path / "cli")])
    assert result.exit_code == 0, result.output
    scene = (Scene(width=240, height=180, shading="flat", quality="fast")
             .add(str(mask), outline=True, color="white")
             .add(str(patch), cmap="magma", alpha=0.5, threshold=0.5)
             .add(table, cmap="viridis", vmin=1.5, vmax=4))
    made = scene.render(views="lateral-left", out=tmp_path / "api", progress=False)
    cli_png = np.asarray(Image.open(tmp_path / "cli" / "ctrl_lateral-left.png"))
    api_png = np.asarray(Image.open(made.files[0]))
    assert made.files[0].name == "ctrl_lateral-left.png" and np.array_equal(cli_png, api_png)
    assert len(np.unique(api_png.reshape(-1, 4), axis=0)) > 50  # drawn: regions, map and lines
    assert [la.kind for la in made.layers] == ["regions", "map"]


def test_a_contour_file_is_read_and_closed(tmp_path):
    """``--contour lh.mask.mgh`` (one file): asking whether it is a volume left the file open (nib.load)."""
    import gc

    from brainpainter.maps.volume import is_volume

    mask = _mgh(tmp_path / "lh.mask.mgh", np.zeros(N5))
    volume = tmp_path / "v.mgh"
    nib.MGHImage(np.zeros((8, 8, 8), np.float32), np.eye(4)).to_filename(volume)
    assert not is_volume(mask) and is_volume(volume)
    gc.collect()  # an unclosed file: a ResourceWarning, an error under pytest
