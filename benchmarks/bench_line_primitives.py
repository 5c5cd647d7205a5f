"""Benchmark: what an orbit frame's tract lines cost llvmpipe (issue 37's tract-orbit bar).

An orbit frame (a view not drawn before) draws a tract part's centrelines again
(:mod:`brainpainter_blender.tract_lines`: one GL line per segment, ``raster_width`` pixels wide).
Two measurements, CPU ms of the whole process (all llvmpipe threads) beside wall ms, medians:

* ``primitives``: 10,000 synthetic streamlines of 11 points (100,000 segments, about 260 pixels
  long each, as in ``bench_tracts.py``'s subcortical orbit), a trivial shader, blended into an
  RGBA16 buffer: as GL lines ``--width`` pixels wide, and as screen-space quads (two triangles,
  indexed) as wide as the GL line and as wide as the line's true footprint
  (``--quad-width``: twice the half width plus the fringe);
* ``layer``: the real tracts' layer of ``bench_tracts.py``'s 10,000 streamlines (the line shader,
  both targets, depth-tested) from the subcortical view, as drawn and in variants that change
  one thing: lines 1 pixel wide, no blending, no depth test, every other segment (half the
  segments, half the length), segments joined five at a time (a fifth of the segments, the
  same length), shaders with the same inputs and outputs that compute nothing.

    python benchmarks/bench_line_primitives.py                 # both, 5 repeats
    python benchmarks/bench_line_primitives.py --only primitives --width 4 --quad-width 2.46

Timings depend on the machine (llvmpipe without a GPU); say which one in docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

WIDTH, HEIGHT = 1200, 900


def _streamlines(n: int = 10_000, m: int = 11, seed: int = 0) -> np.ndarray:
    """`n` gently bent streamlines of `m` points in normalised device coordinates, shape (n, m, 2)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, m)[None, :, None]
    start = rng.uniform(-0.6, 0.2, (n, 1, 2))
    direction = rng.normal(size=(n, 1, 2))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    bend = rng.normal(0.0, 0.05, (n, 1, 2))
    return (start + t * direction * 0.45 + np.sin(np.pi * t) * bend).astype(np.float32)


