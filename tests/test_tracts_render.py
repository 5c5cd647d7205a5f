"""Tracts drawn by the Blender renderer: colours at the right place in the right view (pixels)."""

from __future__ import annotations

import os
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_tracts import bundle, write

from brainpainter.rendering.settings import RenderSettings
from brainpainter.rendering.tract_parts import TractLayer
from brainpainter.rendering.views import get_view
from brainpainter.tracts.model import TractSpec

pytestmark = pytest.mark.render

RED, BLUE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)


def _mask(img: np.ndarray, rgb, tol: float = 12) -> np.ndarray:
    return np.abs(img[..., :3].astype(float) - np.round(np.asarray(rgb) * 255)).max(axis=-1) <= tol


@pytest.fixture(scope="module")
def bundles(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bundles")
    write(folder / "AF_L.trk", bundle(-30.0, n=40, z=30.0, length=60.0))
    write(folder / "CST_R.tck", bundle(30.0, n=40, seed=1, z=30.0, length=60.0))
    return folder


def _painter(tiny, bundles, nodes=(), **settings):
    from brainpainter.rendering.painter import Painter

    s = {"width": 320, "height": 240, "shading": "flat", "quality": "fast", "glass_opacity": 0.0,
         "background": (1.0, 1.0, 1.0), **settings}
    return Painter("dk", str(tiny), settings=RenderSettings(**s),
                   layers=(TractLayer(TractSpec((str(bundles),), space="template"), nodes),))


def test_a_red_bundle_is_drawn_red_on_its_side_seen_from_above(tiny, bundles):
    with _painter(tiny, bundles, (("AF_left", 1), ("CST_right", 1))) as p:
        img = p.paint_colors({"tract:AF_left": RED, "tract:CST_right": BLUE}, get_view("subcortical-dorsal"))
    red, blue = _mask(img, RED), _mask(img, BLUE)
    # lines anti-aliased at output resolution: the fringe pixels are not the exact colour
    assert red.sum() > 200 and blue.sum() > 200
    # from above: the image's right is the subject's right
    assert np.nonzero(red)[1].mean() < img.shape[1] / 2 < np.nonzero(blue)[1].mean()
    # flat shading: the median colour of the bundle's pixels is its colour
    near_red = img[np.abs(img[..., :3].astype(float) - [255, 0, 0]).max(-1) < 80][:, :3]
    assert np.abs(np.median(near_red, axis=0) - [255, 0, 0]).max() <= 12


def test_an_along_tract_profile_runs_from_the_first_colour_to_the_last(tiny, bundles, tmp_path):
    from PIL import Image

    from brainpainter.color.scale import make_scale
    from brainpainter.layers.tracts import tract_colors

    scale = make_scale(vmin=0, vmax=3, cmap="viridis")
    values = {f"tract:AF_left:{k}": 3.0 * k / 9 for k in range(10)}
    with _painter(tiny, bundles, (("AF_left", 10),)) as p:
        img = p.paint_colors(tract_colors(values, scale), get_view("subcortical-dorsal"))
    first, last = (np.asarray(scale(np.array([v]))[0][:3]) * 255 for v in (0.0, 3.0))
    Image.fromarray(img).save(tmp_path / "profile.png")
    rgb = img[..., :3].astype(float)
    tract = (np.ptp(rgb, axis=-1) > 40) & (np.arange(img.shape[1]) < img.shape[1] / 2)[None, :]
    rows = np.nonzero(tract)[0]
    assert len(rows) > 300
    # the bundle runs posterior -> anterior (oriented; node 0 first); from above, anterior is up
    bottom = np.median(rgb[tract & (np.arange(img.shape[0]) >= np.percentile(rows, 97))[:, None]], axis=0)
    top = np.median(rgb[tract & (np.arange(img.shape[0]) <= np.percentile(rows, 3))[:, None]], axis=0)
    assert np.abs(bottom - first).max() <= 25 and np.abs(top - last).max() <= 25, (bottom, top, first, last)


def test_direction_colours_without_values(tiny, bundles):
    with _painter(tiny, bundles) as p:
        img = p.paint_colors({}, get_view("subcortical-dorsal"))
    # streamlines along y: green (anterior-posterior)
    green = (img[..., 1] > 200) & (img[..., 0] < 120) & (img[..., 2] < 120)
    assert green.sum() > 300


def test_lit_tubes_are_shaded_and_glass_covers_them(tiny, bundles):
    with _painter(tiny, bundles, (("AF_left", 1),), shading="default", quality="default",
                  glass_opacity=0.3) as p:
        img = p.paint_colors({"tract:AF_left": RED}, get_view("subcortical"))
    reddish = (img[..., 0] > img[..., 1] + 40) & (img[..., 0] > img[..., 2] + 40)
    assert reddish.sum() > 200
    assert np.ptp(img[reddish][:, 0].astype(int)) > 30  # lit: not one flat colour


def _tubes_built(painter) -> list[bool]:
    return [p.tubes_built for p in painter.scene.geometry._lazy.built_parts() if p.kind == "tract"]


def test_a_default_render_draws_the_centrelines_and_builds_no_tubes(tiny, bundles):
    with _painter(tiny, bundles, (("AF_left", 1),), shading="default", quality="default") as p:
        img = p.paint_colors({"tract:AF_left": RED}, get_view("subcortical"))
        assert p.load().draws_tubes is False
        assert _tubes_built(p) == [False, False]  # tracts-lh and tracts-rh: lines only
    assert ((img[..., 0] > img[..., 1] + 40) & (img[..., 0] > img[..., 2] + 40)).sum() > 200


def test_cycles_and_the_export_get_the_tubes(tiny, bundles):
    from brainpainter.media.export import tract_meshes

    with _painter(tiny, bundles, (("AF_left", 1),), shading="default", quality="high") as p:
        assert p.load().draws_tubes is True
        assert _tubes_built(p) == [True, True]  # uploaded to Blender's scene
    with _painter(tiny, bundles, (("AF_left", 1),)) as p:
        meshes = tract_meshes(p.scene, {"tract:AF_left": RED})
    assert [len(m.faces) for m in meshes] == [40 * 31 * 3 * 2] * 2  # 40 streamlines of 32 points, 3 sides
    assert np.allclose(meshes[0].vertex_colors, RED)


def test_a_cortex_view_shows_its_hemispheres_bundle_through_the_glass_cortex(tiny, bundles):
    colors = {"tract:AF_left": RED, "tract:CST_right": BLUE}
    nodes = (("AF_left", 1), ("CST_right", 1))
    with _painter(tiny, bundles, nodes, glass_opacity=0.25) as p:  # cortex "auto": glass, as tracts are given
        glass = p.paint_colors(colors, get_view("lateral-left"))
    with _painter(tiny, bundles, nodes, glass_opacity=0.25, cortex="opaque") as p:
        opaque = p.paint_colors(colors, get_view("lateral-left"))
    rgb = glass[..., :3].astype(int)
    reddish = (rgb[..., 0] > rgb[..., 1] + 60) & (rgb[..., 0] > rgb[..., 2] + 60)
    bluish = (rgb[..., 2] > rgb[..., 0] + 60) & (rgb[..., 2] > rgb[..., 1] + 60)
    assert reddish.sum() > 300  # the left bundle, seen through the left cortex
    assert bluish.sum() == 0  # the right hemisphere's bundle is not drawn in a left view
    # the glass cortex is drawn around it (more than the bundle is not background)
    assert ((rgb < 250).any(axis=-1) & ~reddish).sum() > reddish.sum()
    # under an opaque cortex the bundle is hidden
    o = opaque[..., :3].astype(int)
    assert ((o[..., 0] > o[..., 1] + 60) & (o[..., 0] > o[..., 2] + 60)).sum() == 0


@pytest.fixture(scope="module")
def minimal_bundles(tmp_path_factory) -> Path:
    """dipy's minimal bundles (AF_L, CST_R, CC_ForcepsMajor; BSD-3), read from dipy's wheel."""
    dipy = pytest.importorskip("dipy")
    zip_path = Path(dipy.__file__).parent / "data" / "files" / "minimal_bundles.zip"
    if not zip_path.is_file():
        pytest.skip("dipy without minimal_bundles.zip")
    folder = tmp_path_factory.mktemp("dipy")
    with zipfile.ZipFile(zip_path) as z:
        z.extractall(folder)
    return folder / "sub_1"


@pytest.mark.integration
def test_dipy_bundles_in_the_default_template(minimal_bundles, tmp_path):
    from brainpainter.rendering.painter import Painter

    np.savetxt(tmp_path / "place.txt", [[1, 0, 0, 0], [0, 1, 0, -10], [0, 0, 1, 25], [0, 0, 0, 1]])
    spec = TractSpec((str(minimal_bundles),), space="fsaverage", affine=str(tmp_path / "place.txt"))
    settings = RenderSettings(width=400, height=300, shading="flat", quality="fast", glass_opacity=0.0)
    colors = {"tract:AF_left": RED, "tract:CST_right": BLUE, "tract:CC_ForcepsMajor": (0.0, 1.0, 0.0)}
    nodes = (("AF_left", 1), ("CST_right", 1), ("CC_ForcepsMajor", 1))
    hidden = ("ventricles", "cerebellum", "brainstem")  # else they hide bundles behind them
    with Painter("dk", settings=settings, layers=(TractLayer(spec, nodes),), hidden=hidden) as p:
        top = p.paint_colors(colors, get_view("subcortical-dorsal"))
        side = p.paint_colors(colors, get_view("subcortical-left"))
    af, cst = _mask(top, RED, 2), _mask(top, BLUE, 2)
    assert af.sum() > 100 and cst.sum() > 100
    assert np.nonzero(af)[1].mean() < np.nonzero(cst)[1].mean()  # from above: AF_L left of CST_R
    rows, cols = np.nonzero(_mask(side, BLUE, 2))
    assert np.ptp(rows) > np.ptp(cols)  # from the side: CST_R taller than long


@pytest.mark.integration
def test_dipy_bundles_in_lateral_left_through_the_glass_cortex(minimal_bundles, tmp_path):
    from brainpainter.rendering.painter import Painter

    np.savetxt(tmp_path / "place.txt", [[1, 0, 0, 0], [0, 1, 0, -10], [0, 0, 1, 25], [0, 0, 0, 1]])
    spec = TractSpec((str(minimal_bundles),), space="fsaverage", affine=str(tmp_path / "place.txt"))
    settings = RenderSettings(width=400, height=300, shading="flat", quality="fast", glass_opacity=0.0)
    colors = {"tract:AF_left": RED, "tract:CST_right": BLUE, "tract:CC_ForcepsMajor": (0.0, 1.0, 0.0),
              "Left-superiortemporal": (1.0, 1.0, 0.0)}
    nodes = (("AF_left", 1), ("CST_right", 1), ("CC_ForcepsMajor", 1))
    with Painter("dk", settings=settings, layers=(TractLayer(spec, nodes),)) as p:
        img = p.paint_colors(colors, get_view("lateral-left"))  # --cortex auto: glass, as tracts are given
    with Painter("dk", settings=replace(settings, cortex="opaque"), layers=(TractLayer(spec, nodes),)) as p:
        hidden = p.paint_colors(colors, get_view("lateral-left"))
    af, cst, cc = _mask(img, RED, 2), _mask(img, BLUE, 2), _mask(img, (0.0, 1.0, 0.0), 2)
    assert af.sum() > 100 and cc.sum() > 20  # the left arcuate and the forceps major (commissural)
    assert cst.sum() == 0  # the right hemisphere's bundle is not drawn in a left view
    # seen from the left, anterior is on the image's left: the forceps major (occipital) is right of AF
    assert np.nonzero(cc)[1].mean() > np.nonzero(af)[1].mean()
    assert _mask(hidden, RED, 2).sum() == 0 and _mask(hidden, (1.0, 1.0, 0.0), 2).sum() > 500


def test_region_borders_are_drawn_on_the_glass_cortex(tiny, bundles):
    """``--outline`` with a glass cortex: the borders of its near side, as lines over the glass."""
    colors = {"tract:AF_left": RED, "Left-antsup": (1.0, 0.8, 0.0)}
    nodes = (("AF_left", 1), ("CST_right", 1))
    dark = {}
    for width in (0.0, 2.0):
        with _painter(tiny, bundles, nodes, glass_opacity=0.25, outline_width=width) as p:
            img = p.paint_colors(colors, get_view("lateral-left"))[..., :3].astype(int)
        dark[width] = int((img.max(axis=-1) < 60).sum())
    assert dark[0.0] == 0 and dark[2.0] > 100, dark


def test_the_borders_on_the_glass_are_its_near_sides_alone(tiny, bundles):
    """The glass's borders are depth-tested on its near side (drawn into the depth alone): those of
    its far side stay hidden, so they lie where the opaque cortex draws its borders in that view."""
    from scipy.ndimage import binary_dilation

    colors = {"Left-antsup": (1.0, 0.8, 0.0)}
    dark = {}
    for cortex in ("glass", "opaque"):
        with _painter(tiny, bundles, glass_opacity=0.25, outline_width=2.0, cortex=cortex) as p:
            img = p.paint_colors(colors, get_view("dorsal"))[..., :3].astype(int)
        dark[cortex] = img.max(axis=-1) < 60
    assert dark["glass"].sum() > 100
    assert not (dark["glass"] & ~binary_dilation(dark["opaque"])).any()  # far side's: ~400 pixels


def _render_bundle_table(tmp_path, bundles, tiny, table, *more):
    """``render`` of a bundle table (its header after the image column, then its rows) seen from above."""
    from click.testing import CliRunner

    from brainpainter.cli.main import cli

    (tmp_path / "fa.csv").write_text(f"Image-name-unique,{table}\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [
        "render", str(tmp_path / "fa.csv"), "--tracts", str(bundles), "--tracts-space", "template",
        "--template", str(tiny), "--views", "subcortical-dorsal", "--size", "320x240", "--shading", "flat",
        "--glass-opacity", "0", "--vmin", "0", "--vmax", "3", "--gradient", "blue,red",
        "--max-streamlines", "60", "--quality", "fast", *more, "--out", str(out)])
    return result, out


