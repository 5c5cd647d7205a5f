"""The layers of a run, each with its colour scale: region values, then tract values or a map over them.

:func:`run_layers` is where a run's scales are made (:func:`run_scale` over all rows): the first
layer's from the plain scale options and its own, a later layer's from its own options
(:class:`~brainpainter.rendering.layers.LayerOptions`) or, given none, the first layer's shared.
:class:`RegionsBelow` gives a map run its region values underneath, per vertex.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import HEMI_PREFIX
from brainpainter.color.scale import ColourScale, ScaleOptions, widen
from brainpainter.errors import BrainPainterError
from brainpainter.maps.inputs import VertexMaps
from brainpainter.maps.layers import map_scale
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.painter import region_colors
from brainpainter.rendering.settings import RGB
from brainpainter.table.region_table import RegionTable
from brainpainter.tracts.values import TractValues


def run_layers(options: Options, table: RegionTable, tract_values: TractValues | None,
               tracts_only: bool, others: Sequence[str] = ()) -> tuple[Layer, ...]:
    """The layers of a region run: its region values (unless it has bundle values only), then tract values.

    The first layer's scale is made from the plain scale options (``--cmap``, ``--vmin``, ...) and
    its own (``--regions-cmap``, ...) over its values and those of every layer sharing it; a tract
    layer given options of its own (``--tracts-cmap``, ``--tracts-vmin``, ...) gets a scale of its
    own over its values alone (a gradient given no range spans them: FA 0.3-0.7, not levels 0-3).
    `others`: the kinds the run draws besides (a map over the regions); options of a layer it does
    not draw are refused.
    """
    data: dict[str, NDArray[Any]] = {}
    if not tracts_only:
        data["regions"] = table.values
    if tract_values is not None:
        data["tracts"] = tract_values.values
    kinds = list(data)
    options.layers.check_drawn([*kinds, *others])
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


@dataclass
class RegionsBelow:
    """Region values under a map (``render table.csv --lh ... --rh ...``): each vertex its region's colour.

    Attributes
    ----------
    table : RegionTable
    scale : ColourScale
        The region layer's.
    vertex_region : dict of str to ndarray of int, shape (n_hemi,)
        Per hemisphere, the index into `keys` of each drawn vertex's region (-1: none, the underlay).
    keys : tuple of str
        Region keys (``Left-insula``).
    """

    table: RegionTable
    scale: ColourScale
    vertex_region: dict[str, NDArray[Any]]
    keys: tuple[str, ...]

    @classmethod
    def of(cls, table: RegionTable, scale: ColourScale, meshes: Mapping[str, Any]) -> RegionsBelow:
        """From the meshes the map is drawn on (:func:`brainpainter.maps.resolution.map_mesh`, by hemisphere):
        a vertex takes the label of a face it is on (faces are labelled whole)."""
        keys: list[str] = []
        vertex_region = {}
        for hemi, mesh in meshes.items():
            names = [HEMI_PREFIX[hemi] + name for name in mesh.label_names]
            index = np.full(len(names) + 1, -1, np.int64)  # the last: no label
            for i, key in enumerate(names):
                if key in table.atlas.keys:
                    if key not in keys:
                        keys.append(key)
                    index[i] = keys.index(key)
            label = np.full(len(mesh.source_vertex), len(names), np.int64)
            faces = np.asarray(mesh.faces, np.int64)
            label[faces.ravel()] = np.repeat(np.asarray(mesh.face_label, np.int64), faces.shape[1])
            vertex_region[hemi] = index[label]
        return cls(table, scale, vertex_region, tuple(keys))

    def colors(self, row: int) -> tuple[dict[str, RGB], dict[str, NDArray[Any]]]:
        """Row `row`'s colours: every region key's, and each drawn vertex's (NaN: none), float32 (n, 3)."""
        regions = region_colors(self.table.row(row), self.table.atlas, self.scale)
        rgb = np.array([regions[k] for k in self.keys] + [(np.nan, np.nan, np.nan)], np.float32)
        return regions, {hemi: rgb[idx] for hemi, idx in self.vertex_region.items()}


def map_layers(options: Options, maps: VertexMaps, table: RegionTable | None, meshes: Mapping[str, Any],
               others: Sequence[str] = ()) -> tuple[tuple[Layer, ...], RegionsBelow | None]:
    """The layers of a map run: the map alone, or region values (`table`) with the map over them.

    The map's scale is its own (``--map-cmap``, ...; else the automatic scale of a map,
    :func:`brainpainter.maps.layers.map_scale`); drawn over region values it covers them by
    ``--map-alpha``. `meshes` are the meshes the map is drawn on, by hemisphere; `others` the
    kinds the run draws besides (a connectome's edges and nodes).
    """
    given = options.layers.label("map")
    label = given if given is not None else Path(maps.source).name or "map"
    alpha = float(options.layers.map_alpha)
    threshold = options.maps.threshold
    options.layers.check_drawn([*(["map"] if table is None else ["regions", "map"]), *others])
    if table is None:
        own = options.layers.scale_options("map", options.scale, first=True)
        assert own is not None
        return (Layer("map", map_scale(own, maps, threshold), alpha, label),), None
    if maps.n_images not in (1, len(table.images)):
        raise BrainPainterError(
            f"a map drawn over region values has one image, or one per row of the table; the map has "
            f"{maps.n_images} and the table {len(table.images)} rows ({table.source}). Give a map of one "
            "image, or as many as the table's rows.")
    regions = run_layers(options, table, None, False, others=("map", *others))[0]
    own = options.layers.scale_options("map", options.scale, first=False)
    plain = ScaleOptions(nan_color=options.scale.nan_color, missing_color=options.scale.missing_color)
    scale = map_scale(own if own is not None else plain, maps, threshold)
    return (regions, Layer("map", scale, alpha, label)), RegionsBelow.of(table, regions.scale, meshes)
