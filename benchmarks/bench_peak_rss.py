"""Peak memory of a CLI render (issue 37: a 100-row run <= 500 MB), installs interleaved.

Each round runs ``brainpainter render`` of a table of `--rows` rows of random DK values (default
views, default size) once per Python, in fresh processes, and reads the child's peak resident
memory (``ru_maxrss`` from ``os.wait4``: the kernel's VmHWM). Prints the median per Python and
the ratio to the first one::

    python benchmarks/bench_peak_rss.py [--rows 100] [--rounds 3] [--python A --python B]

Where the memory goes inside a run: ``/proc/self/status`` VmRSS sampled beside the stack of the
main thread (docs/benchmarks.md, "Issue 37").
"""

from __future__ import annotations

import argparse
import csv
import os
import random
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "brainpainter_dk.csv"
_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def write_table(path: Path, rows: int) -> None:
    """`rows` rows of random values (0-3) for every region of the bundled DK example's columns."""
    with open(EXAMPLE, newline="", encoding="utf-8") as f:
        header = next(csv.reader(f))
    rng = random.Random(0)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for i in range(rows):
            w.writerow([f"img{i:04d}", *(f"{3 * rng.random():.3f}" for _ in header[1:])])


def peak_mb(cmd: list[str]) -> float:
    """Run `cmd` and return its peak resident memory in MB."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            cwd=tempfile.gettempdir(), env=_ENV)
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed")
    return usage.ru_maxrss / 1024  # KB on Linux


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=100)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--python", action="append", default=None, help="Python to measure (repeatable)")
    args = parser.parse_args()
    pythons = args.python or [sys.executable]
    got: dict[str, list[float]] = {py: [] for py in pythons}
    with tempfile.TemporaryDirectory() as tmp:
        table = Path(tmp) / "rows.csv"
        write_table(table, args.rows)
        for r in range(args.rounds):
            for py in pythons:
                script = Path(py).parent / "brainpainter"
                command = [str(script)] if script.is_file() else [py, "-m", "brainpainter"]
                got[py].append(peak_mb([*command, "render", str(table), "--atlas", "dk", "-q",
                                        "--out", str(Path(tmp) / f"out{r}-{pythons.index(py)}")]))
    first = statistics.median(got[pythons[0]])
    for py, values in got.items():
        m = statistics.median(values)
        print(f"{py}: peak RSS median {m:.0f} MB of {len(values)} ({', '.join(f'{v:.0f}' for v in values)}), "
              f"{m / first:.3f} x the first")


if __name__ == "__main__":
    main()
