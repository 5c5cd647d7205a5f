"""Start-up cost of the command line, over a bare ``python -c pass`` (issue 25).

Each of five rounds runs, interleaved, in fresh processes: ``python -c pass``,
``python -c "import bpy"`` (Blender's own start-up: no first image can be cheaper),
``brainpainter --help``, and ``brainpainter render`` of a one-row table into
one image (the first image of a cold process, default options, lateral-left),
once as a user's second run finds it (brainpainter's cache folder kept: the
installed plugins, Mesa's compiled shaders) and once with ``BRAINPAINTER_CACHE=off``
(nothing kept between runs). Prints the median of each and the costs over
``python -c pass`` (targets: ``--help`` <= 0.12 s, first image <= 0.9 s, issue 37)::

    python benchmarks/bench_startup.py [--rounds 5] [--python /other/python ...]

``--python`` (repeatable) times other installs too (e.g. a release next to a
branch), interleaved in the same rounds; the default is this Python.

For where the time goes: ``python -X importtime -m brainpainter --help 2> imports.txt``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: As a user's install runs: .pyc files written (the warm-up round writes them; pip writes them at
#: install). Some shells and CI images set PYTHONDONTWRITEBYTECODE, which makes every start compile
#: the sources again (~0.25 s of a first image here).
_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _time(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """Wall seconds and CPU seconds (user + system, all threads: less sensitive to load) of `cmd`."""
    t0 = time.perf_counter()
    # run outside any checkout: ``-m`` puts the working directory first on sys.path
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            cwd=tempfile.gettempdir(), env={**_ENV, **(env or {})})
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed")
    return time.perf_counter() - t0, usage.ru_utime + usage.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--python", action="append", default=None, help="Python to time (repeatable)")
    args = parser.parse_args()
    pythons = args.python or [sys.executable]
    times: dict[str, list[tuple[float, float]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        table = Path(tmp) / "one.csv"
        table.write_text("id,Left-Hippocampus,lh_precentral\nrow1,0.5,0.9\n", encoding="utf-8")
        runs = iter(range(10**6))
        for _ in range(args.rounds + 1):  # the first round warms the OS file cache and .pyc files
            for py in pythons:
                for name, cmd in _commands(py, table).items():
                    if name.startswith("first image"):  # a new output folder each time
                        cmd = [*cmd, str(Path(tmp) / f"out{next(runs)}")]
                    env = {"BRAINPAINTER_CACHE": "off"} if name.endswith("caches off") else None
                    times.setdefault(f"{py}: {name}", []).append(_time(cmd, env))
    for py in pythons:
        med = {name.split(": ", 1)[1]: (statistics.median(w for w, _ in v[1:]),
                                         statistics.median(c for _, c in v[1:]))
               for name, v in times.items() if name.startswith(f"{py}: ")}
        base, base_cpu = med["python -c pass"]
        print(py)
        for name, (m, cpu) in med.items():
            extra = "" if name == "python -c pass" else (
                f"  (+{m - base:.3f} s over python -c pass; CPU +{cpu - base_cpu:.3f} s)")
            print(f"  {name:24s} median {m:.3f} s of {args.rounds}, CPU {cpu:.3f} s{extra}")


def _commands(py: str, table: Path) -> dict[str, list[str]]:
    # as a user types it: the console script that pip wrote next to this Python (``python -m
    # brainpainter`` where there is none, e.g. an install that put its scripts elsewhere)
    script = Path(py).parent / "brainpainter"
    command = [str(script)] if script.is_file() else [py, "-m", "brainpainter"]
    first = [*command, "render", str(table), "--atlas", "dk", "--views", "lateral-left", "-q", "--out"]
    return {
        "python -c pass": [py, "-c", "pass"],
        "import bpy": [py, "-c", "import bpy"],  # Blender's own start, the floor of any first image
        "brainpainter --help": [*command, "--help"],
        "first image": first,
        "first image, caches off": first,  # BRAINPAINTER_CACHE=off: nothing kept between runs
    }


if __name__ == "__main__":
    main()
