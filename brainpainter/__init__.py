"""brainpainter: a table of numbers per brain region -> 3D images and movies.

Importing this package is cheap: it never imports ``bpy``; renderers, atlases
and templates are loaded on first use through entry-point registries.

>>> import brainpainter
>>> brainpainter.list_atlases()
['destrieux', 'dk', 'dkt']
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

try:
    __version__ = version("brainpainter")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "BrainPainterError",
    "__version__",
    "get_atlas",
    "list_atlases",
    "load_template",
    "make_scale",
    "read_table",
    "render",
]

if TYPE_CHECKING:
    from brainpainter.atlas import get_atlas, list_atlases
    from brainpainter.colormap import make_scale
    from brainpainter.errors import BrainPainterError
    from brainpainter.inputs import read_table
    from brainpainter.render import render
    from brainpainter.template import load_template

_LAZY = {
    "BrainPainterError": "brainpainter.errors",
    "get_atlas": "brainpainter.atlas",
    "list_atlases": "brainpainter.atlas",
    "load_template": "brainpainter.template",
    "make_scale": "brainpainter.colormap",
    "read_table": "brainpainter.inputs",
    "render": "brainpainter.render",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'brainpainter' has no attribute {name!r}")
