"""CLI: atlas list/show, plugins, errors as one line with exit code 2."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from click.testing import CliRunner

from brainpainter.cli.main import cli


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "brainpainter", *args], capture_output=True, text=True)


def test_atlas_list_prints_the_three_atlases():
    result = CliRunner().invoke(cli, ["atlas", "list"])
    assert result.exit_code == 0
    names = [line.split()[0] for line in result.output.splitlines()]
    assert names == ["destrieux", "dk", "dkt"]
    assert "alias: tourville" in result.output


@pytest.mark.parametrize(("name", "n"), [("dk", 34), ("destrieux", 74), ("dkt", 31), ("tourville", 31)])
def test_atlas_show_json_counts(name, n):
    result = CliRunner().invoke(cli, ["atlas", "show", name, "--json"])
    assert result.exit_code == 0
    data = json.loads(result.output)
    assert data["n_cortical_per_hemisphere"] == {"lh": n, "rh": n}
    keys = {r["key"] for r in data["regions"]}
    assert {"Left-Hippocampus", "Right-Thalamus", "Brain-Stem"} <= keys


def test_atlas_show_text_lists_regions():
    result = CliRunner().invoke(cli, ["atlas", "show", "dkt"])
    assert result.exit_code == 0
    assert "cortical, left hemisphere (31)" in result.output
    assert "Left-insula" in result.output and "Left-bankssts" not in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["atlas", "show", "dkk"], "'dkk' was given. Did you mean 'dk'?"),
        (["render", "x.csv", "--out", "o", "--atlas", "destrieuxx"], "Did you mean 'destrieux'?"),
        (["render", "x.csv", "--out", "o", "--gradient", "white,yelow"], "Did you mean 'yellow'?"),
        (["render", "x.csv", "--out", "o", "--cmap", "virdis"], "Did you mean 'viridis'?"),
        (["atlas", "lst"], "No such command"),
    ],
)
def test_errors_are_one_line_exit_2_no_traceback(tmp_path, args, message):
    proc = subprocess.run([sys.executable, "-m", "brainpainter", *args], capture_output=True,
                          text=True, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_plugins_json_lists_builtins():
    result = CliRunner().invoke(cli, ["plugins", "--json"])
    assert result.exit_code == 0
    rows = {(r["group"], r["name"]) for r in json.loads(result.output)}
    assert {("brainpainter.atlases", "dk"), ("brainpainter.renderers", "blender"),
            ("brainpainter.templates", "fsaverage")} <= rows
