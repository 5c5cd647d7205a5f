"""The whole bad-input corpus (``corpus.CASES`` and ``corpus.INPROCESS``), in-process through the CLI.

Each case runs :func:`brainpainter.cli.main.main` (what the ``brainpainter``
console script runs, given the arguments) in click's ``CliRunner`` isolation,
inside its own folder, with a stand-in renderer registered as ``solid``: a
user error must give exit code 2, exactly one line on stderr (``error: ...``
with the expected text), no traceback, and leave the case folder, HOME and
the temporary folder exactly as they were. Accepted cases (``code=0``) must
print the expected warning and write only into ``o/``. What only a real
process shows (the console entry point, signals, os._exit, real streams and
file descriptors) is checked on a sample in test_bad_inputs.py.
"""

from __future__ import annotations

import fcntl
import importlib
import os
import tempfile
from pathlib import Path

import pytest
from bad_inputs import corpus
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.cli.main import main
from brainpainter.testing import stand_in

ALL = [*corpus.CASES, *corpus.INPROCESS]


def _tree(folder: Path) -> dict[str, int]:
    out = {}
    for p in sorted(folder.rglob("*")):
        try:
            out[str(p.relative_to(folder))] = p.lstat().st_size
        except OSError:
            pass
    return out


def invoke(args: list[str]) -> tuple[int, str, str]:
    """Run the CLI in-process as ``brainpainter ARGS``: (exit code, stdout, stderr)."""
    runner = CliRunner()
    with runner.isolation() as (out, err, _):
        try:
            main(args)
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
    return code, out.getvalue().decode(), err.getvalue().decode() if err else ""


def test_corpus_has_150_cases_of_every_class():
    ids = [c.id for c in ALL]
    assert len(ids) == len(set(ids))
    assert len(ids) >= 150, len(ids)
    commands = {c.command for c in ALL}
    assert {"check", "render", "figure", "movie", "atlas", "template"} <= commands


def _prepare(case: corpus.Case, folder: Path, monkeypatch: pytest.MonkeyPatch, request) -> Path:
    """Write the case, apply its patches and environment, give it an empty TMPDIR (returned)."""
    shared = request.getfixturevalue("big_files") if corpus.is_big(case) else None
    corpus.write(case, folder, shared)
    if case.lock:
        (folder / case.lock).mkdir(exist_ok=True)
    for target, value in case.patch.items():
        module, attr = target.split(":")
        monkeypatch.setattr(importlib.import_module(module), attr, value)
    for key, value in case.env.items():
        monkeypatch.setenv(key, value)
    temp = folder.parent / "tmp"
    temp.mkdir()
    monkeypatch.setenv("TMPDIR", str(temp))
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    monkeypatch.chdir(folder)
    return temp


def _run_locked(case: corpus.Case, folder: Path, args: list[str]) -> tuple[int, str, str]:
    lock_fd = None
    if case.lock:
        lock_fd = os.open(folder / case.lock, os.O_RDONLY)
        fcntl.flock(lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # "another run" holds the folder
    try:
        with stand_in("solid"):
            return invoke(args)
    finally:
        if lock_fd is not None:
            os.close(lock_fd)
        registry.atlases.reset()


@pytest.mark.parametrize("case", corpus.params(ALL))
def test_bad_input_in_process(case, tmp_path, tiny, monkeypatch, request):
    folder = tmp_path / "case"
    temp = _prepare(case, folder, monkeypatch, request)
    home = Path(os.environ["HOME"])
    args = [case.command, *[a.replace("{tiny}", str(tiny)) for a in case.args]]
    before, home_before = _tree(folder), _tree(home)
    code, out, err = _run_locked(case, folder, args)
    lines = err.strip().splitlines()
    assert "Traceback" not in out + err
    assert _tree(temp) == {}, "temporary files left behind"
    def kept(tree: dict[str, int]) -> dict[str, int]:  # a run that succeeds keeps its caches there
        return {k: v for k, v in tree.items() if case.code != 0 or not k.startswith(".cache")}

    assert kept(_tree(home)) == kept(home_before), "something was written into HOME"
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
