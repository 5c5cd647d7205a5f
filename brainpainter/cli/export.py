"""The ``export`` command: one row as an interactive 3D brain (``.glb`` or self-contained ``.html``).

Registered on the ``brainpainter`` group in cli.py. Only click is imported at
module level.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from brainpainter.cli.options import (
    input_options,
    make_render_options,
    map_colour_options,
    render_kwargs,
    tables_or_maps,
)
from brainpainter.cli.params import CONTEXT, OutPath
from brainpainter.media.export import EXPORT_OPTIONS
from brainpainter.media.export import export as run


@click.command(context_settings=CONTEXT)
@click.argument("inputs", nargs=-1, required=False, metavar="[INPUT...]",
                type=click.Path(path_type=Path, dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(["glb", "html"]), default=None,
              help="glb: glTF binary for 3D software; html: one file that opens in any browser. "
                   "Default: from --out's suffix, else html.")
@click.option("--out", "-o", type=OutPath(path_type=Path, dir_okay=False), default=None,
              help="File to write (default: out/IMAGE.FORMAT).")
@click.option("--row", default=None, help="Image name of the row to export (needed when there are several).")
@click.option("--title", default=None, help="Heading of the HTML page (default: the image name).")
@click.option("--label", default=None, help="Colour-bar label of the HTML page, e.g. 'z-score'.")
@make_render_options(only=("atlas", *EXPORT_OPTIONS))
@map_colour_options
@input_options
def export(inputs: tuple[Path, ...], fmt: str | None, out: Path | None, row: str | None, title: str | None,
           label: str | None, **options: Any) -> None:
    """One row of INPUT as an interactive 3D brain: a .glb, or an .html to rotate in a browser.

    \b
    One mesh per region, named by its region (Left-insula, ...) and in its
    colour; the HTML page needs no network and shows the region under the
    mouse. Colour options as for render (the scale spans all rows).
    Example:
      brainpainter export examples/brainpainter_dk.csv --row stage-4 --format html --out out/stage-4.html
    """
    from brainpainter.io.output import safe_name

    if fmt is None:
        fmt = out.suffix.lstrip(".").lower() if out is not None and out.suffix else "html"
    if out is None:
        out = Path("out") / f"{safe_name(row) if row else 'brain'}.{fmt}"
    kwargs = render_kwargs(options)
    data = tables_or_maps(inputs, kwargs)
    path = run(data, out, format=fmt, row=row, title=title, label=label, **kwargs)
    size = path.stat().st_size / 1e6
    click.echo(f"{fmt} written to {path} ({size:.1f} MB)")
