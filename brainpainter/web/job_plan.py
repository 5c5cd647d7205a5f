"""A job's plan, made before it is queued: its rows and views, and a PNG figure's pixels laid out as
``brainpainter figure`` lays them out (in a request process: :mod:`brainpainter.web.work_processes`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.web.options import ExportParams, FigureParams, MovieParams, Prepared, RenderOptions, prepare


def job_plan(data: bytes, name: str, options: RenderOptions, kind: str, figure: FigureParams,
             movie: MovieParams, export: ExportParams, *, max_images: int, max_pixels: int,
             max_figure_pixels: int, data_dir: Path | None = None, **uploads: Any) -> tuple[int, int]:
    """``(progress total, rows)`` of a job of `kind` on an upload, after the checks a job gets before it is
    queued (the run's options, the image limit; a PNG figure's pixels against `max_figure_pixels`).

    Raises
    ------
    BrainPainterError
        One line: the first option or limit the job does not fit.
    """
    prep = prepare(data, name, options, max_images=max_images, max_pixels=max_pixels, data_dir=data_dir,
                   **uploads)
    n_rows, n_views = len(prep.run.table.images), len(prep.run.views)
    keys = n_rows  # a movie's key frames: one row cut open by a sweeping plane is a movie too
    if kind == "movie" and movie.clip_sweep:
        from brainpainter.rendering.clip import parse_sweep

        parse_sweep(movie.clip_sweep)
        keys = max(n_rows, 2)
    if kind == "movie" and keys < 2:
        raise BrainPainterError(f"a movie needs at least 2 rows (key frames); the table has {n_rows}.")
    if kind == "export" and export.row >= n_rows:
        raise BrainPainterError(f"row must be 0..{n_rows - 1}; {export.row} was given.")
    if kind == "figure" and figure.format == "png":  # a PDF embeds the renders as they are
        check_figure_pixels(*figure_pixels(prep, figure), max_figure_pixels)
    total = n_rows * n_views if kind == "images" else movie.n_frames(keys) if kind == "movie" else 1
    return total, n_rows


def figure_pixels(prep: Prepared, params: FigureParams) -> tuple[int, int]:
    """``(width, height)`` in pixels of a figure job's PNG, laid out as ``brainpainter figure`` does
    (:func:`brainpainter.media.layout.plan_grid`) before anything is rendered.

    The width is exact; the height takes each view's crop to have its render's shape (a content box can
    be taller or wider than its frame, so the worker checks the composed figure again:
    :func:`check_figure_pixels`).
    """
    from brainpainter.media.colorbar import colorbar_height
    from brainpainter.media.layout import FigureOptions, plan_grid

    opts = FigureOptions(grid=params.grid, title=params.title or None, label=params.label or None,
                         dpi=params.dpi, fig_width=params.fig_width, font_size=params.font_size)
    settings, views = prep.run.settings, [v.name for v in prep.run.views]

    def bar_h(usable: float) -> float:  # inches, whatever the dpi: measured at 100 to keep it cheap
        return colorbar_height(prep.run.scale, usable, dpi=100.0, label=opts.label, fontsize=opts.font_size)

    grid = plan_grid({v: settings.height / settings.width for v in views}, list(prep.run.table.images), views,
                     opts, bar_h)
    return round(grid.width * opts.dpi), round(grid.height * opts.dpi)


def check_figure_pixels(width: int, height: int, max_pixels: int) -> None:
    """Refuse a figure of more than `max_pixels` pixels.

    Raises
    ------
    BrainPainterError
        One line: the figure's size, the limit and what to do.
    """
    if width * height > max_pixels:
        raise BrainPainterError(
            f"the figure would be {width}x{height} = {width * height} pixels; this server makes figures of "
            f"at most {max_pixels} pixels. Choose a lower dpi or fig_width, fewer rows or views, or a PDF."
        )


