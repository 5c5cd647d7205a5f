"""Publication figures: renders laid out with matplotlib, with a colour bar and titles.

Two layouts share one colour scale and one colour bar:

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
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from brainpainter.color.rgb import ColorLike, to_rgb
from brainpainter.color.scale import DEFAULT_MISSING_COLOR, DEFAULT_NAN_COLOR, ColourScale
from brainpainter.errors import BrainPainterError, nearest

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from brainpainter.atlas.model import Atlas
    from brainpainter.atlas.template import Template
    from brainpainter.rendering.views import View
    from brainpainter.table.region_table import RegionTable

FIGURE_FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg", ".tif": "tiff", ".tiff": "tiff"}
VECTOR_FORMATS = ("pdf", "svg")
ONE_COLUMN_IN = 3.5  # inches; journals: 85-90 mm single column, 170-183 mm double
TWO_COLUMN_IN = 7.2


# -- shared by figures and movies ------------------------------------------------
def check_out_file(out: str | Path, suffixes: Iterable[str], what: str = "--out") -> Path:
    """Check that a file can be written at `out` without creating anything.

    Parameters
    ----------
    out : path-like
    suffixes : iterable of str
        Allowed file-name endings, e.g. ``(".png", ".pdf")``.
    what : str
        The option name used in messages.

    Returns
    -------
    Path

    Raises
    ------
    BrainPainterError
        Wrong ending, an existing folder of that name, or a folder that does not
        exist and cannot be created, or cannot be written to.
    """
    path = Path(out)
    suffixes = tuple(suffixes)
    if path.suffix.lower() not in suffixes:
        raise BrainPainterError(
            f"{what} must be a file name ending in {', '.join(suffixes)}; {str(out)!r} was given."
        )
    if path.is_dir():
        raise BrainPainterError(f"{what} {str(out)!r} is a folder; give a file name such as "
                                f"{str(path / ('figure' + suffixes[0]))!r}.")
    parent = path.parent
    ancestor = parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise BrainPainterError(
            f"{what} {str(out)!r} cannot be written: {str(ancestor)!r} is a file, not a folder; "
            "choose another path."
        )
    if parent.exists():
        import tempfile

        try:
            with tempfile.NamedTemporaryFile(dir=parent, prefix=".bp-write-test-"):
                pass
        except OSError as exc:
            raise BrainPainterError(
                f"{what} {str(out)!r} cannot be written: folder {str(parent)!r} is not writable "
                f"({exc.strerror or exc}); choose another path."
            ) from None
    elif not os.access(ancestor, os.W_OK | os.X_OK):
        raise BrainPainterError(
            f"{what} {str(out)!r} cannot be written: folder {str(ancestor)!r} is not writable; "
            "choose another path."
        )
    return path


def check_figure_text(font_size: float, fig_width: float | None) -> None:
    """Font size in 1..72 points, figure width in 1..40 inches (or None); finite numbers only."""
    try:
        ok = 1.0 <= float(font_size) <= 72.0 and (fig_width is None or 1.0 <= float(fig_width) <= 40.0)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise BrainPainterError(
            f"font size must be 1..72 points and figure width 1..40 inches; font_size={font_size}, "
            f"fig_width={fig_width} were given."
        )


def select_rows(images: Sequence[str], rows: Iterable[str | int] | str | None,
                what: str = "--rows") -> list[int]:
    """Positions of the chosen rows.

    Parameters
    ----------
    images : sequence of str
        The table's image names.
    rows : iterable of str or int, or a comma-separated str, optional
        Image names (exact, else case-insensitive), or ints as 0-based
        positions. None: every row.
    what : str
        The option's name in error messages.

    Returns
    -------
    list of int
    """
    if rows is None:
        return list(range(len(images)))
    items: list[str | int] = ([r for r in rows.split(",") if r.strip()] if isinstance(rows, str)
                              else list(rows))
    folded = {n.lower(): i for i, n in enumerate(images)}
    out: list[int] = []
    for item in items:
        if isinstance(item, int | np.integer) and not isinstance(item, bool):
            if not -len(images) <= int(item) < len(images):
                raise BrainPainterError(
                    f"row {int(item)} does not exist; the table has {len(images)} row(s) (0-based positions)."
                )
            out.append(int(item) % len(images))
            continue
        name = str(item).strip()
        if name in images:
            out.append(images.index(name))
        elif name.lower() in folded:
            out.append(folded[name.lower()])
        else:
            close = nearest(name, images)
            shown = list(images[:8]) + (["..."] if len(images) > 8 else [])
            raise BrainPainterError(
                f"{what}: {name!r} is not an image name of the table; its images are {shown}"
                + (f". Did you mean {close[0]!r}?" if close else ".")
            )
    if not out:
        raise BrainPainterError(f"no row was chosen in {rows!r}; e.g. --rows stage-1,stage-4")
    return list(dict.fromkeys(out))


def drawn_keys(atlas: Atlas, views: Sequence[View], hidden: Iterable[str] = ()) -> list[str]:
    """Region keys that some view draws: its hemispheres' cortex, or the subcortical structures."""
    from brainpainter.rendering.framing import shows

    hidden = set(hidden)
    return [r.key for r in atlas.regions if r.key not in hidden and any(
        shows(v, "cortex", r.hemi) if r.kind == "cortical" else shows(v, "subcortical", None)
        for v in views)]