def test_render_command_with_a_bundle_table(tmp_path, bundles, tiny):
    from PIL import Image


    result, out = _render_bundle_table(tmp_path, bundles, tiny, "AF_L,CST_R\nctrl,3,0", "--tract-radius", "1")
    assert result.exit_code == 0, result.output
    img = np.asarray(Image.open(out / "ctrl_subcortical-dorsal.png").convert("RGB"))
    red, blue = _mask(img, RED, 20), _mask(img, BLUE, 20)
    assert red.sum() > 200 and blue.sum() > 200
    assert np.nonzero(red)[1].mean() < np.nonzero(blue)[1].mean()
    # each bundle's median pixel colour is its colour on the scale (3 -> red, 0 -> blue), flat shading
    left = np.arange(img.shape[1]) < img.shape[1] // 2
    for side, rgb in ((left, RED), (~left, BLUE)):
        drawn = (np.ptp(img.astype(int), axis=-1) > 60) & side[None, :]
        assert np.abs(np.median(img[drawn], axis=0) - np.asarray(rgb) * 255).max() <= 12
    assert os.path.exists(out / "manifest.json")
    assert "tracts: 2 bundle(s) (AF_left, CST_right), 60 streamlines drawn" in result.output
    assert "note: AF_left: 30 of 40 streamlines drawn" in result.output


