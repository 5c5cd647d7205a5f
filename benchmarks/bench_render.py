"""Benchmark: render the bundled example scaled to many rows.

Prints images per second, median seconds per image, time to the first image
from a cold process, and peak memory for two row counts (to show that memory
does not grow with the number of rows). Then, in the same run, the peer
comparison: brainpainter's render + read-back of one 1200x900 view against
PyVista/VTK's with its fastest fair settings (off screen, 4x MSAA, one
headlight, the same normals given once, back faces culled, a warm-up
screenshot, a real render forced before every read-back; the same
left-hemisphere mesh and colours, fpng for both PNGs), the two interleaved
in alternating fresh processes, and their ratio.

    python benchmarks/bench_render.py                 # 50 rows x 3 default views, 1200x900
    python benchmarks/bench_render.py --rows 10 --quality fast
    python benchmarks/bench_render.py --no-peer       # without PyVista (pip install -e .[bench])
    python benchmarks/bench_render.py --profile       # also: where one image's time goes

``--profile`` adds, from a separate process: the start-up steps up to the
first image, and per view the triangles drawn and the median seconds of each
step of one image (palette, clear, each part, glass, resolve, read-back, each
waited for, so they add up to more than an ordinary image, whose steps
overlap), the whole image, its CPU seconds, and the PNG encoding.

Record results in docs/benchmarks.md with the machine they ran on.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
import pandas as pd
import brainpainter
from brainpainter.rendering.run import render
args = json.loads(sys.argv[1])
frame = pd.read_csv(args["example"])
rows = [frame.iloc[i % len(frame)].copy() for i in range(args["rows"])]
big = pd.DataFrame(rows).reset_index(drop=True)
big["Image-name-unique"] = [f"row{i:03d}" for i in range(len(big))]
stamps = []
import brainpainter.io.output as output
_orig = output.write_png
def timed_write(path, image, metadata=None):
    _orig(path, image, metadata)
    stamps.append(time.perf_counter())
output.write_png = timed_write
render(big, "dk", out=args["out"], views=args["views"], width=args["width"], height=args["height"],
       quality=args["quality"], progress=False)
t_end = time.perf_counter()
peak_mb = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:")) / 1024
print(json.dumps({"t_first": stamps[0] - t0, "t_total": t_end - t0, "stamps": [s - t0 for s in stamps],
                  "peak_mb": peak_mb, "cpu_s": time.process_time()}))
"""


# Render + read-back of one view, brainpainter and PyVista/VTK alike: the left hemisphere's pial
# mesh of the bundled template, lateral-left, a random colour per region for every image.
PEER = r"""
import json, sys, time
import numpy as np
args = json.loads(sys.argv[1])
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import get_view
painter = Painter("dk", settings=RenderSettings(args["width"], args["height"]))
view = get_view("lateral-left")
part = next(p for p in painter.scene.geometry.parts if p.name == "cortex-lh")
rng = np.random.default_rng(0)
palettes = [rng.random((painter.scene.geometry.n_slots, 3)) for _ in range(args["n"] + 2)]
keys = painter.scene.geometry.keys
from brainpainter.io.output import png_bytes  # fpng, both sides
times, cpu, png = [], [], []
if args["engine"] == "brainpainter":
    painter.load()
    for i, pal in enumerate(palettes):
        colors = {k: tuple(pal[3 + j]) for j, k in enumerate(keys)}
        t, c = time.perf_counter(), time.process_time()
        img = painter.paint_colors(colors, view)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        t = time.perf_counter()
        png_bytes(img)
        png.append(time.perf_counter() - t)
else:
    # PyVista's fastest fair settings (issue 25): 4x MSAA (we supersample 2x2), one headlight, the
    # same normals given once (no smooth_shading: it re-runs a normals filter after every colour
    # change), back faces culled, a warm-up screenshot, a real render before each read-back.
    import pyvista as pv
    pose = painter.scene.geometry.camera(view, args["width"] / args["height"])
    faces = np.hstack([np.full((len(part.triangles), 1), 3), part.triangles]).astype(np.int64).ravel()
    mesh = pv.PolyData(part.vertices.astype(np.float64), faces)
    mesh.point_data["Normals"] = part.normals
    mesh.point_data.active_normals_name = "Normals"
    mesh.point_data["rgb"] = np.zeros((len(part.vertices), 3), np.uint8)
    pl = pv.Plotter(off_screen=True, window_size=(args["width"], args["height"]), lighting="none")
    pl.add_light(pv.Light(light_type="headlight"))
    pl.set_background("white")
    actor = pl.add_mesh(mesh, scalars="rgb", rgb=True, smooth_shading=False, culling="back")
    actor.prop.interpolation = "gouraud"  # per-vertex lighting from the given normals, like ours
    pl.enable_anti_aliasing("msaa", multi_samples=4)
    pl.camera.SetParallelProjection(True)
    pl.camera.position = tuple(pose.location)
    pl.camera.focal_point = tuple(pose.location - 100 * pose.back)
    pl.camera.up = tuple(pose.up)
    pl.camera.parallel_scale = pose.ortho_scale / args["width"] * args["height"] / 2
    pl.renderer.ResetCameraClippingRange()
    pl.camera_set = True  # else the first render resets the camera to its own framing (smaller brain)
    pl.render()
    pl.screenshot(return_img=True)  # warm-up
    for pal in palettes:
        t, c = time.perf_counter(), time.process_time()
        mesh.point_data["rgb"][:] = np.round(pal[part.palette_index] * 255).astype(np.uint8)
        mesh.point_data["rgb"] = mesh.point_data["rgb"]  # marks the array modified
        pl.render()  # force a real render: a screenshot alone may return the last frame
        img = pl.screenshot(return_img=True)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        t = time.perf_counter()
        png_bytes(np.ascontiguousarray(img))
        png.append(time.perf_counter() - t)
    assert img.shape[:2] == (args["height"], args["width"])
    pl.close()
print(json.dumps({"times": times[2:], "cpu": cpu[2:], "png": png[2:]}))
"""


