"""Benchmark: a 400-node connectome (top 1 % of its edges) against a Schaefer-400 region render, per image.

Issue 36's bar: a real 400 x 400 resting-state matrix on Schaefer-400 (7 networks), top 1 % of
the edges, costs at most 1.5x a Schaefer-400 region render per image, in the same run. The
matrix is brainspace's group matrix (``holdout_group/schaefer_400_mean_connectivity_matrix.csv``,
a test extra); the atlas is the schaefer-yeo plugin's ``schaefer400_7n`` read from the checkout.

Three painters in one process, each warmed on each view, then their images interleaved
(``--repeats`` rounds of every view):

* ``regions``: random values on the 400 regions (the cortex opaque);
* ``connectome``: the connectome alone (400 node spheres, 798 edge cylinders, the smooth glass
  brain: ``--cortex auto``);
* ``connectome, --cortex glass``: the same inside the pial cortex drawn as glass (kept per view);
* ``both``: the region values with the connectome inside the cortex drawn as glass;
* ``glass``: the region values on the cortex drawn as glass, nothing inside (what the glass costs).

Prints the median seconds per image of each (wall clock, and the process's CPU seconds: all threads,
less swayed by other jobs on a shared machine), the ratios to ``regions``, the scene's triangles
and the time to build the connectome's parts.

    python benchmarks/bench_connectome.py                       # 1200x900, dorsal and lateral-left
    python benchmarks/bench_connectome.py --size 800x600 --repeats 10
"""

from __future__ import annotations

import argparse
import importlib.metadata
import statistics
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SCHAEFER400 = (REPO / "plugins" / "atlases" / "brainpainter-atlas-schaefer-yeo" / "bp_atlas_schaefer_yeo"
               / "data" / "schaefer400_7n")
MATRIX = "brainspace/datasets/matrices/holdout_group/schaefer_400_mean_connectivity_matrix.csv"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1200x900")
    parser.add_argument("--views", default="dorsal,lateral-left")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--top", default="99%", help="--edge-threshold of the connectome")
    args = parser.parse_args()

    from brainpainter.atlas.model import load_atlas_dir
    from brainpainter.rendering.run import prepare_run
    from brainpainter.rendering.views import parse_views

    width, height = (int(v) for v in args.size.split("x"))
    atlas = load_atlas_dir(SCHAEFER400)
    matrix = str(importlib.metadata.distribution("brainspace").locate_file(MATRIX))
    values = dict(zip(atlas.keys, np.random.default_rng(0).uniform(0, 1, len(atlas.keys)), strict=False))
    common = {"width": width, "height": height, "views": args.views}
    t0 = time.perf_counter()
    runs = {"regions": prepare_run(values, atlas, **common),
            "connectome": prepare_run(None, atlas, connectome=matrix, edge_threshold=args.top, **common),
            "connectome, --cortex glass": prepare_run(None, atlas, connectome=matrix, edge_threshold=args.top,
                                                      cortex="glass", **common),
            "both": prepare_run(values, atlas, connectome=matrix, edge_threshold=args.top, **common),
            "glass": prepare_run(values, atlas, cortex="glass", **common)}
    print(f"read the matrix and placed its nodes twice: {time.perf_counter() - t0:.1f} s")
    painters, items = {}, {}
    for name, run in runs.items():
        painters[name] = run.painter()
        t0 = time.perf_counter()
        parts = painters[name].scene.geometry.parts
        built = time.perf_counter() - t0
        tris = {p.kind: len(p.triangles) for p in parts if p.kind in ("node", "edge")}
        print(f"{name}: geometry {built:.2f} s, {sum(len(p.triangles) for p in parts):,} triangles "
              f"(nodes and edges: {tris})")
        items[name] = [run.item(0, view) for view in parse_views(args.views)]
        for item in items[name]:  # warm: the renderer starts, each view's parts are uploaded
            painters[name].paint_colors(item.colors, item.view)
    times: dict[str, list[float]] = {name: [] for name in runs}
    cpu: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(args.repeats):
        for name in runs:
            for item in items[name]:
                t0, c0 = time.perf_counter(), time.process_time()
                painters[name].paint_colors(item.colors, item.view)
                times[name].append(time.perf_counter() - t0)
                cpu[name].append(time.process_time() - c0)
    base, base_cpu = statistics.median(times["regions"]), statistics.median(cpu["regions"])
    edges = runs["connectome"].connectome
    n_edges = 0 if edges is None else len(edges.edges()[2])
    print(f"{args.size}, views {args.views}, {args.repeats} rounds, {n_edges} edges drawn")
    for name, ts in times.items():
        m, c = statistics.median(ts), statistics.median(cpu[name])
        print(f"  {name:10s} median {m * 1000:7.1f} ms/image  ({m / base:.2f}x regions), "
              f"CPU {c * 1000:7.1f} ms  ({c / base_cpu:.2f}x)")
    for painter in painters.values():
        painter.close()


if __name__ == "__main__":
    main()
