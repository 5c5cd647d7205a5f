"""The ``brainpainter`` command line: a click group of small commands.

Every command maps user errors (:class:`BrainPainterError`) to one line on
stderr and exit code 2. Heavy modules (bpy, nibabel, pandas) are imported
inside the commands, so ``brainpainter --help`` stays fast.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Any

import click

from brainpainter.cli.atlas import atlas
from brainpainter.cli.options import (
    CONTEXT,
    OutPath,
    echo_json,
    input_options,
    map_options,
    option_group,
    parallel_options,
    render_kwargs,
    render_options,
    tables_or_maps,
)
from brainpainter.color.scale import ScaleOptions
from brainpainter.errors import BrainPainterError

COMMANDS_GROUP = "brainpainter.commands"

#: Built-in commands loaded only when they run or their help is asked for (their options pull in
#: the media stack: numpy, matplotlib), with the short help that ``brainpainter --help`` lists.
LAZY_COMMANDS = {
    "figure": ("brainpainter.cli.media:figure",
               "A publication figure of INPUT rows: renders, titles and one colour bar."),
    "movie": ("brainpainter.cli.media:movie",
              "A movie through the rows of INPUT: each row a key frame, eased in between."),
    "export": ("brainpainter.cli.export:export",
               "One row of INPUT as an interactive 3D brain: a .glb, or an HTML page."),
    "serve": ("brainpainter.web.command:serve",
              "Serve the web page and JSON API: upload a table, check it, render it."),
}


class CommandsFromPlugins(click.Group):
    """The top-level group plus the commands that distributions add through ``brainpainter.commands``.

    The template builder adds ``template`` this way, so core never imports it;
    an entry point is imported only when its command runs (or ``--help`` lists it).
    """

    def _entry_points(self, ctx: click.Context) -> dict[str, Any]:
        # Scanning every installed distribution's metadata costs ~50 ms in a full environment: once a
        # command line (``--help`` lists the commands, then loads the plugins' ones).
        meta = ctx.find_root().meta
        if "brainpainter.entry_points" not in meta:
            from importlib.metadata import entry_points

            meta["brainpainter.entry_points"] = {ep.name: ep for ep in entry_points(group=COMMANDS_GROUP)}
        found: dict[str, Any] = meta["brainpainter.entry_points"]
        return {name: ep for name, ep in found.items() if name not in self.commands}

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*super().list_commands(ctx), *LAZY_COMMANDS, *self._entry_points(ctx)})

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list of ``--help``, without importing the lazy built-in commands."""
        from click.utils import make_default_short_help

        rows = []
        for name in self.list_commands(ctx):
            if name in LAZY_COMMANDS and name not in self.commands:
                rows.append((name, make_default_short_help(LAZY_COMMANDS[name][1],
                                                           formatter.width - 6 - len(name))))
                continue
            command = self.get_command(ctx, name)
            if command is not None and not command.hidden:
                rows.append((name, command.get_short_help_str(formatter.width - 6 - len(name))))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        command = super().get_command(ctx, cmd_name)
        if command is None and cmd_name in LAZY_COMMANDS:
            module, _, attr = LAZY_COMMANDS[cmd_name][0].partition(":")
            command = getattr(importlib.import_module(module), attr)
            self.add_command(command, cmd_name)
        entry = None if command is not None else self._entry_points(ctx).get(cmd_name)
        if entry is None:
            return command
        try:
            loaded = entry.load()
        except Exception as exc:  # a broken plugin: one line, not a traceback
            raise BrainPainterError(f"the command {cmd_name!r} from {entry.value!r} could not be loaded "
                                    f"({type(exc).__name__}: {exc}); reinstall the distribution that "
                                    "provides it.") from exc
        if not isinstance(loaded, click.Command):
            raise BrainPainterError(f"the entry point {cmd_name!r} = {entry.value!r} is not a click "
                                    "command; fix or uninstall the distribution that provides it.")
        return loaded


@click.group(cls=CommandsFromPlugins, context_settings=CONTEXT)
@click.version_option(package_name="brainpainter", prog_name="brainpainter")
def cli() -> None:
    """Paint numbers per brain region onto 3D brains.

    \b
    Quick start:
      brainpainter render examples/brainpainter_dk.csv --atlas dk --out out/
      brainpainter atlas list
      brainpainter atlas show dk
    """


cli.add_command(atlas)


