"""Per-image cost of two installs of brainpainter, interleaved in one run (e.g. a release and a branch).

Each round starts one fresh process per Python and times ``Painter.paint_colors``
(render + read-back, default settings, 1200x900, random colours per image) for
the lateral-left, medial-left and subcortical views; rounds alternate, so load
on the machine falls on both alike. Prints the median per view and overall,
and B over A::

    python benchmarks/bench_ab.py --a /path/to/release/python --b /path/to/branch/python [--rounds 4]

``--rows N`` times whole runs instead: ``render`` of the bundled example
scaled to N rows x the three views, PNGs written (``bench_render.py``'s
child), per run the images after the first over the time after the first
PNG (start-up left out) and the run's CPU seconds per image.

(On the development machine: ``--a python3`` is main's editable install and
``--b /work/venvs/picture/bin/python`` this branch's.)
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import tempfile

CHILD = r"""
import json, sys, time
import numpy as np
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import get_view
args = json.loads(sys.argv[1])
painter = Painter("dk", settings=RenderSettings(args["width"], args["height"]))
keys = [r.key for r in painter.atlas.regions]
rng = np.random.default_rng(0)
out = {}
for name in args["views"]:
    view = get_view(name)
    times = []
    for i in range(args["n"] + 2):
        colors = {k: tuple(rng.random(3)) for k in keys}
        t = time.perf_counter()
        painter.paint_colors(colors, view)
        times.append(time.perf_counter() - t)
    out[name] = times[2:]
painter.close()
print(json.dumps(out))
"""


def end_to_end(py: str, rows: int, width: int, height: int, cwd: str) -> dict[str, float]:
    """One run of ``bench_render.py``'s child: seconds per image after the first, CPU s per image."""
    from bench_render import CHILD, EXAMPLE

    with tempfile.TemporaryDirectory() as out:
        cfg = {"example": str(EXAMPLE), "rows": rows, "out": out, "width": width, "height": height,
               "views": ["lateral-left", "medial-left", "subcortical"], "quality": "default"}
        proc = subprocess.run([py, "-c", CHILD, json.dumps(cfg)], capture_output=True, text=True, check=True,
                              cwd=cwd)
    got = json.loads([x for x in proc.stdout.splitlines() if x.startswith("{")][-1])
    stamps = got["stamps"]
    return {"per_image": (stamps[-1] - stamps[0]) / (len(stamps) - 1),
            "cpu_per_image": got["cpu_s"] / len(stamps)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--a", required=True, help="Python of install A (the reference)")
    parser.add_argument("--b", required=True, help="Python of install B")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--n", type=int, default=10, help="images per view per round")
    parser.add_argument("--size", default="1200x900")
    parser.add_argument("--rows", type=int, default=0, help="time whole runs of this many rows x 3 views")
    args = parser.parse_args()
    w, h = (int(x) for x in args.size.split("x"))
    if args.rows:
        runs: dict[str, list[dict[str, float]]] = {"A": [], "B": []}
        with tempfile.TemporaryDirectory() as cwd:
            for _ in range(args.rounds):
                for key, py in (("A", args.a), ("B", args.b)):
                    runs[key].append(end_to_end(py, args.rows, w, h, cwd))
        for what in ("per_image", "cpu_per_image"):
            a = statistics.median(r[what] for r in runs["A"])
            b = statistics.median(r[what] for r in runs["B"])
            each = "  ".join(f"{ra[what] * 1000:.0f}/{rb[what] * 1000:.0f}"
                             for ra, rb in zip(runs["A"], runs["B"], strict=True))
            print(f"{what:14s} A {a * 1000:6.1f} ms  B {b * 1000:6.1f} ms  B/A {b / a:.3f}"
                  f"   (A/B per round, ms: {each})")
        return
    cfg = json.dumps({"width": w, "height": h, "n": args.n,
                      "views": ["lateral-left", "medial-left", "subcortical"]})
    got: dict[str, dict[str, list[float]]] = {"A": {}, "B": {}}
    with tempfile.TemporaryDirectory() as cwd:  # not the repository: its checkout would shadow an install
        for _ in range(args.rounds):
            for key, py in (("A", args.a), ("B", args.b)):
                proc = subprocess.run([py, "-c", CHILD, cfg], capture_output=True, text=True, check=True,
                                      cwd=cwd)
                line = [x for x in proc.stdout.splitlines() if x.startswith("{")][-1]
                for view, times in json.loads(line).items():
                    got[key].setdefault(view, []).extend(times)
    for view in got["A"]:
        a, b = statistics.median(got["A"][view]), statistics.median(got["B"][view])
        print(f"{view:14s} A {a * 1000:6.1f} ms  B {b * 1000:6.1f} ms  B/A {b / a:.3f}")
    a = statistics.median(t for v in got["A"].values() for t in v)
    b = statistics.median(t for v in got["B"].values() for t in v)
    print(f"{'all views':14s} A {a * 1000:6.1f} ms  B {b * 1000:6.1f} ms  B/A {b / a:.3f}")


if __name__ == "__main__":
    main()
