"""Interactive 3D export: a glTF binary (``.glb``) or one self-contained HTML file.

One row of a table becomes a coloured 3D brain: one mesh per drawn region
(named by its region key, e.g. ``Left-insula``, in the region's colour), both
cortical hemispheres plus the subcortical structures, in the template's
millimetre space. The ``.glb`` opens in Blender, MeshLab, PowerPoint, or any
glTF viewer. The ``.html`` file inlines a three.js viewer (vendored in
``brainpainter/data``, MIT licence beside it) and the ``.glb``: it opens in any
browser without a network, with rotate (drag), zoom (wheel), pan (right
drag), a tooltip naming the region under the mouse and its value, toggles
for each part, and the colour bar. The page embeds the compact, quantised
``.glb`` (:mod:`brainpainter.media.glb`) gzip-compressed: a few MB.

Nothing here needs Blender: the meshes come straight from the template.
"""

from __future__ import annotations

import base64
import gzip
import html
import json
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Unpack

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.atlas.model import HEMI_PREFIX, Atlas
from brainpainter.atlas.template import Template
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.layers.vertex_map import VertexColors
from brainpainter.media.glb import RegionMesh, glb_bytes, packed
from brainpainter.rendering.layers import LayerOptions
from brainpainter.rendering.options import Options, RenderKwargs, option_names
from brainpainter.rendering.scene import Scene
from brainpainter.rendering.settings import RGB

if TYPE_CHECKING:
    from brainpainter.connectome.model import Connectome
    from brainpainter.rendering.checked_run import Run

FORMATS = ("glb", "html")
#: Colour of subcortical structures the atlas does not colour (as the Blender renderer draws them).
NEUTRAL_GREY: RGB = (0.8, 0.8, 0.8)


