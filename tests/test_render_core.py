"""The render pipeline with a stand-in renderer: naming, manifest, metadata, errors.

The real Blender renderer is tested in test_renderer_blender.py; here a tiny
numpy renderer paints each image with the colour of ``Left-insula`` so that the
core's work (reading, colour mapping, files, manifest) is checked quickly.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.painter import Painter, resolve_hidden
from brainpainter.rendering.run import render
from brainpainter.testing import StandInRenderer, stand_in

#: Paints each image in the colour of Left-insula.
Solid = StandInRenderer.with_(layout="solid", regions=("Left-insula",))


@pytest.fixture
def solid():
    with stand_in("solid", Solid) as registered:
        yield registered


def csv(tmp_path, text):
    p = tmp_path / "in.csv"
    p.write_text(text)
    return p


def test_one_png_per_row_and_view_with_manifest(tmp_path, solid, tiny):
    data = csv(tmp_path, "Image-name-unique,Left-insula,Right-insula\nA,1.2,0\nB,3,1\n")
    out = tmp_path / "out"
    result = render(data, "dk", out=out, template=str(tiny), renderer=solid, width=40, height=30,
                    views="lateral-left,medial-left,subcortical", progress=False)
    names = sorted(p.name for p in out.iterdir())
    views = ("lateral-left", "medial-left", "subcortical")
    assert names == sorted([f"{i}_{v}.png" for i in "AB" for v in views] + ["manifest.json"])
    assert Solid.scenes == 1  # scene loaded once for all 6 images
    manifest = json.loads((out / "manifest.json").read_text())
    pairs = [(f["image"], f["view"]) for f in manifest["files"]]
    assert pairs[:2] == [("A", "lateral-left"), ("A", "medial-left")]
    assert manifest["settings"]["scale"]["vmax"] == 3.0 and manifest["input"]["n_regions_matched"] == 2
    img = Image.open(out / "A_lateral-left.png")
    assert img.size == (40, 30)
    # 1.2 on white, yellow, orange, red = 80% yellow + 20% orange
    assert tuple(np.asarray(img)[0, 0, :3]) == (255, round(255 * (0.8 + 0.2 * 165 / 255)), 0)
    settings = json.loads(img.text["brainpainter:settings"])
    assert settings["atlas"] == "dk" and img.text["Software"].startswith("brainpainter ")
    assert len(result.files) == 6


def test_in_memory_render_returns_arrays(solid, tiny):
    result = render({"Left-insula": [0.0]}, "dk", template=str(tiny), renderer=solid, width=16,
                    height=16, views=["lateral-left"], progress=False)
    assert list(result.images) == [("1", "lateral-left")]
    assert result.images[("1", "lateral-left")].shape == (16, 16, 4)


def test_image_names_are_sanitised(tmp_path, solid, tiny):
    data = csv(tmp_path, "Image-name-unique,Left-insula\n../../etc/passwd,1\n")
    out = tmp_path / "out"
    render(data, "dk", out=out, template=str(tiny), renderer=solid, width=16, height=16,
           views="lateral-left", progress=False)
    assert sorted(p.name for p in out.iterdir()) == ["etc_passwd_lateral-left.png", "manifest.json"]
    assert not (tmp_path / "etc").exists()


def test_absent_and_nan_regions_get_their_colours(solid, tiny):
    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.scene import RenderSettings
    from brainpainter.rendering.views import get_view

    painter = Painter("dk", str(tiny), renderer=solid, settings=RenderSettings(width=16, height=16))
    scale = make_scale(nan_color="#000080", missing_color="#008000")
    nan_img = painter.paint({"Left-insula": float("nan")}, get_view("lateral-left"), scale)
    absent_img = painter.paint({}, get_view("lateral-left"), scale)
    assert tuple(nan_img[0, 0, :3]) == (0, 0, 128)
    assert tuple(absent_img[0, 0, :3]) == (0, 128, 0)


def test_hide_groups_and_names():
    from brainpainter.atlas.registry import get_atlas

    dk = get_atlas("dk")
    assert resolve_hidden(["cerebellum"], dk) == {
        "Left-Cerebellum-Cortex", "Right-Cerebellum-Cortex",
        "Left-Cerebellum-White-Matter", "Right-Cerebellum-White-Matter"}
    assert resolve_hidden(["hippocampus", "Brain-Stem"], dk) == {
        "Left-Hippocampus", "Right-Hippocampus", "Brain-Stem"}
    with pytest.raises(BrainPainterError, match="Did you mean 'cerebellum'"):
        resolve_hidden(["cerebelum"], dk)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"views": "sideways"}, "view must be one of"),
        ({"width": 0}, "width must be between"),
        ({"glass_opacity": 2.0}, "glass opacity"),
        ({"surface": "smooth"}, "surface must be one of"),
        ({"renderer": "povray"}, "'renderer' must be one of"),
    ],
)
def test_bad_options_fail_before_writing(tmp_path, solid, tiny, kwargs, message):
    data = csv(tmp_path, "Image-name-unique,Left-insula\nA,1\n")
    out = tmp_path / "out"
    with pytest.raises(BrainPainterError, match=message):
        render(data, "dk", out=out, template=str(tiny), progress=False, **{"renderer": solid, **kwargs})
    assert not out.exists()


def test_unwritable_output_folder(tmp_path, solid, tiny):
    data = csv(tmp_path, "Image-name-unique,Left-insula\nA,1\n")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(BrainPainterError, match="is not a folder"):
        render(data, "dk", out=blocker, template=str(tiny), renderer=solid, progress=False)
    with pytest.raises(BrainPainterError, match="is a file, not a folder"):
        render(data, "dk", out=blocker / "sub", template=str(tiny), renderer=solid, progress=False)


def test_written_files_get_the_usual_permissions(tmp_path, solid, tiny):
    import os

    data = csv(tmp_path, "Image-name-unique,Left-insula\nA,1\n")
    out = tmp_path / "out"
    render(data, "dk", out=out, template=str(tiny), renderer=solid, width=16, height=16,
           views="lateral-left", progress=False)
    mask = os.umask(0)
    os.umask(mask)
    for path in out.iterdir():
        assert path.stat().st_mode & 0o777 == 0o666 & ~mask, path.name


def test_png_writer_writes_in_order_and_reraises(tmp_path):
    from brainpainter.io.output import PngWriter

    img = np.zeros((4, 4, 4), np.uint8)
    with PngWriter(max_pending=1) as writer:
        for k in range(5):
            writer.submit(tmp_path / f"{k}.png", img)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{k}.png" for k in range(5)]
    with pytest.raises(BrainPainterError, match="cannot write"), PngWriter() as writer:
        writer.submit(tmp_path / "missing-folder" / "x.png", img)
    assert not (tmp_path / "missing-folder").exists()
