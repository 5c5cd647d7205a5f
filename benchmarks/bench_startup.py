"""Start-up cost of the command line, over a bare ``python -c pass`` (issue 25).

Each of five rounds runs, interleaved, in fresh processes: ``python -c pass``,
``brainpainter --help``, and ``brainpainter render`` of a one-row table into
one image (the first image of a cold process, default options, lateral-left).
Prints the median of each and the two costs over ``python -c pass``
(targets: ``--help`` <= 0.12 s, first image <= 0.8 s)::

    python benchmarks/bench_startup.py [--rounds 5]

For where the time goes: ``python -X importtime -m brainpainter --help 2> imports.txt``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _time(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        table = Path(tmp) / "one.csv"
        table.write_text("id,Left-Hippocampus,lh_precentral\nrow1,0.5,0.9\n", encoding="utf-8")
        commands = {
            "python -c pass": [py, "-c", "pass"],
            "brainpainter --help": [py, "-m", "brainpainter", "--help"],
            "first image": [py, "-m", "brainpainter", "render", str(table), "--atlas", "dk",
                            "--views", "lateral-left", "--out"],
        }
        runs = iter(range(10**6))

        def argv(name: str) -> list[str]:  # a new output folder each time
            cmd = commands[name]
            return [*cmd, str(Path(tmp) / f"out{next(runs)}")] if name == "first image" else cmd

        _time(argv("first image"))  # warm the OS file cache (and .pyc files) once
        times: dict[str, list[float]] = {k: [] for k in commands}
        for _ in range(args.rounds):
            for name in commands:
                times[name].append(_time(argv(name)))
    med = {k: statistics.median(v) for k, v in times.items()}
    base = med["python -c pass"]
    for name, m in med.items():
        extra = "" if name == "python -c pass" else f"  (+{m - base:.3f} s over python -c pass)"
        print(f"{name:22s} median {m:.3f} s of {len(times[name])}{extra}")


if __name__ == "__main__":
    main()
