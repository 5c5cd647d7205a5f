"""render(..., painter=...) in a notebook: the second table reuses the loaded Blender scene.

Renders the bundled example's stage-1..3 rows (one row per call, lateral-left,
800x600, default quality) three times without a painter and three times with
one warm painter, counting Blender scene builds (BlenderRenderer instances)
and timing each call. Run: python benchmarks/bench_painter_reuse.py
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import brainpainter
from brainpainter_blender.renderer import BlenderRenderer

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "brainpainter_dk.csv"
builds = 0
_init = BlenderRenderer.__init__


def counting_init(self, *args, **kwargs):
    global builds
    builds += 1
    _init(self, *args, **kwargs)


BlenderRenderer.__init__ = counting_init  # type: ignore[method-assign]
kw = {"views": "lateral-left", "progress": False}


def timed(label: str, **extra) -> None:
    before = builds
    times = []
    for row in ("stage-1", "stage-2", "stage-3"):
        t0 = time.perf_counter()
        brainpainter.render(EXAMPLE, "dk", rows=[row], **kw, **extra)
        times.append(time.perf_counter() - t0)
    print(f"{label:<28} calls: {', '.join(f'{t:.2f} s' for t in times)}; scene builds: {builds - before}")


print(f"load average before: {os.getloadavg()[0]:.1f}")
timed("render() x3, no painter", width=800, height=600)
settings = brainpainter.RenderSettings(width=800, height=600)
with brainpainter.Painter("dk", settings=settings) as painter:
    t0 = time.perf_counter()
    painter.load()
    print(f"Painter.load() (scene build): {time.perf_counter() - t0:.2f} s")
    timed("render(painter=p) x3", painter=painter)
print(f"load average after: {os.getloadavg()[0]:.1f}")
