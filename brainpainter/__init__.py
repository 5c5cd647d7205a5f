"""brainpainter: a table of numbers per brain region -> 3D images and movies.

Importing this package is cheap: it never imports ``bpy``; renderers, atlases
and templates are loaded on first use through entry-point registries.

>>> import brainpainter
>>> brainpainter.list_atlases()
['destrieux', 'dk', 'dkt']
"""

from __future__ import annotations

import sys
import types
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

try:
    __version__ = version("brainpainter")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "BrainPainterError",
    "Painter",
    "RenderResult",
    "RenderSettings",
    "__version__",
    "export",
    "figure",
    "get_atlas",
    "list_atlases",
    "load_template",
    "make_scale",
    "movie",
    "plot",
    "read_table",
    "render",
]

if TYPE_CHECKING:
    from brainpainter.atlas import get_atlas, list_atlases
    from brainpainter.colormap import make_scale
    from brainpainter.errors import BrainPainterError
    from brainpainter.figure import make_figure as figure
    from brainpainter.inputs import read_table
    from brainpainter.interactive import export
    from brainpainter.movie import make_movie as movie
    from brainpainter.plotting import plot
    from brainpainter.render import Painter, RenderResult, render
    from brainpainter.scene import RenderSettings
    from brainpainter.template import load_template

# public name -> (module, attribute), imported on first use
_LAZY = {
    "BrainPainterError": ("brainpainter.errors", "BrainPainterError"),
    "Painter": ("brainpainter.render", "Painter"),
    "RenderResult": ("brainpainter.render", "RenderResult"),
    "RenderSettings": ("brainpainter.scene", "RenderSettings"),
    "export": ("brainpainter.interactive", "export"),
    "figure": ("brainpainter.figure", "make_figure"),
    "get_atlas": ("brainpainter.atlas", "get_atlas"),
    "list_atlases": ("brainpainter.atlas", "list_atlases"),
    "load_template": ("brainpainter.template", "load_template"),
    "make_scale": ("brainpainter.colormap", "make_scale"),
    "movie": ("brainpainter.movie", "make_movie"),
    "plot": ("brainpainter.plotting", "plot"),
    "read_table": ("brainpainter.inputs", "read_table"),
    "render": ("brainpainter.render", "render"),
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'brainpainter' has no attribute {name!r}")


class _Package(types.ModuleType):
    """The package module, keeping ``brainpainter.render`` (and figure, movie, export) callable.

    Importing a submodule binds it on its package: ``import brainpainter.render``
    would otherwise replace the function ``brainpainter.render`` by the module
    of the same name (``TypeError: 'module' object is not callable`` on the
    next call). A submodule that shares its name with a public function binds
    that function instead; the submodule stays importable by its full name.
    """

    def __setattr__(self, name: str, value: Any) -> None:
        target = _LAZY.get(name)
        if isinstance(value, types.ModuleType) and target is not None and value.__name__ == target[0]:
            value = getattr(value, target[1])
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
