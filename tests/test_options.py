"""The options of a run are defined once: value objects checked when made; keywords, CLI and web
options made from them."""

from __future__ import annotations

import click
import pytest
from click.testing import CliRunner

from brainpainter.cli.main import cli
from brainpainter.color.scale import ScaleKwargs, ScaleOptions
from brainpainter.errors import AmbiguousColumnError, BrainPainterError, ColumnNotFoundError
from brainpainter.media.layout import FigureKwargs, FigureOptions
from brainpainter.media.movie import MakeMovieKwargs, MovieOptions
from brainpainter.rendering.options import (
    GROUPS,
    Options,
    RenderKwargs,
    RunnerKwargs,
    RunnerOptions,
    SceneKwargs,
    SceneOptions,
    option_names,
)
from brainpainter.rendering.settings import LIGHTINGS, RenderSettings, SettingsKwargs
from brainpainter.table.options import TableKwargs, TableOptions

PAIRS = [(ScaleKwargs, ScaleOptions), (SettingsKwargs, RenderSettings), (TableKwargs, TableOptions),
         (SceneKwargs, SceneOptions), (RunnerKwargs, RunnerOptions), (FigureKwargs, FigureOptions)]


@pytest.mark.parametrize("kwargs, cls", PAIRS, ids=[c.__name__ for _, c in PAIRS])
def test_each_keyword_type_names_the_fields_of_its_options_class(kwargs, cls):
    assert list(kwargs.__annotations__) == option_names(cls)


def test_the_run_keywords_are_the_groups_together():
    assert set(RenderKwargs.__annotations__) == {n for g in GROUPS.values() for n in option_names(g)}
    movie = set(MakeMovieKwargs.__annotations__) - set(RenderKwargs.__annotations__)
    assert movie == set(option_names(MovieOptions))


def test_options_sort_keywords_into_groups_and_round_trip():
    o = Options.of({"cmap": "viridis", "width": 640, "hide": "cerebellum", "strict": True, "jobs": "2"})
    assert o.scale.cmap == "viridis" and o.settings.width == 640 and o.scene.hide == ("cerebellum",)
    assert o.table.strict is True and o.runner.n_jobs == 2
    assert Options.of(o.flat()) == o
    assert Options.of({}, width=800).settings.width == 800              # a caller's own default
    assert Options.of({"width": 300}, width=800).settings.width == 300  # the user's value wins


def test_an_unknown_keyword_is_a_type_error_naming_the_function():
    with pytest.raises(TypeError, match=r"make_figure\(\) got an unexpected keyword argument 'colour'"):
        Options.of({"colour": "red"}, "make_figure")


def test_an_unknown_keyword_says_which_was_meant():
    """The command line's names in Python: ``size=`` is width/height, ``thresold=`` close to threshold."""
    with pytest.raises(TypeError, match=r"'size'; the command line's --size WxH is width=W, height=H$"):
        Options.of({"size": "800x600"}, "render")
    with pytest.raises(TypeError, match=r"'thresold'; did you mean 'threshold'\?$"):
        Options.of({"thresold": 2.3}, "render")


@pytest.mark.parametrize("kwargs, message", [
    ({"width": 9000}, "width must be between 16 and 8192 pixels"),
    ({"height": 12.5}, "height must be between 16 and 8192 pixels (a whole number)"),
    ({"glass_opacity": 2}, "glass opacity must be in [0, 1]"),
    ({"quality": "ultra"}, "quality must be one of"),
    ({"surface": "smooth"}, "surface must be one of"),
    ({"views": "lateral-lft"}, "Did you mean 'lateral-left'?"),
    ({"cmap": "viridis", "gradient": "red,blue"}, "not both"),
    ({"vmin": 3, "vmax": 1}, "vmax must be greater than vmin"),
    ({"jobs": 0}, "--jobs must be a positive whole number"),
])
def test_bad_options_fail_when_the_options_are_made(kwargs, message):
    with pytest.raises(BrainPainterError) as info:
        Options.of(kwargs)
    assert message in str(info.value)


def test_settings_are_normalised_once():
    s = RenderSettings(width=640.0, height=480, background="black", glass_opacity=1)  # type: ignore[arg-type]
    assert (s.width, s.height, s.background, s.glass_opacity) == (640, 480, (0.0, 0.0, 0.0), 1.0)
    assert isinstance(s.width, int) and s.size == "640x480"


def test_the_colour_scale_colours_are_made_once(monkeypatch):
    import brainpainter.color.scale as scale_module

    calls = []
    real = scale_module.cmap_colors
    monkeypatch.setattr(scale_module, "cmap_colors", lambda name: calls.append(name) or real(name))
    options = ScaleOptions(cmap="magma")
    a, b = options.scale([0.0, 2.0]), options.scale([5.0, 9.0])
    assert calls == ["magma"]
    assert (a.vmin, a.vmax, b.vmin, b.vmax) == (0.0, 2.0, 5.0, 9.0)


def test_click_options_come_from_the_fields():
    runner = CliRunner()
    help_text = runner.invoke(cli, ["render", "--help"], terminal_width=200).output
    for lighting in LIGHTINGS:
        assert lighting in help_text
    params = {p.name: p for p in cli.commands["render"].params}
    assert params["nan_color"].default == ScaleOptions().nan_color
    assert params["glass_opacity"].default == RenderSettings().glass_opacity
    assert list(params["surface"].type.choices) == ["pial", "white", "inflated"]
    # figure, movie, export and serve load when used (brainpainter --help stays cheap)
    movie = {p.name: p for p in cli.get_command(click.Context(cli), "movie").params}
    easing = MovieOptions.__dataclass_fields__["easing"].metadata["choices"]
    assert list(movie["easing"].type.choices) == list(easing)
    # no size given: the API's own default (a movie's 800x600), which an atlas of another shape reshapes
    assert movie["size"].default is None and "default: 800x600" in movie["size"].help


def test_web_options_use_the_core_definitions():
    from brainpainter.web.options import RenderOptions

    web = RenderOptions()
    assert web.lighting == RenderSettings().lighting and web.nan_color == ScaleOptions().nan_color
    assert RenderOptions(lighting="sulc").lighting == "sulc"  # every choice of the core, none re-typed
    kwargs = RenderOptions(size="320x240", transparent=True).run_kwargs()
    assert Options.of(kwargs).settings == RenderSettings(width=320, height=240, background=None)
    for no_size in (None, ""):  # the page's empty field: the default, reshaped by an atlas of another shape
        checked = Options.of(RenderOptions(size=no_size).run_kwargs())
        assert not checked.size_given and checked.settings.size == RenderSettings().size


def test_column_errors_are_types(tmp_path):
    from brainpainter.io.readers import read_raw
    from brainpainter.table.shape import find_column

    path = tmp_path / "t.csv"
    path.write_text("image,age,age\na,1,2\n")
    raw = read_raw(path)
    with pytest.raises(AmbiguousColumnError):
        find_column(raw, "age", "--time-column")
    with pytest.raises(ColumnNotFoundError):
        find_column(raw, "years", "--time-column")
