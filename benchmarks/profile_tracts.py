"""Where a tract image's time goes: variants of the tract parts, timed against the same scene without tracts.

Not a feature: a measurement for issue 24's speed bar. Loads the DK scene with
``--streamlines`` synthetic streamlines (``bench_tracts.write_tractogram``) and,
per view and variant, makes a ``GpuDraw`` from a copy of the scene's geometry
whose tract parts are changed, then draws the variants in turn (interleaved,
so a loaded machine's swings hit them alike), timing CPU seconds per image (all
threads; steadier than the wall clock) and then the steps of one image
(``GpuDraw.profile``, wall clock, each step waited for). Variants:

* ``no tracts``: the reference;
* ``lines``: as drawn (the centrelines as lines, ``brainpainter_blender.tract_lines``);
* ``tubes``: the tubes drawn as opaque parts into the supersampled buffer (the drawing up to session 6;
  every ``tubes`` variant drops the parts' centrelines, so the renderer draws their triangles);
* ``tubes, no fill``: the same triangles with a radius of 0.001 mm (almost no pixels);
* ``tubes, natural order``: the tubes' vertices and triangles in the order built, not Morton-sorted;
* ``tubes, half points``: every other ring;
* ``tubes, front to back`` / ``back to front``: triangles sorted by depth for the view;
* ``tubes, no perspective``: as drawn, with the colour interpolated linearly in screen space.

    python benchmarks/profile_tracts.py --streamlines 10000 --repeats 12 --views subcortical
"""

from __future__ import annotations

import argparse
import copy
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from bench_tracts import write_tractogram


