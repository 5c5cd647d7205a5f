"""A run whose first layer is a per-vertex map (:mod:`brainpainter.maps`), painted through the one loop.

:func:`prepare_map_run` reads the maps (any input :func:`brainpainter.maps.inputs.read_maps`
takes) and builds the same :class:`~brainpainter.rendering.run.Run` as a region table's, whose first
layer is :class:`~brainpainter.layers.vertex_map.MapColors`: its painter draws a per-vertex scene
(``coloring="vertices"``) and its items carry :class:`~brainpainter.layers.vertex_map.VertexColors`.
So ``render``, ``--jobs`` and Dask paint maps exactly as they paint tables.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.surfaces import Surface, read_surfaces, surface_template
from brainpainter.atlas.template import Template, load_template
from brainpainter.connectome.series import check_images
from brainpainter.errors import BrainPainterError
from brainpainter.layers.kinds import open_layers
from brainpainter.layers.over import over_layers
from brainpainter.layers.readers import is_map_data
from brainpainter.layers.vertex_map import MapColors
from brainpainter.maps.flat import check_flat, flat_labels, flat_sheet
from brainpainter.maps.inputs import VertexMaps, read_maps
from brainpainter.maps.outlines import mesh_edges
from brainpainter.maps.resolution import map_mesh, own_vertex_count
from brainpainter.rendering.blob_layers import blob_kinds, blob_layer, drawn_blobs, load_blobs
from brainpainter.rendering.checked_run import Run
from brainpainter.rendering.composition import cortex_for, line_layers, map_layers
from brainpainter.rendering.connectome_layers import connectome_kinds, connectome_layers
from brainpainter.rendering.options import Options
from brainpainter.rendering.painter import flat_aspect
from brainpainter.rendering.settings import with_aspect
from brainpainter.rendering.sulc import convexity
from brainpainter.rendering.tract_run import given_tract_values
from brainpainter.rendering.views import parse_views, with_clip
from brainpainter.table.region_table import RegionTable, read_table

#: Default views of a map run: both hemispheres, outside and inside.
MAP_VIEWS = "lateral-left,medial-left,lateral-right,medial-right"


@dataclass
class MapTable:
    """What a map run has where a region run has its table: image names, the atlas, a summary."""

    maps: VertexMaps
    atlas: Atlas
    below: RegionTable | None = None  # region values under the map: its rows are the images

    @property
    def images(self) -> list[str]:
        return list(self.maps.images if self.below is None else self.below.images)

    @property
    def regions(self) -> list[str]:
        """Every region key: a map leaves no region without a colour (no "missing" swatch)."""
        return list(self.atlas.keys)

    @property
    def values(self) -> NDArray[Any]:
        """No NaN region values (a map's NaN vertices show the underlay): zeros, (images, regions)."""
        return np.zeros((len(self.images), len(self.atlas.keys)))  # a table's rows under a map of one image

    def summary(self) -> dict[str, Any]:
        return self.maps.summary() if self.below is None else {**self.maps.summary(),
                                                               "table": self.below.summary()}


def prepare_map_run(data: Any, atlas: Atlas | None, options: Options) -> Run:
    """Read the maps and check the options of a map run (as ``prepare_run`` does for a table)."""
    from brainpainter.atlas.registry import get_atlas

    table = None
    if data is not None and not is_map_data(data):  # a region table, the map drawn over its colours
        table = read_table(data, atlas, **options.table.kwargs())
        data, atlas = None, table.atlas
    m = options.maps
    outline = options.maps.outline
    contours, settings = line_layers(options, "a map over region values",
                                     None if table is None else (table.atlas.name,))
    # --outline ATLAS: the map is drawn on that atlas's mesh, whose vertices carry its labels
    atlas_obj = get_atlas(outline) if outline is not None else atlas if atlas is not None else get_atlas("dk")
    surfaces = options.maps.surfaces
    if surfaces:  # the user's own surfaces: the run's template, maps of their vertex counts drawn as they are
        if table is not None or options.maps.contour is not None:
            raise BrainPainterError("--lh-surface/--rh-surface draw per-vertex maps (--lh/--rh) on your own "
                                    "surfaces; a region table is drawn on the template's regions and "
                                    "--contour on fsaverage: leave the surfaces out, or give maps alone.")
        read = _own_surfaces(options, surfaces)
        maps = read_maps(data, m.lh, m.rh, m.volume, space=m.space, frames=m.frames,
                         mesh={hemi: s.n_vertices for hemi, s in read.items()})
        folder = surface_template(read, atlas_obj.template_labels)  # written only for maps that fit
        options = replace(options, scene=replace(options.scene, template=str(folder)))
    template = options.scene.template
    tpl = template if isinstance(template, Template) else load_template(template)
    # a template made from another surface than fsaverage's family (a subject's, the user's) takes maps of
    # that surface's vertex count, drawn as they are
    own = {hemi: n for hemi in ("lh", "rh") if (n := own_vertex_count(tpl, hemi)) is not None}
    if not surfaces:
        maps = read_maps(data, m.lh, m.rh, m.volume, space=m.space, frames=m.frames, projection=m.projection,
                         radius=m.projection_radius, mesh=own or None)
    labels = atlas_obj.template_labels if atlas_obj.template_labels in tpl.label_sets else "dk"
    meshes = {hemi: map_mesh(tpl, labels, hemi) for hemi in ("lh", "rh")}
    views = options.scene.views if options.scene.views is not None else _map_views(maps, surfaces, options)
    view_list = with_clip(parse_views(views if isinstance(views, str) else list(views)), options.scene.clips)
    source_vertex = {hemi: np.asarray(m.source_vertex) for hemi, m in meshes.items()}
    edges = ({hemi: mesh_edges(m.faces) for hemi, m in meshes.items()} if options.maps.outline_threshold
             else None)
    masks = {hemi: surface_masks(tpl, labels, meshes[hemi], n) for hemi, n in own.items()} if own else None
    scene = options.scene
    tract_values = given_tract_values(scene)
    connectome = options.connectome.load(atlas_obj if atlas is None else atlas, tpl, options.scene.surface)
    check_images(connectome, maps.n_images, "the maps have")
    blobs = load_blobs(options)
    drawn = open_layers(options.scene.layer, options.scene.layer_opt)
    layers, below = map_layers(options, maps, table, meshes, tract_values,
                               others=(*connectome_kinds(connectome), *blob_kinds(blobs)))
    # what is drawn inside the brain (a connectome, blobs, a plugin's layer) over the map: it stays opaque
    settings = cortex_for(settings, cortex_values=True, tracts=bool(options.scene.tracts),
                          connectome=connectome is not None or blobs is not None or bool(drawn))
    layers += connectome_layers(options, connectome, first=False) if connectome is not None else ()
    layers += (blob_layer(options, blobs, first=False),) if blobs is not None else ()
    layers += tuple(layer.layer() for layer in drawn)
    drawn = (*drawn_blobs(blobs, layers), *drawn)
    flat = flat_edges = None
    if any(v.content == "flat" for v in view_list):  # the flat maps: fsaverage's templates only
        check_flat(tpl, labels)
        flat = {hemi: flat_sheet(hemi).nearest for hemi in ("lh", "rh")}
        if edges is not None:
            flat_edges = {hemi: mesh_edges(flat_sheet(hemi).faces) for hemi in flat}
        if below is not None:
            below = below.on_flat({hemi: flat_labels(tpl, labels, hemi) for hemi in flat},
                                  {hemi: tpl.cortex(labels, hemi).label_names for hemi in flat})
    depth = {hemi: np.asarray(m.sulc) for hemi, m in meshes.items() if getattr(m, "sulc", None) is not None}
    if not options.size_given and (aspect := flat_aspect(view_list)):  # flat maps: wider than a brain
        settings = with_aspect(settings, aspect)
    map_layer = next(layer for layer in layers if layer.kind == "map")
    base = MapColors(maps, atlas_obj, map_layer.scale, map_layer.opacity, options.maps, source_vertex, edges,
                     depth, masks, flat, flat_edges, below)
    map_table = MapTable(maps, atlas_obj, table)
    return Run(map_table, layers[0].scale, view_list, settings, options, base,
               over_layers(layers, map_table.images, tract_values, connectome, drawn), layers, tract_values,
               contours, connectome, blobs, drawn)


def _map_views(maps: VertexMaps, surfaces: dict[str, Any], options: Options) -> str:
    """The views of a map run whose views were not given: both hemispheres (a volume also colours the
    subcortical structures; tracts show in the subcortical view), or one hemisphere's of a map of one."""
    if len(surfaces) == 1:  # one surface of your own: the views of its hemisphere
        side = "left" if "lh" in surfaces else "right"
        return f"lateral-{side},medial-{side}"
    if len(maps.values) == 1 and not maps.regions:  # one hemisphere's map (--lh alone): its side
        side = "left" if "lh" in maps.values else "right"
        return f"lateral-{side},medial-{side}" + (",subcortical" if options.scene.tracts else "")
    return MAP_VIEWS + (",subcortical" if maps.regions or options.scene.tracts else "")


def _own_surfaces(options: Options, surfaces: dict[str, Any]) -> dict[str, Surface]:
    """The user's surfaces read (:mod:`brainpainter.atlas.surfaces`), once the options allow them."""
    if options.scene.surface != "pial":
        raise BrainPainterError(
            f"--surface {options.scene.surface} picks one of the template's surfaces; with --lh-surface/"
            "--rh-surface your own surface file is drawn: give the inflated one there (lh.inflated, "
            "*.inflated.surf.gii) and leave out --surface.")
    if options.scene.tracts:
        raise BrainPainterError("--tracts are placed on the fsaverage template, not on your own surfaces "
                                "(--lh-surface/--rh-surface); leave out one or the other.")
    return read_surfaces(surfaces)


def surface_masks(template: Template, labels: str, mesh: Any, n: int) -> dict[str, NDArray[Any]]:
    """The ``cortex``, ``sulc`` and ``curv`` masks of the `n`-vertex surface a template was made from.

    At the vertices the template's mesh keeps (its ``source_vertex``), from its
    ``sulc`` and the ``cortex`` and ``curv`` arrays found beside the user's
    surface (:mod:`brainpainter.atlas.surfaces`); without them every vertex is
    cortex and the deeper half of the mesh by
    :func:`~brainpainter.rendering.sulc.convexity` is a sulcus.

    Returns
    -------
    dict of str to ndarray of bool, shape (n,)
    """
    entry = template.manifest["labels"][labels]["cortex"][mesh.hemi]
    z = template._npz(template.manifest["labels"][entry.get("base", labels)]["cortex"][mesh.hemi]["file"])
    sv = np.asarray(mesh.source_vertex, np.int64)
    if mesh.sulc is not None:
        deep = np.asarray(mesh.sulc) > 0
    else:
        depth = convexity(mesh.vertices["pial"], mesh.faces)
        deep = depth > np.median(depth)
    kept = {"cortex": np.asarray(z["cortex"]) > 0 if "cortex" in z else np.ones(len(sv), bool), "sulc": deep,
            "curv": np.asarray(z["curv"]) > 0 if "curv" in z else deep}
    out = {}
    for name, mask in kept.items():
        out[name] = np.zeros(n, bool)
        out[name][sv] = mask
    return out

