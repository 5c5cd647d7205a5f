"""A run: a table read and every option checked (:func:`prepare_run`), then its images painted.

:func:`prepare_run` is the one place where a command's input and options are
checked, before anything is rendered or written: ``render``, ``figure``,
``movie``, ``plot``, ``export`` and the web API all start with it.
:func:`render` paints every chosen row from every view and writes PNGs plus a
manifest (or returns the images in memory).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Unpack

from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.registry import get_atlas, load_atlas_config
from brainpainter.errors import BrainPainterError
from brainpainter.layers.readers import first_layer_kind
from brainpainter.rendering.checked_run import Run
from brainpainter.rendering.composition import line_entries
from brainpainter.rendering.options import GROUPS, Options, RenderKwargs, RunnerOptions, option_names
from brainpainter.rendering.painter import Painter, RenderResult, resolve_hidden
from brainpainter.rendering.parallel import LocalRunner, PainterSpec, Runner, SerialRunner, chunked
from brainpainter.rendering.views import ImagesByView, View
from brainpainter.table.rows import select_rows

if TYPE_CHECKING:
    from brainpainter.io.transaction import FolderTransaction


def resolve_atlas(atlas: Atlas | str | None, atlas_config: str | Path | None) -> Atlas | None:
    """The atlas object of `atlas` (a name) or `atlas_config` (a region-group TOML file), if any."""
    if atlas_config is not None:
        if atlas is not None:
            raise BrainPainterError("give an atlas or an atlas config (--atlas-config), not both; the "
                                    "config's [atlas] base names the atlas it groups.")
        return load_atlas_config(atlas_config)
    return get_atlas(atlas) if isinstance(atlas, str) else atlas


def prepare_run(data: Any, atlas: Atlas | str | None = None, *, options: Options | None = None,
                **kwargs: Unpack[RenderKwargs]) -> Run:
    """Read the input and check every option, before anything is rendered or written.

    Used by every command (render, figure, movie, plot, export, the web API).
    Cheap option errors come first, so they do not wait for a big input file.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table`; a map (``{"lh": array, "rh": array}``,
        or ``lh=``/``rh=`` options): :func:`brainpainter.maps.inputs.read_maps`. The readers
        (:func:`brainpainter.layers.readers.first_layer_kind`) say which kind of first layer it is.
    atlas : str or Atlas, optional
        Inferred from the region names when not given.
    options : Options, optional
        The options, already checked; else made from `kwargs`.
    **kwargs
        The options as flat keywords, see :class:`~brainpainter.rendering.options.Options`.
    """
    from brainpainter.rendering.maprun import prepare_map_run
    from brainpainter.rendering.region_run import prepare_region_run

    if options is None:
        options = Options.of(kwargs, "prepare_run")
    atlas_obj = resolve_atlas(atlas, options.scene.atlas_config)
    prepare = {"map": prepare_map_run, "regions": prepare_region_run}
    return prepare[first_layer_kind(data, options.maps.given)](data, atlas_obj, options)


def layer_summaries(painter: Painter) -> dict[str, Any]:
    """Each scene layer's manifest entry by its kind: ``tracts`` (what was drawn of the tractograms:
    subsampling notes), ``connectome`` (its nodes and the edges drawn), ``blobs``, plugin layers'."""
    return {layer.kind: layer.summary() for layer in painter.scene.layers}


def make_runner(painter: Painter, template: Any = None, options: RunnerOptions | None = None,
                n_items: int | None = None) -> Runner:
    """The runner for a run's options: serial, local processes, or Dask.

    Parameters
    ----------
    painter : Painter
        The run's painter (not loaded; a serial runner loads it).
    template : str or Template, optional
        What the caller gave as the template (a name travels as a name).
    options : RunnerOptions, optional
        Where to render (default: serially, in this process).
    n_items : int, optional
        Images (or frames) to paint: no more local workers than that are started.
    """
    options = options or RunnerOptions()
    n = options.n_jobs
    if n_items is not None:
        n = min(n, max(1, n_items))
    if options.cluster:
        from brainpainter.rendering.cluster import DaskRunner

        return DaskRunner(spec=PainterSpec.of(painter, template), client=options.client,
                          address=options.scheduler)
    if n > 1:
        return LocalRunner(n_workers=n, spec=PainterSpec.of(painter, template))
    return SerialRunner(painter=painter)


# -- render ---------------------------------------------------------------------------------
def render(data: Any = None, atlas: Atlas | str | None = None, *, out: str | Path | None = None,
           painter: Painter | None = None, rows: Iterable[str | int] | str | None = None,
           progress: bool = True, **options: Unpack[RenderKwargs]) -> RenderResult:
    """Render every row of a region-value table from every view.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table` (several inputs are merged by image name).
        A map instead: ``{"lh": array, "rh": array}``, or None with ``lh=``/``rh=`` files
        (:func:`brainpainter.maps.inputs.read_maps`, docs/maps.md).
    atlas : str or Atlas, optional
        ``"dk"``, ``"destrieux"``, ``"dkt"`` (alias ``"tourville"``) or a plugin atlas;
        inferred from the region names when not given.
    out : path, optional
        Output folder for ``{image}_{view}.png`` and ``manifest.json``. Without
        it the images are returned in memory (``result.images``).
    painter : Painter, optional
        A loaded painter to draw with (it stays open): no new scene is built, so
        a notebook renders table after table without reloading Blender. Its
        atlas is the default `atlas`, and its template, surface, hidden regions,
        renderer and image settings are used; giving one of those that differs
        from the painter's is an error.
    rows : iterable of str or int, or a comma-separated str, optional
        Image names (or 0-based positions) to render, in that order; default all
        rows. The colour scale is computed over all rows either way.
    progress : bool
        Show a progress bar.
    **options
        Every option of a run, as keywords: see :class:`brainpainter.rendering.options.Options`
        (``views``, ``template``, ``surface``, ``hide``, ``renderer``, ``atlas_config``;
        ``gradient``, ``cmap``, ``vmin``, ``vmax``, ``center``, ``nan_color``,
        ``missing_color``; ``width``, ``height``, ``background``, ``quality``,
        ``shading``, ``lighting``, ``glass_opacity``; ``image_column``, ``value``,
        ``region_column``, ``strict``; ``jobs``, ``client``, ``scheduler``).

    Returns
    -------
    RenderResult
    """
    checked = Options.of(options, "render")
    if painter is not None:
        atlas = painter.atlas if atlas is None and checked.scene.atlas_config is None else atlas
        checked = painter_options(painter, checked)
    # Validate everything before the first image so bad input leaves nothing behind.
    run = prepare_run(data, atlas, options=checked)
    chosen = select_rows(run.table.images, rows)
    own = painter is None
    if painter is None:
        painter = run.painter()
    elif painter.scene.coloring != run.coloring:
        raise BrainPainterError(
            f"the painter colours {painter.scene.coloring} but the data is "
            f"{'a map' if run.coloring == 'vertices' else 'a region table'}; make a Painter for it "
            "(brainpainter.Painter(coloring='vertices') draws maps).")
    elif checked.maps.surfaces and str(run.options.scene.template) != str(painter.scene.template.path):
        raise BrainPainterError(
            f"the maps are drawn on your own surfaces (lh_surface/rh_surface), but the painter draws "
            f"template {painter.scene.template.name!r}; leave out painter= (or the surfaces).")
    elif painter.atlas.name != run.table.atlas.name:  # type: ignore[union-attr]
        raise BrainPainterError(
            f"the table was read with atlas {run.table.atlas.name!r} but the painter draws "
            f"{painter.atlas.name!r}; give atlas= the painter's atlas, or make a Painter for this one.")  # type: ignore[union-attr]
    for view in (v for v in run.views if v.clip):  # a cut that leaves nothing: an error before any output
        painter.scene.geometry.visible(view)
    runner = make_runner(painter, run.options.scene.template, checked.runner,
                         n_items=len(chosen) * len(run.views))
    # The renderer (or every worker's) starts before any output exists: one that cannot start leaves none.
    runner.start()
    try:
        files, images, manifest = write_images(run, painter, runner, chosen, out, progress)
    finally:
        if own or not isinstance(runner, SerialRunner):  # a painter given by the caller stays open
            runner.close()
    return RenderResult(files, images, manifest, run.scale, run.table, runner.summary(), run.layers)


def painter_options(painter: Painter, options: Options) -> Options:
    """`options` with the painter's scene and image settings; an error where they were given otherwise."""
    defaults, own = Options(), Options(settings=painter.scene.settings)
    own_scene = {"template": painter.scene.template.name, "surface": painter.surface,
                 "renderer": painter.renderer}
    clash = [name for name in ("template", "surface", "renderer")
             if getattr(options.scene, name) != getattr(defaults.scene, name)
             and getattr(options.scene, name) != own_scene[name]]
    assert isinstance(painter.atlas, Atlas)
    if options.scene.hide and resolve_hidden(options.scene.hide, painter.atlas) != painter.scene.hidden:
        clash.append("hide")
    clash += [name for name in option_names(GROUPS["settings"])
              if getattr(options.settings, name) != getattr(defaults.settings, name)
              and getattr(options.settings, name) != getattr(own.settings, name)]
    if clash:
        raise BrainPainterError(
            f"render(painter=...) draws with the painter's scene and image settings, but {clash} "
            "were also given with other values; leave them out, or make a Painter with them "
            "(brainpainter.Painter(atlas, settings=RenderSettings(...)))."
        )
    scene = replace(options.scene, template=painter.scene.template, surface=painter.surface,
                    renderer=painter.renderer)
    return replace(options, scene=scene, settings=painter.scene.settings, size_given=True)


