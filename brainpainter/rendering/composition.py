"""The layers of a region run, each with its colour scale: region values, then tract values.

:func:`run_layers` is where a run's scales are made (:func:`run_scale` over all rows): the first
layer's from the plain scale options and its own, a later layer's from its own options
(:class:`~brainpainter.rendering.layers.LayerOptions`) or, given none, the first layer's shared.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.scale import ColourScale, ScaleOptions, widen
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.options import Options
from brainpainter.table.region_table import RegionTable
from brainpainter.tracts.values import TractValues


def run_layers(options: Options, table: RegionTable, tract_values: TractValues | None,
               tracts_only: bool) -> tuple[Layer, ...]:
    """The layers of a region run: its region values (unless it has bundle values only), then tract values.

    The first layer's scale is made from the plain scale options (``--cmap``, ``--vmin``, ...) and
    its own (``--regions-cmap``, ...) over its values and those of every layer sharing it; a tract
    layer given options of its own (``--tracts-cmap``, ``--tracts-vmin``, ...) gets a scale of its
    own over its values alone (a gradient given no range spans them: FA 0.3-0.7, not levels 0-3).
    """
    data: dict[str, NDArray[Any]] = {}
    if not tracts_only:
        data["regions"] = table.values
    if tract_values is not None:
        data["tracts"] = tract_values.values
    kinds = list(data)
    own = {kind: options.layers.scale_options(kind, options.scale, k == 0) for k, kind in enumerate(kinds)}
    first_options = own[kinds[0]]
    assert first_options is not None
    shared = np.concatenate([np.ravel(data[kind]) for kind in kinds if kind == kinds[0] or own[kind] is None])
    profiles = tract_values is not None and any(n > 1 for _, n in tract_values.nodes)
    first_scale = run_scale(first_options, shared, tracts_only and profiles)
    layers = []
    for k, kind in enumerate(kinds):
        mine = own[kind]
        scale = first_scale if k == 0 or mine is None else run_scale(mine, data[kind], kind == "tracts")
        layers.append(Layer(kind, scale, 1.0, layer_label(options, kind, table),
                            own_scale=k == 0 or mine is not None))
    return tuple(layers)


def layer_label(options: Options, kind: str, table: RegionTable) -> str:
    """A layer's colour-bar label: as given (``--tracts-label``), else the name of what it was read from."""
    given = options.layers.label(kind)
    if given is not None:
        return given
    if kind == "tracts":
        scene = options.scene
        if scene.tract_value is not None:
            return scene.tract_value
        if isinstance(scene.tract_values, str | Path):
            return Path(scene.tract_values).name
        if table.regions:  # bundle columns beside region columns in one table
            return f"{Path(table.source).name} (tracts)"
    return Path(table.source).name if table.source else kind


def run_scale(options: ScaleOptions, values: NDArray[Any], measures: bool) -> ColourScale:
    """The colour scale of a run whose values (all rows) are `values`, shape any.

    `measures`: the values are measures along tracts (profiles alone, FA 0.2-0.7, MD 0.0007), not
    BrainPainter's levels 0..N-1, so a gradient given no vmin/vmax spans their range.
    """
    if measures and options.cmap is None and options.vmin is None and options.vmax is None \
            and options.center is None:
        finite = np.asarray(values, dtype=float)[np.isfinite(values)]
        if finite.size:
            lo, hi = float(finite.min()), float(finite.max())
            lo, hi = widen(lo) if hi <= lo else (lo, hi)
            options = replace(options, vmin=lo, vmax=hi)
    return options.scale(values)
