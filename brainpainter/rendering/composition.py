"""The layers of a run, each with its colour scale: region values, then tract values or a map over them,
then lines (an atlas's outline, a second map's contour).

:func:`run_layers` is where a run's scales are made (:func:`run_scale` over all rows): the first
layer's from the plain scale options and its own, a later layer's from its own options
(:class:`~brainpainter.rendering.layers.LayerOptions`) or, given none, the first layer's shared.
:class:`RegionsBelow` gives a map run its region values underneath, per vertex. :func:`line_layers`
is where ``--outline ATLAS`` and ``--contour FILE`` enter every run (of regions or of a map).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import HEMI_PREFIX
from brainpainter.color.scale import ColourScale, ScaleOptions, widen
from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError
from brainpainter.layers.kinds import DrawnLayer, PartsLayer
from brainpainter.layers.regions import region_colors
from brainpainter.maps.inputs import VertexMaps, read_maps
from brainpainter.maps.layers import map_scale
from brainpainter.maps.options import MapOptions
from brainpainter.maps.outlines import Contours
from brainpainter.rendering.connectome_layers import ConnectomeLayer
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.settings import RGB, RenderSettings, outlined
from brainpainter.rendering.tract_parts import TractLayer
from brainpainter.table.region_table import RegionTable
from brainpainter.tracts.values import TractValues

if TYPE_CHECKING:
    from brainpainter.connectome.model import Connectome
    from brainpainter.maps.clusters import Blobs


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

    def on_flat(self, labels: Mapping[str, NDArray[Any]], names: Mapping[str, Sequence[str]]) -> RegionsBelow:
        """These regions also under the flat maps' vertices (``flat-lh``, ``flat-rh``): `labels`, per
        hemisphere, index `names` (the map mesh's label names), shape (32492,)."""
        regions = dict(self.vertex_region)
        for hemi, label in labels.items():
            index = np.array([self.keys.index(k) if (k := HEMI_PREFIX[hemi] + n) in self.keys else -1
                              for n in names[hemi]], np.int64)
            regions[f"flat-{hemi}"] = index[np.asarray(label, np.int64)]
        return replace(self, vertex_region=regions)

    def colors(self, row: int) -> tuple[dict[str, RGB], dict[str, NDArray[Any]]]:
        """Row `row`'s colours: every region key's, and each drawn vertex's (NaN: none), float32 (n, 3)."""
        regions = region_colors(self.table.row(row), self.table.atlas, self.scale)
        rgb = np.array([regions[k] for k in self.keys] + [(np.nan, np.nan, np.nan)], np.float32)
        return regions, {hemi: rgb[idx] for hemi, idx in self.vertex_region.items()}


def map_layers(options: Options, maps: VertexMaps, table: RegionTable | None, meshes: Mapping[str, Any],
               tract_values: TractValues | None = None,
               others: Sequence[str] = ()) -> tuple[tuple[Layer, ...], RegionsBelow | None]:
    """The layers of a map run: the map alone, or region values (`table`) with the map over them;
    then tract values, if given.

    The map's scale is its own (``--map-cmap``, ...; else the automatic scale of a map,
    :func:`brainpainter.maps.layers.map_scale`); drawn over region values it covers them by
    ``--map-alpha``. `meshes` are the meshes the map is drawn on, by hemisphere. Tract values have a
    scale of their own (:func:`tract_layer`).
    `others`: the kinds the run draws besides (a connectome's edges and nodes).
    """
    given = options.layers.label("map")
    label = given if given is not None else maps.label or Path(maps.source).name or "map"
    alpha = float(options.layers.map_alpha)
    threshold = options.maps.threshold
    tracts = ["tracts"] if tract_values is not None else []
    drawn = ["map", *tracts] if table is None else ["regions", "map", *tracts]
    options.layers.check_drawn([*drawn, *others])
    if table is None:
        own = options.layers.scale_options("map", options.scale, first=True)
        assert own is not None
        layers: tuple[Layer, ...] = (Layer("map", map_scale(own, maps, threshold), alpha, label),)
        return layers + tract_layer(options, tract_values), None
    if maps.n_images not in (1, len(table.images)):
        raise BrainPainterError(
            f"a map drawn over region values has one image, or one per row of the table; the map has "
            f"{maps.n_images} and the table {len(table.images)} rows ({table.source}). Give a map of one "
            "image, or as many as the table's rows.")
    regions = run_layers(options, table, None, False, others=("map", *tracts, *others))[0]
    own = options.layers.scale_options("map", options.scale, first=False)
    plain = ScaleOptions(nan_color=options.scale.nan_color, missing_color=options.scale.missing_color)
    scale = map_scale(own if own is not None else plain, maps, threshold)
    layers = (regions, Layer("map", scale, alpha, label))
    return layers + tract_layer(options, tract_values), RegionsBelow.of(table, regions.scale, meshes)


def region_run_layers(options: Options, table: RegionTable, tract_values: TractValues | None,
                      bundles_only: bool, connectome: Connectome | None, blobs: Blobs | None,
                      alone: str | None) -> tuple[Layer, ...]:
    """A region run's layers: the table's (or, `alone`, a connectome's or blobs' first), then a
    connectome's edges and nodes, then the blobs."""
    from brainpainter.rendering.blob_layers import blob_kinds, blob_layer
    from brainpainter.rendering.connectome_layers import connectome_kinds, connectome_layers

    others = (*connectome_kinds(connectome), *blob_kinds(blobs))
    layers: tuple[Layer, ...] = ()
    if alone is None:
        layers = run_layers(options, table, tract_values, bundles_only and tract_values is not None,
                            others=others)
    else:
        options.layers.check_drawn(others)
    if connectome is not None:
        layers += connectome_layers(options, connectome, first=not layers)
    if blobs is not None:
        layers += (blob_layer(options, blobs, first=not layers),)
    return layers


def tract_layer(options: Options, tract_values: TractValues | None) -> tuple[Layer, ...]:
    """The tract values' layer of a map run (none without them), always on a scale of its own.

    A map and bundle values are two measures (thickness 2-3 mm and FA 0.3-0.7), and the map's scale
    spans the map alone: shared, every bundle took the colour of one end of the map's colour bar.
    Their scale is made from their own options (``--tracts-cmap``, ...; else the default gradient)
    over their values (a gradient given no range spans them).
    """
    if tract_values is None:
        return ()
    own = options.layers.scale_options("tracts", options.scale, first=False)
    plain = ScaleOptions(nan_color=options.scale.nan_color, missing_color=options.scale.missing_color)
    scale = run_scale(own if own is not None else plain, tract_values.values, True)
    given = options.layers.label("tracts")
    scene = options.scene
    label = given if given is not None else scene.tract_value or Path(str(scene.tract_values)).name
    return (Layer("tracts", scale, 1.0, label, own_scale=True),)


def line_layers(options: Options, drawn: str,
                outlines: Sequence[str] | None) -> tuple[Contours | None, RenderSettings]:
    """The lines of a run: ``--outline ATLAS`` (its region borders) and ``--contour FILE`` (iso-lines).

    Both are drawn at ``--outline-width`` pixels in ``--outline-color``
    (:mod:`brainpainter.rendering.borders`), over region values or a map alike.

    Parameters
    ----------
    options : Options
    drawn : str
        What the run draws, for the message about an outline it cannot draw (``a region render``).
    outlines : sequence of str, optional
        The one atlas whose borders the run can draw (a region table's: its name, its label set's);
        None: any (a map alone is drawn on the outline atlas's mesh).

    Returns
    -------
    contours : Contours or None
        The contour map on fsaverage and its levels (``regions``: the atlas's borders drawn too).
    settings : RenderSettings
        The image settings, with a line width where lines are drawn.
    """
    outline = options.maps.outline
    if outline is not None and outlines is not None and outline not in outlines:
        raise BrainPainterError(
            f"{drawn} outlines its own atlas's regions ({outlines[0]!r}); --outline {outline!r} was given. "
            f"Give --outline {outlines[0]}, or draw a map alone (--lh/--rh).")
    contours = read_contours(options.maps)
    return contours, outlined(options.settings, outline if contours is None else "contour")


def line_entries(options: Options, contours: Contours | None,
                 settings: RenderSettings | None = None) -> list[dict[str, Any]]:
    """The manifest's ``lines`` (and a figure's line legend): the outline's atlas and the contour's levels,
    each with its line as drawn (colour, width in pixels, style) where `settings` (the run's) are given."""
    outline = options.maps.outline
    entries: list[dict[str, Any]] = [{"kind": "outline", "atlas": outline}] if outline is not None else []
    entries += [{"kind": "contour", "levels": list(contours.levels)}] if contours is not None else []
    for entry in entries:
        if settings is not None:
            color, width, style = settings.line(str(entry["kind"]))
            entry.update({"color": list(color), "width": width, "style": style})
    return entries


def read_contours(options: MapOptions) -> Contours | None:
    """The second map of ``--contour`` (``FILE`` or ``LH,RH``) and its levels, on fsaverage (None without)."""
    if options.contour is None:
        return None
    given = options.contour
    parts = [p.strip() for p in given.split(",")] if isinstance(given, str) else None
    pair = parts is not None and len(parts) == 2
    try:
        maps = read_maps(None, parts[0], parts[1]) if parts is not None and pair else read_maps(given)
    except BrainPainterError as exc:  # the readers speak of --lh/--rh: say which option it was
        what = given if isinstance(given, str) else "(a map)"
        raise BrainPainterError(f"--contour {what}: {str(exc).rstrip('.')}; --contour takes one file whose "
                                "name says its hemisphere, or two: LH,RH.") from None
    if maps.n_images != 1:
        raise BrainPainterError(f"--contour takes a map of one image; {maps.source} has {maps.n_images}. "
                                "Give one image (a cluster mask, a p-map).")
    values = {hemi: np.asarray(maps.on_fsaverage(hemi, 0), np.float32) for hemi in maps.values}
    finite = np.concatenate([v[np.isfinite(v)] for v in values.values()])
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (np.nan, np.nan)
    below = -np.inf if finite.size < sum(v.size for v in values.values()) else lo  # NaN: below every level
    if not any(below < level <= hi for level in options.levels):  # an empty mask drew nothing, silently
        warnings.warn(f"--contour {maps.source}: its values are {lo:g}..{hi:g}, which no level of "
                      f"{list(options.levels)} divides, so it draws no line; give --contour-levels "
                      "between its values (a mask of 0 and 1: 0.5).", stacklevel=2)
    return Contours(values, options.levels, regions=options.outline is not None)


def cortex_for(settings: RenderSettings, *, cortex_values: bool, tracts: bool,
               connectome: bool) -> RenderSettings:
    """``--cortex auto`` resolved where the cortex carries values: opaque, in its true colours.

    A glass cortex shows its colours at ``glass_opacity`` (0.12): a thickness map or region values
    drawn as glass over white read as a few pale wisps, no longer the colours of their colour bar.
    So with tracts, ``auto`` draws glass only where the cortex carries no values (the tracts then
    show through a grey cortex); where it carries them the cortex views draw it opaque and the
    tracts show in the subcortical views (``--cortex glass`` shows them through it). A connectome
    over a cortex that carries values is drawn over the opaque cortex (its nodes and edges are drawn
    on top of every other part: the regions' or the map's colours read true around them, issue 44);
    a connectome over a cortex without values is drawn in the smooth glass brain (``hull``: the
    subcortical views' glass hulls, ~6,000 triangles, where the pial cortex as glass is ~300,000
    drawn twice and its folds crowd the nodes). Other settings are returned unchanged.
    """
    if settings.cortex != "auto":
        return settings
    if connectome and not cortex_values:
        return replace(settings, cortex="hull")
    if cortex_values and (tracts or connectome):
        return replace(settings, cortex="opaque")
    return settings


def scene_layers(options: Options, tract_values: TractValues | None, connectome: Connectome | None,
                 drawn: Sequence[DrawnLayer]) -> tuple[PartsLayer, ...]:
    """What a run adds to the scene, in the order drawn: the tracts (``--tracts``; their bundles with
    values coloured by them), a connectome's nodes and edges, then the blobs and plugin layers."""
    spec = options.scene.tract_spec()
    tracts = () if spec is None else (TractLayer(spec, tract_values.nodes if tract_values is not None else (),
                                                 options.scene.tract_radius),)
    network = () if connectome is None else (ConnectomeLayer(connectome),)
    return (*tracts, *network, *drawn)