def test_a_region_table_with_tracts_draws_its_cortex_in_its_colours(tmp_path, bundles, tiny):
    """``--cortex auto``: a cortex carrying values is opaque in the cortex views (as glass, at 0.12
    opacity, its colours were a few pale wisps under a colour bar they did not show)."""
    from click.testing import CliRunner
    from PIL import Image

    from brainpainter.cli.main import cli

    (tmp_path / "t.csv").write_text("Left-insula,Left-precuneus,Left-superiorfrontal,AF_L\n3,3,3,0\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [
        "render", str(tmp_path / "t.csv"), "--tracts", str(bundles), "--tracts-space", "template",
        "--template", str(tiny), "--views", "lateral-left", "--size", "160x120", "--shading", "flat",
        "--quality", "fast", "--vmin", "0", "--vmax", "3", "--gradient", "blue,red", "--out", str(out)])
    assert result.exit_code == 0, result.output
    img = np.asarray(Image.open(out / "1_lateral-left.png").convert("RGB"))
    brain = np.ptp(img.astype(int), axis=-1) > 30
    assert brain.sum() > 1000 and _mask(img, RED, 12).sum() > 0.5 * brain.sum()


def test_render_command_with_jobs_2_draws_the_bundles_in_every_view(tmp_path, bundles, tiny):
    from click.testing import CliRunner
    from PIL import Image

    from brainpainter.cli.main import cli

    (tmp_path / "fa.csv").write_text("Image-name-unique,AF_L,CST_R\nctrl,3,0\npat,0,3\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [
        "render", str(tmp_path / "fa.csv"), "--tracts", str(bundles), "--tracts-space", "template",
        "--template", str(tiny), "--views", "lateral-left,subcortical-dorsal", "--size", "240x180",
        "--shading", "flat", "--glass-opacity", "0.2", "--vmin", "0", "--vmax", "3", "--gradient", "blue,red",
        "--quality", "fast", "--tract-radius", "1", "--jobs", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    def tinted(path: Path, channel: int) -> np.ndarray:  # pixels where red (0) or blue (2) dominates
        img = np.asarray(Image.open(path).convert("RGB")).astype(int)
        return (img[..., channel] > img[..., 2 - channel] + 60) & (img[..., channel] > img[..., 1] + 60)

    for image, af in (("ctrl", 0), ("pat", 2)):
        # AF_left through the glass cortex, in its colour on the scale (3: red, 0: blue); CST_right not drawn
        assert tinted(out / f"{image}_lateral-left.png", af).sum() > 100, image
        assert tinted(out / f"{image}_lateral-left.png", 2 - af).sum() == 0, image
        # both bundles from above, through the glass brain
        assert tinted(out / f"{image}_subcortical-dorsal.png", 0).sum() > 100
        assert tinted(out / f"{image}_subcortical-dorsal.png", 2).sum() > 100


def test_a_new_colour_in_the_same_view_recolours_the_kept_lines(tiny, bundles):
    # the renderer draws a view's lines once and colours them for each image (tract_lines)
    view = get_view("subcortical-dorsal")
    with _painter(tiny, bundles, (("AF_left", 1), ("CST_right", 1))) as p:
        first = p.paint_colors({"tract:AF_left": RED, "tract:CST_right": BLUE}, view)
        swapped = p.paint_colors({"tract:AF_left": BLUE, "tract:CST_right": RED}, view)
    assert _mask(first, RED).sum() > 200 and _mask(swapped, RED).sum() > 200
    middle = first.shape[1] / 2
    assert np.nonzero(_mask(first, RED))[1].mean() < middle < np.nonzero(_mask(swapped, RED))[1].mean()
    # the same lines, coloured the other way round
    drawn = [_mask(img, RED) | _mask(img, BLUE) for img in (first, swapped)]
    assert (drawn[0] != drawn[1]).sum() <= 0.01 * drawn[0].sum()


@pytest.mark.parametrize("quality", ["fast", "default"])
def test_a_new_view_draws_the_opaque_parts_once(tiny, bundles, monkeypatch, quality):
    # issue 37 (a movie's orbit: a new view every frame): at output resolution the lines are
    # depth-tested against the image's own depth, not against the opaque parts drawn again
    from brainpainter_blender.gpu_draw import GpuDraw

    calls = []
    draw_opaque = GpuDraw._draw_opaque

    def counted(self, *args, **kwargs):
        calls.append(1)
        return draw_opaque(self, *args, **kwargs)

    monkeypatch.setattr(GpuDraw, "_draw_opaque", counted)
    with _painter(tiny, bundles, (("AF_left", 1),), quality=quality) as p:
        for azimuth in (0.0, 20.0, 40.0):
            view = replace(get_view("subcortical-dorsal"), azimuth=azimuth)
            p.paint_colors({"tract:AF_left": RED}, view)
    assert len(calls) == 3


@pytest.mark.parametrize("z", [-20.0, 20.0])
def test_a_bundle_below_a_structure_is_hidden_by_it_from_above(tiny, tmp_path, z):
    # the tiny template's structures: boxes within |x| <= 25, |y| <= 10, |z| <= 5
    folder = tmp_path / "under"
    folder.mkdir()
    write(folder / "AF_L.trk", bundle(-17.0, n=20, z=z, length=60.0))
    with _painter(tiny, folder, (("AF_left", 1),)) as p:
        img = p.paint_colors({"tract:AF_left": RED}, get_view("subcortical-dorsal"))
    rows = np.nonzero(_mask(img, RED).any(axis=1))[0]
    assert len(rows) > 40
    # the box spans a third of the bundle's length, in the middle of its rows (anterior up)
    middle = (rows.min() + rows.max()) / 2
    through = np.abs(rows - middle) < 0.1 * np.ptp(rows)
    assert through.any() == (z > 0)


def test_an_image_does_not_depend_on_the_views_drawn_before(tiny, bundles):
    # the tracts' output-sized buffers are shared between views (tract_lines): nothing of a view
    # drawn before may show in the next (a stale column at the tracts' box edge did once)
    colours = {"tract:AF_left": RED, "tract:CST_right": BLUE}
    dorsal = get_view("subcortical-dorsal")
    nodes = (("AF_left", 1), ("CST_right", 1))
    with _painter(tiny, bundles, nodes, quality="default") as p:  # tract layers, edge buffers kept
        fresh = p.paint_colors(colours, dorsal)
    with _painter(tiny, bundles, nodes, quality="default") as p:
        for name in ("subcortical", "subcortical-left", "subcortical-ventral"):
            p.paint_colors({"tract:AF_left": BLUE, "tract:CST_right": RED}, get_view(name))
        after = p.paint_colors(colours, dorsal)
    assert np.array_equal(fresh, after)


def test_the_tracts_box_lies_on_whole_output_pixels():
    # a supersampled pass over the box must read only output pixels the output-sized passes wrote
    from types import SimpleNamespace

    from brainpainter.rendering.parts import Centrelines, PartGeometry
    from brainpainter_blender.tract_lines import TractLines

    rng = np.random.default_rng(0)
    points = rng.uniform(-40, 40, (30, 8, 3)).astype(np.float32)
    empty = np.zeros((0, 3), np.float32)
    part = PartGeometry("tracts", "tract", None, empty, empty, np.zeros((0, 3), np.uint32),
                        np.zeros(0, np.int32), np.zeros(0, np.float32), points.reshape(-1, 3),
                        centrelines=Centrelines(points, np.zeros((30, 8), np.int32), 0.37))
    mvp = np.diag([1 / 97.3, 1 / 73.1, 1 / 100.0, 1.0])
    mvp[:2, 3] = (0.013, -0.021)
    width, height = 317, 239
    box = np.asarray(TractLines(width, height)._box([part], SimpleNamespace(mvp=mvp)))
    pixels = (box + 1.0) / 2.0 * np.array([width, height, width, height])
    assert np.allclose(pixels, np.round(pixels), atol=1e-6)
    assert 0 <= pixels[0] < pixels[2] <= width and 0 <= pixels[1] < pixels[3] <= height


def _line_coverage(start, end, radius: float, size: int = 200) -> np.ndarray:
    """Coverage (the tracts' layer's alpha), shape (size, size), row 0 at the bottom, of one
    streamline of 11 points from `start` to `end` (millimetres; 2 pixels a millimetre)."""
    from types import SimpleNamespace

    from brainpainter.rendering.parts import Centrelines, PartGeometry
    from brainpainter_blender import _bpy
    from brainpainter_blender.gpu_context import in_gpu_context
    from brainpainter_blender.gpu_lighting import FLAT
    from brainpainter_blender.tract_lines import TractLines

    t = np.linspace(0.0, 1.0, 11)[:, None]
    points = (np.asarray(start, float) + t * (np.asarray(end, float) - start))[None].astype(np.float32)
    empty = np.zeros((0, 3), np.float32)
    part = PartGeometry("tracts", "tract", None, empty, empty, np.zeros((0, 3), np.uint32),
                        np.zeros(0, np.int32), np.zeros(0, np.float32), points.reshape(-1, 3),
                        centrelines=Centrelines(points, np.zeros((1, 11), np.int32), radius))

    def job() -> np.ndarray:
        import gpu
        from mathutils import Matrix

        mvp = Matrix(np.diag([1 / 50, 1 / 50, 1 / 100, 1.0]).tolist())
        aim = SimpleNamespace(mvp=mvp, back=(0.0, 0.0, 1.0))
        lines = TractLines(size, size)
        layer = lines._draw_layer([part], aim, FLAT, lambda: None, lambda step: None)
        buf = gpu.types.Buffer("FLOAT", size * size * 4)
        with gpu.types.GPUFrameBuffer(color_slots=layer.shade).bind():
            gpu.state.active_framebuffer_get().read_color(0, 0, size, size, 4, 0, "FLOAT", data=buf)
        lines.close()
        return np.array(buf, np.float32).reshape(size, size, 4)[..., 3]

    with _bpy.LOCK:
        return in_gpu_context(job)


@pytest.mark.parametrize("end", [(20.15, 0.15, 0.0), (15.15, 15.15, 0.0)], ids=["horizontal", "diagonal"])
def test_a_line_covers_its_width_times_its_length_to_both_ends(end):
    # a centreline 2 * half_width wide (anti-aliased: its coverage sums to its area), reaching out
    # by half its width plus the fringe at both ends (square caps), at any angle: a GL line is
    # widened along one axis only, so a diagonal one must be drawn wider (tract_lines.raster_width)
    off_centre = np.array([0.3, 0.3, 0.0])  # millimetres: no edge on a pixel's centre
    start, end = off_centre - end, off_centre + end
    half = 2.0  # pixels: a radius of 1 mm at 2 pixels a millimetre
    cov = _line_coverage(start, end, radius=1.0)
    length = np.linalg.norm(end - start) * 2.0
    area = 2.0 * half * (length + 2.0 * (half + 0.5))
    assert abs(cov.sum() - area) < 0.04 * area, (cov.sum(), area)
    # across the middle, the profile is as wide as the line, fully covered at its centre
    direction = (end - start)[:2] / np.linalg.norm(end - start)
    centre = (start + end)[:2] / 2.0 * 2.0 + 100.0  # pixel coordinates (x, y)
    rows, cols = np.mgrid[0:200, 0:200]
    across = (cols + 0.5 - centre[0]) * -direction[1] + (rows + 0.5 - centre[1]) * direction[0]
    along = (cols + 0.5 - centre[0]) * direction[0] + (rows + 0.5 - centre[1]) * direction[1]
    assert cov[(np.abs(across) < 0.5) & (np.abs(along) < length / 2)].min() > 0.99
    assert cov[np.abs(across) > half + 1.5].max() == 0.0
    # both ends covered, the centreline out to its cap; nothing beyond (a wide GL line's ends are
    # cut along its minor axis: slanted by up to 45 degrees, they reach a half width further on one
    # side and fall short on the other)
    for sign in (-1.0, 1.0):
        beyond = sign * along - length / 2
        assert cov[(np.abs(across) < half - 0.5) & (beyond > -2.0) & (beyond < 0.5)].min() > 0.99
        assert cov[(np.abs(across) < 0.5) & (beyond > 0.0) & (beyond < half)].min() > 0.99
        assert cov[sign * along > length / 2 + 2.0 * (half + 0.5) + 0.5].max() == 0.0


MAGMA_ENDS = ((0.001462, 0.000466, 0.013866), (0.987053, 0.991438, 0.749504))  # magma's first and last


def _layers_table(tmp_path: Path) -> Path:
    """Thickness 1.5-4 on the left hemisphere's regions, and bundle FA 0.3 (AF_L) and 0.7 (CST_R)."""
    path = tmp_path / "thick.csv"
    path.write_text("Image-name-unique,lh_insula,lh_precuneus,lh_superiorfrontal,AF_L,CST_R\n"
                    "ctrl,1.5,4,2.75,0.3,0.7\n")
    return path


LAYER_OPTIONS = ["--cmap", "viridis", "--vmin", "1.5", "--vmax", "4", "--tracts-cmap", "magma",
                 "--tracts-vmin", "0.3", "--tracts-vmax", "0.7", "--tracts-label", "FA"]


def test_tracts_with_their_own_scale_span_its_colours_and_the_cortex_keeps_its_own(tmp_path, bundles, tiny):
    import json

    from click.testing import CliRunner
    from matplotlib import colormaps
    from PIL import Image

    from brainpainter.cli.main import cli
    from brainpainter.rendering.run import prepare_run

    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [
        "render", str(_layers_table(tmp_path)), "--tracts", str(bundles), "--tracts-space", "template",
        "--template", str(tiny), "--views", "subcortical-dorsal", "--size", "320x240",
        "--shading", "flat", "--glass-opacity", "0", "--background", "#808080", "--max-streamlines", "60",
        "--quality", "fast", "--tract-radius", "1", *LAYER_OPTIONS, "--out", str(out)])
    assert result.exit_code == 0, result.output
    top = np.asarray(Image.open(out / "ctrl_subcortical-dorsal.png").convert("RGB"))
    left = np.arange(top.shape[1]) < top.shape[1] // 2
    # FA 0.3 (AF, left) is magma's first colour, FA 0.7 (CST, right) its last: not the cortex's viridis
    first, last = (_mask(top, rgb, 20) for rgb in MAGMA_ENDS)
    assert (first & left[None, :]).sum() > 200 and (last & ~left[None, :]).sum() > 200
    # the cortex (glass in a tract render) on its own 1.5-4 scale: the regions' colours of the same run
    run = prepare_run(_layers_table(tmp_path), tracts=[str(bundles)], tracts_space="template",
                      template=str(tiny), cmap="viridis", vmin=1.5, vmax=4, tracts_cmap="magma",
                      tracts_vmin=0.3, tracts_vmax=0.7)
    colors = run.item(0, get_view("lateral-left")).colors
    viridis = colormaps["viridis"]
    for region, value in (("Left-insula", 1.5), ("Left-precuneus", 4.0)):
        assert np.allclose(colors[region], viridis((value - 1.5) / 2.5)[:3], atol=0.01), region
    layers = json.loads((out / "manifest.json").read_text())["settings"]["layers"]
    assert [(la["kind"], la["label"], la["scale"]["name"], la["scale"]["vmin"], la["scale"]["vmax"])
            for la in layers] == [("regions", "thick.csv", "viridis", 1.5, 4.0),
                                  ("tracts", "FA", "magma", 0.3, 0.7)]


