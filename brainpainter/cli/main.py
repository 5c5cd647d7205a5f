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
from typing import Any

import click

from brainpainter.cli.params import CONTEXT
from brainpainter.errors import BrainPainterError

COMMANDS_GROUP = "brainpainter.commands"

#: The built-in commands, each loaded only when it runs or its help is asked for (their options
#: pull in the option classes of core, the media stack: numpy, matplotlib), with the short help that
#: ``brainpainter --help`` lists (``tests/test_cli_lazy.py`` checks it against the command's own).
LAZY_COMMANDS = {
    "atlas": ("brainpainter.cli.atlas:atlas", "List, inspect, add and remove atlases."),
    "check": ("brainpainter.cli.render:check",
              "Read INPUT tables exactly as render would and report how, without rendering."),
    "plugins": ("brainpainter.cli.plugins:plugins", "Installed plugins, and which failed to load and why."),
    "layers": ("brainpainter.cli.plugins:layers",
               "Installed layer kinds (built-in and plugins') and their options (--layer KIND:FILE)."),
    "render": ("brainpainter.cli.render:render",
               "Render every image of INPUT tables (CSV, TSV, .xlsx; see \"check\") or maps (--lh/--rh), "
               "from every view."),
    "figure": ("brainpainter.cli.media:figure",
               "A publication figure of INPUT rows (or maps, --lh/--rh): renders, titles and one "
               "colour bar."),
    "movie": ("brainpainter.cli.media:movie",
              "A movie through the rows of INPUT (or a map series, --lh/--rh): key frames, values "
              "interpolated."),
    "export": ("brainpainter.cli.export:export",
               "One row of INPUT as an interactive 3D brain: a .glb, or an .html to rotate in a browser."),
    "serve": ("brainpainter.web.command:serve",
              "Serve the web page and JSON API: upload a table, check it, preview it, render it."),
}


class CommandsFromPlugins(click.Group):
    """The top-level group plus the commands that distributions add through ``brainpainter.commands``.

    The template builder adds ``template`` this way, so core never imports it;
    an entry point is imported only when its command runs (or ``--help`` lists it).
    """

    def _entry_points(self, ctx: click.Context) -> dict[str, Any]:
        # Scanning every installed distribution's metadata: once a command line (``--help`` lists the
        # commands, then loads the plugins' ones).
        meta = ctx.find_root().meta
        if "brainpainter.entry_points" not in meta:
            from brainpainter.cli.entry_points import entry_points

            meta["brainpainter.entry_points"] = entry_points(COMMANDS_GROUP)
        found: dict[str, Any] = meta["brainpainter.entry_points"]
        return {name: ep for name, ep in found.items() if name not in self.commands}

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*super().list_commands(ctx), *LAZY_COMMANDS, *self._entry_points(ctx)})

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list of ``--help``, without importing the lazy built-in commands."""
        rows = []
        for name in self.list_commands(ctx):
            command: click.Command | None
            if name in LAZY_COMMANDS and name not in self.commands:
                # a stand-in with the listed help: click shortens it as it would the command's own
                command = click.Command(name, help=LAZY_COMMANDS[name][1])
            else:
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
