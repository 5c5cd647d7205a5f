"""``--colorbar-position bottom|right`` (issue 35): a figure's colour bars, one per scaled layer, each
labelled, horizontal under the images or upright at their right."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.color.scale import make_scale
from brainpainter.errors import BrainPainterError
from brainpainter.media.layout import FigureOptions, compose_figure


def _images(names, views):
    img = np.full((60, 80, 4), 255, np.uint8)
    img[10:50, 10:70, :3] = 90  # a content box to crop to
    return {(n, v): img for n in names for v in views}


def _inside(fig, ax):
    from brainpainter.media.colorbar import decorations_bbox

    fig.draw_without_rendering()
    box = decorations_bbox(ax)
    return 0 <= box.x0 and box.x1 <= fig.bbox.width + 0.5 and 0 <= box.y0 and box.y1 <= fig.bbox.height + 0.5


def test_bars_at_the_right_stand_upright_beside_the_images_each_labelled():
    names, views = ["a", "b"], ["lateral-left", "medial-left"]
    thickness, fa = make_scale(cmap="viridis", vmin=1.5, vmax=4), make_scale(cmap="magma", vmin=0.3, vmax=0.7)
    opts = FigureOptions(label="thickness (mm)", colorbar_position="right")
    layout = compose_figure(_images(names, views), names, views, thickness, opts, nan=True,
                            more_bars=[(fa, "FA")])
    bars, fig = layout.colorbar_axes, layout.figure
    images_right = max(ax.get_position().x1 for ax in layout.image_axes.values())
    images_bottom = min(ax.get_position().y0 for ax in layout.image_axes.values())
    assert [ax.get_ylabel() for ax in bars] == ["thickness (mm)", "FA"]
    for ax in bars:
        box = ax.get_position()
        assert box.x0 > images_right and box.y0 >= images_bottom - 1e-6  # at the right, not below
        assert box.height * fig.bbox.height > 3 * box.width * fig.bbox.width  # upright
        assert _inside(fig, ax)  # ticks and label inside the figure
    assert bars[0].get_position().x1 < bars[1].get_position().x0  # side by side, left to right
    bottom = compose_figure(_images(names, views), names, views, thickness, FigureOptions(label="t"),
                            more_bars=[(fa, "FA")])
    assert [ax.get_xlabel() for ax in bottom.colorbar_axes] == ["t", "FA"]
    under = min(ax.get_position().y0 for ax in bottom.image_axes.values())
    assert all(ax.get_position().y1 < under for ax in bottom.colorbar_axes)  # under the images
    assert fig.get_size_inches()[1] < bottom.figure.get_size_inches()[1]  # no bar row under the images


def test_a_long_label_of_an_upright_bar_stays_inside_a_short_figure():
    names, views = ["a"], ["lateral-left", "medial-left", "lateral-right", "medial-right"]
    opts = FigureOptions(label="atrophy (SD from age-matched controls)", colorbar_position="right")
    layout = compose_figure(_images(names, views), names, views, make_scale(vmin=0, vmax=3), opts)
    assert layout.figure.get_size_inches()[1] < 1.5 and _inside(layout.figure, layout.colorbar_ax)


def test_a_label_on_two_lines_breaks_at_a_space_never_in_a_word():
    """``thickness (mm)`` beside a short row of images: ``thickness`` / ``(mm)`` (was ``thicknes`` /
    ``s (mm)``)."""
    from brainpainter.media.layout import colorbar_width

    scale = make_scale(cmap="viridis", vmin=1.5, vmax=4)
    for text, lines in (("thickness (mm)", ["thickness", "(mm)"]),
                        ("atrophy (SD from controls)", ["atrophy (SD", "from controls)"])):
        _, label = colorbar_width(scale, label=text, room=0.3)
        assert label is not None and label.split("\n") == lines


def test_a_colorbar_position_not_known_is_one_line():
    with pytest.raises(BrainPainterError, match=r"colorbar_position must be one of \['bottom', 'right'\]; "
                                                r"'left' was given"):
        FigureOptions(colorbar_position="left")


def test_the_figure_command_takes_colorbar_position(tmp_path):
    from click.testing import CliRunner

    from brainpainter.cli.main import cli

    result = CliRunner().invoke(cli, ["figure", "t.csv", "--out", str(tmp_path / "f.pdf"),
                                      "--colorbar-position", "top"])
    assert result.exit_code == 2 and "'top' is not one of 'bottom', 'right'" in result.output


@pytest.mark.render
def test_a_scene_figure_draws_a_labelled_upright_bar_per_layer(tmp_path):
    """Scene.figure(colorbar_position="right"): region values and a map over them, two upright bars."""
    from matplotlib import colormaps

    from brainpainter import Scene

    table = tmp_path / "thick.csv"
    table.write_text("Image-name-unique,lh_precentral,lh_insula\nctrl,1.5,4\nad,2,3\n")  # two rows, one map
    scene = (Scene(width=160, height=120, quality="fast", shading="flat")
             .add(table, cmap="viridis", vmin=1.5, vmax=4, label="thickness (mm)")
             .add({"lh": np.linspace(0, 1, 10242)}, cmap="magma", vmin=0, vmax=1, alpha=0.5, label="p"))
    result = scene.figure(tmp_path / "fig.png", views="lateral-left", colorbar_position="right",
                          progress=False)
    assert result.path is not None and result.path.stat().st_size > 1000 and len(result.images) == 2
    axes = result.colorbar_axes
    assert [ax.get_ylabel() for ax in axes] == ["thickness (mm)", "p"]
    for ax, cmap in zip(axes, ("viridis", "magma"), strict=True):
        bar = np.asarray(ax.get_images()[0].get_array())[..., :3].reshape(-1, 3)
        ends = np.asarray([colormaps[cmap](1.0)[:3], colormaps[cmap](0.0)[:3]])  # upright: top is vmax
        assert np.abs(bar[[0, -1]] - ends).max() < 0.02, cmap
