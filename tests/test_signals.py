"""Signals at any moment: SIGINT/SIGTERM to the process group from start-up on.

A real ``python -m brainpainter render`` with the Blender renderer gets the
signal after several delays: while Python imports the command line, while
Blender loads (``import bpy`` runs Blender's own start-up scripts; an
exception raised there was a segmentation fault), and while it renders.
Every run must end with 130 (SIGINT) or 143 (SIGTERM) and one line, or, when
the signal came after the run ended, 0 with complete output; never a
traceback, a crash or an exit 0 without output. Nothing is published, no
staging folder and no temporary folder (``brainpainter-run-*``,
``blender_*``) is left.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from bad_inputs.corpus import GOOD

from brainpainter.io import interrupts

DELAYS = (0.5, 1.5, 3.0, 5.0, 7.0, 10.0)
CODES = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated")}


def _run_and_signal(root: Path, tiny: Path, delay: float, signum: int, extra: list[str]) -> dict:
    work = root / f"{signum}-{delay}-{len(extra)}"
    tmp = work / "tmp"
    tmp.mkdir(parents=True)
    (work / "in.csv").write_bytes(GOOD)
    env = {k: v for k, v in os.environ.items() if k != "BRAINPAINTER_DEBUG"}
    env["TMPDIR"] = str(tmp)
    args = ["render", "in.csv", "--out", "out", "--template", str(tiny), "--views",
            "lateral-left,medial-left",
            "--size", "48x48", "--quality", "fast", "-q", *extra]
    proc = subprocess.Popen([sys.executable, "-m", "brainpainter", *args], cwd=work, env=env,
                            start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    try:
        os.killpg(proc.pid, signum)
    except ProcessLookupError:
        pass
    _, err = proc.communicate(timeout=300)
    time.sleep(0.5)  # worker processes of --jobs finish dying
    return {"code": proc.returncode, "err": err, "out": work / "out", "tmp": sorted(os.listdir(tmp)),
            "work": sorted(p.name for p in work.iterdir())}


def _check(result: dict, signum: int, delay: float) -> None:
    code, word = CODES[signum]
    lines = result["err"].strip().splitlines()
    assert "Traceback" not in result["err"], result["err"][-2000:]
    assert "KeyboardInterrupt" not in result["err"], result["err"][-2000:]
    assert result["code"] != -signal.SIGSEGV, f"segmentation fault after {delay} s"
    if result["code"] == -signum:  # still in Python's own start-up (site): the signal's default action,
        assert lines == [], (delay, lines)  # which a shell reports as 128 + signum; nothing was run yet
    elif result["code"] == 0:  # the signal came after the run: complete output
        assert sorted(p.name for p in result["out"].iterdir()) == [
            "A_lateral-left.png", "A_medial-left.png", "manifest.json"], delay
    else:
        assert result["code"] == code, (delay, result["code"], result["err"][-2000:])
        assert lines == [f"{word}: nothing was published; partial output was removed"], (delay, lines)
        assert not result["out"].exists(), delay  # nothing published, no staging folder
    assert result["tmp"] == [], (delay, result["tmp"])  # no brainpainter-run-*, no blender_*
    assert result["work"] in (["in.csv", "out", "tmp"], ["in.csv", "tmp"]), result["work"]


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_at_any_moment_stops_cleanly(tmp_path, tiny, signum):
    pytest.importorskip("bpy")
    with ThreadPoolExecutor(max_workers=3) as pool:
        results = list(pool.map(lambda d: _run_and_signal(tmp_path, tiny, d, signum, []), DELAYS))
    for delay, result in zip(DELAYS, results, strict=True):
        _check(result, signum, delay)
    assert any(r["code"] != 0 for r in results)  # at least one run was really interrupted


@pytest.mark.render
@pytest.mark.slow
def test_jobs_workers_leave_no_blender_folders(tmp_path, tiny):
    pytest.importorskip("bpy")
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(lambda d: _run_and_signal(tmp_path, tiny, d, signal.SIGTERM, ["--jobs", "2"]),
                                (6.0, 9.0)))
    for delay, result in zip((6.0, 9.0), results, strict=True):
        _check(result, signal.SIGTERM, delay)


def test_a_signal_in_a_held_section_is_delivered_after_it():
    """The guard's handler defers a signal while a renderer holds (Blender starting up), then raises."""
    seen: list[str] = []

    def handler(signum, frame):
        if interrupts.defer(signum):
            seen.append("deferred")
            return
        seen.append("raised")
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGINT, handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with interrupts.held():
                signal.raise_signal(signal.SIGINT)
                seen.append("section finished")
    finally:
        signal.signal(signal.SIGINT, old)
    assert seen == ["deferred", "section finished", "raised"]


def test_a_signal_while_publishing_waits_and_the_run_reports_the_complete_output(tmp_path, monkeypatch):
    """SIGTERM between two renames of the publish: the folder is published whole, exit 0, a true line.

    (Found by --jobs 2 killed at 6 s: the output was complete on disk while the command said
    "terminated: nothing was published".)
    """
    import click
    from test_transaction import _png

    from brainpainter.cli import guard
    from brainpainter.io import transaction

    real_replace = os.replace
    calls: list[str] = []

    def replace_then_signal(src, dst):
        real_replace(src, dst)
        calls.append(os.path.basename(dst))
        if len(calls) == 1:
            signal.raise_signal(signal.SIGTERM)  # in the middle of the publish

    monkeypatch.setattr(transaction.os, "replace", replace_then_signal)
    out = tmp_path / "out"

    @click.command()
    def publish() -> None:
        with transaction.FolderTransaction(out) as tx:
            for n in ("a.png", "b.png"):
                tx.path(n).write_bytes(_png())
                tx.expect(n, size=(8, 6))
            tx.commit({"files": ["a.png", "b.png"]})

    code = guard.run(publish, [])
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "b.png", "manifest.json"]
    assert calls == ["a.png", "b.png", "manifest.json"]