def swatches_needed(table: RegionTable, rows: Sequence[int], views: Sequence[View],
                    hidden: Iterable[str] = ()) -> tuple[bool, bool]:
    """Whether the NaN colour and the missing colour appear in the drawn regions of `rows`.

    Returns
    -------
    nan, missing : bool
    """
    keys = set(drawn_keys(table.atlas, views, hidden))
    cols = [j for j, k in enumerate(table.regions) if k in keys]
    values = table.values[np.ix_(list(rows), cols)] if cols else np.zeros((0, 0))
    nan = bool(np.isnan(values).any())
    missing = bool(keys - set(table.regions))
    return nan, missing


# -- layout ------------------------------------------------------------------------
def content_box(image: np.ndarray, background: ColorLike | None, tol: int = 6) -> tuple[int, int, int, int]:
    """Rows and columns holding the brain: ``(top, bottom, left, right)``, end-exclusive.

    ``(0, 0, 0, 0)`` when the image is background only.

    Parameters
    ----------
    image : ndarray of uint8, shape (h, w, 4)
    background : colour or None
        The render's background; None: transparent (alpha decides).
    """
    alpha = image[..., 3] > 0
    if background is None:
        mask = alpha
    else:
        bg = np.round(np.array(to_rgb(background)) * 255).astype(int)
        mask = alpha & (np.abs(image[..., :3].astype(int) - bg).max(axis=-1) > tol)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return 0, 0, 0, 0
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def common_crop(images: Sequence[np.ndarray], background: ColorLike | None,
                pad: float = 0.02) -> tuple[slice, slice]:
    """One crop holding the brain in all `images` (same shape), with `pad` of the size around it.

    Images with nothing but background are ignored; when all are, nothing is cropped.
    """
    h, w = images[0].shape[:2]
    boxes = np.array([b for b in (content_box(im, background) for im in images) if b[1] > b[0]]
                     or [(0, h, 0, w)])
    p = round(pad * max(h, w))
    top, bottom = max(0, boxes[:, 0].min() - p), min(h, boxes[:, 1].max() + p)
    left, right = max(0, boxes[:, 2].min() - p), min(w, boxes[:, 3].max() + p)
    return slice(int(top), int(bottom)), slice(int(left), int(right))


def pretty_view(name: str) -> str:
    """``lateral-left`` -> ``lateral left``."""
    return name.replace("-", " ")


@dataclass
class FigureLayout:
    """The composed figure and where its parts are (for callers and tests).

    Attributes
    ----------
    figure : matplotlib.figure.Figure
    colorbar_ax : matplotlib.axes.Axes
    image_axes : dict of (str, str) to Axes
        ``(image name, view name) -> Axes``.
    """

    figure: Figure
    colorbar_ax: Axes
    image_axes: dict[tuple[str, str], Axes] = field(default_factory=dict)


