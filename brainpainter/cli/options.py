"""Click options shared by the commands that render: atlas, views, colours, image settings.

``@render_options`` adds the options of ``brainpainter render`` with the same
names and defaults; :func:`render_kwargs` turns the values click passes into
keyword arguments of :func:`brainpainter.render`,
:func:`brainpainter.media.figure.make_figure` and :func:`brainpainter.media.movie.make_movie`.
``@input_options`` adds how tables are read (``--image-column``, ``--value``,
``--region-column``, ``--strict``). Only click is imported here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import click

from brainpainter.errors import BrainPainterError

F = TypeVar("F", bound=Callable[..., Any])

DEFAULT_VIEWS = "lateral-left,medial-left,subcortical"
DEFAULT_SIZE = "1200x900"

#: Names of the parameters added by ``render_options`` (click's Python names).
RENDER_OPTION_NAMES = (
    "atlas", "views", "template", "surface", "gradient", "cmap", "vmin", "vmax", "center", "nan_color",
    "missing_color", "hide", "background", "transparent", "size", "quality", "shading", "lighting",
    "glass_opacity", "renderer", "atlas_config",
)
INPUT_OPTION_NAMES = ("image_column", "value", "region_column", "strict")
PARALLEL_OPTION_NAMES = ("jobs", "scheduler")


class FiniteFloat(click.ParamType):
    """A float option that refuses NaN and infinities (``--vmin nan``) before anything runs."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        import math

        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number.", param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number; give a number such as 1.5.", param, ctx)
        return number


#: Click type of every float option: finite numbers only.
FINITE = FiniteFloat()


def split_commas(ctx: click.Context, param: click.Parameter, value: tuple[str, ...]) -> list[str]:
    """Callback for repeatable options that also take comma-separated lists."""
    return [v.strip() for item in value for v in item.split(",") if v.strip()]


def make_render_options(views: str = DEFAULT_VIEWS, size: str = DEFAULT_SIZE,
                        only: tuple[str, ...] | None = None) -> Callable[[F], F]:
    """A decorator adding the render options, with the given defaults for ``--views`` and ``--size``.

    `only` keeps just the options of those Python names (see :data:`RENDER_OPTION_NAMES`).
    """

    options = [
        click.option("--atlas", "-a", default=None,
                     help="Atlas: dk, destrieux, dkt (alias tourville) or a plugin atlas. "
                          "Default: inferred from the region names."),
        click.option("--views", default=views, show_default=True,
                     help="Comma-separated views, 'all', or camera:AZ:EL[:ZOOM]."),
        click.option("--template", default="fsaverage", show_default=True, help="Template name or folder."),
        click.option("--surface", default="pial", show_default=True,
                     type=click.Choice(["pial", "white", "inflated"])),
        click.option("--gradient", default=None,
                     help="Control colours, e.g. white,yellow,orange,red (the default). Values 0..N-1."),
        click.option("--cmap", default=None,
                     help="A matplotlib colour map instead of a gradient, e.g. viridis."),
        click.option("--vmin", type=FINITE, default=None, help="Value at the first colour."),
        click.option("--vmax", type=FINITE, default=None, help="Value at the last colour."),
        click.option("--center", type=FINITE, default=None, help="Diverging: value at the middle colour."),
        click.option("--nan-color", default="#8c8c8c", show_default=True, help="Colour of empty cells."),
        click.option("--missing-color", default="#d0d0d0", show_default=True,
                     help="Colour of regions with no column."),
        click.option("--hide", multiple=True, callback=split_commas,
                     help="Regions or groups not drawn (cerebellum, ventricles, brainstem, ventraldc). "
                          "Repeatable."),
        click.option("--background", default="white", show_default=True, help="Background colour."),
        click.option("--transparent", is_flag=True, help="Transparent background."),
        click.option("--size", default=size, show_default=True,
                     help="Size of each rendered view, WIDTHxHEIGHT pixels."),
        click.option("--quality", default="default", show_default=True,
                     type=click.Choice(["fast", "default", "high"])),
        click.option("--shading", default="default", show_default=True,
                     type=click.Choice(["default", "flat"])),
        click.option("--lighting", default="studio", show_default=True,
                     type=click.Choice(["studio", "soft", "flat-studio", "sulc"]),
                     help="sulc: studio light with sulci darkened slightly (sulcal depth)."),
        click.option("--glass-opacity", type=FINITE, default=0.12, show_default=True),
        click.option("--renderer", default="blender", show_default=True),
        click.option("--atlas-config", type=click.Path(dir_okay=False), default=None,
                     help="Region-group TOML file defining the atlas (instead of --atlas); "
                          "see docs/atlases.md."),
    ]

    if only is not None:
        options = [opt for opt, name in zip(options, RENDER_OPTION_NAMES, strict=True) if name in only]

    def decorate(f: F) -> F:
        for opt in reversed(options):
            f = opt(f)
        return f

    return decorate


#: ``@render_options``: the render options with ``brainpainter render``'s defaults.
render_options = make_render_options()


def input_options(f: F) -> F:
    """Options that say how INPUT tables are read (as for ``render`` and ``check``)."""
    for opt in reversed([
        click.option("--image-column", default=None,
                     help="Column with image names (default Image-name-unique, a FreeSurfer first column, "
                          "subject...; otherwise rows are numbered)."),
        click.option("--value", default=None,
                     help="Long tables: the column with the values, e.g. d_icv."),
        click.option("--region-column", default=None,
                     help="Long tables: the column with region names (auto-detected when unambiguous)."),
        click.option("--strict", is_flag=True, help="Names that match no region are an error."),
    ]):
        f = opt(f)
    return f


def parallel_options(f: F) -> F:
    """``--jobs`` and ``--scheduler``: where the images are rendered (see brainpainter.rendering.parallel)."""
    for opt in reversed([
        click.option("--jobs", "-j", default="1", show_default=True, metavar="N|auto",
                     help="Render in N processes on this machine ('auto': one per core); output identical "
                          "to one process."),
        click.option("--scheduler", default=None, envvar="BRAINPAINTER_SCHEDULER", metavar="ADDRESS",
                     help="Render on a Dask cluster, e.g. tcp://host:8786 (default: "
                          "$BRAINPAINTER_SCHEDULER); needs pip install 'brainpainter[cluster]'."),
    ]):
        f = opt(f)
    return f


def parse_size(size: str) -> tuple[int, int]:
    """``"1200x900"`` -> ``(1200, 900)``."""
    try:
        w, h = (int(x) for x in str(size).lower().replace("×", "x").split("x"))
    except ValueError:
        raise BrainPainterError(f"--size must be WIDTHxHEIGHT, e.g. 1200x900; {size!r} was given.") from None
    return w, h


def render_kwargs(options: dict[str, Any]) -> dict[str, Any]:
    """Pop the render and input options from `options` and return API keyword arguments.

    ``--size`` becomes ``width``/``height`` and ``--transparent`` a ``None``
    background; everything else keeps its name.
    """
    names = (*RENDER_OPTION_NAMES, *INPUT_OPTION_NAMES, *PARALLEL_OPTION_NAMES)
    out = {name: options.pop(name) for name in names if name in options}
    if "size" in out:
        out["width"], out["height"] = parse_size(out.pop("size"))
    if out.pop("transparent", False):
        out["background"] = None
    if "hide" in out:
        out["hide"] = list(out["hide"])
    return out