def test_a_figure_of_regions_and_tracts_draws_two_labelled_colour_bars(tmp_path, bundles, tiny):
    from matplotlib import colormaps

    from brainpainter.media.figure import make_figure

    result = make_figure(_layers_table(tmp_path), tracts=[str(bundles)], tracts_space="template",
                         template=str(tiny), views="subcortical-dorsal", width=160, height=120,
                         quality="fast", max_streamlines=20, cmap="viridis", vmin=1.5, vmax=4,
                         tracts_cmap="magma", tracts_vmin=0.3, tracts_vmax=0.7, tracts_label="FA",
                         progress=False)
    axes = result.colorbar_axes
    assert [ax.get_xlabel() for ax in axes] == ["thick.csv", "FA"]
    assert axes[0].get_position().x1 < axes[1].get_position().x0  # side by side
    for ax, cmap in zip(axes, ("viridis", "magma"), strict=True):
        bar = np.asarray(ax.get_images()[0].get_array())[..., :3].reshape(-1, 3)
        ends = np.asarray([colormaps[cmap](0.0)[:3], colormaps[cmap](1.0)[:3]])
        assert np.abs(bar[[0, -1]] - ends).max() < 0.02, cmap


def test_tracts_recoloured_through_the_glass_draw_the_glass_once(tiny, bundles, glass_draws):
    """Issue 36: with tract lines between the glass's far and near sides, each side is a layer of
    the view (glass_layers), drawn on its first image; recoloured tracts draw neither again, and the
    pixels are a direct draw's within a level."""
    drawn = glass_draws
    nodes = (("AF_left", 1), ("CST_right", 1))
    view = get_view("lateral-left")
    red, blue = ({"tract:AF_left": c, "tract:CST_right": c} for c in (RED, BLUE))
    kw = {"glass_opacity": 0.25, "quality": "default", "shading": "default"}
    with _painter(tiny, bundles, nodes, **kw) as p, _painter(tiny, bundles, nodes, **kw) as direct:
        first = p.paint_colors(red, view)
        assert drawn == ["FRONT", "BACK"]
        recoloured = p.paint_colors(blue, view)
        assert drawn == ["FRONT", "BACK"], "recoloured tracts drew the glass again"
        assert np.array_equal(p.paint_colors(red, view), first)
        direct.load()._gpu._glass = None
        for colours, img in ((red, first), (blue, recoloured)):
            d = np.abs(img.astype(int) - direct.paint_colors(colours, view).astype(int))
            assert d.max() <= 2 and (d.max(axis=-1) > 0).mean() < 0.01, (d.max(), (d.max(axis=-1) > 0).mean())
    rgb = recoloured[..., :3].astype(int)
    assert ((rgb[..., 2] > rgb[..., 0] + 60) & (rgb[..., 2] > rgb[..., 1] + 60)).sum() > 300  # blue, drawn


def test_a_bundle_without_a_value_beside_valued_ones_is_drawn_in_the_missing_colour(tmp_path, bundles, tiny):
    """Issue 44 item 5: a table naming AF_L only draws CST_R in the tract scale's missing colour (as regions
    without values), not in direction colours beside a white-red bar."""
    from PIL import Image


    result, out = _render_bundle_table(tmp_path, bundles, tiny, "AF_L\nctrl,3", "--missing-color", "#00ff00")
    assert result.exit_code == 0, result.output
    img = np.asarray(Image.open(out / "ctrl_subcortical-dorsal.png").convert("RGB"))
    right = np.arange(img.shape[1]) >= img.shape[1] // 2
    drawn = (np.ptp(img.astype(int), axis=-1) > 60) & right[None, :]  # CST_R: the subject's right
    assert drawn.sum() > 200
    err = np.abs(img[drawn].astype(float) - [0, 255, 0]).max(axis=-1)
    assert np.median(err) <= 10  # lines: their anti-aliased fringes mix with the background
    assert _mask(img, RED, 20)[:, ~right].sum() > 200  # AF_L: its value's colour
