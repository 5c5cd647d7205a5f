"""The "done when" of issue 46 against a real ``brainpainter serve`` on 127.0.0.1 (not a test): prints
numbers.

Two hostile clients send the worst requests of the review at once, and a third checks a table:

- labels: a CIFTI dlabel of 8000 labels named with 900 characters each (8 MB, under the upload
  limit), then a PNG figure job of it (sizing its colour-bar key ran on a server thread for more than
  20 minutes before);
- edges: a connectome of 1000 nodes with every edge (499,500; a 4 MB ``.npy`` with a nodes file),
  previewed with no options (42 s, 3.7 GB and a MemoryError before);
- check: another client's ``POST /api/check`` of the example table, every 0.2 s while the two run:
  its round trips (bar: under 1 s);
- sigterm: seconds from SIGTERM to the server's exit while a hostile figure job is being planned.

    python benchmarks/bench_web_hostile.py                 # Blender renderer, 1 job worker
    python benchmarks/bench_web_hostile.py --rounds 3      # each hostile request 3 times

Record results in docs/benchmarks.md with the machine and its load (``uptime``).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import signal
import statistics
import tempfile
import threading
import time
from pathlib import Path

import httpx
import nibabel as nib
import numpy as np
from nibabel.cifti2 import cifti2_axes as axes
from serve_process import Serve

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
OCTET = {"content-type": "application/octet-stream"}


def client(name: str) -> httpx.Client:
    token = (name + "-bench-web-hostile-" + "0" * 32)[:40]
    return httpx.Client(headers={"x-brainpainter-client": token}, timeout=600)


def dlabel(folder: Path, n_labels: int = 8000, chars: int = 900) -> bytes:
    rng = np.random.default_rng(0)
    table = {0: ("???", (0.0, 0.0, 0.0, 0.0))}
    table.update({k: (f"{k:05d}" + "x" * (chars - 5), (*rng.random(3), 1.0)) for k in range(1, n_labels + 1)})
    labels = (np.arange(32492) % n_labels + 1)[None].astype(np.float32)
    cortex = axes.BrainModelAxis.from_surface(np.arange(32492), 32492, "CortexLeft")
    path = folder / "p.dlabel.nii"
    nib.Cifti2Image(labels, header=(axes.LabelAxis(["p"], [table]), cortex)).to_filename(str(path))
    return path.read_bytes()


def dense(n: int = 1000) -> tuple[bytes, bytes]:
    rng = np.random.default_rng(1)
    w = rng.random((n, n)).astype(np.float32) + 0.01
    buf = io.BytesIO()
    np.save(buf, (w + w.T) / 2)
    nodes = "name,x,y,z\n" + "".join(f"n{i:04d},{-60 + i % 120},{-80 + i % 160},{i % 60}\n" for i in range(n))
    return buf.getvalue(), nodes.encode()


def hostile_figure(url: str, data: bytes, rounds: int, out: dict[str, list[float]]) -> None:
    with client("labels") as c:
        t0 = time.perf_counter()
        uid = c.post(f"{url}/api/uploads", params={"name": "p.dlabel.nii"}, content=data, headers=OCTET)
        out["labels_upload_s"].append(time.perf_counter() - t0)
        uid.raise_for_status()
        for _ in range(rounds):
            t0 = time.perf_counter()
            r = c.post(f"{url}/api/jobs", json={"upload_id": uid.json()["upload_id"], "kind": "figure",
                                                "options": {"size": "480x360", "views": "lateral-left"},
                                                "figure": {"format": "png", "dpi": 150}})
            out["labels_figure_submit_s"].append(time.perf_counter() - t0)
            out["labels_figure_status"].append(r.status_code)


def hostile_preview(url: str, files: tuple[bytes, bytes], rounds: int, out: dict[str, list[float]]) -> None:
    matrix, nodes = files
    with client("edges") as c:
        t0 = time.perf_counter()
        r = c.post(f"{url}/api/connectomes", params={"name": ["m.npy", "nodes.csv"],
                                                      "size": [len(matrix), len(nodes)]},
                   content=matrix + nodes, headers=OCTET)
        out["edges_upload_s"].append(time.perf_counter() - t0)
        r.raise_for_status()
        for _ in range(rounds):
            t0 = time.perf_counter()
            p = c.post(f"{url}/api/preview", json={"upload_id": r.json()["upload_id"], "view": "dorsal",
                                                   "options": {}})
            out["edges_preview_s"].append(time.perf_counter() - t0)
            out["edges_preview_status"].append(p.status_code)


def checks_while(url: str, busy: list[threading.Thread]) -> list[float]:
    with client("check") as c:
        uid = c.post(f"{url}/api/uploads", params={"name": "t.csv"}, content=EXAMPLE.read_bytes(),
                     headers=OCTET).json()["upload_id"]
        times = []
        while any(t.is_alive() for t in busy):
            t0 = time.perf_counter()
            r = c.post(f"{url}/api/check", json={"upload_id": uid, "options": {}})
            times.append(time.perf_counter() - t0)
            assert r.status_code == 200, r.text
            time.sleep(0.2)
        return times


def sigterm(data_dir: Path, renderer: str, labels: bytes) -> float:
    """Seconds from SIGTERM to exit while a hostile figure job is being submitted."""
    serve = Serve(data_dir, "--renderer", renderer)
    out: dict[str, list[float]] = {k: [] for k in ("labels_upload_s", "labels_figure_submit_s",
                                                   "labels_figure_status")}
    thread = threading.Thread(target=lambda: _quiet(hostile_figure, serve.url, labels, 5, out), daemon=True)
    thread.start()
    while not out["labels_upload_s"] and thread.is_alive():
        time.sleep(0.1)
    time.sleep(1.0)
    t0 = time.perf_counter()
    os.kill(serve.proc.pid, signal.SIGTERM)
    serve.proc.wait(timeout=600)
    took = time.perf_counter() - t0
    serve.log.close()
    return took


def _quiet(func, *args) -> None:
    try:
        func(*args)
    except httpx.HTTPError:
        pass  # the server stopped under it


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", default="blender")
    ap.add_argument("--rounds", type=int, default=2)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        labels, edges = dlabel(folder), dense()
        serve = Serve(folder / "data", "--renderer", a.renderer)
        out: dict[str, list[float]] = {k: [] for k in (
            "labels_upload_s", "labels_figure_submit_s", "labels_figure_status", "edges_upload_s",
            "edges_preview_s", "edges_preview_status")}
        try:
            busy = [threading.Thread(target=hostile_figure, args=(serve.url, labels, a.rounds, out)),
                    threading.Thread(target=hostile_preview, args=(serve.url, edges, a.rounds, out))]
            for t in busy:
                t.start()
            checks = checks_while(serve.url, busy)
            for t in busy:
                t.join()
        finally:
            serve.close()
        result = {"renderer": a.renderer, "labels_bytes": len(labels), "edges_bytes": len(edges[0]),
                  **{k: [round(v, 2) for v in vs] for k, vs in out.items()},
                  "checks": len(checks), "check_median_s": round(statistics.median(checks), 3),
                  "check_max_s": round(max(checks), 3),
                  "sigterm_exit_s": round(sigterm(folder / "data2", a.renderer, labels), 2),
                  "load": os.getloadavg()}
        print(json.dumps(result))


if __name__ == "__main__":
    main()
