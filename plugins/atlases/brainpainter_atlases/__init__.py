"""The built-in atlases (DK, Destrieux, DKT) and the default fsaverage template.

Registered through the ``brainpainter.atlases`` and ``brainpainter.templates``
entry points exactly like a third-party plugin. Each atlas is a data
directory under ``data/`` (``atlas.json`` + ``regions.tsv``, made by the
template builder from FreeSurfer's colour tables) plus the shared
``data/aseg.tsv`` of subcortical structures.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from brainpainter.atlas.model import Atlas, load_atlas_dir

_DATA = resources.files(__name__) / "data"


def _load(name: str) -> Atlas:
    return load_atlas_dir(Path(str(_DATA / name)))


def dk() -> Atlas:
    """Desikan-Killiany (FreeSurfer ``aparc``): 34 cortical regions per hemisphere."""
    return _load("dk")


def destrieux() -> Atlas:
    """Destrieux (FreeSurfer ``aparc.a2009s``): 74 cortical regions per hemisphere."""
    return _load("destrieux")


def dkt() -> Atlas:
    """Desikan-Killiany-Tourville (DKT40): 31 cortical regions per hemisphere."""
    return _load("dkt")


def fsaverage_template() -> Path:
    """Directory of the bundled fsaverage template."""
    return Path(str(resources.files(__name__) / "templates" / "fsaverage"))
