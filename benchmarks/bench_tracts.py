"""Benchmark: images with streamlines against a DK region render, per image, in the same process.

Writes a synthetic whole-brain-like tractogram (``--streamlines`` smooth arcs
inside the fsaverage brain, 40 points each, as .tck with nibabel), loads it as
bundles (read, subsample, resample, orient, tubes and centrelines), then times per image at
``--size``:

* the DK table's first row from ``lateral-left`` and ``subcortical`` without tracts (the references);
* the same row from ``subcortical`` with each tractogram, in direction colours
  and in one colour per bundle, and from ``lateral-left`` (the left bundles
  through the cortex drawn as glass, ``--cortex auto``);
* with one colour per bundle, also images whose bundle colours change every
  time (a table of bundle values, row by row): the Blender renderer keeps
  each view's lines, uncoloured (:mod:`brainpainter_blender.tract_lines`),
  so this is the cost of colouring them again;
* a movie's orbit: every image a view not drawn before, where the lines
  themselves are drawn again;

and, with ``--peer``, PyVista (VTK) drawing the same centrelines alone as tubes
recoloured each image, in another process; then prints the median seconds per
image, the ratios (the issue's bar: 10,000 streamlines <= 2x a DK region
render), the tube triangles and the scene load time.
``--cpu`` times the process's CPU seconds per image (all threads) instead of
the wall clock: on a machine loaded by other jobs the wall-clock ratios swing
by 2x from run to run, the CPU ones much less.

    python benchmarks/bench_tracts.py                          # 3,000 and 10,000 streamlines, 1200x900
    python benchmarks/bench_tracts.py --streamlines 2000 --size 800x600 --repeats 3
    python benchmarks/bench_tracts.py --cpu --streamlines 10000 --tract-quality fast   # no anti-aliasing
    python benchmarks/bench_tracts.py --streamlines 10000 --profile    # where an orbit frame's time goes

``--profile`` also prints the median milliseconds of each step of an orbit's frame (a view
not drawn before, one colour per bundle; ``GpuDraw.profile``: each step waited for).

Timings depend on the machine (llvmpipe without a GPU); say which one in docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
BUNDLES = ("AF_left", "CST_right", "CC_ForcepsMajor", "UF_left", "ILF_right")


def write_tractogram(folder: Path, n: int, seed: int = 0) -> Path:
    """`n` smooth streamlines split over a few bundle files, inside the brain (RAS mm, MNI-like)."""
    import nibabel as nib

    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    per = np.array_split(np.arange(n), len(BUNDLES))
    t = np.linspace(0.0, 1.0, 40)[:, None]
    for name, idx in zip(BUNDLES, per, strict=True):
        centre = rng.uniform([-35, -60, -10], [35, 30, 40])
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        lines = []
        for _ in idx:
            start = centre + rng.normal(0, 6, 3) - direction * 35
            bend = rng.normal(0, 10, 3)
            pts = start + t * direction * 70 + np.sin(np.pi * t) * bend
            lines.append(pts.astype(np.float32))
        tg = nib.streamlines.Tractogram(lines, affine_to_rasmm=np.eye(4))
        nib.streamlines.save(tg, str(folder / f"{name}.tck"))
    return folder


CLOCK = time.perf_counter


def _time(painter, images: list) -> float:
    """Median seconds per image of painting `images` (colours, view), the first one not timed."""
    painter.paint_colors(*images[0])  # the first image of a view uploads its parts
    per = []
    for colors, view in images[1:]:
        t = CLOCK()
        painter.paint_colors(colors, view)
        per.append(CLOCK() - t)
    return statistics.median(per)


def _recoloured(colors, view, repeats: int) -> list:
    """Images whose bundles take colours not seen before, every one."""
    return [({**colors, **{f"tract:{b}": (i / (repeats + 1), 0.3, 0.9) for b in BUNDLES}}, view)
            for i in range(repeats + 1)]


def _orbit(colors, view, repeats: int) -> list:
    """Images of a movie's orbit: every one a view not drawn before (5-degree steps)."""
    return [(colors, replace(view, azimuth=(view.azimuth + 5.0 * i) % 360.0)) for i in range(repeats + 1)]


