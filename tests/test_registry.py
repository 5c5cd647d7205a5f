"""Entry-point registries: built-ins, third-party plugins, broken plugins."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.cli.main import cli
from brainpainter.errors import BrainPainterError
from brainpainter.testing import fake_distribution, installed

ATLAS_MODULE = textwrap.dedent(
    '''
    from brainpainter.atlas.model import Atlas, Region

    def toy():
        return Atlas(name="toy", title="Toy atlas", template_labels="dk", regions=(
            Region(1001, "bankssts", "lh", "cortical", (25, 100, 40)),
            Region(2001, "bankssts", "rh", "cortical", (25, 100, 40)),
        ))
    '''
)


def test_builtin_atlases_register_through_entry_points():
    assert registry.atlases.names() == ["destrieux", "dk", "dkt"]
    assert registry.atlases.canonical("Tourville") == "dkt"
    assert {e.distribution for e in registry.atlases.entries()} == {"brainpainter"}


@pytest.mark.parametrize(("name", "n"), [("dk", 34), ("destrieux", 74), ("dkt", 31)])
def test_builtin_atlas_region_counts(name, n):
    atlas = registry.atlases.get(name)
    assert len(atlas.cortical("lh")) == n
    assert len(atlas.cortical("rh")) == n
    assert {r.name for r in atlas.subcortical()} >= {"Hippocampus", "Thalamus", "Putamen", "Brain-Stem"}


def test_aliases_declared_by_atlas_data_resolve():
    assert registry.atlases.canonical("Desikan-Killiany") == "dk"
    assert registry.atlases.canonical("aparc.a2009s") == "destrieux"
    assert registry.atlases.get("DKT40").name == "dkt"


def test_bad_atlas_name_suggests_nearest():
    with pytest.raises(BrainPainterError, match=r"'dkk' was given\. Did you mean 'dk'\?"):
        registry.atlases.get("dkk")


def test_atlas_of_a_plugin_not_installed_names_its_package(tmp_path):
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-Auditory\nA,1\n")
    result = subprocess.run([sys.executable, "-m", "brainpainter", "render", str(table), "--atlas", "mouse",
                             "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2 and not result.stdout, result
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "'mouse' is provided by the brainpainter-atlas-mouse package" in result.stderr
    assert "pip install plugins/atlases/brainpainter-atlas-mouse" in result.stderr
    assert not (tmp_path / "out").exists()
    with pytest.raises(BrainPainterError, match="pip install brainpainter-atlas-schaefer-yeo"):
        registry.atlases.get("Schaefer400_17n")


def test_known_atlas_plugins_are_the_repositorys_plugins():
    """The table of plugins not installed says what each plugin's pyproject.toml registers."""
    import tomllib
    from pathlib import Path

    found = {}
    for pyproject in (Path(__file__).parents[1] / "plugins" / "atlases").glob("*/pyproject.toml"):
        project = tomllib.loads(pyproject.read_text())["project"]
        assert project["name"] == pyproject.parent.name  # the folder the hint names
        found[project["name"]] = set(project["entry-points"]["brainpainter.atlases"])
    assert found == {dist: set(names) for dist, names in registry.KNOWN_ATLAS_PLUGINS.items()}


def test_pip_installed_plugin_appears_in_atlas_list(tmp_path):
    """A real throw-away distribution, built and installed by pip into tmp_path."""
    src = tmp_path / "src"
    (src / "toy_atlas").mkdir(parents=True)
    (src / "toy_atlas" / "__init__.py").write_text(ATLAS_MODULE)
    (src / "pyproject.toml").write_text(textwrap.dedent(
        """
        [build-system]
        requires = ["setuptools"]
        build-backend = "setuptools.build_meta"
        [project]
        name = "toy-atlas"
        version = "0.1"
        [project.entry-points."brainpainter.atlases"]
        toy = "toy_atlas:toy"
        """
    ))
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--no-index", "--target", str(target), str(src)],
        check=True, capture_output=True,
    )
    with installed(target):
        result = CliRunner().invoke(cli, ["atlas", "list", "--json"])
        assert result.exit_code == 0, result.output
        rows = {r["name"]: r for r in json.loads(result.output)}
        assert rows["toy"]["distribution"] == "toy-atlas"
        assert rows["toy"]["title"] == "Toy atlas"
        assert {"dk", "destrieux", "dkt"} <= set(rows)
    assert "toy" not in registry.atlases.names()


def test_broken_plugin_is_reported_not_fatal(tmp_path):
    root = fake_distribution(
        tmp_path / "site", "broken-atlas",
        {"brainpainter.atlases": {"broken": "broken_atlas:atlas", "notatlas": "broken_atlas:other"}},
        {"broken_atlas/__init__.py": "raise ImportError('needs libfoo')\n"},
    )
    with installed(root):
        runner = CliRunner()
        listed = runner.invoke(cli, ["atlas", "list"])
        assert listed.exit_code == 0
        assert "dk" in listed.output and "BROKEN" in listed.output
        report = runner.invoke(cli, ["plugins", "--json"])
        assert report.exit_code == 0
        rows = {(r["group"], r["name"]): r for r in json.loads(report.output)}
        broken = rows[("brainpainter.atlases", "broken")]
        assert broken["status"] == "failed"
        assert "needs libfoo" in broken["error"] and broken["distribution"] == "broken-atlas"
        assert rows[("brainpainter.atlases", "dk")]["status"] == "ok"


def test_plugin_breaking_the_contract_is_named(tmp_path):
    root = fake_distribution(
        tmp_path / "site", "wrong-atlas", {"brainpainter.atlases": {"wrong": "wrong_atlas:thing"}},
        {"wrong_atlas/__init__.py": "thing = 42\n"},
    )
    expected = r"'wrong'.*not a brainpainter\.atlas\.model\.Atlas"
    with installed(root), pytest.raises(BrainPainterError, match=expected):
        registry.atlases.get("wrong")


def test_duplicate_names_are_refused(tmp_path):
    root = fake_distribution(
        tmp_path / "site", "clash-atlas", {"brainpainter.atlases": {"dk": "clash_atlas:dk"}},
        {"clash_atlas/__init__.py": "dk = None\n"},
    )
    with installed(root):
        assert "dk" not in registry.atlases.names()
        assert "two plugins register the atlas name 'dk'" in registry.atlases.errors()["dk"]
    with pytest.raises(BrainPainterError, match="already registered"):
        registry.atlases.register("dk", lambda: None)
