"""Per-image cost of a per-vertex map vs a DK region render, and the memory a map adds (issue 21).

Same run, same views and size: a warm region painter and a warm per-vertex
painter draw N images each, interleaved (new colours each image, as a
table's rows or a map series would), and the mean seconds per image are
compared (target: map <= 1.5x region). Memory: resident-set growth of reading a full-resolution
fsaverage map pair and building its first image's colours (target <= 150 MB).

    python benchmarks/bench_maps.py [--n 20] [--size 1200x900] [--shared ../shared/data]
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np


def rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * resource.getpagesize() / 2**20


def main() -> None:
    from brainpainter.color.scale import make_scale
    from brainpainter.layers.vertex_map import VertexColors
    from brainpainter.maps.inputs import read_maps
    from brainpainter.maps.layers import vertex_colors
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings, parse_size
    from brainpainter.rendering.views import get_view

    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--size", default="1200x900")
    ap.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    args = ap.parse_args()
    w, h = parse_size(args.size)
    settings = RenderSettings(width=w, height=h)
    views = [get_view(v) for v in ("lateral-left", "medial-left")]
    scale = make_scale(cmap="viridis", vmin=0, vmax=1)
    rng = np.random.default_rng(0)
    surf = Path(args.shared) / "freesurfer" / "subjects" / "fsaverage" / "surf"
    out: dict[str, float] = {}
    with Painter("dk", settings=settings) as region, \
            Painter("dk", settings=settings, coloring="vertices") as vert:
        keys = list(region.atlas.keys)
        region.paint({k: 0.5 for k in keys}, views[0], scale)  # warm both (scenes loaded)
        sv = vert.scene.geometry.source_vertex
        vert.paint_colors(VertexColors({}, {}), views[0])
        before = rss_mb()
        t = time.perf_counter()
        m = read_maps(lh=surf / "lh.sulc", rh=surf / "rh.sulc")
        out["read_map_s"] = time.perf_counter() - t
        colors = vertex_colors(m, 0, sv, make_scale(cmap="viridis", vmin=-1, vmax=1), "sulc")
        vert.paint_colors(VertexColors({}, colors), views[0])
        out["map_memory_mb"] = rss_mb() - before  # reading the map, its colours, its first image
        values = {h: rng.uniform(size=(args.n, 163842)).astype(np.float32) for h in ("lh", "rh")}
        series = read_maps(values)
        spent = {"region": 0.0, "map": 0.0}
        for i in range(args.n):  # interleaved: both see the same machine load
            t = time.perf_counter()
            region.paint({k: float(rng.uniform()) for k in keys}, views[i % 2], scale)
            spent["region"] += time.perf_counter() - t
            t = time.perf_counter()  # the map's colours are composited per image, as a render does
            c = vertex_colors(series, i, sv, scale, "sulc", threshold=0.2)
            vert.paint_colors(VertexColors({}, c), views[i % 2])
            spent["map"] += time.perf_counter() - t
        out["region_s_per_image"] = spent["region"] / args.n
        out["map_s_per_image"] = spent["map"] / args.n
    out["ratio"] = out["map_s_per_image"] / out["region_s_per_image"]
    print(json.dumps({k: round(v, 4) for k, v in out.items()}, indent=1))


if __name__ == "__main__":
    main()
