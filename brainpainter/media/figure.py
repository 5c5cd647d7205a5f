"""Publication figures: renders laid out with matplotlib, with a colour bar and titles.

Two layouts share the colour bars: one per scale (the first layer's, and each later layer's with a
scale of its own, such as tract values beside region values):

* **per row** (default): each chosen input row is a line of the chosen views
  side by side (one line: a single-image figure; several: stacked, each
  labelled with its image name);
* **grid**: input rows as columns (e.g. stages 1 to 4, headed by their image
  names) and views as rows, as in BrainPainter's progression figures.

The figure is laid out at its printed size (default 7.2 in, a two-column
journal width, or 3.5 in for one or two image columns) with 8 pt text, so
fonts stay readable at column width. PNG and TIFF are written at ``dpi``;
PDF and SVG embed the renders at full resolution with text as text (TrueType
fonts in PDF). Every render is cropped to what a view shows in any row, so
images in one row or column align.

>>> from brainpainter.media.figure import make_figure
>>> make_figure("examples/brainpainter_dk.csv", atlas="dk", out="fig.pdf", grid=True,
...             views="lateral-left,medial-left", label="atrophy")   # doctest: +SKIP
"""

from __future__ import annotations

import io
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Unpack

from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.color.scale import ColourScale
from brainpainter.media.drawn import common_crop, content_box, drawn_kinds, swatches_needed
from brainpainter.media.layout import FigureKwargs, FigureLayout, FigureOptions, compose_figure, plan_grid
from brainpainter.media.outfile import check_out_file
from brainpainter.media.plain_text import quiet_glyphs
from brainpainter.media.volume_panels import PanelKwargs, PanelOptions, label_panels, volume_panels
from brainpainter.rendering.kept import is_kept, kept_painter, put_back, release
from brainpainter.rendering.layers import colorbar_layers, first_bar_label, without_regions
from brainpainter.rendering.options import Options, RenderKwargs, take
from brainpainter.rendering.parallel import SerialRunner
from brainpainter.rendering.run import make_runner, paint, prepare_run
from brainpainter.rendering.views import ImagesByView, View
from brainpainter.table.rows import select_rows

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from brainpainter.rendering.checked_run import Run
    from brainpainter.rendering.painter import Painter

__all__ = ["FigureResult", "check_out_file", "common_crop", "compose_figure", "content_box", "figure_bytes",
           "make_figure", "save_figure", "select_rows"]

FIGURE_FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg", ".tif": "tiff", ".tiff": "tiff"}
VECTOR_FORMATS = ("pdf", "svg")


class MakeFigureKwargs(FigureKwargs, PanelKwargs, RenderKwargs, total=False):
    """The keywords of :func:`make_figure`: :class:`FigureOptions`, :class:`PanelOptions` and the run's
    options."""


# -- the job -----------------------------------------------------------------------
@dataclass
class FigureResult:
    """What :func:`make_figure` made.

    Attributes
    ----------
    figure : matplotlib.figure.Figure
    path : Path or None
        The file written (None when no `out` was given).
    scale : ColourScale
    images : dict of (str, str) to ndarray
        The renders, ``(image name, view name) -> RGBA (h, w, 4)``.
    colorbar_ax : matplotlib.axes.Axes
        The first colour bar's.
    image_axes : dict of (str, str) to Axes
        Where each render is: ``(image name, view name) -> Axes``.
    colorbar_axes : list of Axes
        Every colour bar's: the first layer's, then each later layer's with a scale of its own.
    input : dict
        How the input was read (a render manifest's ``input``: unmatched names, notes).
    """

    figure: Figure
    path: Path | None
    scale: ColourScale
    images: dict[tuple[str, str], NDArray[Any]]
    colorbar_ax: Axes
    image_axes: dict[tuple[str, str], Axes] = field(default_factory=dict)
    colorbar_axes: list[Axes] = field(default_factory=list)
    input: dict[str, Any] = field(default_factory=dict)

    def __repr__(self) -> str:
        """One short line."""
        w, h = self.figure.get_size_inches()
        where = f" written to {self.path}" if self.path is not None else ""
        return f"<FigureResult: {len(self.images)} render(s), {w:.2f} x {h:.2f} in{where}>"

    def _repr_png_(self) -> bytes:  # notebooks
        buf = io.BytesIO()
        self.figure.savefig(buf, format="png", dpi=100)
        return buf.getvalue()