# Where the time goes: start-up steps, then each view's steps (GpuDraw.profile) and the PNG.
PROFILE = r"""
import json, statistics, sys, time
t0 = time.perf_counter()
steps = {}
def mark(name):
    steps[name] = round(time.perf_counter() - t0, 3)
import numpy as np
import pandas
mark("import numpy, pandas")
from brainpainter.rendering.painter import Painter
from brainpainter.io.output import png_bytes
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import get_view
mark("import brainpainter")
args = json.loads(sys.argv[1])
painter = Painter("dk", settings=RenderSettings(args["width"], args["height"], quality=args["quality"]))
mark("load atlas and template")
from brainpainter_blender import _bpy
_bpy.import_bpy()
mark("import bpy")
geometry = painter.scene.geometry
mark("scene geometry")
gpu = painter.load()._gpu
mark("renderer: upload batches, compile shaders")
views = [get_view(v) for v in args["views"]]
painter.paint_colors({}, views[0])
mark("first image")
rng = np.random.default_rng(0)
out = {"startup_s": steps, "views": {}}
for view in views:
    rows, whole, cpu, png = [], [], [], []
    for i in range(args["n"] + 2):
        rgb = rng.random((geometry.n_slots, 3))
        rows.append(gpu.profile(rgb, view))
        t, c = time.perf_counter(), time.process_time()
        img = gpu.render(rng.random((geometry.n_slots, 3)), view)
        whole.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        t = time.perf_counter()
        png_bytes(img)
        png.append(time.perf_counter() - t)
    med = {k: round(statistics.median(r[k] for r in rows[2:]), 4) for k in rows[2]}
    med["image (steps overlapping)"] = round(statistics.median(whole[2:]), 4)
    med["image CPU s (all threads)"] = round(statistics.median(cpu[2:]), 4)
    med["png (fpng)"] = round(statistics.median(png[2:]), 4)
    triangles = {p.name: len(p.triangles) for p in geometry.visible(view)}
    out["views"][view.name] = {"triangles": triangles, "median_s": med}
print(json.dumps(out))
"""


def run_profile(args: argparse.Namespace, n: int = 10) -> dict:
    """Start-up steps and per-view step medians, from a fresh process."""
    cfg = {"width": args.width, "height": args.height, "quality": args.quality, "n": n,
           "views": args.views.split(",")}
    proc = subprocess.run([sys.executable, "-c", PROFILE, json.dumps(cfg)], capture_output=True, text=True,
                          check=True)
    return _last_json(proc.stdout)


def run_peer(engine: str, args: argparse.Namespace, n: int = 20) -> dict[str, list[float]]:
    """Wall and CPU seconds of each render + read-back, and of its PNG encoding (fpng), one process."""
    cfg = {"engine": engine, "width": args.width, "height": args.height, "n": n}
    proc = subprocess.run([sys.executable, "-c", PEER, json.dumps(cfg)], capture_output=True, text=True,
                          check=True)
    return _last_json(proc.stdout)


