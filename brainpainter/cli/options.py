"""Click options shared by the commands that render: atlas, views, colours, image settings.

The options are generated from their one definition, the option dataclasses
(:mod:`brainpainter.rendering.options`): flag names, defaults, choices and help
come from their fields. ``@render_options`` adds the options of ``brainpainter
render``; :func:`render_kwargs` turns the values click passes into keyword
arguments of :func:`brainpainter.render`, :func:`brainpainter.media.figure.make_figure`
and :func:`brainpainter.media.movie.make_movie`. ``@input_options`` adds how tables
are read (``--image-column``, ``--value``, ``--region-column``, ``--strict``).
No heavy package (bpy, matplotlib, pandas) is imported here.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import fields
from typing import Any, TypeVar

import click

from brainpainter.cli.params import FINITE, split_commas
from brainpainter.color.scale import ScaleOptions
from brainpainter.connectome.options import ConnectomeOptions
from brainpainter.maps.options import MapOptions
from brainpainter.rendering.layers import LayerOptions
from brainpainter.rendering.options import DEFAULT_VIEWS, RunnerOptions, SceneOptions
from brainpainter.rendering.settings import RenderSettings, parse_size
from brainpainter.table.options import TableOptions

__all__ = ["DEFAULT_SIZE", "DEFAULT_VIEWS", "FINITE", "field_option", "input_options", "make_render_options",
           "option_group", "parallel_options", "parse_size", "render_kwargs", "render_options",
           "split_commas"]

F = TypeVar("F", bound=Callable[..., Any])

DEFAULT_SIZE = RenderSettings().size

#: Names of the parameters added by ``render_options`` (click's Python names).
RENDER_OPTION_NAMES = (
    "atlas", "views", "template", "surface", "gradient", "cmap", "vmin", "vmax", "center", "nan_color",
    "missing_color", "hide", "background", "transparent", "size", "quality", "shading", "lighting",
    "glass_opacity", "cortex", "outline_width", "outline_color", "outline_style", "contour_width",
    "contour_color", "contour_style", "renderer", "atlas_config", "tracts",
    "tracts_space", "tracts_affine", "max_streamlines", "tract_values", "tract_value", "tract_radius",
    "connectome", "nodes", "node_values", "node_categories", "directed", "edge_threshold", "top_edges",
    "edges_of", "nodes_space", "node_labels", "node_labels_top", "node_labels_per_category",
    "volume_surface", "min_cluster_mm3", "clip", "layer", "layer_opt",
    *(f.name for f in fields(LayerOptions)),
)
INPUT_OPTION_NAMES = ("image_column", "value", "region_column", "strict")
PARALLEL_OPTION_NAMES = ("jobs", "scheduler")
MAP_OPTION_NAMES = ("lh", "rh", "volume", "projection", "projection_radius", "underlay", "underlay_contrast",
                    "threshold", "outline", "outline_threshold", "space", "frames", "lh_surface",
                    "rh_surface", "contour", "contour_levels")


def field_option(cls: type, name: str, *decls: str, **overrides: Any) -> Callable[[F], F]:
    """A click option made from field `name` of the options dataclass `cls`.

    The flag (``--nan-color``), default, choices, help and type (finite
    numbers for floats, a flag for booleans) come from the field; `overrides`
    are click keywords that the field cannot say (``multiple``, ``envvar``...).
    """
    f = next(f for f in fields(cls) if f.name == name)
    meta = f.metadata
    default = meta.get("cli_default", f.default)
    kwargs: dict[str, Any] = {"default": default, "help": meta.get("help") or None}
    kind = str(f.type)
    if "choices" in meta:
        kwargs["type"] = click.Choice(list(meta["choices"]), case_sensitive=False)  # fslr is fsLR
    elif kind == "bool":
        kwargs["is_flag"] = True
    elif kind in ("int", "int | None"):
        kwargs["type"] = int
    elif kind in ("float", "float | None"):
        kwargs["type"] = FINITE
    if default is not None and default is not False and default != ():
        kwargs["show_default"] = True
    kwargs.update(overrides)
    return click.option(*decls or ("--" + name.replace("_", "-"),), **kwargs)


def option_group(cls: type, names: Sequence[str] | None = None,
                 **overrides: dict[str, Any]) -> Callable[[F], F]:
    """A decorator adding the options of `cls` (those of `names`, in that order) as click options."""
    chosen = list(names) if names is not None else [f.name for f in fields(cls)
                                                     if f.init and f.metadata.get("cli", True)]
    return stack([field_option(cls, name, **overrides.get(name, {})) for name in chosen])


def stack(options: Sequence[Callable[[F], F]]) -> Callable[[F], F]:
    """One decorator applying `options` so that they show in this order in ``--help``."""
    def decorate(f: F) -> F:
        for opt in reversed(options):
            f = opt(f)
        return f

    return decorate


def render_option_list(views: str | None = None, size: str = DEFAULT_SIZE) -> dict[str, Any]:
    """The render options by Python name (see :data:`RENDER_OPTION_NAMES`), as click options."""
    scene, scale, settings = SceneOptions, ScaleOptions, RenderSettings
    return {
        "atlas": click.option("--atlas", "-a", default=None,
                              help="Atlas: dk, destrieux, dkt (alias tourville) or a plugin atlas. "
                                   "Default: inferred from the region names."),
        "views": field_option(scene, "views", default=views),
        "template": field_option(scene, "template"),
        "surface": field_option(scene, "surface"),
        **{name: field_option(scale, name) for name in ("gradient", "cmap", "vmin", "vmax", "center",
                                                         "nan_color", "missing_color")},
        "hide": field_option(scene, "hide", multiple=True, callback=split_commas, default=(),
                             show_default=False),
        "background": field_option(settings, "background"),
        "transparent": click.option("--transparent", is_flag=True, help="Transparent background."),
        "size": click.option("--size", default=None, metavar="WIDTHxHEIGHT", help=(
            f"Size of each rendered view in pixels [default: {size}; an atlas of another shape, such "
            "as the mouse, reshapes it to as many pixels]."), callback=_check_size),
        **{name: field_option(settings, name)
           for name in ("quality", "shading", "lighting", "glass_opacity", "cortex")},
        "outline_width": field_option(settings, "outline_width", metavar="PX", show_default=False),
        "outline_color": field_option(settings, "outline_color", metavar="COLOUR"),
        "outline_style": field_option(settings, "outline_style"),
        "contour_width": field_option(settings, "contour_width", metavar="PX", show_default=False),
        "contour_color": field_option(settings, "contour_color", metavar="COLOUR"),
        "contour_style": field_option(settings, "contour_style"),
        "renderer": field_option(scene, "renderer"),
        "atlas_config": field_option(scene, "atlas_config", type=click.Path(dir_okay=False)),
        "tracts": field_option(scene, "tracts", multiple=True, default=(), show_default=False,
                               type=click.Path()),
        "tracts_space": field_option(scene, "tracts_space"),
        "tracts_affine": field_option(scene, "tracts_affine", type=click.Path(dir_okay=False)),
        "max_streamlines": field_option(scene, "max_streamlines", type=click.IntRange(min=1)),
        "tract_values": field_option(scene, "tract_values", type=click.Path(dir_okay=False)),
        "tract_value": field_option(scene, "tract_value"),
        "tract_radius": field_option(scene, "tract_radius"),
        "volume_surface": field_option(scene, "volume_surface", type=click.Path(dir_okay=False),
                                       metavar="FILE"),
        "min_cluster_mm3": field_option(scene, "min_cluster_mm3", type=FINITE, metavar="MM3"),
        "clip": field_option(scene, "clip", multiple=True, default=(), show_default=False, metavar="AXIS<MM"),
        "layer": field_option(scene, "layer", multiple=True, default=(), show_default=False,
                              metavar="KIND:FILE"),
        "layer_opt": field_option(scene, "layer_opt", multiple=True, default=(), show_default=False,
                                  metavar="KIND.NAME=VALUE"),
        # several matrices, one per image: a folder, a.csv,b.csv or a glob (docs/connectomes.md)
        "connectome": field_option(ConnectomeOptions, "connectome", type=click.Path(), metavar="FILE"),
        **{name: field_option(ConnectomeOptions, name, type=click.Path(dir_okay=False), metavar="FILE")
           for name in ("nodes", "node_values", "node_categories")},
        "directed": field_option(ConnectomeOptions, "directed"),
        "edge_threshold": field_option(ConnectomeOptions, "edge_threshold", type=str, metavar="W|P%"),
        "top_edges": field_option(ConnectomeOptions, "top_edges", type=click.IntRange(min=1), metavar="K"),
        "edges_of": field_option(ConnectomeOptions, "edges_of", metavar="NODE"),
        "nodes_space": field_option(ConnectomeOptions, "nodes_space"),
        "node_labels": field_option(ConnectomeOptions, "node_labels"),
        "node_labels_top": field_option(ConnectomeOptions, "node_labels_top", type=click.IntRange(min=1),
                                        metavar="K"),
        "node_labels_per_category": field_option(ConnectomeOptions, "node_labels_per_category"),
        **{f.name: field_option(LayerOptions, f.name, **_layer_click(f.name)) for f in fields(LayerOptions)},
    }


def _layer_click(name: str) -> dict[str, Any]:
    """What click needs beyond the field for a layer's option: a metavar, or the 0..1 range of an opacity."""
    if name.endswith("_alpha"):
        return {"type": click.FloatRange(0.0, 1.0), "metavar": "0..1"}
    if name.endswith(("_vmin", "_vmax", "_center")):
        return {}
    return {"metavar": "TEXT"} if name.endswith("_label") else {"metavar": "NAME"}


