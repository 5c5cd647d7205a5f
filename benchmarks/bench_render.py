"""Benchmark: render the bundled example scaled to many rows.

Prints images per second, median seconds per image, time to the first image
from a cold process, and peak memory for two row counts (to show that memory
does not grow with the number of rows).

    python benchmarks/bench_render.py                 # 50 rows x 3 default views, 1200x900
    python benchmarks/bench_render.py --rows 10 --quality fast

Record results in docs/benchmarks.md with the machine they ran on.
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
import pandas as pd
import brainpainter
from brainpainter.render import render
args = json.loads(sys.argv[1])
frame = pd.read_csv(args["example"])
rows = [frame.iloc[i % len(frame)].copy() for i in range(args["rows"])]
big = pd.DataFrame(rows).reset_index(drop=True)
big["Image-name-unique"] = [f"row{i:03d}" for i in range(len(big))]
stamps = []
import brainpainter.output as output
_orig = output.write_png
def timed_write(path, image, metadata=None):
    _orig(path, image, metadata)
    stamps.append(time.perf_counter())
output.write_png = timed_write
render(big, "dk", out=args["out"], views=args["views"], width=args["width"], height=args["height"],
       quality=args["quality"], progress=False)
t_end = time.perf_counter()
peak_mb = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:")) / 1024
print(json.dumps({"t_first": stamps[0] - t0, "t_total": t_end - t0, "stamps": [s - t0 for s in stamps],
                  "peak_mb": peak_mb}))
"""


def run_child(rows: int, args: argparse.Namespace) -> dict:
    with tempfile.TemporaryDirectory() as out:
        cfg = {"example": str(EXAMPLE), "rows": rows, "out": out, "views": args.views,
               "width": args.width, "height": args.height, "quality": args.quality}
        code = CHILD
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", code, json.dumps(cfg)], capture_output=True,
                              text=True, check=True)
        wall = time.perf_counter() - start
        result = json.loads(proc.stdout.strip().splitlines()[-1])
        result["wall"] = wall
        result["n_images"] = len(list(Path(out).glob("*.png")))
        return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=50)
    parser.add_argument("--small-rows", type=int, default=10, help="row count for the memory comparison")
    parser.add_argument("--views", default="lateral-left,medial-left,subcortical")
    parser.add_argument("--size", default="1200x900")
    parser.add_argument("--quality", default="default")
    args = parser.parse_args()
    args.width, args.height = (int(x) for x in args.size.split("x"))

    small = run_child(args.small_rows, args)
    big = run_child(args.rows, args)
    stamps = big["stamps"]
    per_image = [b - a for a, b in itertools.pairwise(stamps)]
    n = big["n_images"]
    amortised = (big["t_total"]) / n
    report = {
        "images": n,
        "size": args.size,
        "quality": args.quality,
        "images_per_second": round(n / big["t_total"], 2),
        "amortised_s_per_image_incl_startup": round(amortised, 3),
        "median_s_per_image_steady": round(statistics.median(per_image), 3) if per_image else None,
        "time_to_first_image_cold_s": round(big["t_first"], 2),
        "process_wall_s": round(big["wall"], 2),
        f"peak_memory_mb_{args.small_rows}_rows": round(small["peak_mb"]),
        f"peak_memory_mb_{args.rows}_rows": round(big["peak_mb"]),
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
