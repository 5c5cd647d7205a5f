"""A figure's cheaper steps draw the same pixels (issue 45's figure cost): the PNG written from the
canvas by fpng, the renders' crop, the colour bar's fit."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from brainpainter.color.rgb import to_rgb
from brainpainter.color.scale import ColourScale, cmap_colors
from brainpainter.media.colorbar import colorbar_figure, draw_colorbar, new_figure
from brainpainter.media.drawn import content_box
from brainpainter.media.figure import figure_bytes


def _figure(background):
    fig = new_figure((3.0, 1.5), 300.0, background)
    rng = np.random.default_rng(3)
    ax = fig.add_axes((0.02, 0.35, 0.45, 0.6))
    ax.imshow(rng.integers(0, 255, (90, 120, 4), dtype=np.uint8), interpolation="antialiased")
    ax.set_axis_off()
    bar = fig.add_axes((0.55, 0.5, 0.4, 0.1))
    draw_colorbar(bar, ColourScale(cmap_colors("viridis"), 2.3, 5.0), label="z-score")
    fig.text(0.5, 0.05, "L  z=50", fontsize=8)
    return fig


@pytest.mark.parametrize("transparent", [False, True])
def test_figure_png_has_matplotlibs_pixels_and_print_size(tmp_path, transparent):
    fig = _figure(None if transparent else "white")
    data = figure_bytes(fig, tmp_path / "fig.png", 300.0, transparent=transparent)
    assert b"fdEC" in data[:200]  # fpng's own chunk: fpng wrote it, not matplotlib's zlib
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=300.0, transparent=transparent,
                facecolor="none" if transparent else fig.get_facecolor())
    ours, theirs = Image.open(io.BytesIO(data)), Image.open(buf)
    assert ours.mode == theirs.mode == "RGBA" and ours.size == theirs.size == (900, 450)
    assert np.array_equal(np.asarray(ours), np.asarray(theirs))
    assert ours.info["dpi"] == pytest.approx((300.0, 300.0), abs=0.01)
    assert ours.info["Software"].startswith("brainpainter ")


def _content_box_int16(image, background, tol=6):
    """content_box as it was written first (int16 differences): the reference."""
    alpha = image[..., 3] > 0
    if background is None:
        mask = alpha
    else:
        bg = np.round(np.array(to_rgb(background)) * 255).astype(np.int16)
        mask = alpha & (np.abs(image[..., :3].astype(np.int16) - bg).max(axis=-1) > tol)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return 0, 0, 0, 0
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


@pytest.mark.parametrize("background", ["white", "black", (0.5, 0.2, 0.9), (0.01, 0.99, 0.5), None])
def test_content_box_as_the_int16_reference(background):
    rng = np.random.default_rng(7)
    bg = np.round(np.array(to_rgb(background or "white")) * 255).astype(int)
    for _ in range(200):  # background within a few levels of the tolerance, a few pixels of anything
        image = rng.integers(0, 256, (30, 40, 4), dtype=np.uint8)
        near = (bg + rng.integers(-8, 9, (30, 40, 3))).clip(0, 255).astype(np.uint8)
        mostly = rng.random((30, 40)) < 0.995
        image[mostly, :3] = near[mostly]
        image[rng.random((30, 40)) < 0.3, 3] = 0
        assert content_box(image, background) == _content_box_int16(image, background)


def test_colour_bar_fit_stops_measuring_once_settled(monkeypatch):
    """Fixed ticks do not move with the bar's size: the second pass finds the first pass's place and the
    fit stops there (before: a third draw of the figure to measure the same again)."""
    from matplotlib.figure import Figure

    draws = []
    original = Figure.draw_without_rendering

    def counted(self):
        draws.append(1)
        return original(self)

    monkeypatch.setattr(Figure, "draw_without_rendering", counted)
    fig = colorbar_figure(ColourScale(cmap_colors("viridis"), 2.3, 5.0), 6.0, 1.0, dpi=100.0, label="z")
    assert len(draws) == 3  # two passes, then the label checked inside the figure
    ax = fig.axes[0]
    box = ax.get_position()
    assert box.width > 0.8  # still grown to the figure's width, its ticks inside


def test_a_colour_bars_measured_height_is_kept_per_bar():
    from brainpainter.media import colorbar

    scale = ColourScale(cmap_colors("viridis"), 2.3, 5.0)
    colorbar._HEIGHTS.clear()
    plain = colorbar.colorbar_height(scale, 3.0, dpi=300.0, fontsize=8.0)
    again = colorbar.colorbar_height(scale, 3.0, dpi=300.0, fontsize=8.0)
    assert len(colorbar._HEIGHTS) == 1 and again == plain
    labelled = colorbar.colorbar_height(scale, 3.0, dpi=300.0, fontsize=8.0, label="z-score")
    swatches = colorbar.colorbar_height(scale, 3.0, dpi=300.0, fontsize=8.0, nan=True, missing=True)
    assert labelled > plain and len(colorbar._HEIGHTS) == 3 and swatches >= plain  # each bar its own
    fresh = colorbar.decorations_bbox(colorbar.colorbar_figure(scale, 3.0, 3.0, dpi=300.0, fontsize=8.0,
                                                                label="z-score").axes[0])
    assert labelled == float(fresh.height) / 300.0 + 2 * 0.04 + 0.02  # what a fresh measure gives