def save_figure(fig: Figure, path: Path, dpi: float, transparent: bool = False) -> None:
    """Write `fig` to `path` atomically, verified; the format follows the file ending."""
    from brainpainter.io.transaction import FileTransaction

    with FileTransaction(path) as tx:
        tx.tmp.write_bytes(figure_bytes(fig, path, dpi, transparent))
        tx.commit()


def figure_bytes(fig: Figure, path: Path, dpi: float, transparent: bool = False) -> bytes:
    """`fig` encoded in the format of `path`'s ending (PNG, TIFF, PDF, SVG)."""
    import matplotlib

    from brainpainter import __version__
    fmt = FIGURE_FORMATS[path.suffix.lower()]
    software = f"brainpainter {__version__}"
    metadata: dict[str, Any] | None = {"png": {"Software": software}, "pdf": {"Creator": software},
                                       "svg": {"Creator": software}}.get(fmt)
    for ax in fig.axes:
        for im in ax.get_images():
            array = im.get_array()
            if array is not None and array.ndim == 3 and array.shape[1] > 1:
                # vector formats embed the full render; raster formats resample it smoothly
                im.set_interpolation("none" if fmt in VECTOR_FORMATS else "antialiased")
    buf = io.BytesIO()
    rc: dict[str, Any] = {"pdf.fonttype": 42, "ps.fonttype": 42, "svg.fonttype": "none",
                          "svg.hashsalt": "brainpainter"}
    extra: dict[str, Any] = {"pil_kwargs": {"compression": "tiff_lzw"}} if fmt == "tiff" else {}
    # PNG: the canvas's pixels as matplotlib draws them for a PNG, encoded by fpng (~10x faster than
    # the zlib of matplotlib's writer: 0.08 s of a 300 dpi figure of two views and four panels)
    drawn = "rgba" if fmt == "png" else fmt
    with matplotlib.rc_context(rc):  # type: ignore[arg-type]
        fig.savefig(buf, format=drawn, dpi=dpi, metadata=None if drawn == "rgba" else metadata,
                    transparent=transparent, facecolor="none" if transparent else fig.get_facecolor(),
                    **extra)
    if drawn == "rgba":
        return _png_of_rgba(buf.getvalue(), fig, dpi, metadata or {})
    return buf.getvalue()


def _png_of_rgba(raw: bytes, fig: Figure, dpi: float, metadata: dict[str, str]) -> bytes:
    """A PNG of `fig`'s canvas drawn at `dpi` (`raw`: its RGBA bytes, as ``savefig(format="rgba")``
    writes them; the canvas is ``int(inches * dpi)`` pixels each way, as Agg sizes it)."""
    import numpy as np

    from brainpainter.io.output import png_bytes

    w, h = int(fig.get_figwidth() * dpi), int(fig.get_figheight() * dpi)
    if len(raw) != w * h * 4:  # pragma: no cover - Agg sized the canvas otherwise
        raise RuntimeError(f"the figure's canvas has {len(raw)} bytes, not {w} x {h} RGBA pixels")
    return png_bytes(np.frombuffer(raw, np.uint8).reshape(h, w, 4), metadata, dpi=dpi)


#: The smallest printed height of a connectome's node labels in a figure, points (issue 44).
MIN_LABEL_PT = 7.0


def printed_labels(run: Run, image_names: list[str], figure_opts: FigureOptions) -> Run:
    """`run` with its connectome's labels tall enough to print at :data:`MIN_LABEL_PT` or more in the figure.

    The text is a share of each render's height (:func:`~brainpainter.rendering.node_labels.text_height`);
    a figure shows a render `row_h` inches tall (:func:`~brainpainter.media.layout.plan_grid`, from the
    uncropped renders: a crop only enlarges them), so the share is at least ``MIN_LABEL_PT / 72 / row_h``.
    """
    from brainpainter.rendering.node_labels import TEXT_SHARE

    connectome = run.connectome
    if connectome is None or not connectome.labelled:
        return run
    s = run.settings
    views = [v.name for v in run.views]
    grid = plan_grid(dict.fromkeys(views, s.height / s.width), image_names, views, figure_opts,
                     lambda usable: 0.0)
    share = max(TEXT_SHARE, MIN_LABEL_PT / 72.0 / min(grid.row_h))
    return replace(run, connectome=replace(connectome, label_share=share))


