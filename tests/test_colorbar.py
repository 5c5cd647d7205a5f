"""Colour bars: ticks, the colours along the bar, swatches, sizes."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.color.scale import make_scale
from brainpainter.errors import BrainPainterError
from brainpainter.media.colorbar import (
    bar_colors,
    colorbar_figure,
    colorbar_image,
    draw_colorbar,
    format_tick,
    new_figure,
    resolve_ticks,
    text_color,
)


def positions_along(pixels: np.ndarray, scale) -> np.ndarray:
    """For each RGB pixel (uint8, shape (n, 3)), its value on `scale` (nearest bar colour)."""
    values, colors = bar_colors(scale, 2048)
    d = np.abs(pixels[:, None, :].astype(float) / 255 - colors[None]).max(axis=-1)
    assert d.min(axis=1).max() < 4 / 255, "a pixel is not a colour of the scale"
    return values[d.argmin(axis=1)]


def test_default_ticks_are_the_gradient_control_points():
    assert resolve_ticks(make_scale(), None).tolist() == [0, 1, 2, 3]
    assert resolve_ticks(make_scale(cmap="viridis", data=[0, 10]), None).tolist() == [0, 2, 4, 6, 8, 10]
    diverging = make_scale(gradient="blue,white,red", center=0, data=[-2, 1])
    assert resolve_ticks(diverging, None).tolist() == [-2, 0, 2]


@pytest.mark.parametrize(("spec", "ticks"), [
    ({"cmap": "viridis", "vmin": 1.5, "vmax": 4}, [1.5, 2, 2.5, 3, 3.5, 4]),       # not 1.5, 2.12, 2.75
    ({"cmap": "viridis", "vmin": 0, "vmax": 254}, [0, 50, 100, 150, 200, 250]),     # not 63.5, 127, 190.5
    ({"cmap": "viridis", "vmin": 0, "vmax": 4.7}, [0, 1, 2, 3, 4]),                 # an end that is not round
    ({"cmap": "RdBu_r", "center": 0, "data": [-7.94, 3]}, [-7.5, -5, -2.5, 0, 2.5, 5, 7.5]),
    ({"cmap": "RdBu_r", "center": 1, "vmin": -3, "vmax": 5}, [-2, 1, 4]),           # the centre is a tick
    ({"vmin": 1.5, "vmax": 4}, [1.5, 2, 2.5, 3, 3.5, 4]),     # a gradient's control colours at 1.5, 2.33, ...
    ({"gradient": "white,yellow,orange,red,black", "vmin": 0, "vmax": 100}, [0, 25, 50, 75, 100]),
])
def test_default_ticks_fall_on_round_numbers(spec, ticks):
    scale = make_scale(**spec)
    got = resolve_ticks(scale, None)
    np.testing.assert_allclose(got, ticks, atol=1e-12)
    assert scale.vmin <= got[0] and got[-1] <= scale.vmax  # the bar still runs from vmin to vmax
    assert scale.ticks().tolist() == got.tolist()          # the web page's bar has the same ticks


def test_chosen_ticks_are_checked():
    scale = make_scale()
    assert resolve_ticks(scale, "0, 1.5,3").tolist() == [0, 1.5, 3]
    assert resolve_ticks(scale, [3, 0]).tolist() == [0, 3]
    with pytest.raises(BrainPainterError, match=r"tick 5 lies outside the colour scale 0\.\.3"):
        resolve_ticks(scale, "0,5")
    with pytest.raises(BrainPainterError, match=r"ticks must be numbers.*'high' was given"):
        resolve_ticks(scale, "0,high")


def test_tick_labels_are_short():
    assert [format_tick(v) for v in (0, -0.0, 1.5, 3.0, 0.001, 12345.0, -2)] == [
        "0", "0", "1.5", "3", "0.001", "1.23e+04", "-2"]


@pytest.mark.parametrize("spec", [{}, {"cmap": "RdBu_r", "center": 0.0, "data": [-2.0, 3.0]}])
def test_the_bar_runs_through_the_scale_in_order(spec):
    scale = make_scale(**spec)
    img = colorbar_image(scale, (400, 90), label="z-score")
    assert img.shape == (90, 400, 4) and img.dtype == np.uint8
    # the bar: the rows where most pixels are not white
    rgb = img[..., :3]
    rows = np.flatnonzero((np.abs(rgb.astype(int) - 255).max(axis=-1) > 30).sum(axis=1) > 200)
    row = rgb[(rows[0] + rows[-1]) // 2]
    inside = np.flatnonzero(np.abs(row.astype(int) - 255).max(axis=-1) > 0)
    x0, x1 = inside[0] + 3, inside[-1] - 3  # inside the frame line
    values = positions_along(row[x0:x1], scale)
    assert np.all(np.diff(values) >= 0)
    span = scale.vmax - scale.vmin
    assert values[0] < scale.vmin + 0.02 * span and values[-1] > scale.vmax - 0.02 * span


def test_swatches_and_label_in_a_horizontal_bar():
    fig = new_figure((4, 1), 100)
    ax = fig.add_axes((0.1, 0.5, 0.5, 0.2))
    draw_colorbar(ax, make_scale(), label="atrophy", nan=True, missing=True)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["no data", "not measured"]
    assert ax.get_xlabel() == "atrophy"
    assert [t.get_text() for t in ax.get_xticklabels()] == ["0", "1", "2", "3"]


def test_vertical_bar_and_bad_orientation():
    fig = new_figure((1, 3), 100)
    ax = fig.add_axes((0.2, 0.2, 0.2, 0.6))
    draw_colorbar(ax, make_scale(), orientation="vertical", ticks=[0, 3], nan=True)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["0", "3"]
    with pytest.raises(BrainPainterError, match="orientation must be one of"):
        draw_colorbar(ax, make_scale(), orientation="diagonal")


def test_everything_fits_in_the_figure():
    fig = colorbar_figure(make_scale(), 2.0, 0.8, dpi=100, label="a rather long label for a bar",
                          nan=True, missing=True)
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    for artist in fig.axes[0].get_children():
        if hasattr(artist, "get_window_extent") and artist.get_visible():
            box = artist.get_window_extent(renderer)
            assert box.x0 >= -1 and box.x1 <= 201, artist


def test_text_colour_follows_the_background():
    assert text_color("white") == "black" and text_color("black") == "white"
    assert text_color(None) == "black"
    img = colorbar_image(make_scale(), (300, 80), background="black", label="x")
    assert tuple(img[0, 0, :3]) == (0, 0, 0)
    assert colorbar_image(make_scale(), (300, 80), background=None)[0, 0, 3] == 0
