"""Benchmark: a Schaefer-1000 render against a DK render, same process, same views.

Needs the Schaefer/Yeo atlas distribution installed
(``pip install plugins/atlases/brainpainter-atlas-schaefer-yeo``). For each
atlas: time to load the scene (template + label-set overlay split into parcels,
Blender objects and materials), then the median of `--repeats` renders of one
view with fresh random values per render (every region re-coloured), and of
`--repeats` renders with unchanged colours.

    python benchmarks/bench_atlas_render.py                 # 800x600, lateral-left, 5 repeats
    python benchmarks/bench_atlas_render.py --atlases dk,schaefer1000_7n,dk,schaefer1000_7n,dk,schaefer1000_7n

Record results in docs/benchmarks.md with the machine and its load.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np


def bench(atlas_name: str, view: str, width: int, height: int, repeats: int) -> dict:
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    atlas = get_atlas(atlas_name)
    t0 = time.perf_counter()
    painter = Painter(atlas, settings=RenderSettings(width=width, height=height))
    painter.load()
    t_load = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    scale = make_scale(cmap="viridis", vmin=0.0, vmax=1.0)
    times = []
    for _ in range(repeats):
        values = dict(zip(atlas.keys, rng.random(len(atlas.keys)).tolist(), strict=True))
        t = time.perf_counter()
        painter.paint(values, get_view(view), scale)
        times.append(time.perf_counter() - t)
    same = []  # the same colours again: what is left without re-colouring the materials
    for _ in range(repeats):
        t = time.perf_counter()
        painter.paint(values, get_view(view), scale)
        same.append(time.perf_counter() - t)
    painter.close()
    return {"atlas": atlas_name, "regions": len(atlas), "load_s": round(t_load, 2),
            "render_median_s": round(statistics.median(times), 3),
            "same_colours_median_s": round(statistics.median(same), 3),
            "renders_s": [round(x, 3) for x in times]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--atlases", default="dk,schaefer1000_7n")
    p.add_argument("--view", default="lateral-left")
    p.add_argument("--size", default="800x600")
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    w, h = (int(x) for x in a.size.split("x"))
    print(json.dumps({"load_average": os.getloadavg()}))
    names = a.atlases.split(",")
    bench(names[0], a.view, w, h, 1)  # warm-up: Blender's start-up is paid here, not by the first atlas
    rows = [bench(name, a.view, w, h, a.repeats) for name in names]
    for r in rows:
        print(json.dumps(r))
    # an atlas named several times (dk,schaefer1000_7n,dk,schaefer1000_7n,...): medians over its runs,
    # so that a changing machine load hits both alike
    by: dict[str, dict[str, list[float]]] = {}
    for r in rows:
        d = by.setdefault(r["atlas"], {"load": [], "render": []})
        d["load"].append(r["load_s"])
        d["render"].extend(r["renders_s"])
    med = {n: (statistics.median(d["load"]), statistics.median(d["render"])) for n, d in by.items()}
    base = names[0]
    for n, (load, rend) in med.items():
        print(f"{n}: load {load:.2f} s, render {rend:.3f} s (median of {len(by[n]['render'])}); "
              f"x{load / med[base][0]:.2f} and x{rend / med[base][1]:.2f} of {base}")


if __name__ == "__main__":
    main()