def run_settings(run: Run, painter: Painter) -> dict[str, Any]:
    """The settings of a run as the manifest and every PNG's metadata record them."""
    lines = line_entries(run.options, run.contours)
    return {
        "atlas": run.table.atlas.name, "template": painter.scene.template.name, "surface": painter.surface,
        "views": [v.to_dict() for v in run.views], "scale": run.scale.to_dict(),
        "layers": [layer.to_dict() for layer in run.layers], **({"lines": lines} if lines else {}),
        "hidden": sorted(painter.scene.hidden), "renderer": painter.renderer, **run.settings.to_dict(),
    }


def png_metadata(image: str, view: View, settings: Mapping[str, Any]) -> dict[str, str]:
    """The PNG text chunks of one image."""
    from brainpainter import __version__

    return {"Software": f"brainpainter {__version__}", "brainpainter:image": image,
            "brainpainter:view": view.name, "brainpainter:settings": json.dumps(settings, sort_keys=True)}


def write_images(run: Run, painter: Painter, runner: Runner, chosen: Sequence[int], out: str | Path | None,
                 progress: bool) -> tuple[list[Path], dict[tuple[str, str], NDArray[Any]], dict[str, Any]]:
    """Paint the chosen rows from every view; write them to `out` (a transaction) or keep them.

    Returns
    -------
    files : list of Path
    images : dict of (str, str) to ndarray of uint8, shape (h, w, 4)
        Empty when written to files.
    manifest : dict
    """
    from brainpainter import __version__
    from brainpainter.io.output import safe_name
    from brainpainter.io.transaction import FolderTransaction

    table, settings = run.table, run_settings(run, painter)
    names = [safe_name(n) for n in table.images]  # distinct, even ignoring case: checked by read_table
    plan = run.items(chosen)
    tx = FolderTransaction(out) if out is not None else None  # lock, stage, verify, publish
    files = [tx.out / f"{names[i]}_{view.name}.png" for i, view in plan] if tx is not None else []
    images: dict[tuple[str, str], NDArray[Any]] = ImagesByView()
    with tx or nullcontext(), progress_bar(len(plan), progress) as bar:
        painted = paint(run, runner, plan, settings if tx is not None else None)
        if tx is None:
            for (i, view), pixels in painted:
                images[(table.images[i], view.name)] = pixels
                bar.update(1)
        else:
            write_pngs(tx, painted, names, lambda i, view: png_metadata(table.images[i], view, settings),
                       (run.settings.width, run.settings.height), bar)
        summary = table.summary()
        if run.tract_values is not None:
            summary["tract_values"] = run.tract_values.summary()
        manifest = {
            "software": {"brainpainter": __version__}, "input": summary, "settings": settings,
            "files": [{"file": path.name, "image": table.images[i], "row": i, "view": view.name}
                      for path, (i, view) in zip(files, plan, strict=False)],
        }
        manifest.update(layer_summaries(painter))
        if tx is not None:
            tx.commit(manifest)  # verify every PNG, then publish them and the manifest last
    return files, images, manifest


