"""Start-up cost of the command line, over a bare ``python -c pass`` (issue 25).

Each of five rounds runs, interleaved, in fresh processes: ``python -c pass``,
``python -c "import bpy"`` (Blender's own start-up: no first image can be cheaper),
``brainpainter --help``, and ``brainpainter render`` of a one-row table into
one image (the first image of a cold process, default options, lateral-left).
Prints the median of each and the two costs over ``python -c pass``
(targets: ``--help`` <= 0.12 s, first image <= 0.8 s)::

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


def _time(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    # run outside any checkout: ``-m`` puts the working directory first on sys.path
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   cwd=tempfile.gettempdir(), env=_ENV)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--python", action="append", default=None, help="Python to time (repeatable)")
    args = parser.parse_args()
    pythons = args.python or [sys.executable]
    times: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        table = Path(tmp) / "one.csv"
        table.write_text("id,Left-Hippocampus,lh_precentral\nrow1,0.5,0.9\n", encoding="utf-8")
        runs = iter(range(10**6))
        for _ in range(args.rounds + 1):  # the first round warms the OS file cache and .pyc files
            for py in pythons:
                for name, cmd in _commands(py, table).items():
                    if name == "first image":  # a new output folder each time
                        cmd = [*cmd, str(Path(tmp) / f"out{next(runs)}")]
                    times.setdefault(f"{py}: {name}", []).append(_time(cmd))
    for py in pythons:
        med = {name.split(": ", 1)[1]: statistics.median(v[1:]) for name, v in times.items()
               if name.startswith(f"{py}: ")}
        base = med["python -c pass"]
        print(py)
        for name, m in med.items():
            extra = "" if name == "python -c pass" else f"  (+{m - base:.3f} s over python -c pass)"
            print(f"  {name:22s} median {m:.3f} s of {args.rounds}{extra}")


def _commands(py: str, table: Path) -> dict[str, list[str]]:
    # as a user types it: the console script that pip wrote next to this Python (``python -m
    # brainpainter`` where there is none, e.g. an install that put its scripts elsewhere)
    script = Path(py).parent / "brainpainter"
    command = [str(script)] if script.is_file() else [py, "-m", "brainpainter"]
    return {
        "python -c pass": [py, "-c", "pass"],
        "import bpy": [py, "-c", "import bpy"],  # Blender's own start, the floor of any first image
        "brainpainter --help": [*command, "--help"],
        "first image": [*command, "render", str(table), "--atlas", "dk",
                        "--views", "lateral-left", "-q", "--out"],
    }


if __name__ == "__main__":
    main()