def _check_size(ctx: click.Context, param: click.Parameter, value: str | None) -> tuple[int, int] | None:
    """``--size`` parsed and checked before anything runs (None when not given)."""
    return None if value is None else parse_size(value)


def make_render_options(views: str | None = None, size: str = DEFAULT_SIZE,
                        only: Sequence[str] | None = None) -> Callable[[F], F]:
    """A decorator adding the render options, with the given defaults for ``--views`` and ``--size``.

    ``--views`` not given (None) leaves the views to the run (a table's, an atlas's or a map's own).

    `only` keeps just the options of those Python names (see :data:`RENDER_OPTION_NAMES`).
    """
    options = render_option_list(views, size)
    return stack([options[name] for name in RENDER_OPTION_NAMES if only is None or name in only])


#: ``@render_options``: the render options with ``brainpainter render``'s defaults.
render_options = make_render_options()

#: ``@input_options``: how INPUT tables are read (as for ``render`` and ``check``).
input_options = option_group(TableOptions)

_MAP_COLOUR_OPTIONS = [
    field_option(MapOptions, "lh", type=click.Path(dir_okay=False), metavar="FILE"),
    field_option(MapOptions, "rh", type=click.Path(dir_okay=False), metavar="FILE"),
    field_option(MapOptions, "volume", type=click.Path(dir_okay=False), metavar="FILE"),
    field_option(MapOptions, "projection"),
    field_option(MapOptions, "projection_radius", metavar="MM"),
    field_option(MapOptions, "underlay"),
    field_option(MapOptions, "underlay_contrast"),
    field_option(MapOptions, "threshold"),
    field_option(MapOptions, "outline", metavar="ATLAS"),
    field_option(MapOptions, "outline_threshold"),
    field_option(MapOptions, "space"),
    field_option(MapOptions, "frames", metavar="ROWS"),
    field_option(MapOptions, "lh_surface", type=click.Path(dir_okay=False), metavar="FILE"),
    field_option(MapOptions, "rh_surface", type=click.Path(dir_okay=False), metavar="FILE"),
]
#: ``@map_colour_options``: what colours a map's vertices (``export``, which draws no lines).
map_colour_options = stack(_MAP_COLOUR_OPTIONS)
#: ``@map_options``: ``--lh``, ``--rh``, ``--volume``, ``--underlay``, ..., ``--contour`` (docs/maps.md).
map_options = stack([
    *_MAP_COLOUR_OPTIONS,
    field_option(MapOptions, "contour", metavar="FILE[,FILE]"),
    field_option(MapOptions, "contour_levels", metavar="V[,V...]"),
])

