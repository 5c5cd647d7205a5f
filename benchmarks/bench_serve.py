"""Benchmark ``brainpainter serve`` (not a test): live-preview latency and jobs per minute.

Starts real servers on 127.0.0.1 (Blender renderer) in a temporary data folder:

- preview: one server with 1 worker; after a warm-up, N previews of the bundled
  example with the gradient, row and view changing each time (as a user does);
  prints the median and 95th percentile of the round trip (HTTP, validation,
  render, PNG) and of the render alone;
- jobs: servers with 1 and 2 workers (no preview process); J "render all"
  jobs (4 rows x 2 views at 320x240 = 8 images each) submitted at once;
  jobs per minute from the first submission to the last job done.

    python benchmarks/bench_serve.py                  # 20 previews, 6 jobs
    python benchmarks/bench_serve.py --previews 40 --jobs 10

Record results in docs/benchmarks.md with the machine and its load (``uptime``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import httpx
from serve_process import Serve

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
GRADIENTS = ["white,yellow,orange,red", "white,blue", "#ffffff,#00aa00", "yellow,red"]
VIEWS = ["lateral-left", "medial-left", "subcortical"]
LIMITS_OFF = ("--max-jobs-per-client", "1000", "--rate", "100000")


def _upload(client: httpx.Client) -> str:
    r = client.post("/api/uploads", params={"name": EXAMPLE.name}, content=EXAMPLE.read_bytes(),
                    headers={"content-type": "application/octet-stream"})
    r.raise_for_status()
    return r.json()["upload_id"]


def bench_preview(tmp: Path, n: int) -> dict:
    server = Serve(tmp / "preview", "--workers", "1", *LIMITS_OFF)
    try:
        with httpx.Client(base_url=server.url, timeout=120) as client:
            uid = _upload(client)
            trip, render = [], []
            for i in range(n + 1):
                body = {"upload_id": uid, "row": i % 4, "view": VIEWS[i % 3],
                        "options": {"gradient": GRADIENTS[i % len(GRADIENTS)]}}
                t0 = time.perf_counter()
                r = client.post("/api/preview", json=body)
                r.raise_for_status()
                if i:  # the first one warms the scene for this table's atlas
                    trip.append(time.perf_counter() - t0)
                    render.append(int(r.headers["x-render-ms"]) / 1000)
    finally:
        server.close()

    def p95(xs: list[float]) -> float:
        return sorted(xs)[max(0, round(0.95 * len(xs)) - 1)]

    return {"previews": n, "ready_s": round(server.ready_s, 1),
            "round_trip_median_s": round(statistics.median(trip), 3), "round_trip_p95_s": round(p95(trip), 3),
            "render_median_s": round(statistics.median(render), 3), "render_p95_s": round(p95(render), 3)}


def bench_jobs(tmp: Path, workers: int, n_jobs: int) -> dict:
    server = Serve(tmp / f"jobs{workers}", "--workers", str(workers), "--no-preview", *LIMITS_OFF)
    try:
        with httpx.Client(base_url=server.url, timeout=120) as client:
            uid = _upload(client)
            t0 = time.perf_counter()
            urls = []
            for i in range(n_jobs):
                r = client.post("/api/jobs", json={"upload_id": uid, "options": {
                    "size": "320x240", "views": "lateral-left,subcortical", "gradient": GRADIENTS[i % 4]}})
                r.raise_for_status()
                urls.append(r.json()["url"])
            pending = set(urls)
            for _ in range(36000):  # at most an hour
                pending = {u for u in pending if client.get(u).json()["status"] not in ("done", "failed")}
                if not pending:
                    break
                time.sleep(0.1)
            seconds = time.perf_counter() - t0
            failed = [u for u in urls if client.get(u).json()["status"] != "done"]
    finally:
        server.close()
    return {"workers": workers, "jobs": n_jobs, "images_per_job": 8, "seconds": round(seconds, 1),
            "jobs_per_minute": round(60 * n_jobs / seconds, 1), "failed": len(failed),
            "ready_s": round(server.ready_s, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--previews", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=6)
    args = ap.parse_args()
    load = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="bp-bench-serve-") as tmp:
        results = {"cpus": os.cpu_count(), "load_before": [round(x, 2) for x in load],
                   "preview": bench_preview(Path(tmp), args.previews),
                   "jobs": [bench_jobs(Path(tmp), w, args.jobs) for w in (1, 2)]}
    results["load_after"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
