"""Numbers at the edges: any finite value gets the colour the scale gives it (clamped), never the NaN colour.

Values like ``1e308``, ``-1e308`` and subnormals (``5e-324``) overflowed
``value - vmin`` or ``vmax - vmin`` into ``inf``/``NaN``: the region was drawn
in the NaN colour, with a RuntimeWarning (an error under pytest). Images,
figures (the colour bar over an extreme range) and movies are checked, and
each scale mode (automatic limits, given limits, diverging).
"""

from __future__ import annotations

import numpy as np
import pytest
from bad_inputs.corpus import RENDER, csv
from test_bad_inputs_inprocess import invoke

import brainpainter
from brainpainter.color.scale import make_scale
from brainpainter.testing import StandInRenderer, stand_in

TINY = 5e-324
BIG = float(np.finfo(float).max)
EXTREMES = [1e308, -1e308, BIG, -BIG, TINY, -TINY, 1e-310, 2.2250738585072014e-308]
SCALES = [
    {"cmap": "viridis"},
    {"cmap": "viridis", "vmin": -1e308, "vmax": 1e308},
    {"cmap": "viridis", "vmin": -BIG, "vmax": BIG},
    {"cmap": "viridis", "vmin": 0.0, "vmax": 1.0},
    {"cmap": "viridis", "vmin": 0.0, "vmax": TINY},
    {"cmap": "RdBu_r", "center": 0.0},
    {"cmap": "RdBu_r", "center": 1e308},
    {"cmap": "RdBu_r", "center": 0.0, "vmin": -BIG, "vmax": BIG},
    {"gradient": "white,red", "vmin": -1e308, "vmax": 1e308},
    {},
]


@pytest.mark.parametrize("options", SCALES, ids=str)
@pytest.mark.parametrize("data", [EXTREMES, [1e308], [-BIG], [TINY], [TINY, 2 * TINY, 4 * TINY]], ids=str)
def test_every_finite_value_gets_a_scale_colour(options, data):
    scale = make_scale(np.array(data), **options)  # RuntimeWarnings are errors here
    values = np.array(EXTREMES + data)
    pos = scale.position(values)
    assert np.isfinite(pos).all() and (pos >= 0).all() and (pos <= scale.n_colors - 1).all()
    colors = scale(values)
    assert np.isfinite(colors).all()
    assert not np.all(colors == np.array(scale.nan_color), axis=1).any() or np.allclose(
        scale.nan_color, scale.colors[0]) or np.allclose(scale.nan_color, scale.colors[-1])
    ticks = scale.ticks()
    assert np.isfinite(ticks).all() and len(ticks) >= 2 and (np.diff(ticks) > 0).all()
    assert scale.vmin <= ticks[0] and ticks[-1] <= scale.vmax
    assert np.isfinite(scale.vmin) and np.isfinite(scale.vmax) and scale.vmin < scale.vmax


def test_extremes_are_clamped_to_the_end_colours():
    scale = make_scale(cmap="viridis", vmin=0.0, vmax=1.0)
    np.testing.assert_allclose(scale(np.array([1e308, BIG, -1e308, -BIG])),
                               [scale.colors[-1], scale.colors[-1], scale.colors[0], scale.colors[0]])
    wide = make_scale(cmap="viridis", vmin=-1e308, vmax=1e308)
    np.testing.assert_allclose(wide.position(np.array([-1e308, 0.0, 1e308, TINY])), [0, 127.5, 255, 127.5])
    sub = make_scale(np.array([TINY, 2 * TINY, 3 * TINY]), cmap="viridis")
    np.testing.assert_allclose(sub.position(np.array([TINY, 2 * TINY, 3 * TINY])), [0, 127.5, 255])


def test_render_draws_extreme_values_in_scale_colours(tiny):
    values = {"Left-insula": 1e308, "Right-insula": -1e308, "Left-Hippocampus": TINY}
    with stand_in("extreme") as name:
        result = brainpainter.render(values, "dk", template=tiny, renderer=name, views="lateral-left",
                                     width=32, height=32, cmap="viridis", progress=False)
        colors, _ = StandInRenderer.calls[-1]
    scale = result.scale
    for region, value in values.items():
        np.testing.assert_allclose(colors[region], scale(np.array([value]))[0])
        assert not np.allclose(colors[region], scale.nan_color)
    np.testing.assert_allclose(colors["Left-insula"], scale.colors[-1])
    np.testing.assert_allclose(colors["Right-insula"], scale.colors[0])


@pytest.mark.parametrize("scale_args", [["--cmap", "viridis", "--vmin", "-1e308", "--vmax", "1e308"],
                                        ["--cmap", "RdBu_r", "--center", "0"], ["--cmap", "viridis"]],
                         ids=" ".join)
def test_figure_colour_bar_over_an_extreme_range_is_readable(tmp_path, monkeypatch, tiny, scale_args):
    (tmp_path / "in.csv").write_bytes(csv("Image-name-unique,Left-insula,Right-insula",
                                          "A,1e308,-1e308", f"B,{TINY},0"))
    monkeypatch.chdir(tmp_path)
    args = ["figure", "in.csv", *[a.replace("{tiny}", str(tiny)) for a in RENDER], "--out", "f.png",
            *scale_args]
    with stand_in("solid"):
        code, _out, err = invoke(args)
    assert code == 0, err
    assert (tmp_path / "f.png").stat().st_size > 1000


def test_figure_colour_bar_ticks_are_labelled_over_any_range(tiny):
    from matplotlib.figure import Figure

    from brainpainter.media.colorbar import draw_colorbar

    for lo, hi in ((-1e308, 1e308), (-BIG, BIG), (0.0, TINY * 4), (1e308, BIG)):
        fig = Figure()
        ax = fig.add_subplot()
        draw_colorbar(ax, make_scale(cmap="viridis", vmin=lo, vmax=hi))
        fig.canvas.draw() if hasattr(fig.canvas, "draw") else None
        labels = [t.get_text() for t in ax.get_xticklabels()]
        assert labels and all(labels) and len(set(labels)) == len(labels), labels


def test_movie_through_extreme_values(tmp_path, monkeypatch, tiny):
    (tmp_path / "in.csv").write_bytes(csv("Image-name-unique,Left-insula,Right-insula",
                                          "A,-1e308,1e308", f"B,1e308,{TINY}"))
    monkeypatch.chdir(tmp_path)
    args = ["movie", "in.csv", *[a.replace("{tiny}", str(tiny)) for a in RENDER], "--out", "m.gif",
            "--cmap", "viridis", "--vmin", "-1e308", "--vmax", "1e308", "--frames-per-step", "3"]
    with stand_in("solid"):
        code, _out, err = invoke(args)
    assert code == 0, err
    assert (tmp_path / "m.gif").stat().st_size > 1000
