"""The default draw path: Blender's ``gpu`` module, indexed batches and a palette texture.

In background mode (``bpy`` as a Python module) Blender refuses ``gpu``
drawing ("GPU functions for drawing are not available in background mode")
except inside a ``RenderEngine`` whose ``bl_use_gpu_context`` is true. So a
tiny render engine is registered once per process and started with
``bpy.ops.render.render()`` on a 4x4-pixel dummy scene (about 0.3 ms); each
call runs one Python function with a GPU context current. Shaders, batches
and offscreen buffers survive between calls.

Per renderer, every part of ``scene.geometry`` becomes one indexed batch
(uploaded once, in an order that suits a software rasteriser's vertex
cache: :mod:`brainpainter_blender.meshorder`); an image uploads only the
palette (a 1-D float texture of linear colours), draws the visible parts
into a supersampled buffer of 16-bit linear light (opaque parts with depth,
then the glass: back faces, then front faces, blended, no depth writes) and
averages each SxS block in a second pass (S a compile-time constant) that
also un-premultiplies alpha and flips rows into an sRGB target, which encodes
linear light to sRGB as it is written. So the read-back (into a flat
``gpu.types.Buffer``; ``np.array`` of a multi-dimensional Buffer gives wrong
strides) is already the image.

Lighting is per vertex, in linear light, from lights fixed to the camera:
a key light from the upper left, a fill light from the right and an
ambient term (:data:`LIGHTING`).
"""

from __future__ import annotations

import atexit
from dataclasses import dataclass
from typing import Any

import numpy as np

from brainpainter.errors import BrainPainterError
from brainpainter.framing import view_projection
from brainpainter.geometry import PartGeometry, SceneGeometry
from brainpainter.scene import RenderSettings
from brainpainter.views import View
from brainpainter_blender import _bpy, meshorder


@dataclass(frozen=True)
class Lighting:
    """Camera-relative lights, in linear light (a white surface facing a light of 1 is 1).

    Attributes
    ----------
    ambient : float
    key, fill : float
        Strength of the key and fill lights.
    key_dir, fill_dir : tuple of float, shape (3,)
        Direction the light comes from, in camera space (x right, y up, z towards the viewer).
    sulc : float
        Darkening at the bottom of sulci (0 = none, 1 = black).
    lit : bool
        False: unlit palette colours (times the sulcal darkening).
    """

    ambient: float
    key: float
    fill: float
    key_dir: tuple[float, float, float] = (-0.45, 0.55, 0.70)
    fill_dir: tuple[float, float, float] = (0.60, -0.20, 0.77)
    sulc: float = 0.0
    lit: bool = True


#: Lighting per ``--lighting`` preset; ``--shading flat`` is always unlit and exact.
LIGHTING = {
    # ambient + key + fill peak near 1 (a facing surface keeps its colour, no clipping to white
    # or to a pure hue on lit slopes) and the median white surface stays near-white
    "studio": Lighting(ambient=0.36, key=0.62, fill=0.10),
    "soft": Lighting(ambient=0.56, key=0.40, fill=0.06),
    "sulc": Lighting(ambient=0.36, key=0.62, fill=0.10, sulc=0.3),
    "flat-studio": Lighting(ambient=1.0, key=0.0, fill=0.0, sulc=0.35, lit=False),
}
FLAT = Lighting(ambient=1.0, key=0.0, fill=0.0, lit=False)
#: Supersampling factor per quality (per axis); ``high`` reaches here only for flat shading.
SUPERSAMPLING = {"fast": 1, "default": 2, "high": 3}
#: Face culling of opaque parts ("BACK": half the triangles are never rasterised; "NONE": draw all).
CULL_OPAQUE = "BACK"
#: Format of the supersampled buffer (linear light, premultiplied alpha; 8 bytes a pixel).
HI_FORMAT = "RGBA16"
#: Largest supersampled buffer (pixels; 8 bytes each): huge images get less supersampling.
MAX_SUPERSAMPLED_PIXELS = 64_000_000
#: Views whose framing a renderer keeps (a movie's orbit has one per frame).
MAX_CACHED_VIEWS = 64
#: Glass: opacity at grazing angles, as a multiple of the opacity facing the camera.
GLASS_EDGE = 2.5

_MODE_LIT, _MODE_GLASS = 0, 1

