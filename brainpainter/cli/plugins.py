"""``brainpainter plugins``: the installed plugins, and which failed to load and why."""

from __future__ import annotations

from typing import Any

import click

from brainpainter.cli.params import CONTEXT, echo_json
from brainpainter.errors import BrainPainterError


@click.command(context_settings=CONTEXT)
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def plugins(as_json: bool) -> None:
    """Installed plugins, and which failed to load and why."""
    from brainpainter.atlas import registry
    report = []
    for reg in (registry.atlases, registry.renderers, registry.templates, registry.layer_kinds,
                registry.readers):
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


@click.command(context_settings=CONTEXT)
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def layers(as_json: bool) -> None:
    """Installed layer kinds (built-in and plugins') and their options (--layer KIND:FILE).

    A plugin's kind is drawn with ``--layer KIND:FILE`` and its options given as
    ``--layer-opt KIND.NAME=VALUE``; a built-in kind is drawn by its own options (listed).
    """
    from brainpainter.atlas import registry
    from brainpainter.layers.kinds import kind_of
    from brainpainter.layers.readers import all_readers

    dists = {e.name: e.distribution for e in registry.layer_kinds.entries()}
    rows: list[dict[str, Any]] = []
    for name in registry.layer_kinds.names():
        kind = kind_of(name)
        suffixes = sorted({s for r in all_readers([name]) for s in r.suffixes})
        rows.append({"name": name, "description": kind.description, "distribution": dists.get(name),
                     "given_as": list(kind.flags) or [f"--layer {name}:FILE"], "options": dict(kind.options),
                     "files": suffixes})
    if as_json:
        echo_json(rows)
        return
    for r in rows:
        click.echo(f"{r['name']:<11} {r['description']} [{r['distribution']}]")
        click.echo(f"    given as: {', '.join(r['given_as'])}" + (
            f"; files: {', '.join(r['files'])}" if r["files"] else ""))
        for option, text in r["options"].items():
            shown = option if option.startswith("-") else f"--layer-opt {r['name']}.{option}=..."
            click.echo(f"    {shown:<34} {text}")


def _command_plugins() -> list[dict[str, Any]]:
    """Rows of ``brainpainter plugins`` for the commands added through ``brainpainter.commands``."""
    from importlib.metadata import entry_points

    from brainpainter.cli.main import COMMANDS_GROUP, cli

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
