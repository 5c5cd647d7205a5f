"""The bad-input corpus through real ``python -m brainpainter`` processes: a sample, one case per reason.

The whole corpus runs in-process (test_bad_inputs_inprocess.py). These
cases run as real processes because a process is what they check:

* the console entry point: ``main()`` turns the run's result into the
  process's exit code (``sys.exit``), and nothing else reaches the real
  stderr (no warning at start-up or exit);
* plugin discovery in a fresh interpreter: the stand-in renderer ``solid`` is
  found as an installed entry point (``PYTHONPATH``), as a user's plugin is;
* ``os._exit``: a run that loaded Blender leaves without its exit handlers;
  its one error line must still be flushed to the real stderr;
* hostile file descriptors (a FIFO without a writer, an endless device): a
  regression would block or fill memory, and only a separate process can be
  stopped by a timeout without taking the test run with it;
* peak memory of a whole interpreter reading a big file (``VmHWM``).

Signals (Ctrl-C, SIGTERM, kill -9), full disks, read-only folders and two
runs at once are real processes in test_reliability.py.

Each must exit with code 2, print exactly one line (``error: ...``,
containing the expected text) on stderr and no traceback, and leave its
folder exactly as it was.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from bad_inputs import corpus

from brainpainter.testing import fake_distribution

#: Case id -> why it runs as a real process.
REAL_PROCESS = {
    "non-numeric-cell": "the console entry point's exit code and the real stderr",
    "render-non-numeric": "the stand-in renderer found as an installed entry point in a fresh interpreter",
    "device-file": "an endless device: a regression would fill memory (the process has a timeout)",
    "table-is-fifo": "a FIFO without a writer: a regression would block (the process has a timeout)",
    "annot-gifti-claims-two-arrays": "a library's warning must not reach the real stderr (Python prints it "
                                     "there as two more lines)",
}
SAMPLE = [c for c in [*corpus.CASES, *corpus.INPROCESS] if c.id in REAL_PROCESS]


@pytest.fixture(scope="module")
def plugin_env(tmp_path_factory):
    """Environment whose Python sees the stand-in renderer as 'solid' (an installed entry point)."""
    entry = {"brainpainter.renderers": {"solid": "brainpainter.testing:StandInRenderer"}}
    site = fake_distribution(tmp_path_factory.mktemp("site"), "bp-solid", entry, {})
    env = {k: v for k, v in os.environ.items() if k != "BRAINPAINTER_DEBUG"}
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env["HOME"] = str(tmp_path_factory.mktemp("home"))
    return env


def _run(args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "brainpainter", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def _tree(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.lstat().st_size for p in sorted(folder.rglob("*"))}


def one_error_line(proc: subprocess.CompletedProcess, message: str) -> None:
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr + proc.stdout
    assert len(lines) == 1 and lines[0].startswith("error: "), proc.stderr[-2000:]
    assert message in lines[0], lines[0]
    assert len(lines[0]) < 600


@pytest.fixture(scope="module")
def results(tmp_path_factory, plugin_env, tiny):
    """Run the sample once, in parallel: id -> (process, files before, files after)."""
    root = tmp_path_factory.mktemp("corpus")
    jobs = {}
    for case in SAMPLE:
        folder = root / case.id
        corpus.write(case, folder)
        args = [case.command, *[a.replace("{tiny}", str(tiny)) for a in case.args]]
        jobs[case.id] = (folder, args, {**plugin_env, **case.env}, _tree(folder))
    with ThreadPoolExecutor(max_workers=len(jobs)) as pool:
        futures = {cid: pool.submit(_run, args, folder, env) for cid, (folder, args, env, _) in jobs.items()}
        return {cid: (futures[cid].result(), jobs[cid][3], _tree(jobs[cid][0])) for cid in jobs}


def test_the_sample_names_each_reason_once():
    assert sorted(c.id for c in SAMPLE) == sorted(REAL_PROCESS)


@pytest.mark.parametrize("case", SAMPLE, ids=lambda c: c.id)
def test_bad_input_fails_cleanly_in_a_real_process(results, case):
    proc, before, after = results[case.id]
    one_error_line(proc, case.message)
    assert after == before  # nothing written, nothing half-written


def test_error_after_blender_loaded_reaches_stderr(tmp_path, plugin_env, tiny):
    """The renderer starts before the output folder is locked: the error comes after ``import bpy``,
    and the run leaves through ``os._exit`` (main), which must not lose the line."""
    pytest.importorskip("bpy")
    (tmp_path / "in.csv").write_bytes(corpus.GOOD)
    (tmp_path / "o").mkdir()
    lock_fd = os.open(tmp_path / "o", os.O_RDONLY)
    fcntl.flock(lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # "another run" holds the folder
    try:
        before = _tree(tmp_path)
        proc = _run(["render", "in.csv", "--out", "o", "--renderer", "blender", "--template", str(tiny),
                     "--views", "lateral-left", "--size", "32x32", "--quality", "fast", "-q"], tmp_path,
                    plugin_env)
    finally:
        os.close(lock_fd)
    one_error_line(proc, "is in use by another brainpainter run")
    assert _tree(tmp_path) == before


def test_path_like_image_names_stay_inside_the_output_folder(tmp_path, plugin_env, tiny):
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


#: Image names in many scripts -> the file-name stem each must get (readable, distinct, short enough).
SCRIPTS = {
    "患者 1": "患者_1", "患者 2": "患者_2", "مريض-٣": "مريض-٣", "José": "José", "Ünïcødé": "Ünïcødé",
    "Ελένη": "Ελένη", "🧠": "🧠", "🧠🔥": "🧠🔥", "👨\u200d👩\u200d👧": "👨\u200d👩\u200d👧", "नमस्ते": "नमस्ते",
    "CON": "CON_", "nul.txt": "nul_.txt",  # names Windows reserves, also with an extension
}


def test_names_in_any_script_give_distinct_readable_files(tmp_path, plugin_env, tiny):
    """Names in any script keep their letters; names too long for a file system end in a short hash."""
    from brainpainter.io.output import MAX_STEM_BYTES, safe_name

    long_names = ["x" * 300, "x" * 299 + "y", "日本語" * 50]
    names = [*SCRIPTS, *long_names]
    rows = "".join(f'"{name}",{i}\n' for i, name in enumerate(names))
    (tmp_path / "in.csv").write_text("Image-name-unique,Left-insula\n" + rows, encoding="utf-8")
    proc = _run(["render", "in.csv", "--out", "out", "--renderer", "solid", "--template", str(tiny),
                 "--views", "lateral-left", "--size", "32x32", "--quiet"], tmp_path, plugin_env)
    assert proc.returncode == 0, proc.stderr
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text("utf-8"))
    by_image = {f["image"]: f["file"] for f in manifest["files"]}
    assert sorted(by_image) == sorted(names)  # every image maps to a file
    assert len(set(by_image.values())) == len(names)  # distinct files
    for name, stem in SCRIPTS.items():
        assert by_image[name] == f"{stem}_lateral-left.png"
    for name in long_names:
        file = by_image[name]
        assert len(file.encode()) <= MAX_STEM_BYTES + 20
        assert re.search(r"-[0-9a-f]{8}_lateral-left\.png$", file)
        assert file.startswith(name[:10]) and file == f"{safe_name(name)}_lateral-left.png"
    on_disk = {p.name for p in (tmp_path / "out").glob("*.png")}
    assert on_disk == set(by_image.values())


# Peak RSS of this process image (VmHWM). ru_maxrss would also count the forking parent's
# memory (a pytest process that has loaded Blender), which made the bound flaky.
PEAK_KB = ("def peak_kb():\n"
           "    for line in open('/proc/self/status'):\n"
           "        if line.startswith('VmHWM:'):\n"
           "            return int(line.split()[1])\n")


@pytest.mark.slow
def test_fifty_megabytes_are_refused_with_little_memory(big_files, plugin_env):
    big = big_files[corpus._big_table]
    assert big.stat().st_size > 50 * 2**20
    code = ("import sys\nfrom brainpainter.table.region_table import read_table\n"
            "try:\n    read_table(sys.argv[1])\nexcept Exception as exc:\n    print(type(exc).__name__)\n"
            + PEAK_KB + "print(peak_kb())\n")
    proc = subprocess.run([sys.executable, "-c", code, str(big)], capture_output=True, text=True,
                          env=plugin_env, check=True)
    name, peak_kb = proc.stdout.split()
    assert name == "BrainPainterError"
    assert int(peak_kb) < 200 * 1024  # the file is never loaded (peak RSS of the whole interpreter)


@pytest.mark.slow
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
