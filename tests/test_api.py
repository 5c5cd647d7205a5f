"""The public Python API: names that stay callable, render(painter=...), plot into Axes, Pythons."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.testing import StandInRenderer, stand_in

VALUES = {"Left-insula": 3.0, "Left-precuneus": 1.0, "Left-superiorfrontal": 0.0}


@pytest.fixture
def counting():
    """A registered stand-in renderer; StandInRenderer.scenes counts the scenes it was given."""
    with stand_in("counting") as name:
        yield name


def test_public_names_stay_callable_after_their_modules_are_imported():
    code = ("import brainpainter, brainpainter.rendering.painter\n"
            "import brainpainter.media.figure, brainpainter.media.movie\n"
            "import brainpainter.media.plot, brainpainter.media.export\n"
            "from brainpainter.rendering.painter import Painter\n"
            "names = ['render', 'figure', 'movie', 'plot', 'export', 'Painter']\n"
            "print([callable(getattr(brainpainter, n)) for n in names])\n"
            "print(brainpainter.figure.__name__, brainpainter.movie.__name__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split("\n")[:2] == ["[True, True, True, True, True, True]", "make_figure make_movie"]


def test_render_three_times_in_one_process(tiny, counting):
    for _ in range(3):
        result = brainpainter.render(VALUES, "dk", template=tiny, renderer=counting, views="lateral-left",
                                     width=40, height=30, progress=False)
        assert callable(brainpainter.render)
        assert set(result.images) == {("1", "lateral-left")}
    assert StandInRenderer.scenes == 3


def test_render_with_a_painter_builds_no_new_scene(tiny, counting, tmp_path):
    settings = brainpainter.RenderSettings(width=40, height=30)
    with brainpainter.Painter("dk", tiny, renderer=counting, settings=settings) as painter:
        a = brainpainter.render(VALUES, painter=painter, views="lateral-left", progress=False)
        b = brainpainter.render({"Left-insula": 0.0}, painter=painter, views="lateral-left,medial-left",
                                out=tmp_path / "o", progress=False)
        c = brainpainter.render(VALUES, painter=painter, views="lateral-left", progress=False)
        assert painter._renderer is not None  # still open for the next table
    assert StandInRenderer.scenes == 1
    assert a.images[("1", "lateral-left")].shape == (30, 40, 4)  # the painter's size
    assert len(b.files) == 2 and b.manifest["settings"]["width"] == 40
    np.testing.assert_array_equal(a.images[("1", "lateral-left")], c.images[("1", "lateral-left")])
    assert not np.array_equal(a.images[("1", "lateral-left")],
                              brainpainter.render({"Left-insula": 0.0}, painter=fresh_painter(tiny, counting),
                                                  views="lateral-left", progress=False)
                              .images[("1", "lateral-left")])


def fresh_painter(tiny, renderer):
    return brainpainter.Painter("dk", tiny, renderer=renderer,
                                settings=brainpainter.RenderSettings(width=40, height=30))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"width": 800}, "['width']"),
    ({"surface": "inflated", "quality": "fast"}, "['surface', 'quality']"),
    ({"atlas": "dkt"}, "painter draws 'dk'"),
])
def test_render_with_a_painter_refuses_other_scene_options(tiny, counting, kwargs, message):
    painter = fresh_painter(tiny, counting)
    with pytest.raises(BrainPainterError, match="painter") as err:
        brainpainter.render(VALUES, painter=painter, progress=False, **kwargs)
    assert message in str(err.value)
    assert StandInRenderer.scenes == 0  # refused before any scene was built


def test_render_rows_selects_and_orders(tiny, counting, tmp_path):
    table = {"a": {"Left-insula": 1.0}, "b": {"Left-insula": 2.0}, "c": {"Left-insula": 3.0}}
    import pandas as pd

    df = pd.DataFrame(table).T.rename_axis("Image-name-unique").reset_index()
    result = brainpainter.render(df, "dk", template=tiny, renderer=counting, views="lateral-left",
                                 width=20, height=16, rows="c,a", progress=False, out=tmp_path / "o")
    assert [p.name for p in result.files] == ["c_lateral-left.png", "a_lateral-left.png"]
    assert result.manifest["settings"]["scale"]["vmax"] == 3.0  # scale over all rows
    with pytest.raises(BrainPainterError, match="'d' is not an image name"):
        brainpainter.render(df, "dk", template=tiny, renderer=counting, rows=["d"], progress=False)


def test_plot_draws_into_the_users_axes_with_a_colour_bar(tiny, counting):
    from matplotlib.figure import Figure

    from brainpainter.media.colorbar import agg_canvas

    fig = Figure(figsize=(6, 3))
    ax_line, ax_brain = fig.subplots(1, 2)
    ax_line.plot([0, 1], [0, 1])
    res = brainpainter.plot(VALUES, view="lateral-left", ax=ax_brain, atlas="dk", template=tiny,
                            renderer=counting, width=60, height=40, label="z", crop=False)
    assert res.ax is ax_brain and res.image.shape == (40, 60, 4)
    np.testing.assert_array_equal(res.artist.get_array(), res.image)
    assert res.colorbar_ax is not None and res.colorbar_ax in ax_brain.child_axes
    assert res.colorbar_ax.get_ylabel() == "z"
    assert not ax_brain.axison
    canvas = agg_canvas(fig)
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba())[..., :3].reshape(-1, 3)
    red = np.round(np.array(res.scale(np.array([3.0]))[0][:3]) * 255)
    assert (np.abs(pixels.astype(int) - red).max(axis=1) <= 2).sum() > 50  # the insula's colour shows


def test_plot_reuses_a_painter_and_picks_a_row(tiny, counting):
    from matplotlib.figure import Figure

    painter = fresh_painter(tiny, counting)
    fig = Figure()
    axes = fig.subplots(1, 2)
    table = [{"Left-insula": 0.0}, {"Left-insula": 3.0}]
    import pandas as pd

    df = pd.DataFrame(table, index=["pre", "post"]).rename_axis("Image-name-unique").reset_index()
    a = brainpainter.plot(df, ax=axes[0], row="pre", painter=painter, colorbar=False)
    b = brainpainter.plot(df, ax=axes[1], row="post", painter=painter, orientation="horizontal")
    assert StandInRenderer.scenes == 1 and a.colorbar_ax is None and b.colorbar_ax is not None
    assert not np.array_equal(a.image, b.image)
    with pytest.raises(BrainPainterError, match="orientation"):
        brainpainter.plot(df, ax=axes[0], painter=painter, orientation="diagonal")


def test_render_result_shows_in_notebooks(tiny, counting, tmp_path):
    shown = brainpainter.render(VALUES, "dk", template=tiny, renderer=counting, views="lateral-left",
                                width=20, height=16, progress=False)._repr_html_()
    assert shown.count("<img") == 1 and "data:image/png;base64," in shown
    written = brainpainter.render(VALUES, "dk", template=tiny, renderer=counting, views="lateral-left",
                                  width=20, height=16, progress=False, out=tmp_path / "o")
    assert written._repr_html_().count("<img") == 1


def test_missing_bpy_names_the_pythons_that_work(monkeypatch):
    import importlib.util

    from brainpainter.rendering import pythons
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "bpy" else real(name, *a))
    monkeypatch.setattr(sys, "version_info", (3, 12, 4, "final", 0))
    with pytest.raises(BrainPainterError) as err:
        pythons.require_bpy()
    msg = str(err.value)
    assert "\n" not in msg and "Python 3.11" in msg and "Python 3.13" in msg and "3.12" in msg
    with pytest.raises(BrainPainterError, match=r"Python 3\.13"):
        brainpainter.Painter("dk")  # the Blender renderer is checked before anything loads


def test_views_error_lists_current_names_first():
    with pytest.raises(BrainPainterError) as err:
        brainpainter.render(VALUES, "dk", views="sideways")
    msg = str(err.value)
    assert msg.index("lateral-left") < msg.index("cortical-outer-left-hemisphere")
    assert msg.startswith("view must be one of ['lateral-left', 'medial-left'")


def test_views_split_by_a_space_still_work(tiny, counting, tmp_path, capsys):
    from brainpainter.cli.main import join_split_lists, main

    assert join_split_lists(["render", "t.csv", "--views", "lateral-left,", "medial-left", "-o", "o"]) == [
        "render", "t.csv", "--views=lateral-left,medial-left", "-o", "o"]
    assert join_split_lists(["--views=a", ",b", "x"]) == ["--views=a,b", "x"]
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula\na,1\n")
    with pytest.raises(SystemExit) as exit_:
        main(["render", str(table), "--views", "lateral-left,", "medial-left", "--template", str(tiny),
              "--renderer", counting, "--size", "40x30", "--out", str(tmp_path / "o"), "-q"])
    assert exit_.value.code == 0, capsys.readouterr().err
    written = sorted(p.name for p in (tmp_path / "o").glob("*.png"))
    assert written == ["a_lateral-left.png", "a_medial-left.png"]


def test_template_build_names_the_builder_extra_when_missing(monkeypatch, tmp_path, capsys):
    import importlib.util

    from brainpainter.cli.main import main

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "pymeshlab" else real(name, *a))
    with pytest.raises(SystemExit) as exit_:
        main(["template", "build", str(tmp_path), "--out", str(tmp_path / "t")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1
    assert "pymeshlab" in err and "pip install 'brainpainter[builder]'" in err
    assert not (tmp_path / "t").exists()


def test_dir_lists_the_public_names_for_tab_completion():
    names = dir(brainpainter)
    assert set(brainpainter.__all__) <= set(names)
    assert not {"Any", "TYPE_CHECKING", "annotations"} & set(names)
    assert "__version__" in names and brainpainter.__version__


def test_reprs_of_results_are_one_short_line(tiny, counting, tmp_path):
    from matplotlib.figure import Figure

    from brainpainter.media.movie import MovieResult

    result = brainpainter.render({"Left-insula": [1.0, 2.0, 3.0]}, "dk", template=tiny, renderer=counting,
                                 views="lateral-left,medial-left", width=32, height=32, progress=False)
    written = brainpainter.render({"Left-insula": [1.0, 2.0]}, "dk", template=tiny, renderer=counting,
                                  views="lateral-left", width=32, height=32, out=tmp_path / "o",
                                  progress=False)
    fig = brainpainter.figure({"Left-insula": [1.0, 2.0]}, "dk", template=tiny, renderer=counting,
                              views="lateral-left", width=32, height=32, progress=False)
    ax = Figure().add_subplot()
    plotted = brainpainter.plot(VALUES, view="lateral-left", ax=ax, atlas="dk", template=tiny,
                                renderer=counting, width=40, height=30)
    movie = MovieResult(tmp_path / "m.mp4", 50, (640, 480), 24.0, [f"k{i}" for i in range(500)],
                        list(range(500)), 1.0)
    for obj, start in ((result, "<RenderResult: 6 image(s) of 32x32"), (written, "<RenderResult: 2 file(s)"),
                       (fig, "<FigureResult: 2 render(s)"), (plotted, "<PlotResult: "),
                       (movie, "<MovieResult: "), (result.scale, "<ColourScale "),
                       (result.table, "<RegionTable 'dict': 3 image(s) x 1 region(s)")):
        text = repr(obj)
        assert "\n" not in text and len(text) < 200 and text.startswith(start), text


def test_a_free_camera_is_found_under_the_name_the_user_gave(tiny, counting):
    result = brainpainter.render({"Left-insula": [1.0, 2.0]}, "dk", template=tiny, renderer=counting,
                                 views="lateral-left,camera:90:0,camera:135:30:1.2", width=32, height=32,
                                 progress=False)
    image = result.images[("1", "camera:90:0")]
    assert image is result.images[("1", "az90-el0")]  # stored under the name its file gets
    assert result.images[("2", "camera:135:30:1.2")].shape == (32, 32, 4)
    assert ("1", "camera:90:0") in result.images and ("1", "camera:91:0") not in result.images
    assert result.images[(1, "Lateral-Left")] is result.images[("1", "lateral-left")]
    with pytest.raises(KeyError):
        result.images[("3", "camera:90:0")]


def test_render_summary_counts_the_rows_rendered(tmp_path, monkeypatch, tiny, counting):
    from bad_inputs.corpus import HEADER, csv
    from test_bad_inputs_inprocess import invoke

    (tmp_path / "in.csv").write_bytes(csv(HEADER.strip(), "A,1,2", "B,2,3", "C,3,4"))
    monkeypatch.chdir(tmp_path)
    code, out, err = invoke(["render", "in.csv", "--out", "o", "--renderer", counting, "--template",
                             str(tiny), "--views", "lateral-left,medial-left", "--size", "32x32",
                             "--rows", "B", "-q"])
    assert code == 0, err
    assert "2 image(s) written to o (1 row(s) of 3;" in out, out
    code, out, err = invoke(["render", "in.csv", "--out", "o2", "--renderer", counting, "--template",
                             str(tiny), "--views", "lateral-left", "--size", "32x32", "-q"])
    assert code == 0 and "3 image(s) written to o2 (3 row(s);" in out, out


@pytest.mark.parametrize("command, out", [("figure", "f.png"), ("movie", "m.gif")])
def test_figures_and_movies_of_names_in_any_script(tmp_path, monkeypatch, tiny, counting, command, out):
    """Names whose characters the fonts lack (CJK, Arabic, emoji) draw without a flood of glyph warnings
    (under pytest: errors) and the file is written."""
    from bad_inputs.corpus import csv
    from test_bad_inputs_inprocess import invoke

    (tmp_path / "in.csv").write_bytes(csv("Image-name-unique,Left-insula", "患者 1,1", "مريض,2", "🧠,3"))
    monkeypatch.chdir(tmp_path)
    code, _out, err = invoke([command, "in.csv", "--out", out, "--renderer", counting, "--template",
                              str(tiny), "--views", "lateral-left", "--size", "32x32", "-q"])
    assert code == 0, err
    assert (tmp_path / out).stat().st_size > 500
