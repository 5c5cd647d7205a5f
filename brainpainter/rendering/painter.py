"""Render a region-value table to images: the main job, as a Python API.

:class:`Painter` is the long-lived object: it loads the scene once and then
paints any number of value sets from any view. ``render()`` drives it for a
whole table and writes PNGs plus a manifest. A server, a movie writer and a
cluster worker reuse :class:`Painter` the same way.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.registry import get_atlas
from brainpainter.atlas.template import Template, load_template, template_for
from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.color.scale import (
    DEFAULT_MISSING_COLOR,
    DEFAULT_NAN_COLOR,
    ColourScale,
    make_scale,
)
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.rendering.geometry import Palette
from brainpainter.rendering.scene import RGB, RenderSettings, Scene
from brainpainter.rendering.views import View, parse_views
from brainpainter.table.region_table import RegionTable, read_table

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


def region_colors(values: Mapping[str, float], atlas: Atlas, scale: ColourScale) -> dict[str, RGB]:
    """Colour of every atlas region for one image.

    Parameters
    ----------
    values : mapping of region key to float
        NaN = empty cell (``scale.nan_color``); keys absent = no data
        (``scale.missing_color``).
    """
    keys = [k for k in atlas.keys if k in values]
    colors: dict[str, RGB] = {k: scale.missing_color for k in atlas.keys}
    if keys:
        rgb = scale(np.array([values[k] for k in keys], dtype=float))
        colors.update({k: (float(c[0]), float(c[1]), float(c[2])) for k, c in zip(keys, rgb, strict=True)})
    return atlas.expand(colors)  # a region group's colour goes to each of its member regions


#: Default views of an atlas without cortical regions (volumetric atlases).
VOLUME_VIEWS = ("subcortical", "subcortical-dorsal")


def load_scene(
    atlas: Atlas | str = "dk",
    template: Template | str = "fsaverage",
    surface: str = "pial",
    hidden: Iterable[str] = (),
    settings: RenderSettings | None = None,
    medial_wall_color: ColorLike = (0.72, 0.72, 0.72),
    atlas_config: str | Path | None = None,
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
        from brainpainter.atlas.registry import load_atlas_config

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
    """

    atlas: Atlas | str = "dk"
    template: Template | str = "fsaverage"
    surface: str = "pial"
    hidden: Iterable[str] = ()
    settings: RenderSettings = field(default_factory=RenderSettings)
    renderer: str = "blender"
    medial_wall_color: ColorLike = (0.72, 0.72, 0.72)
    atlas_config: str | Path | None = None
    _renderer: Any = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.atlas, self.scene = load_scene(self.atlas, self.template, self.surface, self.hidden,
                                            self.settings, self.medial_wall_color, self.atlas_config)
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

    def paint_colors(self, colors: Mapping[str, RGB], view: View) -> np.ndarray:
        """Render explicit region colours (group keys colour their members); RGBA uint8, (h, w, 4)."""
        assert isinstance(self.atlas, Atlas)
        scene = self.scene
        palette = Palette(self.atlas.expand(colors), lambda: scene.geometry)
        return self.load().render(palette, view)

    def paint(self, values: Mapping[str, float], view: View, scale: ColourScale) -> np.ndarray:
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
    """

    files: list[Path]
    images: dict[tuple[str, str], np.ndarray]
    manifest: dict[str, Any]
    scale: ColourScale | None = None
    table: RegionTable | None = None
    workers: dict[str, Any] = field(default_factory=dict)

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


@dataclass
class Run:
    """A checked run: the table, its colour scale (fixed over all rows), views and settings."""

    table: RegionTable
    scale: ColourScale
    views: list[View]
    settings: RenderSettings


def prepare_run(
    data: Any,
    atlas: Atlas | str | None = None,
    *,
    atlas_config: str | Path | None = None,
    views: str | Sequence[str] | None = None,
    gradient: Sequence[ColorLike] | str | None = None,
    cmap: str | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    center: float | None = None,
    nan_color: ColorLike = DEFAULT_NAN_COLOR,
    missing_color: ColorLike = DEFAULT_MISSING_COLOR,
    background: ColorLike | None = "white",
    width: int = 1200,
    height: int = 900,
    quality: str = "default",
    shading: str = "default",
    lighting: str = "studio",
    glass_opacity: float = 0.12,
    image_column: str | None = None,
    value: str | None = None,
    region_column: str | None = None,
    strict: bool = False,
) -> Run:
    """Read the table and check every option, before anything is rendered or written.

    Used by :func:`render`, figures and movies alike; parameters as for :func:`render`.
    Cheap option errors come first, so they do not wait for a big input file.
    """
    if atlas_config is not None:
        if atlas is not None:
            raise BrainPainterError("give an atlas or an atlas config (--atlas-config), not both; the "
                                    "config's [atlas] base names the atlas it groups.")
        from brainpainter.atlas.registry import load_atlas_config

        atlas = load_atlas_config(atlas_config)
    if isinstance(atlas, str):
        atlas = get_atlas(atlas)
    make_scale(gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center,
               nan_color=nan_color, missing_color=missing_color)
    if views is None and isinstance(atlas, Atlas) and not atlas.cortical():
        views = VOLUME_VIEWS  # a volumetric atlas alone: its structures, not a grey cortex
    view_list = parse_views(views)
    for what, n in (("width", width), ("height", height)):
        try:
            ok = float(n) == int(n) and 16 <= int(n) <= 8192
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise BrainPainterError(f"{what} must be between 16 and 8192 pixels (a whole number); {n!r} was "
                                    "given.")
    if not 0.0 <= glass_opacity <= 1.0:
        raise BrainPainterError(f"glass opacity must be in [0, 1]; {glass_opacity} was given.")
    settings = RenderSettings(
        width=int(width), height=int(height),
        background=None if background is None else to_rgb(background),
        quality=quality, shading=shading, lighting=lighting, glass_opacity=float(glass_opacity),
    )
    table = read_table(data, atlas, image_column=image_column, value=value,
                       region_column=region_column, strict=strict)
    scale = make_scale(gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center,
                       nan_color=nan_color, missing_color=missing_color, data=table.values)
    return Run(table, scale, view_list, settings)


def render(
    data: Any,
    atlas: Atlas | str | None = None,
    *,
    out: str | Path | None = None,
    views: str | Sequence[str] | None = None,
    template: Template | str = "fsaverage",
    surface: str = "pial",
    gradient: Sequence[ColorLike] | str | None = None,
    cmap: str | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    center: float | None = None,
    nan_color: ColorLike = DEFAULT_NAN_COLOR,
    missing_color: ColorLike = DEFAULT_MISSING_COLOR,
    hide: Iterable[str] = (),
    background: ColorLike | None = "white",
    width: int = 1200,
    height: int = 900,
    quality: str = "default",
    shading: str = "default",
    lighting: str = "studio",
    glass_opacity: float = 0.12,
    renderer: str = "blender",
    image_column: str | None = None,
    strict: bool = False,
    progress: bool = True,
    value: str | None = None,
    region_column: str | None = None,
    atlas_config: str | Path | None = None,
    painter: Painter | None = None,
    rows: Iterable[str | int] | str | None = None,
    jobs: int | str = 1,
    client: Any = None,
    scheduler: str | None = None,
) -> RenderResult:
    """Render every row of a region-value table from every view.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table` (several inputs are merged by image name).
    atlas : str or Atlas, optional
        ``"dk"``, ``"destrieux"``, ``"dkt"`` (alias ``"tourville"``) or a plugin atlas;
        inferred from the region names when not given.
    out : path, optional
        Output folder for ``{image}_{view}.png`` and ``manifest.json``. Without
        it the images are returned in memory (``result.images``).
    views : str or list of str, optional
        Default: BrainPainter's ``lateral-left, medial-left, subcortical``.
    gradient, cmap, vmin, vmax, center, nan_color, missing_color
        Colour scale, see :func:`brainpainter.color.scale.make_scale`.
    hide : iterable of str
        Regions, hemisphere-free names or groups (``cerebellum``) not to draw.
    background : colour or None
        None renders a transparent background.
    image_column, value, region_column, strict
        How the table is read, see :func:`brainpainter.table.region_table.read_table`.
    atlas_config : path, optional
        Region-group TOML file (:mod:`brainpainter.atlas.config`) defining the
        atlas; give it instead of `atlas`.
    painter : Painter, optional
        A loaded painter to draw with (it stays open): no new scene is built, so
        a notebook renders table after table without reloading Blender. Its
        atlas is the default `atlas`, and its template, surface, hidden regions,
        renderer and image settings are used; giving one of those that differs
        from the painter's is an error.
    rows : iterable of str or int, or a comma-separated str, optional
        Image names (or 0-based positions) to render, in that order; default all
        rows. The colour scale is computed over all rows either way.
    jobs : int or "auto"
        Worker processes on this machine (``"auto"``: one per core), each with
        a warm renderer; the output is byte-identical to ``jobs=1``.
    client : distributed.Client, optional
        Render on this Dask cluster instead (see :mod:`brainpainter.rendering.parallel`).
    scheduler : str, optional
        A Dask scheduler address (``tcp://host:8786``) to connect to instead of `client`.

    Returns
    -------
    RenderResult
    """
    from contextlib import nullcontext

    from brainpainter import __version__
    from brainpainter.io.output import PngWriter, atomic_write_bytes, safe_name
    from brainpainter.io.transaction import FolderTransaction
    from brainpainter.rendering.parallel import Item, SerialRunner, check_options, chunked, make_runner

    if painter is not None:
        atlas = painter.atlas if atlas is None and atlas_config is None else atlas
        _check_painter_options(painter, {
            "template": template, "surface": surface, "hide": hide, "renderer": renderer,
            "background": background, "width": width, "height": height, "quality": quality,
            "shading": shading, "lighting": lighting, "glass_opacity": glass_opacity})
        ps = painter.scene.settings
        background, width, height, quality = ps.background, ps.width, ps.height, ps.quality
        shading, lighting, glass_opacity = ps.shading, ps.lighting, ps.glass_opacity
        surface, renderer = painter.surface, painter.renderer
    # Validate everything before the first image so bad input leaves nothing behind.
    check_options(jobs, client, scheduler)
    run = prepare_run(
        data, atlas, atlas_config=atlas_config, views=views, gradient=gradient, cmap=cmap, vmin=vmin,
        vmax=vmax, center=center, nan_color=nan_color, missing_color=missing_color,
        background=background, width=width, height=height, quality=quality, shading=shading,
        lighting=lighting, glass_opacity=glass_opacity, image_column=image_column, value=value,
        region_column=region_column, strict=strict,
    )
    table, scale, view_list, settings = run.table, run.scale, run.views, run.settings
    atlas = table.atlas
    names = [safe_name(n) for n in table.images]  # distinct, even ignoring case: checked by read_table
    from brainpainter.media.figure import select_rows

    chosen = select_rows(table.images, rows)
    own = painter is None
    if painter is None:
        painter = Painter(atlas, template, surface, hide, settings, renderer)
    elif painter.atlas.name != atlas.name:  # type: ignore[union-attr]
        raise BrainPainterError(
            f"the table was read with atlas {atlas.name!r} but the painter draws {painter.atlas.name!r}; "  # type: ignore[union-attr]
            "give atlas= the painter's atlas, or make a Painter for this one.")
    runner = make_runner(painter, template, jobs=jobs, client=client, scheduler=scheduler,
                         n_items=len(chosen) * len(view_list))
    # The renderer (or every worker's) starts before any output exists: one that cannot start leaves none.
    runner.start()
    try:
        tx = FolderTransaction(out) if out is not None else None  # lock, stage, verify, publish
        settings_dict = {
            "atlas": atlas.name, "template": painter.scene.template.name, "surface": surface,
            "views": [v.to_dict() for v in view_list], "scale": scale.to_dict(),
            "hidden": sorted(painter.scene.hidden), "renderer": renderer, **settings.to_dict(),
        }

        def path_meta(i: int, view: View) -> tuple[str, dict[str, str]]:
            """File name and PNG text of one image."""
            return f"{names[i]}_{view.name}.png", {
                "Software": f"brainpainter {__version__}",
                "brainpainter:image": table.images[i],
                "brainpainter:view": view.name,
                "brainpainter:settings": json.dumps(settings_dict, sort_keys=True),
            }

        plan = [(i, view) for i in chosen for view in view_list]
        files = [tx.out / path_meta(i, view)[0] for i, view in plan] if tx is not None else []
        entries = [{"file": path.name, "image": table.images[i], "row": i, "view": view.name}
                   for path, (i, view) in zip(files, plan, strict=False)]  # none without an output folder
        images: dict[tuple[str, str], np.ndarray] = {}
        size = (settings.width, settings.height)
        from tqdm.auto import tqdm

        with tx or nullcontext(), tqdm(total=len(plan), unit="img", desc="rendering",
                                       disable=not progress) as bar:
            if isinstance(runner, SerialRunner):
                with PngWriter() as writer:
                    for i, view in plan:
                        pixels = painter.paint(table.row(i), view, scale)
                        if tx is None:
                            images[(table.images[i], view.name)] = pixels
                        else:
                            name, meta = path_meta(i, view)
                            writer.submit(tx.path(name), pixels, meta)
                            tx.expect(name, size=size)
                        bar.update(1)
                    writer.wait()
            else:
                chunks = chunked(plan, runner.chunk_size(len(plan)))
                items = ([Item(region_colors(table.row(i), atlas, scale), view,
                               None if tx is None else path_meta(i, view)[1], table.images[i])
                          for i, view in chunk] for chunk in chunks)
                by_index: dict[int, list[np.ndarray]] = {}
                for index, results in runner.map(items, encode=tx is not None):
                    if tx is None:
                        by_index[index] = results
                    else:  # the workers' PNG files: the bytes a serial run writes
                        for (i, view), data in zip(chunks[index], results, strict=True):
                            name = path_meta(i, view)[0]
                            atomic_write_bytes(tx.path(name), data)
                            tx.expect(name, size=size)
                    bar.update(len(results))
                for index in sorted(by_index):
                    for (i, view), pixels in zip(chunks[index], by_index[index], strict=True):
                        images[(table.images[i], view.name)] = pixels
            manifest = {
                "software": {"brainpainter": __version__},
                "input": table.summary(),
                "settings": settings_dict,
                "files": entries,
            }
            if tx is not None:
                tx.commit(manifest)  # verify every PNG, then publish them and the manifest last
    finally:
        if own or not isinstance(runner, SerialRunner):  # a painter given by the caller stays open
            runner.close()
    return RenderResult(files, images, manifest, scale, table, runner.summary())


def _check_painter_options(painter: Painter, given: Mapping[str, Any]) -> None:
    """Refuse scene options passed to ``render(painter=...)`` that differ from the painter's own."""
    defaults = render.__kwdefaults__ or {}
    s = painter.scene.settings
    own = {"template": painter.scene.template.name, "surface": painter.surface, "renderer": painter.renderer,
           "background": s.background, "width": s.width, "height": s.height, "quality": s.quality,
           "shading": s.shading, "lighting": s.lighting, "glass_opacity": s.glass_opacity}
    clash = []
    for name, value in given.items():
        if name == "hide":
            if list(value) and frozenset(resolve_hidden(value, painter.atlas)) != painter.scene.hidden:  # type: ignore[arg-type]
                clash.append(name)
        elif name == "background":
            if value != defaults[name] and (None if value is None else to_rgb(value)) != own[name]:
                clash.append(name)
        elif value != defaults[name] and value != own[name]:
            clash.append(name)
    if clash:
        raise BrainPainterError(
            f"render(painter=...) draws with the painter's scene and image settings, but {clash} "
            "were also given with other values; leave them out, or make a Painter with them "
            "(brainpainter.Painter(atlas, settings=RenderSettings(...)))."
        )