#: ``@parallel_options``: ``--jobs`` and ``--scheduler``, where the images are rendered.
parallel_options = stack([
    field_option(RunnerOptions, "jobs", "--jobs", "-j", default="1", type=str, metavar="N|auto"),
    field_option(RunnerOptions, "scheduler", envvar="BRAINPAINTER_SCHEDULER", metavar="ADDRESS"),
])


def tables_or_maps(inputs: Sequence[Any], kwargs: dict[str, Any]) -> Any:
    """The data of a command: INPUT tables (one, or a list), or None (maps by ``--lh/--rh/--volume``,
    ``--tract-values`` or ``--connectome`` alone). INPUT with maps: the maps are drawn over the tables'
    region colours.

    Raises
    ------
    BrainPainterError
        Neither given.
    """
    from brainpainter.errors import BrainPainterError

    maps = any(kwargs.get(name) is not None for name in ("lh", "rh", "volume", "volume_surface"))
    alone = ("tract_values", "connectome")
    if not (inputs or maps or any(kwargs.get(name) is not None for name in alone) or kwargs.get("layer")):
        raise BrainPainterError("give INPUT tables, or maps: --lh FILE and/or --rh FILE, or --volume FILE, "
                                "or tract values alone: --tract-values FILE --tracts DIR, or a connectivity "
                                "matrix: --connectome FILE, or a layer: --layer KIND:FILE.")
    if not inputs:
        return None
    return inputs[0] if len(inputs) == 1 else list(inputs)


def render_kwargs(options: dict[str, Any]) -> dict[str, Any]:
    """Pop the render and input options from `options` and return API keyword arguments.

    ``--size`` becomes ``width``/``height`` and ``--transparent`` a ``None``
    background; everything else keeps its name.
    """
    names = (*RENDER_OPTION_NAMES, *INPUT_OPTION_NAMES, *PARALLEL_OPTION_NAMES, *MAP_OPTION_NAMES)
    out = {name: options.pop(name) for name in names if name in options}
    size = out.pop("size", None)
    if size is not None:  # not given: the API's own default, reshaped by an atlas of another shape
        out["width"], out["height"] = size
    if out.pop("transparent", False):
        out["background"] = None
    if "hide" in out:
        out["hide"] = list(out["hide"])
    if "tracts" in out:
        out["tracts"] = list(out["tracts"])
    if "clip" in out:
        out["clip"] = list(out["clip"]) or None
    return out
