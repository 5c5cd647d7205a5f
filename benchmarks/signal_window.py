"""Measure the start-up window in which a SIGINT still gives Python's own ``KeyboardInterrupt`` (not a test).

Runs the installed console script (``brainpainter --version``, next to this
Python) many times and sends SIGINT after 0, 2, 4... ms; each run ends in one
of:

- ``python``: Python's defaults were still in place (interpreter and
  ``site`` start-up, before ``brainpainter/cli/entry.py`` ran): no output
  and status -2 (before Python's own handler), or a ``KeyboardInterrupt``
  traceback (status 1 inside ``site``);
- ``brainpainter``: exit 130 and the one line ``interrupted: nothing was published...``;
- ``finished``: the command was done before the signal (exit 0).

It prints, per delay, how many runs fell in each class, and the start-up time
of a bare ``python -c pass`` for comparison: the window is about that time
plus a few milliseconds. See the docstring of ``brainpainter/cli/entry.py``.

    python benchmarks/signal_window.py                  # 0..80 ms, 5 runs each
    python benchmarks/signal_window.py --max-ms 150 --runs 10
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path


def one(cmd: list[str], delay_s: float) -> str:
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(delay_s)
    try:
        os.kill(proc.pid, signal.SIGINT)
    except ProcessLookupError:
        pass
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        return "finished"
    if proc.returncode == 130 and "Traceback" not in err and err.strip().startswith("interrupted:"):
        return "brainpainter"
    if "KeyboardInterrupt" in err or proc.returncode == -signal.SIGINT:
        return "python"
    return f"other({proc.returncode}: {err.strip()[-80:]!r})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-ms", type=int, default=80)
    ap.add_argument("--step-ms", type=int, default=5)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    script = Path(sys.executable).parent / "brainpainter"
    start = [str(script)] if script.exists() else [sys.executable, "-m", "brainpainter"]
    cmd = [*start, "--version"]
    starts = []
    for _ in range(10):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        starts.append((time.perf_counter() - t0) * 1000)
    print(f"command: {' '.join(cmd)}")
    print(f"bare 'python -c pass': median {statistics.median(starts):.1f} ms")
    last_python = None
    for ms in range(0, args.max_ms + 1, args.step_ms):
        seen: dict[str, int] = {}
        for _ in range(args.runs):
            kind = one(cmd, ms / 1000)
            seen[kind] = seen.get(kind, 0) + 1
        if "python" in seen:
            last_python = ms
        print(f"{ms:4d} ms: " + ", ".join(f"{k} {n}" for k, n in sorted(seen.items())))
    print(f"last delay with Python's own KeyboardInterrupt: {last_python} ms")


if __name__ == "__main__":
    main()