def run_peers(args: argparse.Namespace, rounds: int = 4, n: int = 10) -> dict[str, object]:
    """brainpainter and PyVista/VTK interleaved (``rounds`` fresh processes each, alternating)."""
    got: dict[str, dict[str, list[float]]] = {e: {"times": [], "cpu": [], "png": []}
                                              for e in ("brainpainter", "pyvista")}
    for _ in range(rounds):
        for engine in got:
            for k, v in run_peer(engine, args, n).items():
                got[engine][k].extend(v)
    med = {e: {k: round(statistics.median(v), 4) for k, v in r.items()} for e, r in got.items()}
    ours, theirs = med["brainpainter"], med["pyvista"]
    return {
        "settings": "pyvista: 4x MSAA, one headlight, normals given once (no smooth_shading), "
                    "back-face culling, warm-up screenshot, render() before each read-back; "
                    "brainpainter: default (2x2 supersampling); both: fpng",
        "render_readback_median_s": {"brainpainter": ours["times"], "pyvista_vtk": theirs["times"]},
        "render_readback_median_cpu_s": {"brainpainter": ours["cpu"], "pyvista_vtk": theirs["cpu"]},
        "png_median_s": {"brainpainter": ours["png"], "pyvista_vtk": theirs["png"]},
        "pyvista_over_brainpainter": round(theirs["times"] / ours["times"], 2),
        "pyvista_over_brainpainter_incl_png": round((theirs["times"] + theirs["png"])
                                                    / (ours["times"] + ours["png"]), 2),
        "pyvista_over_brainpainter_cpu": round(theirs["cpu"] / ours["cpu"], 2),
    }


def _last_json(text: str) -> dict:
    return json.loads([line for line in text.splitlines() if line.startswith("{")][-1])


def run_child(rows: int, args: argparse.Namespace) -> dict:
    with tempfile.TemporaryDirectory() as out:
        cfg = {"example": str(EXAMPLE), "rows": rows, "out": out, "views": args.views,
               "width": args.width, "height": args.height, "quality": args.quality}
        code = CHILD
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", code, json.dumps(cfg)], capture_output=True,
                              text=True, check=True)
        wall = time.perf_counter() - start
        result = _last_json(proc.stdout)
        result["wall"] = wall
        result["n_images"] = len(list(Path(out).glob("*.png")))
        return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=50)
    parser.add_argument("--small-rows", type=int, default=10, help="row count for the memory comparison")
    parser.add_argument("--views", default="lateral-left,medial-left,subcortical")
    parser.add_argument("--size", default="1200x900")
    parser.add_argument("--quality", default="default")
    parser.add_argument("--no-peer", action="store_true", help="skip the PyVista/VTK comparison")
    parser.add_argument("--profile", action="store_true",
                        help="also time the steps of start-up and of one image")
    args = parser.parse_args()
    args.width, args.height = (int(x) for x in args.size.split("x"))

    load_before = [round(x, 2) for x in os.getloadavg()]
    small = run_child(args.small_rows, args)
    big = run_child(args.rows, args)
    stamps = big["stamps"]
    per_image = [b - a for a, b in itertools.pairwise(stamps)]
    n = big["n_images"]
    amortised = (big["t_total"]) / n
    report = {
        "load_average_before": load_before,
        "images": n,
        "size": args.size,
        "quality": args.quality,
        "images_per_second": round(n / big["t_total"], 2),
        # CPU seconds (all threads) per image: what the run costs whatever the machine's load
        "cpu_s_per_image_incl_startup": round(big["cpu_s"] / n, 3),
        "amortised_s_per_image_incl_startup": round(amortised, 3),
        "median_s_per_image_steady": round(statistics.median(per_image), 3) if per_image else None,
        "time_to_first_image_cold_s": round(big["t_first"], 2),
        "process_wall_s": round(big["wall"], 2),
        f"peak_memory_mb_{args.small_rows}_rows": round(small["peak_mb"]),
        f"peak_memory_mb_{args.rows}_rows": round(big["peak_mb"]),
    }
    if not args.no_peer:
        try:
            report["peer"] = run_peers(args)
        except subprocess.CalledProcessError as exc:
            report["peer_error"] = exc.stderr.strip().splitlines()[-1:]
    if args.profile:
        report["profile"] = run_profile(args)
    report["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
