"""Benchmark: the glass put over from its kept layers (``brainpainter_blender.glass_layers``) or drawn anew.

Two painters of each scene in one process, one with its glass layers and one without
(``GpuDraw._glass = None``: the glass drawn into every image, as before the layers), their
images interleaved; three cases, 1200x900:

* ``series``: the Schaefer-400 connectome (top 1 % of the edges), one view (dorsal), the edges'
  colours changing every image (a connectome series, or a table's rows): the glass's colours stay,
  its layer is drawn once;
* ``orbit``: the same connectome, a new view every image (a movie's orbit): a layer drawn every
  image;
* ``map``: a map series on a glass cortex (``--cortex glass``), lateral-left: the glass's colours
  change every image, a layer drawn every image.

Prints per case the median CPU ms per image (the process's, all threads: less swayed by other
jobs on a shared machine) and wall ms of each, and the layers drawn::

    python benchmarks/bench_glass_layers.py [--n 16]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from bench_connectome import MATRIX, SCHAEFER400
from bench_layers import inputs


def main() -> None:
    from brainpainter.atlas.model import load_atlas_dir
    from brainpainter.rendering.run import prepare_run
    from brainpainter.rendering.views import parse_views

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=16, help="images of each painter per case")
    args = parser.parse_args()
    size = {"width": 1200, "height": 900}
    atlas = load_atlas_dir(SCHAEFER400)
    matrix = str(importlib.metadata.distribution("brainspace").locate_file(MATRIX))
    connectome = prepare_run(None, atlas, connectome=matrix, edge_threshold="99%", views="dorsal", **size)
    with tempfile.TemporaryDirectory() as tmp:
        series = inputs(Path(tmp), args.n + 1, 10)["series"]
    maps = prepare_run(series, cortex="glass", views="lateral-left", cmap="viridis", threshold=0.5, **size)
    dorsal, lateral = parse_views("dorsal,lateral-left")
    base = connectome.item(0, dorsal).colors
    rng = np.random.default_rng(0)
    edges = [k for k in base if k.startswith("edge")] or list(base)

    def recoloured(i: int) -> dict[str, Any]:  # the edges in other colours, as a series' next matrix
        return {**base, **{k: tuple(rng.uniform(0, 1, 3)) for k in edges}}

    cases = {"series": (connectome, lambda i: (dorsal, recoloured(i))),
             "orbit": (connectome, lambda i: (parse_views(f"camera:{15 * i}:30")[0], base)),
             "map": (maps, lambda i: (lateral, maps.item(i, lateral).colors))}
    for name, (run, image) in cases.items():
        painters = {"layers": run.painter(), "direct": run.painter()}
        view0, colours0 = image(0)
        for painter in painters.values():  # started, the first view's parts uploaded
            painter.paint_colors(colours0, view0)
        painters["direct"].load()._gpu._glass = None
        cpu: dict[str, list[float]] = {k: [] for k in painters}
        wall: dict[str, list[float]] = {k: [] for k in painters}
        for i in range(1, args.n + 1):
            view, colours = image(i)
            for label in sorted(painters, reverse=bool(i % 2)):
                t, c = time.perf_counter(), time.process_time()
                painters[label].paint_colors(colours, view)
                wall[label].append(time.perf_counter() - t)
                cpu[label].append(time.process_time() - c)
        drawn = painters["layers"].load()._gpu._glass.drawn
        ms = {k: (statistics.median(cpu[k]) * 1000, statistics.median(wall[k]) * 1000) for k in painters}
        print(f"{name:7s} " + ", ".join(f"{k} {c:6.1f} CPU ms ({w:6.1f} wall)" for k, (c, w) in ms.items())
              + f"; {args.n} images each, glass layers drawn: {drawn}", flush=True)
        for painter in painters.values():
            painter.close()


if __name__ == "__main__":
    main()