_VERTEX = """
void main()
{
  vec3 base = texelFetch(palette, int(pal + 0.5), 0).rgb;
  vec3 n = normalize(nrm);
  if (dot(n, back) < 0.0) {
    n = -n;  /* seen from inside (a hole, the cut medial wall): light the side we see */
  }
  float shade = ambient + key * max(dot(n, key_dir), 0.0) + fill * max(dot(n, fill_dir), 0.0);
  shade *= 1.0 - sulc_strength * sulc;
  vec3 c = base * shade;
  if (mode == 1) {
    float facing = clamp(abs(dot(normalize(nrm), back)), 0.0, 1.0);
    float a = clamp(mix(glass_alpha * glass_edge, glass_alpha, facing), 0.0, 1.0);
    color = vec4(base * a, a);
  } else {
    color = vec4(c, 1.0);
  }
  gl_Position = mvp * vec4(pos, 1.0);
}
"""

_FRAGMENT = """
void main()
{
  fragColor = color;
}
"""

_RESOLVE_VERTEX = """
void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
"""

_RESOLVE_FRAGMENT = """
void main()
{
  /* FACTOR (the supersampling factor) is a compile-time constant, so the loops unroll */
  ivec2 p = ivec2(gl_FragCoord.xy);
  /* flipped: row 0 of the read-back is the image's top row */
  ivec2 src = ivec2(p.x, out_height - 1 - p.y) * FACTOR;
  vec4 sum = vec4(0.0);
  for (int j = 0; j < FACTOR; j++) {
    for (int i = 0; i < FACTOR; i++) {
      sum += texelFetch(image, src + ivec2(i, j), 0);
    }
  }
  sum *= 1.0 / float(FACTOR * FACTOR);
  /* linear light out: the sRGB target encodes it */
  fragColor = vec4(sum.a > 0.0 ? sum.rgb / sum.a : vec3(0.0), sum.a);
}
"""


def srgb_to_linear(rgb: np.ndarray) -> np.ndarray:
    """The IEC 61966-2-1 sRGB transfer function inverted, for an array of sRGB 0-1 values."""
    c = np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# -- the render engine that lends us a GPU context -------------------------------------------
_engine: dict[str, Any] = {}


def _engine_class():
    import bpy

    class BrainPainterGpuEngine(bpy.types.RenderEngine):
        """Runs queued Python functions while Blender holds a GPU context (background mode)."""

        bl_idname = "BRAINPAINTER_GPU"
        bl_label = "brainpainter gpu"
        bl_use_gpu_context = True

        def render(self, depsgraph):
            job = _engine.pop("job", None)
            if job is None:
                return
            try:
                _engine["result"] = job()
            except BaseException as exc:  # re-raised outside Blender's call
                _engine["error"] = exc

    return BrainPainterGpuEngine


