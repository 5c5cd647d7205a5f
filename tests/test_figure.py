"""Figures: layout, colour bar, swatches, formats, errors.

A stand-in renderer draws a rectangle "brain" in stripes of region colours on
the background, so cropping and colours are easy to check. One test renders
with the real Blender renderer (marked ``render``).
"""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from brainpainter.errors import BrainPainterError
from brainpainter.media.colorbar import bar_colors
from brainpainter.media.figure import common_crop, content_box, make_figure, select_rows
from brainpainter.testing import StandInRenderer, stand_in

REGIONS = ("Left-insula", "Left-precuneus")
W, H = 160, 120
THREE = "Image-name-unique,Left-insula,Left-precuneus\nstage-1,0,0\nstage-2,1.5,1\nstage-3,3,2\n"


#: A 'brain' in the middle of the image: one stripe per region of REGIONS, in its colour.
Stripes = StandInRenderer.with_(layout="band", regions=REGIONS)


@pytest.fixture
def stripes():
    with stand_in("stripes", Stripes) as registered:
        yield registered


def table(tmp_path, text, name="in.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def figure(tmp_path, stripes, tiny, text=THREE, **kw):
    kw = {"views": "lateral-left,medial-left", "template": tiny, "renderer": stripes, "width": W,
          "height": H, "progress": False, **kw}
    return make_figure(table(tmp_path, text), "dk", **kw)


# -- the colour bar ---------------------------------------------------------------------
def test_colour_bar_pixels_run_through_the_gradient_in_order(tmp_path, stripes, tiny):
    out = tmp_path / "fig.png"
    result = figure(tmp_path, stripes, tiny, out=out, grid=True, dpi=200, label="atrophy (SD)")
    png = np.asarray(Image.open(out).convert("RGB"))
    assert png.shape[1] == round(result.figure.get_figwidth() * 200)
    box = result.colorbar_ax.get_window_extent()
    row = png[png.shape[0] - round((box.y0 + box.y1) / 2), round(box.x0) + 3:round(box.x1) - 3]
    assert len(row) > 300  # about 2 inches at 200 dpi
    values, colors = bar_colors(result.scale, 2048)
    dist = np.abs(row[:, None, :].astype(float) / 255 - colors[None]).max(axis=-1)
    assert dist.min(axis=1).max() < 5 / 255  # every pixel is a colour of the gradient
    pos = values[dist.argmin(axis=1)]
    assert np.all(np.diff(pos) >= 0)  # ... in order: white, yellow, orange, red
    assert pos[0] < 0.05 and pos[-1] > 2.95
    # the control colours are on the way, at their ticks
    for v, rgb in zip((0, 1, 2, 3), ((255, 255, 255), (255, 255, 0), (255, 165, 0), (255, 0, 0)),
                      strict=True):
        assert np.abs(row[np.argmin(np.abs(pos - v))].astype(int) - rgb).max() <= 6
    ticks = [t.get_text() for t in result.colorbar_ax.get_xticklabels()]
    assert ticks == ["0", "1", "2", "3"] and result.colorbar_ax.get_xlabel() == "atrophy (SD)"


def test_chosen_ticks_and_a_colour_map(tmp_path, stripes, tiny):
    result = figure(tmp_path, stripes, tiny, cmap="viridis", ticks="0,1,2", label="z-score")
    assert [t.get_text() for t in result.colorbar_ax.get_xticklabels()] == ["0", "1", "2"]
    assert result.scale.vmin == 0 and result.scale.vmax == 3  # over all rows


# -- layout -------------------------------------------------------------------------------
def test_grid_puts_rows_in_columns_and_views_in_rows(tmp_path, stripes, tiny):
    result = figure(tmp_path, stripes, tiny, grid=True, title="Progression")
    pos = {k: ax.get_position() for k, ax in result.image_axes.items()}
    xs = [pos[(s, "lateral-left")].x0 for s in ("stage-1", "stage-2", "stage-3")]
    assert xs == sorted(xs) and len(set(np.round(xs, 6))) == 3
    assert pos[("stage-1", "lateral-left")].y0 > pos[("stage-1", "medial-left")].y0  # views top to bottom
    assert pos[("stage-2", "lateral-left")].y0 == pytest.approx(pos[("stage-1", "lateral-left")].y0)
    texts = [t.get_text() for t in result.figure.texts]
    assert texts[-1] == "Progression" and {"stage-1", "stage-2", "stage-3"} <= set(texts)
    # the colour bar sits under the images and inside the figure
    bar = result.colorbar_ax.get_position()
    assert bar.y1 < min(p.y0 for p in pos.values()) and bar.y0 > 0 and 0 < bar.x0 < bar.x1 < 1
    assert result.figure.get_figwidth() == pytest.approx(7.2)  # two journal columns for 3 columns


def test_per_row_figure_puts_views_side_by_side(tmp_path, stripes, tiny):
    result = figure(tmp_path, stripes, tiny, rows=["stage-3"], views="lateral-left,subcortical")
    a, b = (result.image_axes[("stage-3", v)].get_position() for v in ("lateral-left", "subcortical"))
    assert a.x1 <= b.x0 and a.y0 == pytest.approx(b.y0) and a.height == pytest.approx(b.height)
    assert result.figure.get_figwidth() == pytest.approx(3.5)  # two images: one journal column
    assert list(result.images) == [("stage-3", "lateral-left"), ("stage-3", "subcortical")]
    # each view is cropped to its brain: the subcortical one is less tall, so it is wider on the page
    assert b.width > a.width


def test_several_rows_stack_with_their_names(tmp_path, stripes, tiny):
    result = figure(tmp_path, stripes, tiny, rows="stage-1,stage-3", view_labels=True)
    pos = {k: ax.get_position() for k, ax in result.image_axes.items()}
    assert pos[("stage-1", "lateral-left")].y0 > pos[("stage-3", "lateral-left")].y0
    texts = {t.get_text() for t in result.figure.texts}
    assert {"stage-1", "stage-3", "lateral left", "medial left"} <= texts


def test_renders_are_cropped_to_the_brain_over_all_rows():
    img = np.full((100, 100, 4), 255, np.uint8)
    a, b = img.copy(), img.copy()
    a[20:40, 30:50, :3] = 0
    b[50:60, 10:20, :3] = 0
    assert content_box(a, "white") == (20, 40, 30, 50)
    rows, cols = common_crop([a, b], "white", pad=0.0)
    assert (rows.start, rows.stop, cols.start, cols.stop) == (20, 60, 10, 50)
    transparent = np.zeros((10, 10, 4), np.uint8)
    transparent[2:4, 3:5, 3] = 255
    assert content_box(transparent, None) == (2, 4, 3, 5)


def test_select_rows_by_name_or_position():
    images = ("stage-1", "stage-2", "stage-3")
    assert select_rows(images, None) == [0, 1, 2]
    assert select_rows(images, "stage-3, STAGE-1") == [2, 0]
    assert select_rows(images, [1, -1]) == [1, 2]
    with pytest.raises(BrainPainterError, match="Did you mean 'stage-2'"):
        select_rows(images, ["stage-22"])


# -- swatches ------------------------------------------------------------------------------
def legend_texts(result):
    legend = result.colorbar_ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def test_swatches_only_when_their_colours_are_drawn(tmp_path, stripes, tiny):
    assert legend_texts(figure(tmp_path, stripes, tiny)) == ["not measured"]  # many regions absent
    names = _lh_names()
    full = ("Image-name-unique," + ",".join(f"Left-{n}" for n in names) + "\n"
            + "".join(f"{im}," + ",".join(["1"] * len(names)) + "\n" for im in "AB"))
    assert legend_texts(figure(tmp_path, stripes, tiny, text=full, views="lateral-left")) == []
    # NaN in a region the tiny template draws (its cortex has 4 labels; a NaN in one it does not draw
    # needs no swatch: media/drawn.py decides from the scene's parts what is drawn)
    at = names.index("insula")
    with_nan = full.replace("\nA," + "1," * at, "\nA," + "1," * at + "X", 1).replace("X1", "")
    assert legend_texts(figure(tmp_path, stripes, tiny, text=full.replace("\nA,1,", "\nA,,"),
                               views="lateral-left")) == []
    assert legend_texts(figure(tmp_path, stripes, tiny, text=with_nan, views="lateral-left")) == ["no data"]
    # the NaN is in row A: a figure of row B alone needs no swatch
    assert legend_texts(figure(tmp_path, stripes, tiny, text=with_nan, views="lateral-left", rows="B")) == []
    # right-hemisphere regions are absent, but a left view does not draw them; a right view does
    assert legend_texts(figure(tmp_path, stripes, tiny, text=full, views="lateral-right")) == ["not measured"]


def _lh_names():
    from brainpainter.atlas.registry import get_atlas

    return [r.name for r in get_atlas("dk").cortical("lh")]


# -- formats -----------------------------------------------------------------------------------
def test_pdf_and_svg_embed_the_renders_with_text_as_text(tmp_path, stripes, tiny):
    pdf = figure(tmp_path, stripes, tiny, out=tmp_path / "f.pdf", grid=True).path
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF")
    widths = [int(w) for w in re.findall(rb"/Subtype /Image.*?/Width (\d+)", data, re.S)]
    # 6 renders at full resolution (cropped to the brain, 126 of 160 px), and the colour bar
    assert sorted(widths)[:6] == [126] * 6 and len(widths) == 7, widths
    assert b"/FontFile2" in data  # TrueType fonts, editable text
    svg = figure(tmp_path, stripes, tiny, out=tmp_path / "f.svg", grid=True).path.read_text()
    assert svg.count("<image") >= 6 and ">stage-2<" in svg
    tif = figure(tmp_path, stripes, tiny, out=tmp_path / "f.tiff", dpi=100).path
    with Image.open(tif) as im:
        assert im.format == "TIFF" and round(im.info["dpi"][0]) == 100


def test_transparent_png(tmp_path, stripes, tiny):
    out = figure(tmp_path, stripes, tiny, out=tmp_path / "t.png", background=None, dpi=72).path
    with Image.open(out) as im:
        rgba = np.asarray(im.convert("RGBA"))
    assert rgba[0, 0, 3] == 0 and rgba[..., 3].max() == 255


# -- CLI and errors ----------------------------------------------------------------------------
def test_cli_figure_with_stand_in_renderer(tmp_path, stripes, tiny):
    from brainpainter.cli.main import cli

    data = table(tmp_path, THREE)
    out = tmp_path / "fig" / "grid.png"
    result = CliRunner().invoke(cli, [
        "figure", str(data), "--atlas", "dk", "--out", str(out), "--grid", "--rows", "stage-1,stage-3",
        "--views", "lateral-left", "--size", f"{W}x{H}", "--template", str(tiny), "--renderer", stripes,
        "--label", "z-score", "--title", "T", "--dpi", "150", "-q"])
    assert result.exit_code == 0, result.output
    assert "2 row(s) x 1 view(s)" in result.output and "at 150 dpi" in result.output
    assert out.is_file() and sorted(p.name for p in out.parent.iterdir()) == ["grid.png"]


def test_cli_figure_warns_of_a_column_it_did_not_draw(tmp_path, stripes, tiny):
    """A misspelt region column: the figure says so, as render does (it drew the region in the missing
    colour without a word)."""
    from brainpainter.cli.main import cli

    data = table(tmp_path, "Image-name-unique,Left-insula,Left-precuneus,Left-insular\nA,1,2,3\n")
    result = CliRunner().invoke(cli, [
        "figure", str(data), "--atlas", "dk", "--out", str(tmp_path / "f.png"), "--views", "lateral-left",
        "--size", f"{W}x{H}", "--template", str(tiny), "--renderer", stripes, "-q"])
    assert result.exit_code == 0, result.output
    assert ("warning: 1 name(s) match no dk region and were not drawn: 'Left-insular' (did you mean "
            "'Left-insula'?)") in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--out", "{d}/f.gif"], "must be a file name ending in .png, .pdf, .svg"),
        (["--out", "{d}/f.png", "--rows", "stage-9"], "'stage-9' is not an image name"),
        (["--out", "{d}/f.png", "--ticks", "0,9"], "tick 9 lies outside the colour scale"),
        (["--out", "{d}/f.png", "--dpi", "5"], "dpi must be between 50 and 1200"),
        (["--out", "{d}/blocker/f.png"], "is a file, not a folder"),
        (["--out", "{d}"], "must be a file name ending in"),
    ],
)
def test_bad_options_fail_with_one_line_and_no_file(tmp_path, args, message):
    data = table(tmp_path, THREE)
    d = tmp_path / "out"
    d.mkdir()
    (d / "blocker").write_text("a file")
    proc = subprocess.run([sys.executable, "-m", "brainpainter", "figure", str(data), "--atlas", "dk",
                           *[a.format(d=d) for a in args]], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert sorted(p.name for p in d.iterdir()) == ["blocker"]


# -- the real renderer -----------------------------------------------------------------------
@pytest.mark.render
def test_grid_figure_with_blender_on_the_bundled_template(tmp_path):
    from conftest import EXAMPLES

    out = tmp_path / "grid.png"
    result = make_figure(EXAMPLES / "brainpainter_dk.csv", "dk", out=out, grid=True,
                         rows="stage-1,stage-4", views="lateral-left,subcortical", width=200, height=150,
                         quality="fast", label="atrophy", dpi=100, progress=False)
    png = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert png.shape[1] == round(result.figure.get_figwidth() * 100)
    h = png.shape[0]
    # every panel shows a brain (not background), and stage-4 is redder than stage-1; stage-1 is
    # near-white on white (0 = white in the gradient, drawn without darkening), so the bar is low

    redness = {}
    for key, ax in result.image_axes.items():
        b = ax.get_window_extent()
        panel = png[h - round(b.y1):h - round(b.y0), round(b.x0):round(b.x1)]
        assert (np.abs(panel - 255).max(axis=-1) > 12).mean() > 0.15, key
        redness[key] = (panel[..., 0] - panel[..., 2]).clip(0).mean()
    assert len(redness) == 4
    assert redness[("stage-4", "lateral-left")] > redness[("stage-1", "lateral-left")]
    assert legend_texts(result) == ["not measured"]  # the example has no ventricle columns
