"""The painter: a loaded scene plus a renderer, that paints region values or colours from any view.

:class:`Painter` is the long-lived object: it loads the scene once and then
paints any number of value sets from any view. :func:`brainpainter.rendering.run.render`
drives it for a whole table and writes PNGs plus a manifest; a server, a movie
writer and a cluster worker reuse :class:`Painter` the same way.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.registry import get_atlas, load_atlas_config
from brainpainter.atlas.template import Template, load_template, template_for
from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.color.scale import ColourScale
from brainpainter.errors import choice_error
from brainpainter.layers.kinds import PartsLayer, for_template
from brainpainter.layers.regions import region_colors
from brainpainter.layers.vertex_map import VertexColors
from brainpainter.maps.outlines import Contours
from brainpainter.rendering.geometry import Palette
from brainpainter.rendering.scene import Scene
from brainpainter.rendering.settings import RGB, RenderSettings
from brainpainter.rendering.views import View
from brainpainter.table.region_table import RegionTable

# Named groups for --hide: structure names (hemisphere-free) they cover.
HIDE_GROUPS: dict[str, tuple[str, ...]] = {
    "cerebellum": ("Cerebellum-Cortex", "Cerebellum-White-Matter"),
    "ventricles": ("Lateral-Ventricle", "Inf-Lat-Vent", "3rd-Ventricle", "4th-Ventricle"),
    "brainstem": ("Brain-Stem",),
    "ventraldc": ("VentralDC",),
}


def resolve_hidden(tokens: Iterable[str], atlas: Atlas) -> frozenset[str]:
    """Region keys hidden by ``--hide`` tokens (keys, bare names or groups).

    ``Left-Hippocampus`` hides one structure, ``Hippocampus`` both, and a
    group name (``cerebellum``, ``ventricles``, ``brainstem``, ``ventraldc``)
    all of its structures.
    """
    by_name: dict[str, list[str]] = {}
    for r in atlas.regions:
        by_name.setdefault(r.name.lower(), []).append(r.key)
        by_name.setdefault(r.key.lower(), []).append(r.key)
    hidden: set[str] = set()
    for token in tokens:
        t = str(token).strip()
        if not t:
            continue
        if t.lower() in HIDE_GROUPS:
            for name in HIDE_GROUPS[t.lower()]:
                hidden.update(by_name.get(name.lower(), []))
        elif t.lower() in by_name:
            hidden.update(by_name[t.lower()])
        else:
            raise choice_error("--hide", t, [*HIDE_GROUPS, *atlas.keys],
                               "Give region names, or a group.")
    return frozenset(hidden)


#: Default views of an atlas without cortical regions (volumetric atlases).
VOLUME_VIEWS = ("subcortical", "subcortical-dorsal")


def flat_aspect(views: Iterable[View]) -> float | None:
    """Image width / height that frames the flat maps (:mod:`brainpainter.maps.flat`) of `views` when all
    are flat views (both sheets side by side: 2, the widest; one: about 1.4), else None."""
    from brainpainter.maps.flat import flat_sheet
    from brainpainter.rendering.framing import views_aspect

    views = list(views)
    if not views or any(v.content != "flat" for v in views):
        return None
    shapes = [views_aspect(np.vstack([flat_sheet(h).vertices[flat_sheet(h).used] for h in v.hemis]),
                           [(v.azimuth, v.elevation)]) for v in views]
    return float(np.exp(np.mean(np.log(shapes))))


def shown_aspect(atlas: Atlas, template: Template | str, views: Iterable[View]) -> float:
    """Image width / height that frames `atlas`'s brain in `views` (a brain of another shape than a
    human's, :attr:`Atlas.image_aspect`, drawn at no size given): its side views wide, its top view tall.
    """
    from brainpainter.rendering.framing import views_aspect

    if atlas.template_dir is not None and template == "fsaverage":
        template = str(atlas.template_dir)
    tpl = template_for(atlas, template if isinstance(template, Template) else load_template(template))
    points = [next(iter(tpl.cortex(atlas.template_labels, hemi).vertices.values()))
              for hemi in ("lh", "rh") if atlas.cortical(hemi)]
    if tpl.manifest.get("subcortical"):
        points.append(tpl.subcortical().vertices)
    if not points:
        return atlas.image_aspect or 4 / 3
    ras = np.vstack(points)[::5] @ np.asarray(tpl.to_ras, dtype=float).T
    return views_aspect(ras, [(v.azimuth, v.elevation) for v in views])


def load_scene(
    atlas: Atlas | str = "dk",
    template: Template | str = "fsaverage",
    surface: str = "pial",
    hidden: Iterable[str] = (),
    settings: RenderSettings | None = None,
    medial_wall_color: ColorLike = (0.72, 0.72, 0.72),
    atlas_config: str | Path | None = None,
    coloring: str = "regions",
    contours: Contours | None = None,
    layers: Iterable[PartsLayer] = (),
) -> tuple[Atlas, Scene]:
    """The atlas and the scene a renderer (or an exporter) draws; nothing is rendered.

    Parameters as for :class:`Painter`. A custom or plugin atlas's own label
    set is added to the template here.

    Returns
    -------
    atlas : Atlas
    scene : Scene
    """
    if atlas_config is not None:
        atlas = load_atlas_config(atlas_config)
    if isinstance(atlas, str):
        atlas = get_atlas(atlas)
    if atlas.template_dir is not None and template == "fsaverage":
        template = str(atlas.template_dir)  # an atlas with a brain of its own (volume only)
    if not isinstance(template, Template):
        template = load_template(template)
    if atlas.label_dir is not None and atlas.template_labels not in template.label_sets:
        # a custom or plugin atlas brings its own label set for this template (and volume meshes)
        template = template_for(atlas, template)
        for hemi in ("lh", "rh"):
            template.cortex(atlas.template_labels, hemi)  # fail now if it does not fit
    elif atlas.volume_dirs:  # a volumetric atlas: its meshes are the subcortical part
        template = template_for(atlas, template)
    scene = Scene(
        template=template,
        labels=atlas.template_labels,
        surface=surface,
        hidden=frozenset(atlas.expand(dict.fromkeys(resolve_hidden(hidden, atlas)))),
        settings=settings or RenderSettings(),
        medial_wall_color=to_rgb(medial_wall_color),
        coloring=coloring,
        contours=contours,
        layers=tuple(for_template(layer, template) for layer in layers),  # the tracts read for the template
    )
    return atlas, scene


@dataclass
class Painter:
    """A loaded scene plus a renderer, reused for every image.

    Parameters
    ----------
    atlas : Atlas or str
    template : Template or str
    surface : {"pial", "white", "inflated"}
    hidden : iterable of str
        ``--hide`` tokens.
    settings : RenderSettings
    renderer : str
        Name in the ``brainpainter.renderers`` registry.
    atlas_config : path, optional
        Region-group TOML file (:mod:`brainpainter.atlas.config`); replaces `atlas`.
    coloring : {"regions", "vertices"}
        ``"vertices"`` draws per-vertex maps (:attr:`brainpainter.rendering.scene.Scene.coloring`).
    contours : Contours, optional
        A second map's iso-lines (:attr:`brainpainter.rendering.scene.Scene.contours`).
    layers : iterable of PartsLayer
        What adds its own parts, in the order drawn (:attr:`brainpainter.rendering.scene.Scene.layers`):
        white-matter bundles (``TractLayer(TractSpec(...), nodes)``), a connectome's nodes and edges
        (``ConnectomeLayer``), a volume's clusters (``BlobLayer``), plugin layers (``--layer KIND:FILE``).
    """

    atlas: Atlas | str = "dk"
    template: Template | str = "fsaverage"
    surface: str = "pial"
    hidden: Iterable[str] = ()
    settings: RenderSettings = field(default_factory=RenderSettings)
    renderer: str = "blender"
    medial_wall_color: ColorLike = (0.72, 0.72, 0.72)
    atlas_config: str | Path | None = None
    coloring: str = "regions"
    contours: Contours | None = None
    layers: Iterable[PartsLayer] = ()
    _renderer: Any = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.layers = tuple(self.layers)
        self.atlas, self.scene = load_scene(self.atlas, self.template, self.surface, self.hidden,
                                            self.settings, self.medial_wall_color, self.atlas_config,
                                            self.coloring, self.contours, self.layers)
        self.template = self.scene.template
        from brainpainter.atlas import registry
        from brainpainter.rendering.pythons import require_bpy

        if self.renderer == "blender":
            require_bpy()  # where no bpy exists (Python 3.12), say which Pythons have one
        # Resolve (import) the renderer now, so a missing bpy fails before any output.
        self._renderer_class = registry.renderers.get(self.renderer)

    def load(self) -> Any:
        """Start the renderer and load the scene (once); later calls return it."""
        if self._renderer is None:
            self._renderer = self._renderer_class(self.scene)
        return self._renderer

    def paint_colors(self, colors: Mapping[str, RGB], view: View) -> NDArray[Any]:
        """Render explicit region colours (group keys colour their members); RGBA uint8, (h, w, 4).

        A :class:`~brainpainter.rendering.geometry.VertexColors` also colours each cortex vertex (a map).
        A connectome's labelled nodes get their labels drawn over the image
        (:func:`~brainpainter.rendering.node_labels.draw_node_labels`).
        """
        assert isinstance(self.atlas, Atlas)
        scene = self.scene
        vertex_rgb = colors.vertices if isinstance(colors, VertexColors) else None
        palette = Palette(self.atlas.expand(colors), lambda: scene.geometry, vertex_rgb)
        pixels: NDArray[Any] = self.load().render(palette, view)
        connectome = scene.connectome
        sides = ({part.hemi for part in scene.geometry.visible(view) if part.kind == "node"}
                 if connectome is not None and connectome.labelled else set())
        if connectome is not None and sides:
            from brainpainter.rendering.connectome_parts import node_hemis
            from brainpainter.rendering.node_labels import draw_node_labels

            hemis = node_hemis(connectome.positions)  # a lateral view: its hemisphere's nodes' labels
            shown = replace(connectome, labelled=tuple(i for i in connectome.labelled if hemis[i] in sides))
            pose = scene.geometry.camera(view, pixels.shape[1] / pixels.shape[0])
            pixels = draw_node_labels(pixels, shown, pose)
        return pixels

    def paint(self, values: Mapping[str, float], view: View, scale: ColourScale) -> NDArray[Any]:
        """Render region values through `scale`; returns RGBA uint8, shape (h, w, 4)."""
        assert isinstance(self.atlas, Atlas)
        return self.paint_colors(region_colors(values, self.atlas, scale), view)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __enter__(self) -> Painter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


#: At most this many written images are shown inline in a notebook.
MAX_SHOWN = 24


@dataclass
class RenderResult:
    """What :func:`render` made.

    Attributes
    ----------
    files : list of Path
        PNGs written (empty when no output folder was given).
    images : dict of (str, str) to ndarray
        ``(image name, view name) -> RGBA (h, w, 4)`` when rendering in memory.
    manifest : dict
    scale : ColourScale
        The colour scale of the run (for a colour bar).
    table : RegionTable
        The table as read.
    workers : dict
        Where it ran (``backend``, ``workers``, ``startup_seconds``, ``retried``);
        not part of the manifest, which is the same however the run was split.
    layers : tuple of Layer
        What was drawn, each with its colour scale (:mod:`brainpainter.rendering.layers`).
    """

    files: list[Path]
    images: dict[tuple[str, str], NDArray[Any]]
    manifest: dict[str, Any]
    scale: ColourScale | None = None
    table: RegionTable | None = None
    workers: dict[str, Any] = field(default_factory=dict)
    layers: tuple[Any, ...] = ()

    def __repr__(self) -> str:
        """One short line (the images and files are many and large)."""
        sizes = {arr.shape[1::-1] for arr in self.images.values()}
        size = "x".join(map(str, next(iter(sizes)))) if len(sizes) == 1 else "mixed"
        what = (f"{len(self.images)} image(s) of {size} in memory" if self.images
                else f"{len(self.files)} file(s)" + (f" in {self.files[0].parent}" if self.files else ""))
        return f"<RenderResult: {what}{'' if self.scale is None else f', scale {self.scale!r}'}>"

    def _repr_html_(self) -> str:  # notebooks: show the images
        import base64
        import html

        from brainpainter.io.output import png_bytes

        shown: list[tuple[str, bytes]] = [(f"{image} · {view}", png_bytes(arr))
                                          for (image, view), arr in self.images.items()]
        for path in self.files[:MAX_SHOWN - len(shown)]:  # rendered to files: show those
            if path.is_file():
                shown.append((path.name, path.read_bytes()))
        parts = [
            '<figure style="display:inline-block">'
            f'<img width="300" src="data:image/png;base64,{base64.b64encode(data).decode()}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>"
            for caption, data in shown
        ]
        if len(self.files) > len(shown):
            parts.append(f"<p>{len(self.files)} file(s) written; {len(shown)} shown</p>")
        return "".join(parts) or "<pre>no image</pre>"
