"""Benchmark (issue 15): one table rendered serially, with --jobs N, and on a Dask LocalCluster of N workers.

Each mode runs in a fresh Python process (so each pays for starting Blender,
as a user's run does), renders the same table into its own folder, and the
outputs are compared byte for byte. Printed per mode: wall time of the whole
``render()`` call, time to start the workers (spawn, import, load the scene:
``start``), each worker's painter start-up, images per second after start-up,
the speed-up over the serial run, and the CPU seconds per image of all the
run's processes (workers included). The Dask cluster's own start-up (before
``render()``) is printed apart, since a cluster normally outlives one run.

    python benchmarks/bench_parallel.py                      # the issue's: 100 rows x 3 views, 1200x900
    python benchmarks/bench_parallel.py --rows 20 --size 400x300 --jobs 2

The machine's load (``/proc/loadavg``) is printed before and after: speed-ups
measured on a busy machine are lower bounds. Record results in
docs/benchmarks.md with the machine and the load.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"

CHILD = r"""
import json, sys, time
args = json.loads(sys.argv[1])
if __name__ == "__main__":
    import pandas as pd
    from brainpainter.rendering.run import render
    frame = pd.read_csv(args["example"])
    rows = [frame.iloc[i % len(frame)].copy() for i in range(args["rows"])]
    big = pd.DataFrame(rows).reset_index(drop=True)
    big["Image-name-unique"] = [f"row{i:03d}" for i in range(len(big))]
    width, height = (int(x) for x in args["size"].split("x"))
    kw = dict(atlas="dk", out=args["out"], views=args["views"], width=width, height=height, progress=False)
    cluster_s = None
    if args["mode"] == "dask":
        from distributed import Client, LocalCluster
        t = time.perf_counter()
        cluster = LocalCluster(n_workers=args["jobs"], threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address="127.0.0.1:0")
        client = Client(cluster)
        cluster_s = time.perf_counter() - t
        kw["client"] = client
    elif args["mode"] == "jobs":
        kw["jobs"] = args["jobs"]
    t = time.perf_counter()
    result = render(big, **kw)
    wall = time.perf_counter() - t
    if args["mode"] == "dask":
        client.close(); cluster.close()
    w = result.workers
    print(json.dumps({"mode": args["mode"], "wall": wall, "images": len(result.files), "cluster_s": cluster_s,
                      "start": w["start_wall"], "startup": w["startup_seconds"], "workers": w["workers"],
                      "retried": len(w["retried"])}))
"""


def loadavg() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "n/a"


def same(a: Path, b: Path) -> bool:
    names = sorted(p.name for p in a.iterdir())
    return names == sorted(p.name for p in b.iterdir()) and all(
        (a / n).read_bytes() == (b / n).read_bytes() for n in names)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=100)
    ap.add_argument("--views", default="lateral-left,medial-left,subcortical")
    ap.add_argument("--size", default="1200x900")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--modes", default="serial,jobs,dask", help="Which runs, comma-separated.")
    args = ap.parse_args()
    n_views = len(args.views.split(","))
    print(f"{args.rows} rows x {n_views} views at {args.size}; {args.jobs} workers; "
          f"{os.cpu_count()} cores; load before {loadavg()}", flush=True)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for mode in args.modes.split(","):
            spec = {"mode": mode, "example": str(EXAMPLE), "rows": args.rows, "views": args.views,
                    "size": args.size, "jobs": args.jobs, "out": str(Path(tmp) / mode)}
            t = time.perf_counter()
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(spec)], capture_output=True,
                                 text=True, check=False)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            if out.returncode != 0:
                sys.exit(f"{mode} failed:\n{out.stderr[-3000:]}")
            r = json.loads(out.stdout.strip().splitlines()[-1])
            r["process"] = time.perf_counter() - t
            # CPU seconds of the run's processes (workers included): on a busy machine, the fairer measure
            r["cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            results[mode] = r
            print(json.dumps(r), f"load {loadavg()}", flush=True)
        base = results.get("serial")
        print("\n| run | workers | render() wall | start of workers | painter start-up each | "
              "images/s after start | speed-up | CPU s per image (all processes) | identical to serial |")
        print("|---|---|---|---|---|---|---|---|---|")
        for mode, r in results.items():
            rate = r["images"] / max(1e-9, r["wall"] - r["start"])
            speed = f"x{base['wall'] / r['wall']:.2f}" if base else "-"
            ident = "-" if mode == "serial" or not base else (
                "yes" if same(Path(tmp) / "serial", Path(tmp) / mode) else "NO")
            startup = ", ".join(f"{s:.1f}" for s in r["startup"])
            print(f"| {mode} | {r['workers']} | {r['wall']:.1f} s | {r['start']:.1f} s | {startup} s | "
                  f"{rate:.2f} | {speed} | {r['cpu'] / r['images']:.2f} | {ident} |")
        if "dask" in results:
            print(f"\nDask LocalCluster start (before render()): {results['dask']['cluster_s']:.1f} s")
    print(f"load after {loadavg()}")


if __name__ == "__main__":
    main()
