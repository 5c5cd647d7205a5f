"""Commands from other packages (``brainpainter.commands`` entry points): the builder's ``template``."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from brainpainter.cli.main import cli, main
from brainpainter.testing import fake_distribution, installed

HELLO = ("import click\n\n@click.command()\n@click.argument('who')\n"
         "def hello(who):\n    'Say hello.'\n    click.echo(f'hello {who}')\n")


def test_the_builder_adds_template_without_core_importing_it():
    ctx = cli.make_context("brainpainter", ["--help"], resilient_parsing=True)
    assert "template" in cli.list_commands(ctx)
    command = cli.get_command(ctx, "template")
    assert command.callback.__module__ == "brainpainter_builder.cli"
    assert set(command.commands) == {"build", "info"}


def test_a_distribution_adds_a_command(tmp_path, capsys):
    root = fake_distribution(tmp_path / "site", "hello-cmd",
                             {"brainpainter.commands": {"hello": "hello_cmd:hello"}},
                             {"hello_cmd/__init__.py": HELLO})
    with installed(root), pytest.raises(SystemExit) as exit_info:
        main(["hello", "world"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out == "hello world\n"


@pytest.mark.parametrize(("module", "expected"), [
    ("raise ImportError('needs libfoo')\n", "could not be loaded (ImportError: needs libfoo)"),
    ("hello = 42\n", "is not a click command"),
])
def test_a_broken_command_is_one_line_exit_2(tmp_path, capsys, module, expected):
    root = fake_distribution(tmp_path / "site", "bad-cmd",
                             {"brainpainter.commands": {"hello": "bad_cmd:hello"}},
                             {"bad_cmd/__init__.py": module})
    with installed(root), pytest.raises(SystemExit) as exit_info:
        main(["hello", "world"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    assert expected in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_plugins_lists_commands_and_the_broken_ones(tmp_path):
    root = fake_distribution(tmp_path / "site", "bad-cmd",
                             {"brainpainter.commands": {"hello": "bad_cmd:hello"}},
                             {"bad_cmd/__init__.py": "hello = 42\n"})
    with installed(root):
        result = CliRunner().invoke(cli, ["plugins", "--json"])
    assert result.exit_code == 0
    rows = {(r["group"], r["name"]): r for r in json.loads(result.output)}
    assert rows[("brainpainter.commands", "template")]["status"] == "ok"
    broken = rows[("brainpainter.commands", "hello")]
    assert broken["status"] == "failed" and "not a click command" in broken["error"]
    assert broken["distribution"] == "bad-cmd"
