"""Commands that only read work on a plain install (no ``builder`` extra).

A ``sitecustomize`` put first on ``PYTHONPATH`` makes ``import pymeshlab``
and ``import skimage`` fail (``sys.modules[name] = None``) in a real ``python -m brainpainter`` process,
as on a machine where ``pip install brainpainter`` did not install the
``[builder]`` extra. Every reading command must work; ``template build``
must say in one line which extra it needs.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

BLOCKER = """
import sys
for name in ("pymeshlab", "skimage"):
    sys.modules[name] = None  # import fails, importlib.util.find_spec returns None: as if not installed
"""
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def plain_env(tmp_path_factory):
    site = tmp_path_factory.mktemp("plain_site")
    (site / "sitecustomize.py").write_text(BLOCKER)
    env = {k: v for k, v in os.environ.items() if k != "BRAINPAINTER_DEBUG"}
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env["HOME"] = str(tmp_path_factory.mktemp("home"))
    return env


def _run(args: list[str], env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "brainpainter", *args], env=env, cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def test_the_blocker_blocks(plain_env, tmp_path):
    proc = subprocess.run([sys.executable, "-c", "import pymeshlab"], env=plain_env, capture_output=True,
                          text=True, cwd=tmp_path)
    assert proc.returncode != 0 and "pymeshlab" in proc.stderr


@pytest.mark.parametrize("args", [["template", "info", "fsaverage"], ["template", "info"],
                                  ["template", "info", "fsaverage", "--json"], ["atlas", "list"],
                                  ["atlas", "show", "dk"],
                                  ["check", str(ROOT / "examples" / "brainpainter_dk.csv")]],
                         ids=" ".join)
def test_reading_commands_need_no_builder_extra(plain_env, tmp_path, args):
    proc = _run(args, plain_env, tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stderr == ""
    if args[:2] == ["template", "info"] and "--json" not in args:
        assert "checks: ok" in proc.stdout
        assert "self-intersections not checked (needs pymeshlab" in proc.stdout


def test_template_build_names_the_extra_in_one_line(plain_env, tmp_path):
    (tmp_path / "subj").mkdir()
    proc = _run(["template", "build", "subj", "--out", "t"], plain_env, tmp_path)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "brainpainter[builder]" in lines[0] and "pymeshlab" in lines[0]
    assert not (tmp_path / "t").exists()