def compose_figure(
    images: Mapping[tuple[str, str], np.ndarray],
    image_names: Sequence[str],
    view_names: Sequence[str],
    scale: ColourScale,
    *,
    grid: bool = False,
    title: str | None = None,
    label: str | None = None,
    ticks: Sequence[float] | str | None = None,
    dpi: float = 300.0,
    fig_width: float | None = None,
    font_size: float = 8.0,
    view_labels: bool = False,
    nan: bool = False,
    missing: bool = False,
    background: ColorLike | None = "white",
) -> FigureLayout:
    """Lay out renders, titles and a colour bar in a matplotlib figure.

    Parameters
    ----------
    images : mapping of (image name, view name) to ndarray of uint8, shape (h, w, 4)
        One render per image and view (all of one view the same shape).
    image_names, view_names : sequence of str
        Order of the rows (input) and views.
    scale : ColourScale
    grid : bool
        False: one line of views per image. True: images as columns, views as rows.
    title : str, optional
        Above everything.
    label : str, optional
        Under the colour bar, e.g. ``"z-score"``.
    ticks : sequence of float or str, optional
        Colour-bar ticks (default: the gradient's control points).
    dpi : float
    fig_width : float, optional
        Inches; default 7.2 (two journal columns), or 3.5 for one or two image columns.
    font_size : float
        Points, for column headings and the colour-bar label (ticks one point less,
        title two more).
    view_labels : bool
        Name the views (row labels in a grid, column headings otherwise).
    nan, missing : bool
        Show swatches for the NaN and missing colours.
    background : colour or None
        Figure background (and the renders'); None: transparent.

    Returns
    -------
    FigureLayout
    """
    from brainpainter.media.colorbar import colorbar_height, draw_colorbar, fit_axes, new_figure, text_color

    check_figure_text(font_size, fig_width)
    crops = {v: common_crop([images[(i, v)] for i in image_names], background) for v in view_names}
    aspect = {v: (crops[v][0].stop - crops[v][0].start) / max(1, crops[v][1].stop - crops[v][1].start)
              for v in view_names}  # height / width
    n_cols = len(image_names) if grid else len(view_names)
    width = fig_width or (TWO_COLUMN_IN if n_cols >= 3 else ONE_COLUMN_IN)
    pt = font_size / 72.0
    gap, pad = 0.04, 0.05
    color = text_color(background)
    col_heads = list(image_names) if grid else ([pretty_view(v) for v in view_names] if view_labels else [])
    row_heads = ([pretty_view(v) for v in view_names] if view_labels else []) if grid else (
        list(image_names) if len(image_names) > 1 else [])
    left = pad + (1.5 * pt if row_heads else 0.0)
    top = pad + (1.6 * (font_size + 2) / 72.0 if title else 0.0) + (1.5 * pt if col_heads else 0.0)
    usable = width - left - pad
    bar_h = 1.1 * pt  # as colorbar_figure draws it
    bottom = 0.08 + colorbar_height(scale, usable, dpi=dpi, label=label, ticks=ticks, nan=nan,
                                    missing=missing, fontsize=font_size)
    if grid:
        cw = (usable - gap * (n_cols - 1)) / n_cols
        col_w = [cw] * n_cols
        row_h = [cw * aspect[v] for v in view_names]
    else:
        inv = [1.0 / aspect[v] for v in view_names]
        rh = (usable - gap * (n_cols - 1)) / sum(inv)
        col_w = [rh * a for a in inv]
        row_h = [rh] * len(image_names)
    if min(col_w) <= 0.05:
        raise BrainPainterError(
            f"the figure is too narrow for {n_cols} image columns at {width:g} in; give a larger "
            "figure width (--fig-width) or fewer rows/views."
        )
    height = top + sum(row_h) + gap * (len(row_h) - 1) + bottom
    fig = new_figure((width, height), dpi, background)
    layout = FigureLayout(fig, None)  # type: ignore[arg-type]

    def box(x: float, y_top: float, w: float, h: float) -> tuple[float, float, float, float]:
        return x / width, (height - y_top - h) / height, w / width, h / height

    y = top
    col_x = [left + sum(col_w[:c]) + gap * c for c in range(n_cols)]
    for r, rh in enumerate(row_h):
        for c in range(n_cols):
            image, view = (image_names[c], view_names[r]) if grid else (image_names[r], view_names[c])
            ax = fig.add_axes(box(col_x[c], y, col_w[c], rh))
            rows, cols = crops[view]
            ax.imshow(images[(image, view)][rows, cols], interpolation="antialiased")
            ax.set_axis_off()
            layout.image_axes[(image, view)] = ax
        if row_heads:
            fig.text((left - 0.4 * pt) / width, 1 - (y + rh / 2) / height, row_heads[r], rotation=90,
                     ha="right", va="center", fontsize=font_size, color=color)
        y += rh + gap
    for c, head in enumerate(col_heads):
        fig.text((col_x[c] + col_w[c] / 2) / width, 1 - (top - 0.35 * pt) / height, head,
                 ha="center", va="bottom", fontsize=font_size, color=color)
    if title:
        fig.text(0.5, 1 - pad / height, title, ha="center", va="top", fontsize=font_size + 2,
                 color=color, fontweight="bold")
    cb_top = top + sum(row_h) + gap * (len(row_h) - 1) + 0.08 + 0.04
    cb_ax = fig.add_axes(box(left, cb_top, usable, bar_h))
    draw_colorbar(cb_ax, scale, label=label, ticks=ticks, nan=nan, missing=missing,
                  fontsize=font_size, color=color)
    avail = box(left, cb_top, usable, height - cb_top)
    fit_axes(cb_ax, avail, grow="x", max_width=min(0.55 * width, 3.2) / width)
    # fit_axes centres vertically; keep the bar right under the images instead.
    pos = cb_ax.get_position()
    cb_ax.set_position((pos.x0, 1 - (cb_top + bar_h) / height, pos.width, bar_h / height))
    layout.colorbar_ax = cb_ax
    return layout


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
    image_axes : dict of (str, str) to Axes
        Where each render is: ``(image name, view name) -> Axes``.
    """

    figure: Figure
    path: Path | None
    scale: ColourScale
    images: dict[tuple[str, str], np.ndarray]
    colorbar_ax: Axes
    image_axes: dict[tuple[str, str], Axes] = field(default_factory=dict)

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
            if im.get_array() is not None and im.get_array().ndim == 3 and im.get_array().shape[1] > 1:
                # vector formats embed the full render; raster formats resample it smoothly
                im.set_interpolation("none" if fmt in VECTOR_FORMATS else "antialiased")
    buf = io.BytesIO()
    rc = {"pdf.fonttype": 42, "ps.fonttype": 42, "svg.fonttype": "none", "svg.hashsalt": "brainpainter"}
    extra: dict[str, Any] = {"pil_kwargs": {"compression": "tiff_lzw"}} if fmt == "tiff" else {}
    with matplotlib.rc_context(rc):
        fig.savefig(buf, format=fmt, dpi=dpi, metadata=metadata, transparent=transparent,
                    facecolor="none" if transparent else fig.get_facecolor(), **extra)
    return buf.getvalue()


def make_figure(
    data: Any,
    atlas: Atlas | str | None = None,
    *,
    out: str | Path | None = None,
    views: str | Sequence[str] | None = None,
    rows: Iterable[str | int] | str | None = None,
    grid: bool = False,
    title: str | None = None,
    label: str | None = None,
    ticks: Sequence[float] | str | None = None,
    dpi: float = 300.0,
    fig_width: float | None = None,
    font_size: float = 8.0,
    view_labels: bool = False,
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
    value: str | None = None,
    region_column: str | None = None,
    strict: bool = False,
    progress: bool = True,
    atlas_config: str | Path | None = None,
    jobs: int | str = 1,
    client: Any = None,
    scheduler: str | None = None,
) -> FigureResult:
    """Render rows of a region-value table and lay them out as a figure with a colour bar.

    Parameters
    ----------
    data : path, DataFrame, dict, or a list of these
        See :func:`brainpainter.table.region_table.read_table`.
    atlas : str or Atlas, optional
        Inferred from the region names when not given.
    out : path, optional
        ``.png``, ``.tif``/``.tiff`` (at `dpi`), ``.pdf`` or ``.svg`` (renders
        embedded at full resolution). Written atomically. Without it only the
        figure object is returned.
    views : str or list of str, optional
        Default: ``lateral-left, medial-left, subcortical``.
    rows : iterable of str or int, or str, optional
        Image names (or 0-based positions) to show, in that order; default all.
    grid : bool
        Rows of the input as columns, views as rows (progression figures).
    title, label, ticks, fig_width, font_size, view_labels
        See :func:`compose_figure`.
    dpi : float
        Resolution of PNG/TIFF output (50 to 1200).
    template, surface, gradient, cmap, vmin, vmax, center, nan_color, missing_color, hide,
    background, width, height, quality, shading, lighting, glass_opacity, renderer
        As for :func:`brainpainter.render` (width, height: pixels of each render).
        The colour scale is computed over all rows of the table, not only `rows`.
    image_column, value, region_column, strict
        How the table is read, see :func:`brainpainter.table.region_table.read_table`.
    progress : bool
        Show a progress bar.
    atlas_config : path, optional
        Region-group TOML file defining the atlas, as for :func:`brainpainter.render`.
    jobs, client, scheduler
        Render on worker processes or a Dask cluster, as for :func:`brainpainter.render`.

    Returns
    -------
    FigureResult
    """
    from contextlib import nullcontext

    from tqdm.auto import tqdm

    from brainpainter.io.transaction import FileTransaction
    from brainpainter.media.colorbar import resolve_ticks
    from brainpainter.rendering.painter import Painter, prepare_run, region_colors
    from brainpainter.rendering.parallel import Item, check_options, make_runner, paint_all

    if not 50 <= float(dpi) <= 1200:
        raise BrainPainterError(f"dpi must be between 50 and 1200; {dpi} was given.")
    check_figure_text(font_size, fig_width)
    path = check_out_file(out, FIGURE_FORMATS) if out is not None else None
    check_options(jobs, client, scheduler)
    run = prepare_run(
        data, atlas, views=views, gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center,
        nan_color=nan_color, missing_color=missing_color, background=background, width=width,
        height=height, quality=quality, shading=shading, lighting=lighting, glass_opacity=glass_opacity,
        image_column=image_column, value=value, region_column=region_column, strict=strict,
        atlas_config=atlas_config,
    )
    resolve_ticks(run.scale, ticks)
    table = run.table
    chosen = select_rows(table.images, rows)
    painter = Painter(table.atlas, template, surface, hide, run.settings, renderer)
    nan, missing = swatches_needed(table, chosen, run.views, painter.scene.hidden)
    plan = [(i, view) for i in chosen for view in run.views]
    items = [Item(region_colors(table.row(i), table.atlas, run.scale), view, label=table.images[i])
             for i, view in plan]
    # the output folder is locked from before the first render until the figure is published
    with FileTransaction(path) if path is not None else nullcontext() as tx:
        with make_runner(painter, template, jobs=jobs, client=client, scheduler=scheduler,
                         n_items=len(plan)) as runner, \
                tqdm(total=len(plan), unit="img", desc="rendering", disable=not progress) as bar:
            pixels = paint_all(runner, items, bar)
        images = {(table.images[i], view.name): px for (i, view), px in zip(plan, pixels, strict=True)}
        layout = compose_figure(
            images, [table.images[i] for i in chosen], [v.name for v in run.views], run.scale, grid=grid,
            title=title, label=label, ticks=ticks, dpi=dpi, fig_width=fig_width, font_size=font_size,
            view_labels=view_labels, nan=nan, missing=missing, background=background,
        )
        if tx is not None:
            tx.tmp.write_bytes(figure_bytes(layout.figure, path, dpi, transparent=background is None))
            tx.commit()
    return FigureResult(layout.figure, path, run.scale, images, layout.colorbar_ax, layout.image_axes)
