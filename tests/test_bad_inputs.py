"""The bad-input corpus (tests/bad_inputs/corpus.py) through the real CLI.

Each case runs ``python -m brainpainter check|render`` in its own empty
folder and must exit with code 2, print exactly one line (``error: ...``,
containing the expected text) on stderr and no traceback, and leave the
folder exactly as it was: no output folder, no partial file. The cases run
in parallel subprocesses (once per module) and are then checked one by one.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from brainpainter.testing import fake_distribution, write_tiny_template

HERE = Path(__file__).parent
_spec = importlib.util.spec_from_file_location("bad_input_corpus", HERE / "bad_inputs" / "corpus.py")
corpus = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = corpus
_spec.loader.exec_module(corpus)

SOLID = '''
import numpy as np


class SolidRenderer:
    def __init__(self, scene):
        self.scene = scene

    def render(self, colors, view):
        s = self.scene.settings
        img = np.zeros((s.height, s.width, 4), np.uint8)
        img[..., 3] = 255
        return img

    def close(self):
        pass
'''


@pytest.fixture(scope="module")
def plugin_env(tmp_path_factory):
    """Environment whose Python sees a stand-in renderer 'solid' (an installed entry point)."""
    site = fake_distribution(tmp_path_factory.mktemp("site"), "bp-solid",
                             {"brainpainter.renderers": {"solid": "bp_solid:SolidRenderer"}},
                             {"bp_solid.py": SOLID})
    env = {k: v for k, v in os.environ.items() if k != "BRAINPAINTER_DEBUG"}
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env["HOME"] = str(tmp_path_factory.mktemp("home"))
    return env


def _run(args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "brainpainter", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def _tree(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.stat().st_size for p in sorted(folder.rglob("*"))}


@pytest.fixture(scope="module")
def results(tmp_path_factory, plugin_env):
    """Run every case once, in parallel: id -> (process, files before, files after)."""
    root = tmp_path_factory.mktemp("corpus")
    jobs = {}
    for case in corpus.CASES:
        folder = root / case.id
        corpus.write(case, folder)
        args = [case.command, *case.args]
        if case.command == "render":
            args += ["--out", "out", "--renderer", "solid", "--quiet"]
        jobs[case.id] = (folder, args, {**plugin_env, **case.env}, _tree(folder))
    with ThreadPoolExecutor(max_workers=min(8, 2 * (os.cpu_count() or 2))) as pool:
        futures = {cid: pool.submit(_run, args, folder, env) for cid, (folder, args, env, _) in jobs.items()}
        return {cid: (futures[cid].result(), jobs[cid][3], _tree(jobs[cid][0])) for cid in jobs}


def test_corpus_is_big_enough():
    ids = [c.id for c in corpus.CASES]
    assert len(ids) == len(set(ids)) and len(ids) >= 40


@pytest.mark.parametrize("case", corpus.CASES, ids=lambda c: c.id)
def test_bad_input_fails_cleanly(results, case):
    proc, before, after = results[case.id]
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr + proc.stdout
    assert len(lines) == 1 and lines[0].startswith("error: "), proc.stderr[-2000:]
    assert case.message in lines[0], lines[0]
    assert len(lines[0]) < 600
    assert after == before  # nothing written, nothing half-written


def test_path_like_image_names_stay_inside_the_output_folder(tmp_path, plugin_env):
    tiny = write_tiny_template(tmp_path / "tiny")
    work = tmp_path / "a" / "b" / "work"
    work.mkdir(parents=True)
    rows = "".join(f'"{name}",{i}\n' for i, name in enumerate(corpus.SAFE))
    (work / "in.csv").write_text("Image-name-unique,Left-insula\n" + rows)
    before = _tree(tmp_path)
    proc = _run(["render", "in.csv", "--out", "out", "--renderer", "solid", "--template", str(tiny),
                 "--views", "lateral-left", "--size", "32x32", "--quiet"], work, plugin_env)
    assert proc.returncode == 0, proc.stderr
    new = sorted(set(_tree(tmp_path)) - set(before))
    assert all(p.startswith("a/b/work/out") for p in new), new
    pngs = sorted(p.name for p in (work / "out").glob("*.png"))
    assert pngs == sorted(f"{safe}_lateral-left.png" for safe in corpus.SAFE.values())
    assert not (tmp_path / "a" / "x_lateral-left.png").exists()


# Peak RSS of this process image (VmHWM). ru_maxrss would also count the forking parent's
# memory (a pytest process that has loaded Blender), which made the bound flaky.
PEAK_KB = ("def peak_kb():\n"
           "    for line in open('/proc/self/status'):\n"
           "        if line.startswith('VmHWM:'):\n"
           "            return int(line.split()[1])\n")


def test_fifty_megabytes_are_refused_with_little_memory(tmp_path, plugin_env):
    big = tmp_path / "big.csv"
    corpus._big_table(big)
    assert big.stat().st_size > 50 * 2**20
    code = ("import sys\nfrom brainpainter.table.region_table import read_table\n"
            "try:\n    read_table(sys.argv[1])\nexcept Exception as exc:\n    print(type(exc).__name__)\n"
            + PEAK_KB + "print(peak_kb())\n")
    proc = subprocess.run([sys.executable, "-c", code, str(big)], capture_output=True, text=True,
                          env=plugin_env, check=True)
    name, peak_kb = proc.stdout.split()
    assert name == "BrainPainterError"
    assert int(peak_kb) < 200 * 1024  # the file is never loaded (peak RSS of the whole interpreter)


def test_largest_accepted_file_reads_in_bounded_memory(tmp_path, plugin_env):
    """A 30 MB table (just under the 32 MB limit) is read; peak memory stays under 20x its size."""
    path = tmp_path / "30mb.csv"
    corpus._big_table(path, megabytes=30)
    code = ("import sys\nfrom brainpainter.table.region_table import read_table\n"
            "t = read_table(sys.argv[1])\n" + PEAK_KB + "print(t.values.shape[0], peak_kb())\n")
    proc = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True,
                          env=plugin_env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows, peak_kb = (int(x) for x in proc.stdout.split())
    assert rows > 30_000
    print(f"30 MB table: peak RSS {peak_kb / 1024:.0f} MB")
    assert peak_kb < 20 * 30 * 1024, peak_kb
