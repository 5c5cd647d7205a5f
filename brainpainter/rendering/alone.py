"""A run without region values: what is drawn alone names the run's images and chooses its views.

Bundle values alone (a table of bundle columns, or ``--tract-values`` without INPUT), a connectome, a
volume's blobs or a plugin layer (``--layer``) can each be drawn without a region table. The run then
has an empty region table whose images are those of what is drawn: the bundle table's rows, a
series' matrices, else one image named after the file.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.registry import get_atlas
from brainpainter.layers.kinds import parse_layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.painter import VOLUME_VIEWS
from brainpainter.table.region_table import RegionTable

#: The views of a connectome, blobs or a plugin layer drawn alone: from above and from the left,
#: through the glass brain.
INSIDE_VIEWS = ("dorsal", "lateral-left")


def drawn_alone(data: Any, options: Options, tract_values: Any, bundles_only: bool, blobs: Any,
                drawn: Sequence[Any]) -> str | None:
    """What the run draws without region values: ``"tracts"`` (the table holds bundle values only),
    ``"connectome"``, ``"blobs"``, ``"drawn"`` (a plugin layer); None: it has a region table."""
    if bundles_only and tract_values is not None:
        return "tracts"
    if data is not None or tract_values is not None:
        return None
    if options.connectome.given:
        return "connectome"
    if blobs is not None:
        return "blobs"
    return "drawn" if drawn else None


def alone_source(alone: str, data: Any, options: Options) -> Any:
    """The file (or object) the images of `alone` are named after."""
    if alone == "tracts":
        return data if data is not None else options.scene.tract_values
    if alone == "connectome":
        return options.connectome.connectome
    if alone == "blobs":
        return options.scene.volume_surface
    return parse_layer(options.scene.layer[0])[1]


def empty_table(atlas: Atlas | None, source: Any, images: Sequence[str] = (),
                what: str = "connectome") -> RegionTable:
    """A region table of no regions: of `images`, else of one image named after the file `source` (or
    the file of a nibabel image; `what` where there is none)."""
    path = source if isinstance(source, str | Path) else getattr(source, "get_filename", lambda: None)()
    name = Path(path).name.split(".")[0] if path else what  # a nibabel image: its file's name
    names = tuple(images) or (name or what,)
    return RegionTable(images=names, regions=(), values=np.zeros((len(names), 0)),
                       atlas=atlas or get_atlas("dk"), source=str(path) if path else what)


def default_views(atlas: Atlas, alone: str | None) -> tuple[str, ...] | None:
    """The views of a run given none: from above and the left for what is drawn inside the glass brain
    alone; the atlas's own (:attr:`Atlas.views`); the subcortical views for a volumetric atlas (its
    structures, not a grey cortex) or bundle values alone (the views that show tracts); else None
    (BrainPainter's three)."""
    if alone in ("connectome", "blobs", "drawn"):
        return INSIDE_VIEWS
    if atlas.views:
        return atlas.views
    return VOLUME_VIEWS if alone == "tracts" or not atlas.cortical() else None