def _quads(a: np.ndarray, b: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Corners (4 per segment, NDC) and triangles of quads `width` pixels wide, reaching out by half
    their width beyond both ends; `a`, `b`: segment ends, shape (k, 2)."""
    px = np.array([2.0 / WIDTH, 2.0 / HEIGHT], np.float32)
    d = (b - a) / px
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-6)
    n = np.stack([-d[:, 1], d[:, 0]], axis=1)
    h = width / 2.0
    corners = np.stack([a - (d + n) * h * px, a - (d - n) * h * px,
                        b + (d - n) * h * px, b + (d + n) * h * px], axis=1)
    tris = (np.arange(len(a)) * 4)[:, None] + np.array([0, 1, 2, 0, 2, 3])[None]
    return corners.reshape(-1, 2).astype(np.float32), tris.reshape(-1, 3).astype(np.uint32)


def _timed(draw: Any, sync: Any, repeats: int) -> tuple[float, float]:
    """Median wall and CPU milliseconds of `draw()` then `sync()` (a 1-pixel read-back)."""
    wall, cpu = [], []
    for _ in range(repeats):
        sync()
        t, c = time.perf_counter(), time.process_time()
        draw()
        sync()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return 1000 * statistics.median(wall), 1000 * statistics.median(cpu)


def primitives(width: float, quad_width: float, repeats: int) -> dict[str, tuple[float, float]]:
    """GL lines against two-triangle quads over the same streamlines (run in a GPU context)."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    info = gpu.types.GPUShaderCreateInfo()
    info.vertex_in(0, "VEC2", "pos")
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source("void main() { gl_Position = vec4(pos, 0.5, 1.0); }")
    info.fragment_source("void main() { fragColor = vec4(0.1, 0.0, 0.0, 0.1); }")
    shader = gpu.shader.create_from_info(info)
    # a framebuffer does not keep its textures alive: hold them, or it draws into nothing (fast)
    color = gpu.types.GPUTexture((WIDTH, HEIGHT), format="RGBA16")
    depth = gpu.types.GPUTexture((WIDTH, HEIGHT), format="DEPTH_COMPONENT32F")
    fb = gpu.types.GPUFrameBuffer(color_slots=color, depth_slot=depth)
    points = _streamlines()
    n, m = points.shape[:2]
    flat = points.reshape(-1, 2)
    first = (np.arange(n)[:, None] * m + np.arange(m - 1)[None]).reshape(-1)
    pairs = np.stack([first, first + 1], axis=-1).astype(np.uint32)
    lines = batch_for_shader(shader, "LINES", {"pos": flat}, indices=pairs)
    batches = {f"GL lines {width:g} px": (lines, width)}
    for w in dict.fromkeys((width, quad_width)):
        corners, tris = _quads(flat[first], flat[first + 1], w)
        batches[f"quads {w:g} px"] = (batch_for_shader(shader, "TRIS", {"pos": corners}, indices=tris), 1.0)

    def sync() -> None:
        fb.read_color(0, 0, 1, 1, 4, 0, "UBYTE", data=gpu.types.Buffer("UBYTE", 4))

    out = {}
    with fb.bind():
        shader.bind()
        gpu.state.blend_set("ALPHA_PREMULT")
        for name, (batch, line_width) in batches.items():
            gpu.state.line_width_set(line_width)
            fb.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            out[name] = _timed(lambda b=batch: b.draw(shader), sync, repeats)
        gpu.state.line_width_set(1.0)
        gpu.state.blend_set("NONE")
    return out


def _constant_line_shader() -> Any:
    """A shader with the line shader's inputs, varyings and outputs that computes nothing."""
    from brainpainter_blender import gpu_shaders

    vertex = """
void main()
{
  centre = vec2(pal, cap);
  dir = tang.xy;
  even_slot = odd_slot = towards_odd = odd;
  gl_Position = mvp * vec4(pos, 1.0);
}
"""
    fragment = """
void main()
{
  lit = vec4(centre.x + dir.x, even_slot + odd_slot, towards_odd, 0.5);
  slot = vec4(1.0);
}
"""
    names = [name for name, _ in gpu_shaders.line_shader().attrs_info_get()]
    inputs = tuple(("VEC3" if name in ("pos", "tang") else "FLOAT", name) for name in names)
    return gpu_shaders._build("line_constant", vertex, fragment, constants=(("MAT4", "mvp"),),
                              inputs=inputs, varyings=tuple(("no_perspective", kind, name) for kind, name in (
                                  ("VEC2", "centre"), ("VEC2", "dir"), ("FLOAT", "even_slot"),
                                  ("FLOAT", "odd_slot"), ("FLOAT", "towards_odd"))),
                              outputs=(("VEC4", "lit"), ("VEC4", "slot")))


def layer(painter: Any, repeats: int) -> tuple[dict[str, tuple[float, float]], str]:
    """The real tracts' layer of the subcortical view, as drawn and in variants (in a GPU context),
    and a line saying how many segments, how long, how wide."""
    import gpu

    from brainpainter.rendering.views import get_view
    from brainpainter_blender import gpu_shaders, tract_lines

    draw = painter.load()._gpu
    aim = draw._aim(get_view("subcortical"))
    lines = draw._lines
    parts = [p for p in aim.visible if p.kind == "tract" and p.centrelines is not None]
    size = (lines.width, lines.height)
    shade = gpu.types.GPUTexture(size, format="RGBA16")
    slots = gpu.types.GPUTexture(size, format="RGBA32F")
    depth = gpu.types.GPUTexture(size, format="DEPTH_COMPONENT32F")
    fb = gpu.types.GPUFrameBuffer(depth_slot=depth, color_slots=(shade, slots))
    half = lines._half_width(parts, aim)
    back = np.asarray(aim.back, np.float64)

    def joined(step: int, skip: bool) -> list[Any]:
        out = []
        for p in parts:
            n, m = p.centrelines.slots.shape
            ends = np.arange(0, m - 1, 2 if skip else step)
            pairs = np.stack([ends, ends + 1 if skip else np.minimum(ends + step, m - 1)], axis=-1)
            idx = (np.arange(n)[:, None, None] * m + pairs[None]).reshape(-1, 2).astype(np.uint32)
            out.append(gpu.types.GPUBatch(type="LINES", buf=lines._vertices(p),
                                          elem=gpu.types.GPUIndexBuf(type="LINES", seq=idx)))
        return out

    variants: dict[str, dict[str, Any]] = {
        "as drawn": {}, "1 px wide": {"width": 1.0}, "no blending": {"blend": "NONE"},
        "no depth test": {"depth": "NONE"}, "every other segment": {"batches": joined(2, True)},
        "segments joined by 5": {"batches": joined(5, False)},
        "constant shaders": {"shader": _constant_line_shader()}}

    def sync() -> None:
        fb.read_color(0, 0, 1, 1, 4, 0, "UBYTE", data=gpu.types.Buffer("UBYTE", 4))

    out = {}
    with fb.bind():
        for name, v in variants.items():
            fb.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            shader = v.get("shader") or gpu_shaders.line_shader()
            shader.bind()
            for key, value in (("mvp", aim.mvp), ("viewport", (float(size[0]), float(size[1]))),
                               ("half_width", half), ("key_dir", (0.0, 0.0, 1.0)),
                               ("fill_dir", (0.0, 0.0, 1.0)), ("ambient", 0.3), ("key", 0.5),
                               ("fill", 0.2), ("contrast", 0.2)):
                if "shader" not in v or key == "mvp":
                    shader.uniform_float(key, value)
            gpu.state.depth_test_set(v.get("depth", "LESS_EQUAL"))
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set(v.get("blend", "ALPHA_PREMULT"))
            gpu.state.line_width_set(v.get("width", float(tract_lines.raster_width(half))))
            fixed = v.get("batches")

            def run(fixed: Any = fixed, shader: Any = shader) -> None:
                for batch in fixed if fixed is not None else [lines._sorted(p, back) for p in parts]:
                    batch.draw(shader)

            out[name] = _timed(run, sync, repeats)
            gpu.state.line_width_set(1.0)
            gpu.state.blend_set("NONE")
            gpu.state.depth_mask_set(True)
            gpu.state.depth_test_set("NONE")
    length = 0.0
    mvp = np.asarray(aim.mvp, np.float64)
    for p in parts:
        xy = (p.centrelines.points @ mvp[:2, :3].T + mvp[:2, 3]) * np.array([size[0] / 2, size[1] / 2])
        length += float(np.abs(np.diff(xy, axis=1)).max(axis=-1).sum())
    return out, (f"layer: {sum(p.centrelines.slots.size - len(p.centrelines.slots) for p in parts):,} "
                 f"segments, {length / 1e6:.2f} million pixels along their major axes, half width "
                 f"{half:.2f} px, GL line width {tract_lines.raster_width(half)} px")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", choices=("primitives", "layer"))
    p.add_argument("--width", type=float, default=4.0, help="GL line width (pixels).")
    p.add_argument("--quad-width", type=float, default=2.46, help="Quads' width (pixels).")
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args()

    from brainpainter_blender import _bpy
    from brainpainter_blender.gpu_context import in_gpu_context

    results: dict[str, tuple[float, float]] = {}
    if args.only in (None, "primitives"):
        with _bpy.LOCK:
            results.update(in_gpu_context(lambda: primitives(args.width, args.quad_width, args.repeats)))
    if args.only in (None, "layer"):
        import bench_tracts

        from brainpainter.rendering.painter import Painter
        from brainpainter.rendering.settings import RenderSettings
        from brainpainter.rendering.tract_parts import TractLayer
        from brainpainter.rendering.views import get_view
        from brainpainter.tracts.model import TractSpec

        with tempfile.TemporaryDirectory() as tmp:
            folder = bench_tracts.write_tractogram(Path(tmp) / "bundles", 10_000)
            with Painter("dk", settings=RenderSettings(width=WIDTH, height=HEIGHT),
                         layers=(TractLayer(TractSpec((str(folder),), max_streamlines=10_000)),)) as painter:
                painter.paint_colors({}, get_view("subcortical"))  # uploads the scene
                with _bpy.LOCK:
                    timed, about = in_gpu_context(lambda: layer(painter, args.repeats))
                results.update(timed)
                print(about)
    for name, (wall, cpu) in results.items():
        print(f"{name:28s} {cpu:7.1f} CPU ms {wall:7.1f} wall ms")


if __name__ == "__main__":
    main()
