"""``brainpainter check`` and ``brainpainter render``: read INPUT tables or maps, and render them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from brainpainter.cli.options import (
    input_options,
    map_options,
    option_group,
    parallel_options,
    render_kwargs,
    render_options,
    tables_or_maps,
)
from brainpainter.cli.params import CONTEXT, OutPath, beyond_scale_note, echo_json, echo_scale
from brainpainter.color.scale import ScaleOptions
from brainpainter.errors import BrainPainterError


def _one_or_many(inputs: tuple[Path, ...]) -> Path | list[Path]:
    return inputs[0] if len(inputs) == 1 else list(inputs)


def echo_input(summary: dict[str, Any]) -> None:
    """The input line of a table (``input: ...``) and its warnings."""
    from brainpainter.table.region_table import summary_line
    from brainpainter.table.report import input_warnings

    click.echo(f"input: {summary_line(summary)}")
    for line in input_warnings(summary):
        click.echo(f"warning: {line}")


def echo_warnings(summary: dict[str, Any]) -> None:
    """The notes and warnings about an input that ``render`` prints with it, for ``figure`` and ``movie``:
    a map's notes, and a table's (one under a map too) unmatched names and notes."""
    from brainpainter.table.report import input_warnings

    if summary.get("kind") == "vertex map":
        for note in summary.get("notes", []):
            click.echo(f"note: {note}")
        summary = summary.get("table", {})
    for line in input_warnings(summary) if summary else []:
        click.echo(f"warning: {line}")


# -- check --------------------------------------------------------------------
@click.command(context_settings=CONTEXT)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...",
                type=click.Path(path_type=Path, dir_okay=False))
@click.option("--atlas", "-a", default=None,
              help="Atlas: dk, destrieux, dkt (alias tourville) or a plugin atlas. "
                   "Default: inferred from the region names.")
@input_options
@option_group(ScaleOptions, ("gradient", "cmap", "vmin", "vmax", "center"),
              gradient={"help": "Colour scale to compare the values with (as for render)."},
              cmap={"help": "Colour map to compare the values with (as for render)."})
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def check(inputs: tuple[Path, ...], atlas: str | None, image_column: str | None, value: str | None,
          region_column: str | None, strict: bool, gradient: str | None, cmap: str | None,
          vmin: float | None, vmax: float | None, center: float | None, as_json: bool) -> None:
    """Read INPUT tables exactly as render would and report how, without rendering.

    \b
    Shows the shape detected, the atlas (inferred when --atlas is not given),
    what each column or name resolved to (or the closest names), regions
    without a value, bad cells and the value range against the colour scale.
    Several INPUTs (e.g. lh and rh aparcstats2table files) are merged by image
    name. Exit code 0: render would accept the table; 2: it would not.
    """
    from brainpainter.table.region_table import inspect_table
    from brainpainter.table.report import check_report, format_report

    if len(inputs) == 1 and _check_other(inputs[0], as_json):  # a map or a connectome
        return
    table = inspect_table(_one_or_many(inputs), atlas, image_column=image_column, value=value,
                          region_column=region_column, strict=strict)
    report = check_report(table, gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center)
    if as_json:
        echo_json(report)
    else:
        click.echo(format_report(report))
    if report["errors"]:
        raise BrainPainterError(report["errors"][0])


def _check_other(path: Path, as_json: bool) -> bool:
    """Report a map or a connectome as ``render`` would draw it; False where `path` is a table."""
    from brainpainter.errors import NoRegionColumnError
    from brainpainter.rendering import input_report as other

    kind = other.input_kind(path)
    if kind is None and path.name.lower().endswith((".csv", ".tsv", ".txt")) and other.square_matrix(path):
        kind = "connectome"
    if kind is None:
        from brainpainter.table.region_table import inspect_table

        try:
            inspect_table(path)
            return False
        except NoRegionColumnError:  # numbers without names: a matrix in an atlas's node order?
            from brainpainter.connectome.matrix import read_matrix

            try:
                read_matrix(path)
            except BrainPainterError:
                return False  # the table's own error, below
            kind = "connectome"
        except BrainPainterError:
            return False
    reports = {"map": other.map_report, "connectome": other.connectome_report}
    report = reports[kind](path) if kind in reports else other.layer_report(path, kind)
    if as_json:
        echo_json(report)
    else:
        click.echo(other.format_input_report(report))
    if report["errors"]:
        raise BrainPainterError(report["errors"][0])
    return True


# -- render -------------------------------------------------------------------
@click.command(context_settings=CONTEXT)
@click.argument("inputs", nargs=-1, required=False, metavar="[INPUT...]",
                type=click.Path(path_type=Path, dir_okay=False))
@click.option("--out", "-o", required=True, type=OutPath(path_type=Path, file_okay=False),
              help="Output folder for {image}_{view}.png and manifest.json.")
@click.option("--rows", default=None,
              help="Image names to render, comma-separated, in this order (default: all rows).")
@render_options
@map_options
@input_options
@parallel_options
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def render(inputs: tuple[Path, ...], out: Path, rows: str | None, quiet: bool, **options: Any) -> None:
    """Render every image of INPUT tables (CSV, TSV, .xlsx; see "check") or maps (--lh/--rh), from every view.

    Several INPUTs (e.g. lh and rh aparcstats2table files) are merged by image name.
    Per-vertex maps (thickness, .mgh, .gii, ...) are given with --lh FILE --rh FILE (docs/maps.md).
    A connectivity matrix (--connectome FILE) is drawn as nodes and edges inside the glass cortex.
    """
    from brainpainter.rendering.run import render as run

    kwargs = render_kwargs(options)
    result = run(tables_or_maps(inputs, kwargs), out=out, progress=not quiet, rows=rows, **kwargs)
    if result.manifest["input"].get("kind") == "vertex map":
        m = result.manifest["input"]
        click.echo(f"{len(result.files)} image(s) written to {out} ({m['n_images']} map image(s), "
                   f"hemispheres {', '.join(m['hemis'])})")
        for note in m.get("notes", []):
            click.echo(f"note: {note}")
        if "table" in m:  # region values under the map
            echo_input(m["table"])
        echo_scale(result.scale, result.layers)
        return
    s = result.manifest["input"]
    connectome = result.manifest.get("connectome")
    rendered = len({f["row"] for f in result.manifest["files"]})  # --rows may choose some of the rows
    if connectome and not inputs:  # a connectome alone: no table to report
        click.echo(f"{len(result.files)} image(s) written to {out}")
    else:
        echo_input(s)
        of = f" of {s['n_images']}" if rendered != s["n_images"] else ""
        click.echo(
            f"{len(result.files)} image(s) written to {out} "
            f"({rendered} row(s){of}; {s['n_regions_matched']}/{s['n_regions_in_atlas']} regions matched, "
            f"{len(s['unmatched_columns'])} unmatched column(s))"
        )
        if (note := beyond_scale_note(s.get("value_range"), result.scale)) is not None:
            click.echo(f"note: {note}")
    if connectome:
        series = connectome.get("series")  # a matrix per image: the edges any of them keeps
        click.echo(f"connectome: {connectome['n_nodes']} node(s), {connectome['n_edges']} edge(s) drawn"
                   + (f" (kept by any of {series['n_matrices']} matrices)" if series else "")
                   + (" (directed)" if connectome["directed"] else ""))
    tracts = result.manifest.get("tracts")
    if tracts:
        drawn = sum(b["drawn"] for b in tracts["bundles"])
        click.echo(f"tracts: {len(tracts['bundles'])} bundle(s) "
                   f"({', '.join(b['name'] for b in tracts['bundles'])}), {drawn:,} streamlines drawn")
        for note in tracts["notes"]:
            click.echo(f"note: {note}")
    w = result.workers
    if w.get("backend") in ("LocalRunner", "DaskRunner"):
        where = "processes" if w["backend"] == "LocalRunner" else "Dask workers"
        click.echo(f"rendered by {w['workers']} {where} (painter start-up {max(w['startup_seconds']):.1f} s"
                   + (f"; {len(w['retried'])} task(s) retried" if w["retried"] else "") + ")")
