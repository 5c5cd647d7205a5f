"""Benchmark map uploads on ``brainpainter serve`` (not a test): upload and live-preview times.

Runs the app in-process (FastAPI's TestClient) with the real preview process
(Blender renderer) and no job worker, in a temporary data folder:

- upload: an fsaverage5 pair (FreeSurfer ``curv`` files written with nibabel),
  a full-resolution fsaverage pair (``.mgh``), a 2 mm MNI152 volume (3-D) and a
  4-D one of ``--volumes`` volumes: seconds from the request to the report
  (the reading process, its imports and, for volumes, the projection included);
- preview: N previews of the fsaverage pair at 800x600 (scaled to 480 wide), the
  threshold and view changing each time (as a user does): median and 95th
  percentile of the round trip and of the render alone (``X-Render-Ms``).

    python benchmarks/bench_web_maps.py                  # 10 previews, 10 volumes
    python benchmarks/bench_web_maps.py --previews 20 --volumes 50

Prints one JSON object. Record results in docs/benchmarks.md with the machine and its load (``uptime``).
"""

from __future__ import annotations

import argparse
import gzip
import json
import statistics
import tempfile
import time
from pathlib import Path

import nibabel as nib
import numpy as np


def volume(n_volumes: int, voxel: float = 2.0) -> bytes:
    """An MNI152 NIfTI (gzip): 5 in a 20 mm ball in the left lateral cortex; 4-D when `n_volumes` > 0."""
    origin = np.array([-90.0, -126.0, -72.0])
    shape = tuple(int(s) for s in np.ceil(np.array([182, 218, 182]) / voxel))
    affine = np.diag([voxel, voxel, voxel, 1.0])
    affine[:3, 3] = origin
    xyz = np.indices(shape).reshape(3, -1).T * voxel + origin
    vol = np.zeros(shape, np.float32)
    vol.reshape(-1)[np.linalg.norm(xyz - [-50, -20, 10], axis=1) < 20] = 5.0
    data = vol if not n_volumes else vol[..., None] * np.linspace(0.2, 1, n_volumes, dtype=np.float32)
    img = nib.Nifti1Image(data, affine)
    img.header.set_sform(affine, 1)
    return gzip.compress(img.to_bytes(), compresslevel=6)


def curv(values: np.ndarray, folder: Path, name: str) -> bytes:
    nib.freesurfer.write_morph_data(str(folder / name), values.astype(np.float32))
    return (folder / name).read_bytes()


def mgh(values: np.ndarray) -> bytes:
    img = nib.MGHImage(values.astype(np.float32).reshape(-1, 1, 1), np.eye(4))
    return bytes(img.to_bytes())


def upload(client, files: list[tuple[str, bytes]]) -> tuple[float, dict]:
    q: dict = {"name": [n for n, _ in files]}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    t0 = time.perf_counter()
    r = client.post("/api/uploads", params=q, content=b"".join(d for _, d in files),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return time.perf_counter() - t0, r.json()


def main() -> None:
    from fastapi.testclient import TestClient

    from brainpainter.web.app import create_app
    from brainpainter.web.config import ServerConfig

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--previews", type=int, default=10)
    ap.add_argument("--volumes", type=int, default=10)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config = ServerConfig(data_dir=folder / "data", workers=0, preview=True, rate_per_minute=100_000,
                              max_upload_mb=200)
        with TestClient(create_app(config)) as client:
            end = time.monotonic() + 300
            while client.get("/readyz").status_code != 200 and time.monotonic() < end:
                time.sleep(0.5)
            pair5 = [(f"{h}.curv", curv(rng.normal(size=10242), folder, f"{h}.curv")) for h in ("lh", "rh")]
            out["upload_fsaverage5_pair_s"] = round(upload(client, pair5)[0], 2)
            full = [(f"{h}.effect.mgh", mgh(rng.normal(size=163842))) for h in ("lh", "rh")]
            seconds, got = upload(client, full)
            out["upload_fsaverage_pair_s"] = round(seconds, 2)
            uid = got["upload_id"]
            out["upload_volume_2mm_s"] = round(upload(client, [("zstat.nii.gz", volume(0))])[0], 2)
            out[f"upload_volume_2mm_{args.volumes}vol_s"] = round(
                upload(client, [("series.nii.gz", volume(args.volumes))])[0], 2)
            trips, renders = [], []
            views = ["lateral-left", "medial-left", "lateral-right", "medial-right"]
            for i in range(args.previews + 1):
                body = {"upload_id": uid, "row": 0, "view": views[i % 4],
                        "options": {"size": "800x600", "threshold": round(0.1 * (i % 5), 2)}}
                t0 = time.perf_counter()
                r = client.post("/api/preview", json=body)
                assert r.status_code == 200, r.text
                if i:  # the first builds the per-vertex scene
                    trips.append(time.perf_counter() - t0)
                    renders.append(int(r.headers["x-render-ms"]) / 1000)
            q = statistics.quantiles
            out["preview_round_trip_median_s"] = round(statistics.median(trips), 3)
            out["preview_round_trip_p95_s"] = round(q(trips, n=20)[-1], 3) if len(trips) > 1 else None
            out["preview_render_median_s"] = round(statistics.median(renders), 3)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
