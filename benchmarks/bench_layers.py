"""Per-image cost of 3-layer scenes (a map, a contour of a cluster mask, tracts with values on their own
scale; region values, a map over them, a contour) vs a one-layer map render, in the same run (issue 35;
target: <= 1.3x).

Both runs are made as ``render`` makes them (:func:`brainpainter.rendering.run.prepare_run`: the
composition, its scales and lines), their painters loaded once; then image after image, interleaved
(A, B, A, B, ... so that load on the machine falls on both alike), each image's colours are
composited (``run.item``: the map over the sulcal underlay, the tract values on their scale) and
drawn. Prints the median seconds per image of each and B over A, in wall clock and in the process's
CPU seconds (all threads; ``... CPU``: less swayed by other jobs on a shared machine)::

    python benchmarks/bench_layers.py [--n 12] [--size 1200x900] [--views lateral-left,medial-left]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import nibabel as nib
import numpy as np

N5 = 10242


def bundle(x: float, n: int, seed: int) -> list[np.ndarray]:
    """`n` curved streamlines along y at x (MNI mm), 20 points each."""
    rng = np.random.default_rng(seed)
    y = np.linspace(-35.0, 35.0, 20)
    return [np.column_stack([np.full(20, x) + rng.normal(0, 2), y, 20 + 4 * np.sin(y / 70 * np.pi)
                             + rng.normal(0, 2)]).astype(np.float32) for _ in range(n)]


def cluster(hemi: str) -> np.ndarray:
    """A cluster mask on fsaverage, float32 (163842,): the pial vertices within 30 mm of a lateral point."""
    from brainpainter.atlas.template import load_template
    from brainpainter.maps.resolution import N_FSAVERAGE, map_mesh

    mesh = map_mesh(load_template("fsaverage"), "dk", hemi)
    pial = mesh.vertices["pial"]
    centre = pial[np.argmin(pial[:, 0])] if hemi == "lh" else pial[np.argmax(pial[:, 0])]
    mask = np.zeros(N_FSAVERAGE, np.float32)
    mask[np.asarray(mesh.source_vertex)[np.linalg.norm(pial - centre, axis=1) < 30.0]] = 1.0
    return mask


def inputs(folder: Path, n_images: int, n_streamlines: int) -> dict[str, object]:
    """A map series of `n_images` images, a mask (its contour), two bundles and their FA per image."""
    rng = np.random.default_rng(0)
    series = {h: rng.normal(size=(n_images, N5)).astype(np.float32) for h in ("lh", "rh")}
    for hemi in ("lh", "rh"):  # a cluster: the cortex within 30 mm of a point on the lateral surface
        nib.MGHImage(cluster(hemi).reshape(-1, 1, 1), np.eye(4)).to_filename(folder / f"{hemi}.mask.mgh")
    bundles = folder / "bundles"
    bundles.mkdir()
    for name, x, seed in (("AF_L.trk", -30.0, 0), ("CST_R.trk", 30.0, 1)):
        lines = nib.streamlines.Tractogram(bundle(x, n_streamlines, seed), affine_to_rasmm=np.eye(4))
        nib.streamlines.save(lines, str(bundles / name))
    fa = folder / "fa.csv"
    fa.write_text("Image-name-unique,AF_L,CST_R\n" + "".join(
        f"map-{i + 1},{0.3 + 0.02 * i:.2f},{0.7 - 0.02 * i:.2f}\n" for i in range(n_images)))  # the map's
    table = folder / "thick.csv"
    regions = ("precentral", "postcentral", "superiorfrontal", "insula", "superiortemporal", "precuneus")
    table.write_text("Image-name-unique," + ",".join(f"{h}_{r}" for h in ("lh", "rh") for r in regions) + "\n"
                     + "".join(f"map-{i + 1}," + ",".join(f"{v:.2f}" for v in rng.uniform(1.5, 4, 12)) + "\n"
                               for i in range(n_images)))
    return {"series": series, "table": str(table), "tracts": [str(bundles)], "tract_values": str(fa),
            "contour": f"{folder / 'lh.mask.mgh'},{folder / 'rh.mask.mgh'}"}


def main() -> None:
    from brainpainter.rendering.run import prepare_run
    from brainpainter.rendering.settings import parse_size
    from brainpainter.rendering.views import get_view

    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=12, help="images per run")
    ap.add_argument("--size", default="1200x900")
    ap.add_argument("--views", default="lateral-left,medial-left")
    ap.add_argument("--streamlines", type=int, default=500, help="per bundle")
    args = ap.parse_args()
    w, h = parse_size(args.size)
    views = [get_view(v) for v in args.views.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        given = inputs(Path(tmp), args.n, args.streamlines)
        common = {"width": w, "height": h, "views": args.views, "cmap": "viridis", "threshold": 0.5}
        tracts = {"tracts": given["tracts"], "tract_values": given["tract_values"], "tracts_cmap": "magma",
                  "tracts_vmin": 0.3, "tracts_vmax": 0.7, "tracts_label": "FA"}
        runs = {
            "map": prepare_run(given["series"], **common),
            "map, --cortex glass": prepare_run(given["series"], cortex="glass", **common),
            "map+contour": prepare_run(given["series"], contour=given["contour"], **common),
            "regions+map+contour": prepare_run(given["table"], lh=given["series"]["lh"],  # type: ignore[index]
                                               rh=given["series"]["rh"], map_alpha=0.6,  # type: ignore[index]
                                               contour=given["contour"], **common),
            # --cortex auto: a cortex that carries a map is opaque (its colours), the tracts inside it
            "map+contour+tracts": prepare_run(given["series"], contour=given["contour"], **tracts, **common),
            "map+contour+tracts, --cortex glass": prepare_run(given["series"], contour=given["contour"],
                                                              cortex="glass", **tracts, **common),
        }
        painters = {name: run.painter() for name, run in runs.items()}
        seconds: dict[str, list[float]] = {name: [] for name in runs}
        cpu: dict[str, list[float]] = {name: [] for name in runs}
        compose: dict[str, list[float]] = {name: [] for name in runs}  # of which: the colours composited
        try:
            for name, painter in painters.items():  # load and warm each (first image not counted)
                t = time.perf_counter()
                painter.paint_colors(runs[name].item(0, views[0]).colors, views[0])
                print(f"{name}: loaded and first image in {time.perf_counter() - t:.2f} s", flush=True)
            for i in range(args.n):
                view = views[i % len(views)]
                for name, run in runs.items():  # interleaved
                    t, c = time.perf_counter(), time.process_time()
                    colors = run.item(i, view).colors
                    composed = time.perf_counter()
                    painters[name].paint_colors(colors, view)
                    seconds[name].append(time.perf_counter() - t)
                    cpu[name].append(time.process_time() - c)
                    compose[name].append(composed - t)
        finally:
            for painter in painters.values():
                painter.close()
    out: dict[str, object] = {name: round(statistics.median(s), 4) for name, s in seconds.items()}
    out.update({f"{name} compositing": round(statistics.median(s), 4) for name, s in compose.items()})
    base = statistics.median(seconds["map"])
    out.update({f"{name} / map": round(statistics.median(s) / base, 3) for name, s in seconds.items()})
    base_cpu = statistics.median(cpu["map"])
    out.update({f"{name} / map, CPU": round(statistics.median(s) / base_cpu, 3) for name, s in cpu.items()})
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
