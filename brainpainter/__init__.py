"""brainpainter: a table of numbers per brain region -> 3D images and movies.

Importing this package is cheap: it never imports ``bpy``; renderers, atlases
and templates are loaded on first use through entry-point registries.

>>> import brainpainter
>>> brainpainter.list_atlases()
['destrieux', 'dk', 'dkt']
"""

from __future__ import annotations

# not typing's TYPE_CHECKING: importing typing (with re, enum, functools: ~20 ms on a bare Python) runs
# before the console command installs its signal handlers (brainpainter/cli/entry.py)
TYPE_CHECKING = False

__all__ = [
    "BrainPainterError",
    "Painter",
    "RenderResult",
    "RenderSettings",
    "Scene",
    "__version__",
    "export",
    "figure",
    "get_atlas",
    "list_atlases",
    "load_template",
    "make_scale",
    "movie",
    "plot",
    "project_volume",
    "read_maps",
    "read_table",
    "render",
    "to_fsaverage",
]

if TYPE_CHECKING:
    from typing import Any

    __version__: str
    from brainpainter.atlas.registry import get_atlas, list_atlases
    from brainpainter.atlas.template import load_template
    from brainpainter.color.scale import make_scale
    from brainpainter.errors import BrainPainterError
    from brainpainter.maps.inputs import maps_to_fsaverage as to_fsaverage
    from brainpainter.maps.inputs import read_maps
    from brainpainter.maps.volume import project_volume
    from brainpainter.media.export import export
    from brainpainter.media.figure import make_figure as figure
    from brainpainter.media.movie import make_movie as movie
    from brainpainter.media.plot import plot
    from brainpainter.media.scene import Scene
    from brainpainter.rendering.painter import Painter, RenderResult
    from brainpainter.rendering.run import render
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.table.region_table import read_table

# public name -> (module, attribute), imported on first use
_LAZY = {
    "BrainPainterError": ("brainpainter.errors", "BrainPainterError"),
    "Painter": ("brainpainter.rendering.painter", "Painter"),
    "RenderResult": ("brainpainter.rendering.painter", "RenderResult"),
    "RenderSettings": ("brainpainter.rendering.settings", "RenderSettings"),
    "Scene": ("brainpainter.media.scene", "Scene"),
    "export": ("brainpainter.media.export", "export"),
    "figure": ("brainpainter.media.figure", "make_figure"),
    "get_atlas": ("brainpainter.atlas.registry", "get_atlas"),
    "list_atlases": ("brainpainter.atlas.registry", "list_atlases"),
    "load_template": ("brainpainter.atlas.template", "load_template"),
    "make_scale": ("brainpainter.color.scale", "make_scale"),
    "movie": ("brainpainter.media.movie", "make_movie"),
    "plot": ("brainpainter.media.plot", "plot"),
    "project_volume": ("brainpainter.maps.volume", "project_volume"),
    "read_maps": ("brainpainter.maps.inputs", "read_maps"),
    "read_table": ("brainpainter.table.region_table", "read_table"),
    "render": ("brainpainter.rendering.run", "render"),
    "to_fsaverage": ("brainpainter.maps.inputs", "maps_to_fsaverage"),
}


def _version() -> str:
    """The installed version (read on first use: importlib.metadata takes a while to import)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("brainpainter")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"


def __dir__() -> list[str]:
    """The public names (tab completion), though most are imported only on first use."""
    return sorted({*__all__, *(name for name in globals() if name.startswith("_"))})


def __getattr__(name: str) -> Any:
    if name == "__version__":
        globals()["__version__"] = value = _version()
        return value
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'brainpainter' has no attribute {name!r}")
