"""The ``figure`` and ``movie`` commands (registered on the ``brainpainter`` group in cli.py).

Only click is imported at module level: matplotlib, pandas and bpy load when
a command runs, so ``brainpainter --help`` stays light.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from brainpainter.cli.options import (
    input_options,
    make_render_options,
    map_options,
    option_group,
    parallel_options,
    render_kwargs,
    render_options,
    tables_or_maps,
)
from brainpainter.cli.params import CONTEXT, OutPath, echo_scale
from brainpainter.cli.render import echo_warnings
from brainpainter.media.layout import FigureOptions
from brainpainter.media.movie import MovieOptions, make_movie
from brainpainter.media.volume_panels import PanelOptions


def _one_or_many(inputs: tuple[Path, ...]) -> Path | list[Path]:
    return inputs[0] if len(inputs) == 1 else list(inputs)


def _rows(value: str | None) -> list[str] | None:
    return None if value is None else [r.strip() for r in value.split(",") if r.strip()]


# -- figure --------------------------------------------------------------------------
@click.command(context_settings=CONTEXT)
@click.argument("inputs", nargs=-1, required=False, metavar="[INPUT...]",
                type=click.Path(path_type=Path, dir_okay=False))
@click.option("--out", "-o", required=True, type=OutPath(path_type=Path),
              help="Figure file: .png or .tif (at --dpi), .pdf or .svg (renders embedded, text as text).")
@option_group(FigureOptions, ("grid",))
@click.option("--rows", default=None,
              help="Image names to show, comma-separated, in this order (default: all rows).")
@option_group(FigureOptions, ("title", "label", "ticks", "dpi", "fig_width", "font_size", "view_labels",
                              "colorbar_position"))
@option_group(PanelOptions, ("slices", "projections", "convention", "slice_outline"),
              slices={"multiple": True, "metavar": "AXIS=MM[,MM...]"}, projections={"metavar": "AXES"},
              slice_outline={"metavar": "FILE"})
@render_options
@map_options
@input_options
@parallel_options
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def figure(inputs: tuple[Path, ...], out: Path, grid: bool, rows: str | None, title: str | None,
           label: str | None, ticks: str | None, dpi: float, fig_width: float | None, font_size: float,
           view_labels: bool, colorbar_position: str, slices: tuple[str, ...], projections: str | None,
           convention: str, slice_outline: str | None, quiet: bool, **options: Any) -> None:
    """A publication figure of INPUT rows (or maps, --lh/--rh): renders, titles and one colour bar.

    \b
    Default: each row is a line of the chosen views side by side.
    --grid:  rows of the input as columns (stages), views as rows.
    --slices, --projections: a volume's slices and glass-brain projections
    beside the views, on the same colour bar (docs/maps-volumes.md).
    One colour scale, computed over all rows, for the whole figure. Swatches
    for the NaN and missing colours appear when those colours are drawn.

    \b
    Example:
      brainpainter figure examples/brainpainter_dk.csv --atlas dk --grid \\
          --views lateral-left,medial-left --label "atrophy (SD)" --out progression.pdf
    """
    from brainpainter.media.figure import make_figure

    kwargs = render_kwargs(options)
    result = make_figure(
        tables_or_maps(inputs, kwargs), out=out, rows=_rows(rows), grid=grid, title=title, label=label,
        ticks=ticks,
        dpi=dpi, fig_width=fig_width, font_size=font_size, view_labels=view_labels,
        colorbar_position=colorbar_position, slices=slices, projections=projections, convention=convention,
        slice_outline=slice_outline, progress=not quiet, **kwargs,
    )
    w, h = result.figure.get_size_inches()
    n_images = len({image for image, _ in result.images})
    panels = {s.name for s in PanelOptions(slices=slices, projections=projections).sections}
    n_views = len({view for _, view in result.images} - panels)
    click.echo(f"figure written to {result.path} ({n_images} row(s) x {n_views} view(s)"
               + (f" + {len(panels)} panel(s), " if panels else ", ")
               + f"{w:.2f} x {h:.2f} in" + (f" at {dpi:g} dpi)" if out.suffix.lower() in
                                            (".png", ".tif", ".tiff") else ")"))
    if panels:
        click.echo(f"slice and projection panels: {convention} convention (left on the "
                   f"{'left' if convention == 'neurological' else 'right'}, labelled L/R)")
    echo_warnings(result.input)
    echo_scale(result.scale)


# -- movie ---------------------------------------------------------------------------
@click.command(context_settings=CONTEXT)
@click.argument("inputs", nargs=-1, required=False, metavar="[INPUT...]",
                type=click.Path(path_type=Path, dir_okay=False))
@click.option("--out", "-o", required=True, type=OutPath(path_type=Path),
              help="Movie file: .mp4 (H.264) or .gif.")
@option_group(MovieOptions, ("frames_per_step", "easing", "time_column", "hold", "fps", "orbit",
                             "clip_sweep"))
@click.option("--rows", default=None,
              help="Image names to use as key frames, comma-separated (default: all).")
@option_group(MovieOptions, ("title", "label", "ticks"))
@make_render_options(size="800x600")
@map_options
@input_options
@parallel_options
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def movie(inputs: tuple[Path, ...], out: Path, frames_per_step: int, easing: str, time_column: str | None,
          hold: int, fps: float, orbit: float, clip_sweep: str | None, rows: str | None, title: str | None,
          label: str | None, ticks: str | None, quiet: bool, **options: Any) -> None:
    """A movie through the rows of INPUT (or a map series, --lh/--rh): key frames, values interpolated.

    \b
    Rows are key frames in table order (or sorted by --time-column); one colour
    scale over the whole movie; the views side by side, with the stage or time,
    a timeline and the colour bar under them. MP4 is H.264 (plays everywhere,
    no ffmpeg install needed); GIF for slides and web pages.

    \b
    Example:
      brainpainter movie examples/brainpainter_dk.csv --atlas dk --views lateral-left,medial-left \\
          --frames-per-step 24 --easing smooth --hold 12 --out progression.mp4
    """
    kwargs = render_kwargs(options)
    result = make_movie(
        tables_or_maps(inputs, kwargs), out=out, rows=_rows(rows), frames_per_step=frames_per_step,
        easing=easing,
        time_column=time_column, hold=hold, fps=fps, orbit=orbit, clip_sweep=clip_sweep, title=title,
        label=label, ticks=ticks,
        progress=not quiet, **kwargs,
    )
    w, h = result.frame_size
    click.echo(f"movie written to {result.path}: {result.n_frames} frames of {w}x{h} at {result.fps:g} fps "
               f"({result.duration:.1f} s; key frames {', '.join(result.keys)}; "
               f"made in {result.seconds:.0f} s)")
    echo_warnings(result.input)
    echo_scale(result.scale)