def paint(run: Run, runner: Runner, plan: Sequence[tuple[int, View]],
          settings: Mapping[str, Any] | None = None) -> Iterator[tuple[tuple[int, View], Any]]:
    """The one paint loop: ``((row, view), image)`` for each of `plan`.

    The image is an RGBA uint8 array of shape (h, w, 4), in the order of
    `plan`; or, when `settings` (the PNG metadata's) is given and the runner
    is not serial, the PNG bytes a worker process encoded, in the order they
    finish (a serial run encodes in a writer thread instead).
    """
    encode = settings is not None and not isinstance(runner, SerialRunner)
    chunks = chunked(plan, runner.chunk_size(len(plan)))
    items = ([run.item(i, view, png_metadata(run.table.images[i], view, settings) if encode and settings
                       else None) for i, view in chunk] for chunk in chunks)
    for index, results in runner.map(items, ordered=not encode, encode=encode):
        yield from zip(chunks[index], results, strict=True)


class _NoBar:
    """What :func:`progress_bar` gives when no bar is shown (tqdm not imported)."""

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def update(self, n: int = 1) -> None:
        """Count nothing."""


def progress_bar(total: int, show: bool) -> Any:
    """A tqdm bar over `total` images, or with `show` false a silent stand-in: ``tqdm.auto`` takes
    ~25 ms CPU to import (its asyncio part), a fortieth of a one-image run's start-up."""
    if not show:
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="img", desc="rendering")


def write_pngs(tx: FolderTransaction, painted: Iterable[tuple[tuple[int, View], Any]], names: Sequence[str],
               metadata: Callable[[int, View], dict[str, str]], size: tuple[int, int], bar: Any) -> None:
    """Write painted images (arrays or PNG bytes) of ``(row, view)`` into the transaction's folder."""
    from brainpainter.io.output import PngWriter, atomic_write_bytes

    with PngWriter() as writer:
        for (i, view), image in painted:
            name = f"{names[i]}_{view.name}.png"
            if isinstance(image, bytes):  # the workers' PNG files: the bytes a serial run writes
                atomic_write_bytes(tx.path(name), image)
            else:
                writer.submit(tx.path(name), image, metadata(i, view))
            tx.expect(name, size=size)
            bar.update(1)
        writer.wait()
