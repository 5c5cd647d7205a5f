"""Schaefer 2018 (100-1000 parcels, 7 and 17 networks) and Yeo 2011 17 networks as brainpainter atlases.

Each atlas is a data folder (``data/NAME``: ``atlas.json``, ``regions.tsv`` and
a label-set overlay ``labels.json``) loaded with
:func:`brainpainter.atlas.model.load_atlas_dir`; the per-vertex parcel labels are in
``data/labels`` (one file per Schaefer scale and hemisphere, shared by the 7-
and 17-network versions, which are the same parcels). ``build_data.py`` beside
this package makes the data from the annotations.

The entry points name the module attributes ``schaefer100_7n`` ...
``schaefer1000_17n`` and ``yeo17``; each is a function returning the atlas.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from importlib import resources
from pathlib import Path

from brainpainter.atlas.model import Atlas, load_atlas_dir

DATA = Path(str(resources.files(__name__) / "data"))
#: Names of the atlases in this distribution (as the entry points register them).
ATLASES: tuple[str, ...] = tuple(json.loads((DATA / "atlases.json").read_text(encoding="utf-8")))


def load(name: str) -> Atlas:
    """The atlas `name` (one of :data:`ATLASES`)."""
    if name not in ATLASES:
        raise KeyError(f"{name!r} is not in this distribution; it has {list(ATLASES)}")
    return load_atlas_dir(DATA / name)


def __getattr__(name: str) -> Callable[[], Atlas]:
    if name in ATLASES:
        def factory() -> Atlas:
            return load(name)

        factory.__name__ = factory.__qualname__ = name
        factory.__doc__ = f"The {name} atlas."
        return factory
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