def line_legend(run: Run, image_axes: list[Axes], font_size: float) -> None:
    """A legend of the run's line layers (``--outline``: its atlas's borders; ``--contour``: its levels), each
    in its own colour, width and dash, in the upper right of the last image (none without lines)."""
    from matplotlib.lines import Line2D

    from brainpainter.rendering.composition import line_entries

    entries = line_entries(run.options, run.contours, run.settings)
    if not entries or not image_axes:
        return
    handles = [Line2D([], [], color=e["color"], linewidth=max(0.8, 0.6 * e["width"]),
                      linestyle="--" if e["style"] == "dashed" else "-",
                      label=(f"{e['atlas']} borders" if e["kind"] == "outline"
                             else "contour at " + ", ".join(f"{v:g}" for v in e["levels"])))
               for e in entries]
    image_axes[-1].legend(handles=handles, loc="upper right", fontsize=font_size - 1, frameon=False,
                          handlelength=2.5, borderaxespad=0.1)


def _bars(run: Run, painter: Painter, figure_opts: FigureOptions) -> tuple[FigureOptions, list[Any]]:
    """The first bar's label and the other layers' bars (scale, label) of a figure of `run`.

    A bar for tracts that no view shows (cortex views, the cortex opaque) would name what is not there.
    """
    tracts_shown = "tract" in drawn_kinds(painter.scene.geometry, run.views)
    more = [(layer.scale, layer.label) for layer in colorbar_layers(run.layers)[1:]
            if layer.kind != "tracts" or tracts_shown]
    return replace(figure_opts, label=first_bar_label(
        run.layers, figure_opts.label, run.options.layers.label(run.layers[0].kind))), more


def _with_panels(images: dict[tuple[str, str], NDArray[Any]], panels: dict[tuple[str, str], NDArray[Any]],
                 panel_opts: PanelOptions, image_names: list[str], run: Run,
                 figure_opts: FigureOptions, **bars: Any) -> FigureLayout:
    """The figure of the renders and the volume's panels (after the views, whole, labelled)."""
    from brainpainter.media.colorbar import text_color

    images.update(panels)
    names = [s.name for s in panel_opts.sections]
    background = run.settings.background
    layout = compose_figure(images, image_names, [v.name for v in run.views] + names, run.scale, figure_opts,
                            background=background, uncropped=names, **bars)
    label_panels(layout.image_axes, panel_opts, text_color(background), figure_opts.font_size - 1)
    return layout


def _legends(run: Any, layout: FigureLayout, background: Any, font_size: float) -> None:
    """A connectome's node-size legend under its bars and the line layers' legend over the views."""
    from brainpainter.media.colorbar import text_color
    from brainpainter.media.node_sizes import node_size_legend

    node_size_legend(run, layout.colorbar_axes, text_color(background), font_size)
    line_legend(run, list(layout.image_axes.values()), font_size)


def _rendered(run: Run, painter: Painter, checked: Options, plan: list[tuple[int, View]], progress: bool,
              on_progress: Callable[[int, int], None] | None) -> dict[tuple[str, str], NDArray[Any]]:
    """The renders of `plan`, by (image, view); the kept painter (:mod:`brainpainter.rendering.kept`)
    stays open for the next figure unless a render failed."""
    from tqdm.auto import tqdm

    table = run.table
    runner = make_runner(painter, run.options.scene.template, checked.runner, n_items=len(plan))
    keep = is_kept(painter) and isinstance(runner, SerialRunner)
    runner.start()
    try:
        with tqdm(total=len(plan), unit="img", desc="rendering", disable=not progress) as bar:
            images: dict[tuple[str, str], NDArray[Any]] = ImagesByView()
            for (i, view), pixels in paint(run, runner, plan):
                images[(table.images[i], view.name)] = pixels
                bar.update(1)
                if on_progress is not None:
                    on_progress(len(images), len(plan))
    except BaseException:
        if keep:  # a renderer that failed is not drawn with again
            release()
        raise
    finally:
        if keep:
            put_back(painter)
        else:
            runner.close()
    return images


