"""The in-process half of the bad-input corpus (``corpus.INPROCESS``), run through the CLI guard.

Each case runs :func:`brainpainter.cli.guard.run` (what ``brainpainter`` runs)
in click's ``CliRunner`` isolation, inside its own folder, with a stand-in
renderer: a user error must give exit code 2, exactly one line on stderr
(``error: ...`` with the expected text), no traceback, and leave the case
folder, HOME and the temporary folder exactly as they were. Accepted cases
(``code=0``) must print the expected warning and write only into ``o/``.
"""

from __future__ import annotations

import fcntl
import importlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.cli.guard import run
from brainpainter.cli.main import cli
from brainpainter.testing import stand_in, write_tiny_template

HERE = Path(__file__).parent
if "bad_input_corpus" in sys.modules:
    corpus = sys.modules["bad_input_corpus"]
else:
    _spec = importlib.util.spec_from_file_location("bad_input_corpus", HERE / "bad_inputs" / "corpus.py")
    corpus = importlib.util.module_from_spec(_spec)
    sys.modules[_spec.name] = corpus
    _spec.loader.exec_module(corpus)


def _tree(folder: Path) -> dict[str, int]:
    out = {}
    for p in sorted(folder.rglob("*")):
        try:
            out[str(p.relative_to(folder))] = p.lstat().st_size
        except OSError:
            pass
    return out


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> Path:
    return write_tiny_template(tmp_path_factory.mktemp("tpl") / "tiny")


def invoke(args: list[str], env: dict[str, str] | None = None) -> tuple[int, str, str]:
    """Run the CLI in-process as ``brainpainter ARGS``: (exit code, stdout, stderr)."""
    runner = CliRunner()
    with runner.isolation(env=env) as (out, err, _):
        code = run(cli, args)
    return code, out.getvalue().decode(), err.getvalue().decode() if err else ""


def test_corpus_has_150_cases_of_every_class():
    ids = [c.id for c in corpus.CASES] + [c.id for c in corpus.INPROCESS]
    assert len(ids) == len(set(ids))
    assert len(ids) >= 150, len(ids)
    commands = {c.command for c in corpus.INPROCESS}
    assert {"check", "render", "figure", "movie", "atlas", "template"} <= commands


@pytest.mark.parametrize("case", corpus.INPROCESS, ids=lambda c: c.id)
def test_bad_input_in_process(case, tmp_path, tiny, monkeypatch):
    folder = tmp_path / "case"
    corpus.write(case, folder)
    for target, value in case.patch.items():
        module, attr = target.split(":")
        monkeypatch.setattr(importlib.import_module(module), attr, value)
    for key, value in case.env.items():
        monkeypatch.setenv(key, value)
    temp = tmp_path / "tmp"
    temp.mkdir()
    monkeypatch.setenv("TMPDIR", str(temp))
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    home = Path(os.environ["HOME"])
    monkeypatch.chdir(folder)
    args = [case.command, *[a.replace("{tiny}", str(tiny)) for a in case.args]]
    lock_fd = None
    if case.lock:
        (folder / case.lock).mkdir(exist_ok=True)
        lock_fd = os.open(folder / case.lock, os.O_RDONLY)
        fcntl.flock(lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # "another run" holds the folder
    before, home_before = _tree(folder), _tree(home)
    try:
        with stand_in("solid"):
            code, out, err = invoke(args)
    finally:
        if lock_fd is not None:
            os.close(lock_fd)
        registry.atlases.reset()
    lines = err.strip().splitlines()
    assert "Traceback" not in out + err
    assert _tree(temp) == {}, "temporary files left behind"
    assert _tree(home) == home_before, "something was written into HOME"
    if case.code == 0:
        assert code == 0, err
        assert case.message in out, out
        assert all(p.startswith("o") for p in set(_tree(folder)) - set(before))
        manifest = folder / "o" / "manifest.json"
        assert not (folder / "o").exists() or manifest.is_file()
        return
    assert code == case.code, (code, out, err)
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert case.message in lines[0], lines[0]
    assert len(lines[0]) < 600
    assert _tree(folder) == before  # nothing written, nothing half-written, nothing deleted
