"""Benchmark tract uploads on ``brainpainter serve`` (not a test): upload and live-preview times.

Runs the app in-process (FastAPI's TestClient) with the real preview process
(Blender renderer) and no job worker, in a temporary data folder:

- upload: two bundles of ``--streamlines`` streamlines each (``.trk`` and
  ``.tck`` of 20 points a streamline, written with nibabel), sent as two files and
  as one zip: seconds from the request to the report (the reading process,
  its imports, the header counts and the CLI's reader included);
- preview: N previews of the bundles with the example region table
  (``subcortical`` and ``lateral-left`` through the glass cortex, 800x600 scaled
  to 480 wide), against N previews of the table alone: median round trip and
  render (``X-Render-Ms``); the first preview with tracts (the scene built with
  the tubes) is reported apart.

    python benchmarks/bench_web_tracts.py                       # 2 x 2,500 streamlines, 10 previews
    python benchmarks/bench_web_tracts.py --streamlines 50000 --previews 20

Prints one JSON object. Record results in docs/benchmarks.md with the machine and its load (``uptime``).
"""

from __future__ import annotations

import argparse
import io
import json
import statistics
import tempfile
import time
import zipfile
from pathlib import Path

import nibabel as nib
import numpy as np

REPO = Path(__file__).resolve().parents[1]


def bundle(x: float, n: int, seed: int) -> list[np.ndarray]:
    """`n` streamlines of 20 points along y at x (MNI152 mm), 80 mm long, some spread."""
    rng = np.random.default_rng(seed)
    y = np.linspace(-60, 20, 20)
    base = np.column_stack([np.full(20, x), y, 25 + 8 * np.sin(y / 80 * np.pi)])
    return [(base + rng.normal(0, 3, 3)).astype(np.float32) for _ in range(n)]


def written(path: Path, streamlines: list[np.ndarray]) -> bytes:
    nib.streamlines.save(nib.streamlines.Tractogram(streamlines, affine_to_rasmm=np.eye(4)), str(path))
    return path.read_bytes()


def post(client, route: str, files: list[tuple[str, bytes]]) -> tuple[float, dict]:
    q: dict = {"name": [n for n, _ in files]}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    t0 = time.perf_counter()
    r = client.post(route, params=q, content=b"".join(d for _, d in files),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return time.perf_counter() - t0, r.json()


def previews(client, uid: str, n: int, options: dict) -> tuple[float, list[float], list[float]]:
    """The first preview's round trip, then the round trips and renders of `n` more (views alternating)."""
    trips, renders, first = [], [], 0.0
    for i in range(n + 1):
        body = {"upload_id": uid, "row": 0, "view": ("subcortical", "lateral-left")[i % 2],
                "options": {"size": "800x600", **options}}
        t0 = time.perf_counter()
        r = client.post("/api/preview", json=body)
        assert r.status_code == 200, r.text
        if i == 0:
            first = time.perf_counter() - t0
        else:
            trips.append(time.perf_counter() - t0)
            renders.append(int(r.headers["x-render-ms"]) / 1000)
    return first, trips, renders


def main() -> None:
    from fastapi.testclient import TestClient

    from brainpainter.web.app import create_app
    from brainpainter.web.config import ServerConfig

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--streamlines", type=int, default=2500, help="per bundle (two bundles)")
    ap.add_argument("--previews", type=int, default=10)
    args = ap.parse_args()
    out: dict = {"streamlines": 2 * args.streamlines}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        files = [("AF_left.trk", written(folder / "AF_left.trk", bundle(-35, args.streamlines, 0))),
                 ("CST_right.tck", written(folder / "CST_right.tck", bundle(35, args.streamlines, 1)))]
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
            for name, data in files:
                zf.writestr(f"bundles/{name}", data)
        out["upload_mb"] = round(sum(len(d) for _, d in files) / 2**20, 1)
        config = ServerConfig(data_dir=folder / "data", workers=0, preview=True, rate_per_minute=100_000,
                              max_upload_mb=500)
        with TestClient(create_app(config)) as client:
            end = time.monotonic() + 300
            while client.get("/readyz").status_code != 200 and time.monotonic() < end:
                time.sleep(0.5)
            seconds, got = post(client, "/api/tracts", files)
            out["upload_two_files_s"] = round(seconds, 2)
            out["report"] = got["report"]["summary"]
            tracts = got["upload_id"]
            out["upload_zip_s"] = round(post(client, "/api/tracts", [("bundles.zip", buf.getvalue())])[0], 2)
            example = (REPO / "examples" / "brainpainter_dk.csv").read_bytes()
            table = post(client, "/api/uploads", [("dk.csv", example)])[1]["upload_id"]
            q = statistics.median
            for label, options in (("table", {}), ("table_and_tracts", {"tracts": tracts})):
                first, trips, renders = previews(client, table, args.previews, options)
                out[f"preview_{label}_first_s"] = round(first, 3)
                out[f"preview_{label}_round_trip_median_s"] = round(q(trips), 3)
                out[f"preview_{label}_render_median_s"] = round(q(renders), 3)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
