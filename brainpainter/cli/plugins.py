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