@quiet_glyphs
def make_figure(data: Any, atlas: Atlas | str | None = None, *, out: str | Path | None = None,
                rows: Iterable[str | int] | str | None = None, progress: bool = True,
                on_progress: Callable[[int, int], None] | None = None,
                **options: Unpack[MakeFigureKwargs]) -> FigureResult:
    """Render rows of a region-value table and lay them out as a figure with a colour bar.

    Parameters
    ----------
    data, atlas
        The table and its atlas, as for :func:`brainpainter.render`.
    out : path, optional
        ``.png``, ``.tif``/``.tiff`` (at `dpi`), ``.pdf`` or ``.svg`` (renders
        embedded at full resolution). Written atomically. Without it only the
        figure object is returned.
    rows : iterable of str or int, or str, optional
        Image names (or 0-based positions) to show, in that order; default all.
        The colour scale is computed over all rows of the table, not only `rows`.
    progress : bool
        Show a progress bar.
    on_progress : callable, optional
        Called as ``on_progress(images_done, n_images)`` after each image is rendered; an exception it
        raises stops the figure (nothing is written), e.g. to cancel it.
    **options
        The layout: :class:`brainpainter.media.layout.FigureOptions` (``grid``,
        ``title``, ``label``, ``ticks``, ``dpi``, ``fig_width``, ``font_size``,
        ``view_labels``); the volume's slice and glass-brain panels beside the views:
        :class:`brainpainter.media.volume_panels.PanelOptions` (``slices``, ``projections``,
        ``convention``, ``slice_outline``); and every option of a run, as for
        :func:`brainpainter.render` (:class:`brainpainter.rendering.options.Options`;
        width, height: pixels of each render).

    Returns
    -------
    FigureResult
    """
    from contextlib import nullcontext

    from brainpainter.io.transaction import FileTransaction
    from brainpainter.media.colorbar import resolve_ticks

    kwargs: dict[str, Any] = dict(options)
    figure_opts = FigureOptions(**take(kwargs, FigureOptions))
    panel_opts = PanelOptions(**take(kwargs, PanelOptions))
    path = check_out_file(out, FIGURE_FORMATS) if out is not None else None
    checked = Options.of(kwargs, "make_figure")
    run = prepare_run(data, atlas, options=checked)
    resolve_ticks(run.scale, figure_opts.ticks)
    table = run.table
    chosen = select_rows(table.images, rows)
    panels = volume_panels(data, run, panel_opts, chosen) if panel_opts.sections else {}
    run = printed_labels(run, [table.images[i] for i in chosen], figure_opts)
    serial = checked.runner.n_jobs <= 1 and not checked.runner.cluster
    plan = run.items(chosen)
    background = run.settings.background
    # the output folder is locked from before the first render until the figure is published
    with FileTransaction(path) if path is not None else nullcontext() as tx:
        # a serial figure draws with the painter kept from the figure before, where its scene is the same
        painter = kept_painter(run.painter(), run.options.scene.template) if serial else run.painter()
        images = _rendered(run, painter, checked, plan, progress, on_progress)  # the kept one put back
        nan, missing = ((False, False) if without_regions(run.layers)
                        else swatches_needed(table, chosen, run.views, painter.scene.geometry))
        figure_opts, more = _bars(run, painter, figure_opts)
        layout = _with_panels(images, panels, panel_opts, [table.images[i] for i in chosen], run, figure_opts,
                              nan=nan, missing=missing, more_bars=more)
        _legends(run, layout, background, figure_opts.font_size)
        if tx is not None and path is not None:
            tx.tmp.write_bytes(figure_bytes(layout.figure, path, figure_opts.dpi,
                                            transparent=background is None))
            tx.commit()
    assert layout.colorbar_ax is not None
    return FigureResult(layout.figure, path, run.scale, images, layout.colorbar_ax, layout.image_axes,
                        layout.colorbar_axes, table.summary())