def in_gpu_context(job):
    """Run ``job()`` with Blender's GPU context current and return its result.

    Call with :data:`brainpainter_blender._bpy.LOCK` held.
    """
    bpy = _bpy.import_bpy()
    if "scene" not in _engine:
        cls = _engine_class()
        bpy.utils.register_class(cls)
        scene = bpy.data.scenes.new("brainpainter:gpu")
        scene.render.engine = cls.bl_idname
        scene.render.resolution_x = scene.render.resolution_y = 4
        scene.render.resolution_percentage = 100
        scene.render.use_compositing = scene.render.use_sequencer = False
        cam = bpy.data.objects.new("brainpainter:gpu-camera", bpy.data.cameras.new("brainpainter:gpu-camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
        _engine["scene"] = scene.name
    _engine["job"] = job
    with _bpy.quiet() as log:
        try:
            bpy.ops.render.render(scene=_engine["scene"])
            failed = None
        except RuntimeError as exc:
            failed = exc
    _engine.pop("job", None)
    if failed is not None:
        text = " ".join("".join(log).split())[-300:]
        raise BrainPainterError(f"Blender's GPU drawing failed to start: {failed} {text}".strip())
    if "error" in _engine:
        raise _engine.pop("error")
    return _engine.pop("result", None)


_shaders: dict[Any, Any] = {}


def _part_shader() -> Any:
    """The shader of every part (compiled once per process, in a GPU context)."""
    if "part" in _shaders:
        return _shaders["part"]
    import gpu

    iface = gpu.types.GPUStageInterfaceInfo("brainpainter_part")
    iface.smooth("VEC4", "color")
    info = gpu.types.GPUShaderCreateInfo()
    for kind, name in (("MAT4", "mvp"), ("VEC3", "back"), ("VEC3", "key_dir"), ("VEC3", "fill_dir"),
                       ("FLOAT", "ambient"), ("FLOAT", "key"), ("FLOAT", "fill"),
                       ("FLOAT", "sulc_strength"), ("FLOAT", "glass_alpha"), ("FLOAT", "glass_edge"),
                       ("INT", "mode")):
        info.push_constant(kind, name)
    info.sampler(0, "FLOAT_1D", "palette")
    info.vertex_in(0, "VEC3", "pos")
    info.vertex_in(1, "VEC3", "nrm")
    info.vertex_in(2, "FLOAT", "pal")
    info.vertex_in(3, "FLOAT", "sulc")
    info.vertex_out(iface)
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source(_VERTEX)
    info.fragment_source(_FRAGMENT)
    return _keep("part", gpu.shader.create_from_info(info), iface)


def _resolve_shader(factor: int) -> Any:
    """The resolve shader for one supersampling factor (compiled once per process and factor)."""
    key = ("resolve", factor)
    if key in _shaders:
        return _shaders[key]
    import gpu

    info = gpu.types.GPUShaderCreateInfo()
    info.define("FACTOR", str(int(factor)))
    info.push_constant("INT", "out_height")
    info.sampler(0, "FLOAT_2D", "image")
    info.vertex_in(0, "VEC2", "pos")
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source(_RESOLVE_VERTEX)
    info.fragment_source(_RESOLVE_FRAGMENT)
    return _keep(key, gpu.shader.create_from_info(info))


def _keep(key: Any, shader: Any, *extra: Any) -> Any:
    if not _shaders:
        # Drop them before Blender's own exit handler, which reports GPU blocks still held.
        atexit.register(_shaders.clear)
    _shaders[key] = shader
    for i, obj in enumerate(extra):
        _shaders[(key, i)] = obj
    return shader


@dataclass(frozen=True)
class _Aim:
    """A view's parts and camera uniforms (``mathutils`` values, world space)."""

    visible: list[PartGeometry]
    mvp: Any
    back: Any
    key_dir: Any
    fill_dir: Any


def _aim_for(geometry: SceneGeometry, view: View, settings: RenderSettings, light: Lighting) -> _Aim:
    """The parts `view` shows, its view-projection matrix and the camera-fixed light directions."""
    from mathutils import Matrix, Vector

    aspect = settings.width / settings.height
    pose = geometry.camera(view, aspect)
    cam = pose.rotation  # columns: right, up, back (camera space -> world)

    def world(d: tuple[float, float, float]) -> Vector:
        v = cam @ np.asarray(d, float)
        return Vector((v / np.linalg.norm(v)).tolist())

    return _Aim(geometry.visible(view), Matrix(view_projection(pose, aspect).tolist()),
                world((0.0, 0.0, 1.0)), world(light.key_dir), world(light.fill_dir))


class GpuDraw:
    """Draws a scene's geometry with Blender's ``gpu`` module (see the module docstring).

    Parameters
    ----------
    geometry : brainpainter.geometry.SceneGeometry
    settings : brainpainter.scene.RenderSettings
    """

    def __init__(self, geometry: SceneGeometry, settings: RenderSettings) -> None:
        self.geometry = geometry
        self.settings = settings
        self.lighting = FLAT if settings.shading == "flat" else LIGHTING[settings.lighting]
        self._batches: dict[str, Any] = {}
        self._aims: dict[View, _Aim] = {}
        self._palette_key: bytes | None = None
        self._palette_tex: Any = None
        self._hi: Any = None
        self._lo: Any = None
        self._lo_tex: Any = None
        self._resolve: Any = None
        self._quad: Any = None
        in_gpu_context(self._upload)

    def _factor(self) -> int:
        import gpu

        s = self.settings
        want = SUPERSAMPLING[s.quality]
        limit = max(1, int(gpu.capabilities.max_texture_size_get()) // max(s.width, s.height))
        budget = int((MAX_SUPERSAMPLED_PIXELS / (s.width * s.height)) ** 0.5)  # GPU memory
        return max(1, min(want, limit, budget))

    def _upload(self) -> None:
        import gpu
        from gpu_extras.batch import batch_for_shader

        part_shader = _part_shader()
        for p in self.geometry.parts:
            order, triangles = meshorder.cache_friendly(p.vertices, p.triangles)
            self._batches[p.name] = batch_for_shader(
                part_shader, "TRIS",
                {"pos": p.vertices[order], "nrm": p.normals[order],
                 "pal": p.palette_index[order].astype(np.float32), "sulc": p.sulc[order]},
                indices=triangles,
            )
        s = self.settings
        self.factor = f = self._factor()
        self._resolve = _resolve_shader(f)
        self._quad = batch_for_shader(self._resolve, "TRIS", {"pos": [(-1, -1), (3, -1), (-1, 3)]})
        # Linear light in 16-bit integers: as exact as half floats for 0-1 and cheaper to write.
        self._hi = gpu.types.GPUOffScreen(s.width * f, s.height * f, format=HI_FORMAT)
        # The resolve writes linear light; the sRGB target encodes it (cheaper than pow() per pixel).
        self._lo_tex = gpu.types.GPUTexture((s.width, s.height), format="SRGB8_A8")
        self._lo = gpu.types.GPUFrameBuffer(color_slots=self._lo_tex)

    def render(self, palette_rgb: np.ndarray, view: View) -> np.ndarray:
        """Draw one image; `palette_rgb` is sRGB 0-1, shape (n_slots, 3). Returns RGBA uint8 (h, w, 4)."""
        aim = self._aim(view)
        return in_gpu_context(lambda: self._draw(np.asarray(palette_rgb, np.float32), aim))

    def _aim(self, view: View) -> _Aim:
        """What `view` draws and its camera uniforms, computed once per view.

        Besides sparing the work, the cache keeps numpy's threaded BLAS out of
        the per-image path: a camera's framing multiplies thousands of hull
        points, which wakes OpenBLAS's worker thread, and that thread then
        spins (``sched_yield``) on a core the rasteriser needs.
        """
        aim = self._aims.get(view)
        if aim is None:
            if len(self._aims) >= MAX_CACHED_VIEWS:  # a movie's orbit: many views, each used once
                self._aims.clear()
            aim = self._aims[view] = _aim_for(self.geometry, view, self.settings, self.lighting)
        return aim

    def _palette(self, rgb: np.ndarray) -> Any:
        import gpu

        key = rgb.tobytes()
        if key != self._palette_key:
            rgba = np.ones((len(rgb), 4), np.float32)
            rgba[:, :3] = srgb_to_linear(rgb)
            buf = gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel())
            self._palette_tex = gpu.types.GPUTexture(len(rgba), format="RGBA32F", data=buf)
            self._palette_key = key
        return self._palette_tex

    def _draw(self, rgb: np.ndarray, aim: _Aim) -> np.ndarray:
        import gpu

        s, light, visible = self.settings, self.lighting, aim.visible
        part_shader, resolve = _part_shader(), self._resolve
        tex = self._palette(rgb)
        bg = s.background
        clear = (0.0, 0.0, 0.0, 0.0) if bg is None else (*srgb_to_linear(np.asarray(bg)).tolist(), 1.0)
        with self._hi.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=clear, depth=1.0)
            part_shader.bind()
            part_shader.uniform_float("mvp", aim.mvp)
            part_shader.uniform_float("back", aim.back)
            part_shader.uniform_float("key_dir", aim.key_dir)
            part_shader.uniform_float("fill_dir", aim.fill_dir)
            part_shader.uniform_float("ambient", light.ambient)
            part_shader.uniform_float("key", light.key if light.lit else 0.0)
            part_shader.uniform_float("fill", light.fill if light.lit else 0.0)
            part_shader.uniform_float("glass_alpha", float(s.glass_opacity))
            part_shader.uniform_float("glass_edge", GLASS_EDGE)
            part_shader.uniform_sampler("palette", tex)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            gpu.state.blend_set("NONE")
            # Parts are closed surfaces: faces turned away are always hidden behind others.
            gpu.state.face_culling_set(CULL_OPAQUE)
            part_shader.uniform_int("mode", _MODE_LIT)
            for p in visible:
                if p.kind == "glass":
                    continue
                part_shader.uniform_float("sulc_strength", light.sulc if p.kind == "cortex" else 0.0)
                self._batches[p.name].draw(part_shader)
            glass = [p for p in visible if p.kind == "glass"]
            if glass and s.glass_opacity > 0:
                gpu.state.depth_mask_set(False)
                gpu.state.blend_set("ALPHA_PREMULT")
                part_shader.uniform_int("mode", _MODE_GLASS)
                part_shader.uniform_float("sulc_strength", 0.0)
                for cull in ("FRONT", "BACK"):  # far side first, then the near side over it
                    gpu.state.face_culling_set(cull)
                    for p in glass:
                        self._batches[p.name].draw(part_shader)
                gpu.state.face_culling_set("NONE")
                gpu.state.blend_set("NONE")
                gpu.state.depth_mask_set(True)
            gpu.state.depth_test_set("NONE")
        with self._lo.bind():
            # the resolve writes every pixel: no clear
            resolve.bind()
            resolve.uniform_int("out_height", s.height)
            resolve.uniform_sampler("image", self._hi.texture_color)
            self._quad.draw(resolve)
            buf = gpu.types.Buffer("UBYTE", s.width * s.height * 4)
            self._lo.read_color(0, 0, s.width, s.height, 4, 0, "UBYTE", data=buf)
        # a view of the Buffer's memory (kept alive by the array), no copy
        return np.frombuffer(buf, dtype=np.uint8).reshape(s.height, s.width, 4)

    def close(self) -> None:
        """Free the batches, textures and offscreen buffers (in a GPU context)."""
        if self._hi is None and not self._batches:
            return

        def drop() -> None:
            if self._hi is not None:
                self._hi.free()
            self._hi = self._lo = self._lo_tex = self._quad = self._palette_tex = None
            self._batches.clear()

        in_gpu_context(drop)