def _no_fill(part: Any) -> Any:
    hull = np.repeat(part.hull, len(part.vertices) // len(part.hull), axis=0)
    return replace(part, vertices=(hull + 0.001 * part.normals).astype(np.float32))


def _half_points(part: Any) -> Any:
    n_lines = len(part.hull) // N_POINTS[0]
    keep = np.r_[0:N_POINTS[0]:2, N_POINTS[0] - 1] if N_POINTS[0] % 2 == 0 else np.r_[0:N_POINTS[0]:2]
    lines = part.hull.reshape(n_lines, N_POINTS[0], 3)[:, keep]
    pal = part.palette_index.reshape(n_lines, N_POINTS[0], -1)[:, keep].reshape(-1)
    from brainpainter.tracts.tubes import SIDES, tube_mesh

    radius = float(np.linalg.norm(part.vertices[0] - part.hull[0]))
    v, nrm, tris = tube_mesh(lines, radius, SIDES)
    return replace(part, vertices=v, normals=nrm, triangles=tris, palette_index=pal,
                   sulc=np.zeros(len(v), np.float32), hull=lines.reshape(-1, 3))


def _sorted(sign: float) -> Callable[[Any], Any]:
    def change(part: Any) -> Any:
        depth = (part.vertices[part.triangles].mean(axis=1) @ BACK[0]) * sign
        return replace(part, triangles=part.triangles[np.argsort(-depth, kind="stable")])
    return change


#: Points per streamline of the tubes and the view's direction to the camera (set in main).
N_POINTS: list[int] = []
BACK: list[np.ndarray] = []
#: Variants whose parts keep the order they are given in (meshorder.cache_friendly is skipped).
KEEP_ORDER = {"tubes, natural order", "tubes, front to back", "tubes, back to front"}

VARIANTS: dict[str, Callable[[Any], Any] | None] = {
    "no tracts": None,
    "lines": lambda p: p,
    "tubes": lambda p: p,
    "tubes, no fill": _no_fill,
    "tubes, natural order": lambda p: p,
    "tubes, half points": _half_points,
    "tubes, front to back": _sorted(1.0),
    "tubes, back to front": _sorted(-1.0),
    "tubes, no perspective": lambda p: p,
}


def _no_perspective_shader() -> Any:
    """The part shader with ``no_perspective`` colour interpolation (in a GPU context)."""
    from brainpainter_blender import gpu_shaders

    return gpu_shaders._build("part_linear", gpu_shaders._VERTEX, gpu_shaders._FRAGMENT,
                              defines={"PALETTE_WIDTH": gpu_shaders.PALETTE_WIDTH},
                              constants=gpu_shaders._PART_CONSTANTS, samplers=("palette",),
                              inputs=gpu_shaders._PART_INPUTS,
                              varyings=(("no_perspective", "VEC4", "color"),))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--streamlines", type=int, default=10000)
    p.add_argument("--size", default="1200x900")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--variants", default=";".join(VARIANTS), help="Semicolon-separated.")
    p.add_argument("--views", default="subcortical,lateral-left")
    args = p.parse_args()
    width, height = (int(v) for v in args.size.split("x"))

    from brainpainter.rendering.mesh_memo import MESH_MEMO
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.tract_parts import TractLayer
    from brainpainter.rendering.views import get_view
    from brainpainter.tracts.model import TractSpec
    from brainpainter_blender import _bpy, gpu_shaders, meshorder
    from brainpainter_blender.gpu_context import in_gpu_context
    from brainpainter_blender.gpu_draw import GpuDraw

    settings = RenderSettings(width=width, height=height)
    views = [get_view(v) for v in args.views.split(",")]
    n = args.streamlines
    with tempfile.TemporaryDirectory() as tmp:
        folder = write_tractogram(Path(tmp) / "bundles", n)
        tracts = TractLayer(TractSpec((str(folder),), max_streamlines=n))
        with Painter("dk", settings=settings, layers=(tracts,)) as painter:
            painter.load()
            geometry = painter.scene.geometry
            rgb = np.asarray(geometry.default_rgb, np.float32)
            tract = [q for q in geometry.parts if q.kind == "tract"]
            from brainpainter.tracts.tubes import SIDES, points_for

            N_POINTS.append(points_for(n, painter.scene.tracts.n_points, SIDES))
            print(f"{n} streamlines: {sum(len(q.triangles) for q in tract):,} tube triangles, "
                  f"{sum(len(q.vertices) for q in tract):,} vertices, {N_POINTS[0]} points a streamline")
            for view in views:
                BACK[:] = [np.asarray(geometry.camera(view, width / height).back, float)]
                names = list(dict.fromkeys(args.variants.split(";")))
                draws = {}
                for name in names:
                    change = VARIANTS[name]
                    g = copy.copy(geometry)
                    g.parts = tuple(q for q in geometry.parts if q.kind != "tract" or change is not None)
                    if change is not None:
                        g.parts = tuple(change(q) if q.kind == "tract" else q for q in g.parts)
                    if name.startswith("tubes"):
                        g.parts = tuple(replace(q, centrelines=None) for q in g.parts)
                    original = meshorder.cache_friendly
                    if name in KEEP_ORDER:
                        meshorder.cache_friendly = lambda v, t: (np.arange(len(v)), t.astype(np.int32))
                    MESH_MEMO.clear()  # no variant draws another's kept order
                    try:
                        with _bpy.LOCK:
                            draws[name] = GpuDraw(g, settings)
                            draws[name].render(rgb, view)  # uploads the batches
                    finally:
                        meshorder.cache_friendly = original
                        MESH_MEMO.clear()
                cpu: dict[str, list[float]] = {name: [] for name in names}
                with _bpy.LOCK:
                    usual = gpu_shaders.part_shader()
                    shader = {name: usual for name in names}
                    if "tubes, no perspective" in names:
                        shader["tubes, no perspective"] = in_gpu_context(_no_perspective_shader)
                    for _ in range(args.repeats):  # interleaved: the machine's load hits every variant alike
                        for name in names:
                            gpu_shaders._shaders["part"] = shader[name]
                            t = time.process_time()
                            draws[name].render(rgb, view)
                            cpu[name].append(time.process_time() - t)
                    for name in names:
                        gpu_shaders._shaders["part"] = shader[name]
                        steps = [draws[name].profile(rgb, view) for _ in range(3)]
                        draws[name].close()
                        med = {k: statistics.median(s[k] for s in steps) for k in steps[0]}
                        text = ", ".join(f"{k} {v * 1000:.0f}" for k, v in med.items())
                        per = [v * 1000 for v in sorted(cpu[name])]
                        print(f"{name:24s} {view.name:13s} {statistics.median(per):6.0f} CPU ms/image "
                              f"(quartiles {per[len(per) // 4]:.0f}-{per[3 * len(per) // 4]:.0f}) "
                              f"| wall ms: {text}", flush=True)
                    gpu_shaders._shaders["part"] = usual


if __name__ == "__main__":
    main()
