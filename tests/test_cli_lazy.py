"""``brainpainter --help`` lists the built-in commands without importing them."""

from __future__ import annotations

import importlib
import subprocess
import sys

import click
import click.testing
import pytest

from brainpainter.cli.main import LAZY_COMMANDS, cli


@pytest.mark.parametrize("name", sorted(LAZY_COMMANDS))
def test_listed_help_is_the_commands_own(name):
    target, listed = LAZY_COMMANDS[name]
    module, _, attr = target.partition(":")
    command = getattr(importlib.import_module(module), attr)
    assert isinstance(command, click.Command)
    assert click.Command(name, help=listed).get_short_help_str(300) == command.get_short_help_str(300)


def test_every_lazy_command_runs_its_help():
    runner = click.testing.CliRunner()
    for name in LAZY_COMMANDS:
        result = runner.invoke(cli, [name, "--help"])
        assert result.exit_code == 0, (name, result.output)
        assert "Usage:" in result.output


def test_help_imports_no_command_module():
    code = ("import sys\nfrom brainpainter.cli.main import main\nsys.argv=['brainpainter','--help']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print('\\n'.join(sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "Commands:" in out and "render" in out and "atlas" in out
    loaded = set(out.split())
    commands = {target.partition(":")[0] for target, _ in LAZY_COMMANDS.values()}
    assert not commands & loaded
    assert not {"numpy", "brainpainter.cli.options", "brainpainter.rendering.options"} & loaded


def test_plugin_commands_are_found_as_importlib_metadata_finds_them():
    from importlib.metadata import entry_points as metadata_entry_points

    from brainpainter.cli.entry_points import entry_points
    from brainpainter.cli.main import COMMANDS_GROUP

    expected = {ep.name: ep.value for ep in metadata_entry_points(group=COMMANDS_GROUP)}
    found = entry_points(COMMANDS_GROUP)
    assert "template" in expected  # the builder's command, from this project's own metadata
    assert {name: e.value for name, e in found.items()} == expected
    assert isinstance(found["template"].load(), click.Group)