# -- plugins ------------------------------------------------------------------
@cli.command(context_settings=CONTEXT)
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def plugins(as_json: bool) -> None:
    """Installed plugins, and which failed to load and why."""
    from brainpainter.atlas import registry
    report = []
    for reg in (registry.atlases, registry.renderers, registry.templates):
        for entry in reg.entries():
            status, error = "ok", None
            try:
                reg.get(entry.name)
            except BrainPainterError as exc:
                status, error = "failed", str(exc)
            report.append({"group": reg.group, "name": entry.name, "aliases": list(entry.aliases),
                           "target": entry.target, "distribution": entry.distribution,
                           "status": status, "error": error})
        for name, error in reg.errors().items():
            if not any(r["group"] == reg.group and r["name"] == name for r in report):
                report.append({"group": reg.group, "name": name, "aliases": [], "target": None,
                               "distribution": None, "status": "failed", "error": error})
    report.extend(_command_plugins())
    if as_json:
        echo_json(report)
        return
    for r in report:
        line = f"{r['group']:<24} {r['name']:<12} {r['status']:<7} {r['distribution'] or ''}"
        click.echo(line + (f"\n    {r['error']}" if r["error"] else ""))


def _command_plugins() -> list[dict[str, Any]]:
    """Rows of ``brainpainter plugins`` for the commands added through ``brainpainter.commands``."""
    from importlib.metadata import entry_points

    rows: list[dict[str, Any]] = []
    ctx = click.Context(cli)
    for entry in entry_points(group=COMMANDS_GROUP):
        status, error = "ok", None
        try:
            cli.get_command(ctx, entry.name)
        except BrainPainterError as exc:
            status, error = "failed", str(exc)
        dist = entry.dist.name if entry.dist is not None else None
        rows.append({"group": COMMANDS_GROUP, "name": entry.name, "aliases": [], "target": entry.value,
                     "distribution": dist, "status": status, "error": error})
    return rows


def _one_or_many(inputs: tuple[Path, ...]) -> Path | list[Path]:
    return inputs[0] if len(inputs) == 1 else list(inputs)


# -- check --------------------------------------------------------------------
@cli.command(context_settings=CONTEXT)
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

    table = inspect_table(_one_or_many(inputs), atlas, image_column=image_column, value=value,
                          region_column=region_column, strict=strict)
    report = check_report(table, gradient=gradient, cmap=cmap, vmin=vmin, vmax=vmax, center=center)
    if as_json:
        echo_json(report)
    else:
        click.echo(format_report(report))
    if report["errors"]:
        raise BrainPainterError(report["errors"][0])


# -- render -------------------------------------------------------------------
@cli.command(context_settings=CONTEXT)
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
    """
    from brainpainter.rendering.run import render as run

    kwargs = render_kwargs(options)
    result = run(tables_or_maps(inputs, kwargs), out=out, progress=not quiet, rows=rows, **kwargs)
    if result.manifest["input"].get("kind") == "vertex map":
        m = result.manifest["input"]
        click.echo(f"{len(result.files)} image(s) written to {out} ({m['n_images']} map image(s), "
                   f"hemispheres {', '.join(m['hemis'])})")
        return
    from brainpainter.table.region_table import summary_line
    from brainpainter.table.report import input_warnings

    s = result.manifest["input"]
    click.echo(f"input: {summary_line(s)}")
    for line in input_warnings(s):
        click.echo(f"warning: {line}")
    rendered = len({f["row"] for f in result.manifest["files"]})  # --rows may choose some of the rows
    of = f" of {s['n_images']}" if rendered != s["n_images"] else ""
    click.echo(
        f"{len(result.files)} image(s) written to {out} "
        f"({rendered} row(s){of}; {s['n_regions_matched']}/{s['n_regions_in_atlas']} regions matched, "
        f"{len(s['unmatched_columns'])} unmatched column(s))"
    )
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




#: Options whose value is a comma-separated list.
LIST_OPTIONS = ("--views", "--hide", "--rows", "--ticks", "--atlas")


def join_split_lists(args: list[str]) -> list[str]:
    """Rejoin a comma-separated option value that the shell split at a space.

    ``--views lateral-left, medial-left`` reaches us as ``["--views",
    "lateral-left,", "medial-left"]``; without this, ``medial-left`` would be
    taken for an input file.
    """
    out: list[str] = []
    i = 0
    while i < len(args):
        arg = args[i]
        name = arg.split("=", 1)[0]
        if name in LIST_OPTIONS and ("=" in arg or i + 1 < len(args)):
            value = arg.split("=", 1)[1] if "=" in arg else args[i + 1]
            i += 1 if "=" in arg else 2
            while i < len(args) and (value.rstrip().endswith(",") or args[i].startswith(",")):
                value += args[i]
                i += 1
            out.append(f"{name}={value}")
            continue
        out.append(arg)
        i += 1
    return out



def main(argv: list[str] | None = None) -> None:
    """Console entry point: user errors become one line and exit code 2 (:mod:`brainpainter.cli.guard`)."""
    from brainpainter.cli.guard import run

    code = run(cli, join_split_lists(sys.argv[1:] if argv is None else list(argv)))
    if argv is None and threading.current_thread() is threading.main_thread():
        # the run is over (published or cleaned up): a signal now must not claim otherwise
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    if argv is None and "bpy" in sys.modules:
        # Blender's own exit handlers (bpy 5.1+) write a shader cache under ~/.cache after the run's
        # private cache folder is gone; the run is complete and published, so leave without them.
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    main()