def _submesh(vertices: NDArray[Any], normals: NDArray[Any],
             faces: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """``(vertices, faces, normals)`` of the part of a mesh that `faces` use, renumbered."""
    used, inverse = np.unique(faces, return_inverse=True)
    return (vertices[used].astype(np.float32), inverse.reshape(faces.shape).astype(np.int32),
            normals[used])


def value_text(value: float) -> str:
    """A region's value for the viewer's tooltip, rounded for people: ``2.35``, ``-0.0012``, ``empty``."""
    if not np.isfinite(value):
        return "empty cell" if np.isnan(value) else f"{value}"
    return "0" if value == 0 else f"{value:.4g}"


def region_meshes(scene: Scene, colors: dict[str, RGB],
                  values: Mapping[str, float] | None = None) -> list[RegionMesh]:
    """Split the template of `scene` into one mesh per region, coloured by `colors`.

    Parameters
    ----------
    scene : Scene
        Template, label set, surface and hidden regions.
    colors : dict of str to (r, g, b)
        sRGB 0-1 colour of every region key (:func:`brainpainter.rendering.painter.region_colors`).
        Cortex labels without a colour join one ``{Left,Right}-medial-wall``
        mesh per hemisphere in ``scene.medial_wall_color``; subcortical
        structures without one are drawn light grey.
    values : mapping of str to float, optional
        The row's value of each region key (group values given to their
        members): the tooltip's text of each region (``no value`` for one
        without); None: no values (a map's structures).

    Returns
    -------
    list of RegionMesh
        Hidden regions and labels with no faces are left out.
    """
    template: Template = scene.template
    out: list[RegionMesh] = []

    def text(key: str) -> str | None:
        return None if values is None else value_text(values[key]) if key in values else "no value"

    for hemi in ("lh", "rh"):
        cm = template.cortex(scene.labels, hemi)
        verts = cm.vertices[scene.surface]
        normals = vertex_normals(verts, cm.faces)
        wall: list[NDArray[Any]] = []
        for i, label in enumerate(cm.label_names):
            key = HEMI_PREFIX[hemi] + label
            faces = cm.faces[cm.face_label == i]
            if key in scene.hidden or not len(faces):
                continue
            if key not in colors:
                wall.append(faces)
                continue
            out.append(RegionMesh(key, hemi, *_submesh(verts, normals, faces), colors[key], value=text(key)))
        if wall:
            out.append(RegionMesh(f"{HEMI_PREFIX[hemi]}medial-wall", hemi,
                                  *_submesh(verts, normals, np.concatenate(wall)), scene.medial_wall_color))
    sub = template.subcortical()
    normals = vertex_normals(sub.vertices, sub.faces)
    for i, key in enumerate(sub.label_names):
        faces = sub.faces[sub.face_label == i]
        if key in scene.hidden or not len(faces):
            continue
        out.append(RegionMesh(key, "subcortical", *_submesh(sub.vertices, normals, faces),
                              colors.get(key, NEUTRAL_GREY), value=text(key)))
    return out


def tract_meshes(scene: Scene, colors: dict[str, RGB]) -> list[RegionMesh]:
    """The scene's white-matter tubes (its parts of kind ``tract``), coloured per vertex by `colors`.

    Parameters
    ----------
    scene : Scene
        With ``scene.tracts`` (none: an empty list).
    colors : dict of str to (r, g, b)
        sRGB 0-1 by palette key (``tract:AF_left``, ``tract:AF_left:17``); direction
        colours need none.

    Returns
    -------
    list of RegionMesh
        One per tract part (``tracts-lh``, ``tracts-rh``, ``tracts``), part ``tracts``.
    """
    return layer_meshes(scene, colors, "tracts")


def layer_meshes(scene: Scene, colors: Mapping[str, RGB], kind: str) -> list[RegionMesh]:
    """The parts of the scene's layer of `kind` (``tracts``, ``blobs``, a plugin's), one mesh each,
    coloured per vertex by `colors` (sRGB 0-1 by palette key), as export part `kind`."""
    from brainpainter.rendering.geometry import Palette

    geometry = scene.geometry
    rgb = Palette(colors, geometry).rgb
    out = []
    for p in geometry.parts:
        if geometry.layer_of.get(p.name) != kind:
            continue
        per_vertex = rgb[p.palette_index]
        mean = per_vertex.mean(axis=0)
        out.append(RegionMesh(p.name, kind, p.vertices, p.triangles.astype(np.int32), p.normals,
                              (float(mean[0]), float(mean[1]), float(mean[2])), per_vertex))
    return out


def connectome_meshes(scene: Scene, connectome: Connectome | None,
                      colors: Mapping[str, RGB]) -> list[RegionMesh]:
    """A connectome's node spheres and edge cylinders, a mesh each, named for the viewer's tooltip.

    A node's mesh is named after the node, with its value (or category); an edge's ``A – B``
    (``A → B`` directed), with its weight. Their geometry is the scene's (parts ``nodes`` and
    ``edges``: one instance of a unit mesh per node or edge, consecutive).

    Parameters
    ----------
    scene : Scene
        With ``scene.connectome``.
    connectome : Connectome, optional
        None: an empty list.
    colors : mapping of str to (r, g, b)
        sRGB 0-1 by key (``node:i``, ``edge:k``); a node without one is drawn in the nodes' grey.

    Returns
    -------
    list of RegionMesh
        Part ``connectome``.
    """
    from brainpainter.connectome.model import edge_keys, node_keys
    from brainpainter.rendering.connectome_parts import NODE_COLOR

    if connectome is None:
        return []
    source, target, weight = connectome.edges()
    arrow = " \u2192 " if connectome.directed else " \u2013 "
    values, categories = connectome.node_values, connectome.node_categories
    shown = ([value_text(v) for v in values] if values is not None else
             list(categories) if categories is not None else [None] * connectome.n_nodes)
    about: dict[str, list[tuple[str, str, str | None]]] = {
        "node": list(zip(connectome.names, node_keys(connectome.n_nodes), shown, strict=True)),
        "edge": [(connectome.names[a] + arrow + connectome.names[b], key, value_text(w))
                 for a, b, w, key in zip(source, target, weight, edge_keys(len(weight)), strict=True)]}
    out = []
    by_key = {key: (name, value) for kind in about for name, key, value in about[kind]}
    key_of = {slot: key for key, slot in scene.geometry.slot_of.items() if key in by_key}
    for p in scene.geometry.parts:  # a hemisphere's nodes or edges (or those between): instances in order
        if p.kind not in about or not about[p.kind]:
            continue
        n = len(np.unique(p.palette_index))  # a slot each
        m, t = len(p.vertices) // n, len(p.triangles) // n  # vertices and triangles of one instance
        for k in range(n):
            key = key_of[int(p.palette_index[k * m])]
            name, value = by_key[key]
            faces = p.triangles[k * t:(k + 1) * t].astype(np.int32) - k * m
            out.append(RegionMesh(name, "connectome", p.vertices[k * m:(k + 1) * m], faces,
                                  p.normals[k * m:(k + 1) * m], colors.get(key, NODE_COLOR), value=value))
    return out


def vertex_meshes(scene: Scene, colors: VertexColors) -> list[RegionMesh]:
    """A map's meshes: each hemisphere's cortex as one mesh coloured per vertex, plus the structures.

    Parameters
    ----------
    scene : Scene
    colors : VertexColors
        One image of a map (:meth:`brainpainter.rendering.run.Run.colors` of a map run).
    """
    from brainpainter.maps.resolution import map_mesh

    out: list[RegionMesh] = []
    for hemi in ("lh", "rh"):
        cm = map_mesh(scene.template, scene.labels, hemi)
        if hemi not in colors.vertices or not len(cm.faces):
            continue
        verts = cm.vertices[scene.surface]
        out.append(RegionMesh(f"{HEMI_PREFIX[hemi]}cortex", hemi, verts.astype(np.float32),
                              np.asarray(cm.faces, np.int32), vertex_normals(verts, cm.faces),
                              scene.medial_wall_color, np.asarray(colors.vertices[hemi], np.float32)))
    return out + [m for m in region_meshes(scene, dict(colors.regions)) if m.part == "subcortical"]


def _viewer_script(name: str = "three-viewer.min.js") -> str:
    """A script of the package data: three.js (``three-viewer.min.js``) or the viewer
    (``export-viewer.js``)."""
    return (resources.files("brainpainter") / "data" / name).read_text(encoding="utf-8")


def _script_json(obj: Any) -> str:
    """JSON safe inside a <script> element."""
    return json.dumps(obj).replace("</", "<\\/")


def html_page(glb: bytes, *, title: str, meshes: Sequence[RegionMesh], background: RGB | None,
              colorbar_png: bytes | None = None, azimuth: float = 180.0,
              more_bars: Sequence[bytes] = ()) -> str:
    """One self-contained HTML page showing `glb` with three.js (no network needed).

    Parameters
    ----------
    glb : bytes
        From :func:`brainpainter.media.glb.glb_bytes` (``compact=True``, then
        :func:`brainpainter.media.glb.packed`: a page of a few MB); embedded
        gzip-compressed (the viewer inflates it with the browser's
        ``DecompressionStream``).
    title : str
        Shown in the page's corner and its title.
    meshes : sequence of RegionMesh
        For the part toggles.
    background : (r, g, b) or None
        Page background, sRGB 0-1 (None: white).
    colorbar_png : bytes, optional
        A colour bar image shown under the title.
    azimuth : float
        Start view, degrees as in :mod:`brainpainter.rendering.views` (180: from the left).
    more_bars : sequence of bytes
        The colour bars (PNG) of further layers with scales of their own, under the first.
    """
    bg = "#{:02x}{:02x}{:02x}".format(*(round(v * 255) for v in (background or (1.0, 1.0, 1.0))))
    dark = background is not None and sum(background) < 1.5
    parts = [p for p in ("lh", "rh", "subcortical", "tracts", "connectome")
             if any(m.part == p for m in meshes)]
    # what lies inside the cortex shows through it: the cortex drawn as glass
    glass = [p for p in ("lh", "rh") if p in parts and ("connectome" in parts or "blobs" in parts)]
    config = {"azimuth": azimuth, "parts": parts, "background": bg, "glass": glass}
    attrs = ['id="colorbar"', *['class="colorbar"'] * len(more_bars)]

    def b64(png: bytes) -> str:
        return base64.b64encode(png).decode()

    bar = "".join(f'<img {attr} alt="colour bar" src="data:image/png;base64,{b64(png)}">'
                  for attr, png in zip(attrs, [colorbar_png, *more_bars], strict=True)
                  if png)
    names = {"lh": "left cortex", "rh": "right cortex", "subcortical": "subcortical", "tracts": "tracts",
             "connectome": "connectome"}
    toggles = "".join(f'<label><input type="checkbox" data-part="{p}" checked> {names[p]}</label>'
                      for p in parts)
    return _PAGE.format(
        title=html.escape(title), bg=bg, fg="#eee" if dark else "#222", bar=bar, toggles=toggles,
        three=_viewer_script(), config=_script_json(config),
        glb=base64.b64encode(gzip.compress(glb, 9, mtime=0)).decode(),
        viewer=_viewer_script("export-viewer.js"),
    )


_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="brainpainter">
<title>{title}</title>
<style>
html, body {{ margin: 0; height: 100%; overflow: hidden; background: {bg}; color: {fg};
  font: 14px/1.4 system-ui, -apple-system, "Segoe UI", sans-serif; }}
#view {{ position: absolute; inset: 0; }}
#panel {{ position: absolute; left: 12px; top: 10px; max-width: 60%; }}
#panel h1 {{ font-size: 16px; margin: 0 0 4px 0; font-weight: 600; }}
#panel label {{ margin-right: 10px; user-select: none; }}
#colorbar, .colorbar {{ display: block; max-width: 100%; margin: 4px 0; }}
#help {{ position: absolute; left: 12px; bottom: 8px; opacity: 0.7; font-size: 12px; }}
#tip {{ position: absolute; pointer-events: none; display: none; padding: 2px 6px; border-radius: 3px;
  background: rgba(0, 0, 0, 0.78); color: #fff; font-size: 13px; white-space: nowrap; }}
#error {{ position: absolute; left: 12px; top: 45%; display: none; color: #b00; }}
</style></head>
<body>
<div id="view"></div>
<div id="panel"><h1>{title}</h1>{bar}<div id="toggles">{toggles}
<label><input type="checkbox" id="flat"> flat colours</label></div></div>
<div id="help">drag: rotate &middot; wheel: zoom &middot; right-drag: pan &middot; double-click: reset</div>
<div id="tip"></div><div id="error"></div>
<script>{three}</script>
<script id="brainpainter-config" type="application/json">{config}</script>
<script id="brainpainter-glb" type="application/octet-stream" data-encoding="gzip">{glb}</script>
<script>{viewer}</script>
</body></html>
"""



#: The options of a run that an export uses (it renders no image: no size, views, quality or workers).
EXPORT_OPTIONS = ("template", "surface", "hide", "atlas_config", "gradient", "cmap", "vmin", "vmax", "center",
                  "nan_color", "missing_color", "background", "image_column", "value", "region_column",
                  "strict", "tracts", "tracts_space", "tracts_affine", "max_streamlines", "tract_values",
                  "tract_value", "tract_radius", "lh", "rh", "volume", "projection", "projection_radius",
                  "underlay", "underlay_contrast", "threshold", "outline", "outline_threshold", "space",
                  "frames", "lh_surface", "rh_surface", *option_names(LayerOptions),  # each layer's own scale
                  "connectome", "nodes", "node_values", "node_categories", "directed", "edge_threshold",
                  "top_edges", "edges_of", "nodes_space", "volume_surface", "min_cluster_mm3", "layer",
                  "layer_opt")


def _row_meshes(run: Run, i: int) -> tuple[Scene, list[RegionMesh]]:
    """The scene of a run and the meshes of its row `i`: a map's cortex coloured per vertex, or
    the regions, then the tracts' tubes, a connectome's nodes and edges, the blobs."""
    from brainpainter.connectome.series import image_connectome
    from brainpainter.layers.connectome import connectome_colors
    from brainpainter.rendering.painter import load_scene

    opts = run.options.scene
    atlas_obj, scene = load_scene(run.table.atlas, opts.template, opts.surface, opts.hide,
                                  layers=run.scene_layers())
    shown = None if run.connectome is None else image_connectome(run.connectome, i)  # a series: row i's
    inside = connectome_meshes(scene, shown, connectome_colors(shown, run.layers)
                               if shown is not None else {})  # a connectome's nodes and edges
    colors = run.colors(i)
    for layer in run.drawn:  # a volume's clusters, plugin layers: their parts, per vertex on their bar
        inside += layer_meshes(scene, colors, layer.kind)
    if run.coloring == "vertices":  # the cortex coloured per vertex: one mesh per hemisphere
        cortex = vertex_meshes(scene, colors)  # type: ignore[arg-type]
    else:  # one mesh per region, its value in the tooltip
        cortex = region_meshes(scene, dict(colors), atlas_obj.expand(run.table.row(i)))
    return scene, cortex + tract_meshes(scene, dict(colors)) + inside


def export(data: Any, out: str | Path, *, format: str | None = None, row: str | int | None = None,
           atlas: Atlas | str | None = None, title: str | None = None, label: str | None = None,
           **options: Unpack[RenderKwargs]) -> Path:
    """Write one row of a table as an interactive 3D brain: ``.glb`` or self-contained ``.html``.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        As for :func:`brainpainter.render`.
    out : path
        File to write (its folder is created). Written atomically.
    format : {"glb", "html"}, optional
        Default: from the suffix of `out`.
    row : str or int, optional
        Image name (or 0-based position) of the row; needed when the table has
        several rows.
    atlas : str or Atlas, optional
        As for :func:`brainpainter.render`.
    title : str, optional
        HTML heading; default the row's image name.
    label : str, optional
        Colour-bar label in the HTML page (its first bar's: one per scaled layer, each labelled).
    **options
        The options of :data:`EXPORT_OPTIONS`, as for :func:`brainpainter.render`
        (:class:`brainpainter.rendering.options.Options`); the colour scale spans
        all rows; `background` is the HTML page's.

    Returns
    -------
    Path
        The file written.
    """
    from brainpainter.io.output import atomic_write_bytes
    from brainpainter.rendering.run import prepare_run
    from brainpainter.table.rows import select_rows

    out = Path(out)
    fmt = (format or out.suffix.lstrip(".")).lower()
    if fmt not in FORMATS:
        raise choice_error("format", format or out.suffix or str(out), FORMATS,
                           "Give --format, or an --out file ending in .glb or .html.")
    extra = sorted(set(options) - set(EXPORT_OPTIONS))
    if extra:
        raise TypeError(f"export() got an unexpected keyword argument {extra[0]!r}")
    checked = Options.of(options, "export")
    run = prepare_run(data, atlas, options=checked)
    table = run.table
    if row is None and len(table.images) > 1:
        shown = list(table.images[:8]) + (["..."] if len(table.images) > 8 else [])
        raise BrainPainterError(f"the table has {len(table.images)} rows {shown}; export draws one: "
                                f"choose it with --row (row= in Python), e.g. --row {table.images[-1]}")
    i = select_rows(table.images, [0 if row is None else row], what="--row")[0]
    scene, meshes = _row_meshes(run, i)
    if not meshes:
        raise BrainPainterError("every region is hidden (--hide); nothing is left to export.")
    if fmt == "glb":
        payload = glb_bytes(meshes)
    else:
        from brainpainter.io.output import png_bytes
        from brainpainter.media.colorbar import colorbar_image
        from brainpainter.media.drawn import swatches_needed
        from brainpainter.rendering.layers import colorbar_layers, first_bar_label
        from brainpainter.rendering.views import parse_views

        views = (run.views if run.coloring == "vertices"
                 else parse_views("lateral-left,medial-right,subcortical"))
        nan, missing = swatches_needed(table, [i], views, scene.geometry)
        layers = colorbar_layers(run.layers)
        label = first_bar_label(run.layers, label, run.options.layers.label(run.layers[0].kind))
        bars = [colorbar_image(layer.scale, (420, 64 if lb else 48), background=run.settings.background,
                               label=lb, fontsize=9.0, **({"nan": nan, "missing": missing} if k == 0 else {}))
                for k, (layer, lb) in enumerate(zip(layers, [label, *(la.label for la in layers[1:])],
                                                    strict=True))]
        payload = html_page(packed(glb_bytes(meshes, compact=True)), title=title or table.images[i],
                            meshes=meshes, background=run.settings.background,
                            colorbar_png=png_bytes(bars[0]),
                            more_bars=[png_bytes(b) for b in bars[1:]]).encode("utf-8")
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(out, payload)
    return out