def _orbit_steps(painter, colors, view, repeats: int) -> dict[str, float]:
    """Median milliseconds of each step of an orbit's frame (views not drawn before), Blender renderer."""
    from brainpainter.rendering.geometry import Palette

    gpu = painter.load()._gpu
    rgb = Palette(colors, painter.scene.geometry).rgb
    rows = [gpu.profile(rgb, replace(view, azimuth=(view.azimuth + 2.5 + 5.0 * i) % 360.0))
            for i in range(repeats)]
    return {k: 1000 * statistics.median(r.get(k, 0.0) for r in rows) for k in rows[0]}


PEER = r"""
# PyVista (VTK) drawing the same centrelines as lit tubes (render_lines_as_tubes), 4x MSAA, a new
# colour per bundle every image, a real render before each read-back (as bench_render.py's peer)
import json, sys, time
import numpy as np
import pyvista as pv
args = json.loads(sys.argv[1])
data = np.load(args["npz"])
points, bundle, pose = data["points"], data["bundle"], data["pose"]
n, m = points.shape[:2]
cells = np.hstack([np.full((n, 1), m), np.arange(n * m).reshape(n, m)]).ravel()
lines = pv.PolyData(points.reshape(-1, 3).astype(np.float64), lines=cells)
lines.point_data["rgb"] = np.zeros((n * m, 3), np.uint8)
pl = pv.Plotter(off_screen=True, window_size=(args["width"], args["height"]))
pl.set_background("white")
pl.add_mesh(lines, scalars="rgb", rgb=True, render_lines_as_tubes=True, line_width=args["line_px"])
pl.enable_anti_aliasing("msaa", multi_samples=4)
location, back, up, scale = pose[0], pose[1], pose[2], pose[3][0]
pl.camera.SetParallelProjection(True)
pl.camera.position = tuple(location)
pl.camera.focal_point = tuple(location - 100 * back)
pl.camera.up = tuple(up)
pl.camera.parallel_scale = scale
pl.renderer.ResetCameraClippingRange()
pl.camera_set = True
pl.render()
pl.screenshot(return_img=True)
per = []
rng = np.random.default_rng(0)
for i in range(args["repeats"]):
    t = time.perf_counter()
    colours = rng.integers(0, 256, (bundle.max() + 1, 3), dtype=np.uint8)
    lines.point_data["rgb"][:] = np.repeat(colours[bundle], m, axis=0)
    lines.point_data["rgb"] = lines.point_data["rgb"]
    pl.render()
    img = pl.screenshot(return_img=True)
    per.append(time.perf_counter() - t)
if args.get("png"):
    pl.screenshot(args["png"])
pl.close()
print(json.dumps(sorted(per)[len(per) // 2]))
"""