def test_a_signal_while_held_takes_its_lock_does_not_deadlock():
    """A handler's defer() can run while the main thread is inside held()'s own locked block."""
    code = (
        "import signal\n"
        "from brainpainter.io import interrupts\n"
        "seen = []\n"
        "def handler(signum, frame):\n"
        "    seen.append('deferred' if interrupts.defer(signum) else 'not held')\n"
        "signal.signal(signal.SIGINT, handler)\n"
        "with interrupts._LOCK:  # where held() counts: the handler runs inside this block\n"
        "    signal.raise_signal(signal.SIGINT)\n"
        "with interrupts.held():\n"
        "    with interrupts._LOCK:\n"
        "        signal.raise_signal(signal.SIGINT)\n"
        "    seen.append('section finished')\n"
        "print(seen)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "['not held', 'deferred', 'section finished', 'not held']"


def test_the_entry_module_installs_its_handlers_before_any_import():
    """The console script's first import installs the handlers, importing nothing before (not even signal)."""
    code = (
        "import os, sys\n"
        "before = set(sys.modules)\n"
        "import brainpainter.cli.entry\n"
        "print(sorted(set(sys.modules) - before), flush=True)\n"
        "os.kill(os.getpid(), 2)  # SIGINT, as soon as the entry module is imported\n"
        "import time; time.sleep(30)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.stdout.strip() == "['brainpainter', 'brainpainter.cli', 'brainpainter.cli.entry']"
    assert proc.returncode == 130 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == "interrupted: nothing was published; partial output was removed"


_HOLD_A_RUN = """
import sys, time
from brainpainter.cli.guard import private_temp
with private_temp() as root:
    print(root, flush=True)
    time.sleep(600)
"""


def test_the_next_run_removes_the_folder_of_a_run_killed_with_sigkill(tmp_path):
    """``kill -9`` leaves a run's temporary folder (issue 33: 3 GB after one bomb); the next run removes
    the folders of dead processes and never those of live ones."""
    import tempfile

    from brainpainter.cli.guard import private_temp

    env = {**os.environ, "TMPDIR": str(tmp_path)}
    procs = [subprocess.Popen([sys.executable, "-c", _HOLD_A_RUN], env=env, stdout=subprocess.PIPE, text=True)
             for _ in range(2)]
    try:
        killed, live = (Path(p.stdout.readline().strip()) for p in procs)
        (killed / "tmp" / "big.bin").write_bytes(b"x" * 1000)
        procs[0].send_signal(signal.SIGKILL)
        procs[0].wait(timeout=30)
        assert killed.is_dir() and live.is_dir()
        saved = tempfile.tempdir
        tempfile.tempdir = str(tmp_path)
        try:
            with private_temp() as mine:
                assert not killed.exists(), "the killed run's folder is left"
                assert live.is_dir() and Path(mine).is_dir()
        finally:
            tempfile.tempdir = saved
        assert sorted(p.name for p in tmp_path.iterdir()) == [live.name]
    finally:
        for p in procs:
            p.kill()
            p.wait(timeout=30)
            p.stdout.close()


FINALISERS = {
    "__del__": ("class Held:\n"
                "    def __del__(self):\n"
                "        signal.raise_signal(signal.SIGTERM)\n"
                "        time.sleep(0.001)\n"
                "held = Held()\n"
                "del held\n"),
    # a WeakValueDictionary's remove callback hashes the key: the signal lands inside weakref.py
    "weakref": ("import weakref\n"
                "class Key:\n"
                "    armed = False\n"
                "    def __hash__(self):\n"
                "        if Key.armed:\n"
                "            Key.armed = False\n"
                "            signal.raise_signal(signal.SIGTERM)\n"
                "            time.sleep(0.001)\n"
                "        return 1\n"
                "class Value:\n"
                "    pass\n"
                "values, key, value = weakref.WeakValueDictionary(), Key(), Value()\n"
                "values[key] = value\n"
                "Key.armed = True\n"
                "del value\n"),
}


@pytest.mark.parametrize("where", sorted(FINALISERS))
def test_a_signal_inside_a_finaliser_is_raised_after_it(tmp_path, where):
    """A signal that lands in a ``__del__`` or a weak-reference callback (the import system's, weakref's:
    where a raised exception is printed as "Exception ignored" and dropped) is raised again once left."""
    script = tmp_path / "finaliser.py"
    body = "".join("    " + line + "\n" for line in FINALISERS[where].splitlines())
    script.write_text(
        "import signal, time\n"
        "from brainpainter.cli import guard\n"
        "signal.signal(signal.SIGTERM, guard._on_signal)\n"
        "try:\n" + body +
        "    time.sleep(2)\n"
        "    print('not stopped')\n"
        "except guard.Terminated:\n"
        "    print('terminated')\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.stdout.strip() == "terminated", done.stdout + done.stderr
    assert "Exception ignored" not in done.stderr, done.stderr
