"""Experiment: camera-facing ribbons (2 triangles a segment) against the 3-sided tubes, same view, same run.

Not a feature: a measurement for issue 24's speed bar. It swaps the tract parts of a
scene for ribbons built for one camera (each segment a quad across the screen, edge
normals tilted towards the camera so the ribbon is lit like a tube) and times the
subcortical view against a DK lateral-left render, in CPU seconds per image (steadier
than the wall clock on a loaded machine). Ribbons are view-dependent geometry, which the
scene model does not have (parts are built once per scene); see docs/tracts.md, "Speed".

    python benchmarks/bench_tract_ribbons.py --streamlines 3000
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from bench_tracts import write_tractogram


def ribbon(part: Any, back: np.ndarray, n_points: int, sides: int) -> Any:
    """The tube `part` as ribbons facing direction `back` (same slots, same radius)."""
    pts = part.hull.reshape(-1, n_points, 3).astype(np.float64)
    side = np.cross(np.gradient(pts, axis=1), back)
    side /= np.maximum(np.linalg.norm(side, axis=2, keepdims=True), 1e-9)
    radius = float(np.linalg.norm(part.vertices[0] - part.hull[0]))
    verts = np.stack([pts - radius * side, pts + radius * side], axis=2)  # (n, m, 2, 3)
    normals = np.stack([0.7 * (back - side), 0.7 * (back + side)], axis=2)
    i = np.arange(n_points - 1)
    a, b, c, d = 2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3
    one = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)])
    tris = (one[None] + (np.arange(len(pts)) * n_points * 2)[:, None, None]).reshape(-1, 3)
    pal = part.palette_index.reshape(len(pts), n_points, sides)[:, :, :2].reshape(-1)
    return replace(part, vertices=verts.reshape(-1, 3).astype(np.float32),
                   normals=normals.reshape(-1, 3).astype(np.float32), triangles=tris.astype(np.uint32),
                   palette_index=pal.astype(np.int32), sulc=np.zeros(len(pal), np.float32))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--streamlines", type=int, default=3000)
    p.add_argument("--repeats", type=int, default=7)
    args = p.parse_args()

    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.tract_parts import TractLayer
    from brainpainter.rendering.views import get_view
    from brainpainter.tracts.model import TractSpec
    from brainpainter.tracts.tubes import SIDES, points_for

    settings = RenderSettings(width=1200, height=900)
    sub, lateral = get_view("subcortical"), get_view("lateral-left")

    def cpu(painter: Painter, view: Any) -> float:
        painter.paint_colors({}, view)
        per = []
        for _ in range(args.repeats):
            t = time.process_time()
            painter.paint_colors({}, view)
            per.append(time.process_time() - t)
        return statistics.median(per)

    n = args.streamlines
    with tempfile.TemporaryDirectory() as tmp, Painter("dk", settings=settings) as ref:
        folder = write_tractogram(Path(tmp) / "bundles", n)
        for kind in ("tubes", "ribbons", "tubes", "ribbons"):
            tracts = TractLayer(TractSpec((str(folder),), max_streamlines=n))
            with Painter("dk", settings=settings, layers=(tracts,)) as p:
                g = p.scene.geometry
                if kind == "ribbons":
                    back = np.asarray(g.camera(sub, settings.width / settings.height).back, float)
                    m = points_for(n, 40, SIDES)
                    g.parts = tuple(ribbon(q, back, m, SIDES) if q.kind == "tract" else q for q in g.parts)
                p.load()
                r1, t, r2 = cpu(ref, lateral), cpu(p, sub), cpu(ref, lateral)
                tris = sum(len(q.triangles) for q in g.parts if q.kind == "tract")
            print(f"{n} streamlines, {kind:7s}: {tris:,} triangles, subcortical {t * 1000:.0f} CPU ms = "
                  f"{t / ((r1 + r2) / 2):.2f} x a DK lateral-left render", flush=True)


if __name__ == "__main__":
    main()