def _peer(painter, view, args, width: int, height: int, png: str = "") -> float:
    """PyVista's median seconds per image of the same centrelines (tubes as wide), in another process."""
    import json
    import subprocess
    import sys

    parts = [q for q in painter.scene.geometry.parts if q.kind == "tract"]
    points = np.concatenate([q.centrelines.points for q in parts])
    bundle = np.concatenate([np.full(len(q.centrelines.points), i) for i, q in enumerate(parts)])
    pose = painter.scene.geometry.camera(view, width / height)
    scale = pose.ortho_scale / width * height / 2
    line_px = 2 * parts[0].centrelines.radius * width / pose.ortho_scale
    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "lines.npz"
        np.savez(npz, points=points, bundle=bundle,
                 pose=np.array([pose.location, pose.back, pose.up, [scale, 0, 0]], np.float64))
        out = subprocess.run([sys.executable, "-c", PEER, json.dumps(
            {"npz": str(npz), "width": width, "height": height, "repeats": args.repeats,
             "line_px": max(1.0, float(line_px)), "png": png})], capture_output=True, text=True, check=True)
    return float(json.loads(out.stdout.strip().splitlines()[-1]))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--streamlines", default="3000,10000", help="Comma-separated counts.")
    p.add_argument("--size", default="1200x900")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--cpu", action="store_true", help="CPU seconds per image (all threads), not wall clock.")
    p.add_argument("--peer", action="store_true",
                   help="Also time PyVista drawing the same centrelines as tubes (needs pyvista).")
    p.add_argument("--peer-png", default="", help="Write PyVista's last image here (to look at it).")
    p.add_argument("--profile", action="store_true", help="Also time the steps of an orbit's frame.")
    p.add_argument("--tract-quality", default="default", choices=("fast", "default"),
                   help="Quality of the images with tracts (the DK references stay default).")
    args = p.parse_args()
    if args.cpu:
        global CLOCK
        CLOCK = time.process_time
    unit = "CPU ms" if args.cpu else "ms"
    width, height = (int(v) for v in args.size.split("x"))

    import pandas as pd

    from brainpainter.color.scale import make_scale
    from brainpainter.layers.regions import region_colors
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.tract_parts import TractLayer
    from brainpainter.rendering.views import get_view
    from brainpainter.table.region_table import read_table
    from brainpainter.tracts.model import TractSpec

    table = read_table(pd.read_csv(EXAMPLE).iloc[:1], "dk")
    scale = make_scale(table.values)
    settings = RenderSettings(width=width, height=height)
    lateral, sub = get_view("lateral-left"), get_view("subcortical")
    with Painter("dk", settings=settings) as painter:
        colors = region_colors(table.row(0), painter.atlas, scale)
        ref = {"lateral-left": _time(painter, [(colors, lateral)] * (args.repeats + 1)),
               "subcortical": _time(painter, [(colors, sub)] * (args.repeats + 1))}
    print(f"DK regions, no tracts: lateral-left {ref['lateral-left'] * 1000:.0f} {unit}/image, subcortical "
          f"{ref['subcortical'] * 1000:.0f} {unit}/image")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(v) for v in args.streamlines.split(",")):
            folder = write_tractogram(Path(tmp) / f"bundles{n}", n)
            spec = TractSpec((str(folder),), max_streamlines=n)
            for label, nodes in (("direction colours", ()), ("one colour per bundle",
                                                             tuple((b, 1) for b in BUNDLES))):
                t0 = time.perf_counter()
                with Painter("dk", settings=replace(settings, quality=args.tract_quality),
                             layers=(TractLayer(spec, nodes),)) as painter:
                    colors = region_colors(table.row(0), painter.atlas, scale)
                    colors.update({f"tract:{b}": (0.9, 0.2, 0.1) for b in BUNDLES})
                    painter.load()
                    load = time.perf_counter() - t0
                    per = _time(painter, [(colors, sub)] * (args.repeats + 1))
                    glass = _time(painter, [(colors, lateral)] * (args.repeats + 1))
                    # the bundles' colours change with every image (a table of bundle values, row
                    # by row): the renderer colours the view's kept lines again, without drawing them
                    new = _time(painter, _recoloured(colors, sub, args.repeats)) if nodes else None
                    orbit = _time(painter, _orbit(colors, sub, args.repeats))
                    steps = None
                    if args.profile and nodes:
                        steps = _orbit_steps(painter, colors, sub, args.repeats)
                    peer = None
                    if args.peer and nodes:
                        peer = _peer(painter, sub, args, width, height, args.peer_png)
                    tris = sum(len(q.triangles) for q in painter.scene.geometry.parts if q.kind == "tract")
                print(f"{n:6d} streamlines, {label:22s}: subcortical {per * 1000:6.0f} {unit}/image = "
                      f"{per / ref['lateral-left']:.2f} x a DK lateral-left render, "
                      f"{per / ref['subcortical']:.2f} x the subcortical view without tracts; "
                      f"{tris:,} tube triangles; scene load {load:.1f} s")
                print(f"{'':46s}lateral-left through the glass cortex {glass * 1000:6.0f} {unit}/image = "
                      f"{glass / ref['lateral-left']:.2f} x a DK lateral-left render")
                print(f"{'':46s}subcortical orbit, a new view each image {orbit * 1000:6.0f} {unit}/image = "
                      f"{orbit / ref['lateral-left']:.2f} x a DK lateral-left render")
                if steps is not None:
                    print(f"{'':46s}an orbit frame, step by step (ms, each waited for): "
                          + ", ".join(f"{k} {v:.0f}" for k, v in steps.items()))
                if peer is not None and new is not None:
                    print(f"{'':46s}PyVista, the same streamlines alone, recoloured each image "
                          f"{peer * 1000:6.0f} ms/image = {peer / new:.2f} x ours (wall clock)")
                if new is not None:
                    print(f"{'':46s}subcortical, bundles recoloured each image "
                          f"{new * 1000:6.0f} {unit}/image = "
                          f"{new / ref['lateral-left']:.2f} x a DK lateral-left render")


if __name__ == "__main__":
    main()
