"""The default draw path: Blender's ``gpu`` module, indexed batches and a palette texture.

Everything runs inside :func:`brainpainter_blender.gpu_context.in_gpu_context` (background mode allows
``gpu`` drawing only there). Shaders, batches and offscreen buffers survive between calls.

Per renderer, every part of ``scene.geometry`` becomes one indexed batch (uploaded once, in an order that
suits a software rasteriser's vertex cache: :mod:`brainpainter_blender.meshorder`); an image uploads only
the palette (a 2-D float texture of linear colours, :data:`~brainpainter_blender.gpu_shaders.PALETTE_WIDTH`
texels a row, looked up in the vertex shader: a map's per-vertex colours are interpolated across each
triangle; a region's three vertices share one slot), draws the visible parts into a buffer of 16-bit linear
light (opaque parts with depth, then the glass: back faces, then front faces, blended, no depth writes; per
view only the triangles that side shows; drawn once per view and glass colours into a layer put over each
image: :mod:`brainpainter_blender.glass_layers`), at output resolution for the default quality, and resolves
it in a second pass: averaging each SxS block of a supersampled buffer (S a compile-time constant,
:data:`SUPERSAMPLING`), or, at the default quality, mixing each pixel that a region border or silhouette
crosses with its neighbour across it by the share of the pixel beyond the edge
(:mod:`brainpainter_blender.edge_aa`: 2x2 supersampling cost llvmpipe about four times the pixels for as
smooth a picture). The resolve also un-premultiplies alpha and flips rows into an sRGB target, which encodes
linear light to sRGB as it is written. Tract parts are drawn as lines at output resolution between the
glass's far and near sides (:mod:`brainpainter_blender.tract_lines`), not through the edge buffer. So the
read-back (into a flat ``gpu.types.Buffer``; ``np.array`` of a multi-dimensional Buffer gives wrong strides)
is already the image. The GLSL sources are in :mod:`brainpainter_blender.gpu_shaders`;
:meth:`GpuDraw.profile` times the steps of one image.

Lighting is per vertex, in linear light, from lights fixed to the camera: a key light from the upper
left, a fill light from the right and an ambient term
(:data:`~brainpainter_blender.gpu_lighting.LIGHTING`), all multiplied by the ambient occlusion the
template has baked per vertex (an extra vertex attribute, ones for old templates), then an S-curve; on a
map's cortex, less of the occlusion and the S-curve (:func:`for_maps`), so its colours read as its
values; a flat map (``flat``) is unlit (:data:`FLAT`); subcortical structures get a darker outline and
the glass a Fresnel-like edge. Colours are multiplied, never mixed towards white or black, and the peak
stays <= 1, so hues stay pure.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from brainpainter.rendering.geometry import PartGeometry, SceneGeometry
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import View
from brainpainter_blender import cutaway, edge_aa, glass_layers, gpu_shaders, outlines, tract_lines
from brainpainter_blender.aim import Aim as _Aim
from brainpainter_blender.aim import aim_for as _aim_for
from brainpainter_blender.aim import on_top
from brainpainter_blender.facing import facing
from brainpainter_blender.gpu_context import in_gpu_context
from brainpainter_blender.gpu_lighting import FLAT, LIGHTING, for_maps
from brainpainter_blender.meshorder import draw_order

#: Supersampling factor per quality (per axis); ``high`` reaches here only for flat shading.
SUPERSAMPLING = {"fast": 1, "default": 1, "high": 3}
#: Qualities whose edges are anti-aliased at output resolution (:mod:`brainpainter_blender.edge_aa`).
EDGE_AA = frozenset({"default"})
#: Face culling of opaque parts ("BACK": half the triangles are never rasterised; "NONE": draw all).
CULL_OPAQUE = "BACK"
#: Format of the supersampled buffer (linear light, premultiplied alpha; 8 bytes a pixel).
HI_FORMAT = "RGBA16"
#: Largest supersampled buffer (pixels; 8 bytes each): huge images get less supersampling.
MAX_SUPERSAMPLED_PIXELS = 64_000_000
#: Views whose framing a renderer keeps (a movie's orbit has one per frame).
MAX_CACHED_VIEWS = 64
#: Views whose front faces a renderer keeps (an index buffer per part, two per glass part: ~0.9 MB each).
MAX_FRONT_VIEWS = 8
#: Glass: opacity at grazing angles, as a multiple of the opacity facing the camera.
GLASS_EDGE = 2.5
#: Glass: extra opacity at the very outline (Fresnel-like), so the glass reads as a shell, not a fog.
GLASS_RIM = 0.5

def srgb_to_linear(rgb: np.ndarray) -> np.ndarray:
    """The IEC 61966-2-1 sRGB transfer function inverted, for an array of sRGB 0-1 values."""
    c = np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


class GpuDraw:
    """Draws a scene's geometry with Blender's ``gpu`` module (see the module docstring).

    Parameters
    ----------
    geometry : brainpainter.rendering.geometry.SceneGeometry
    settings : brainpainter.rendering.scene.RenderSettings
    """

    def __init__(self, geometry: SceneGeometry, settings: RenderSettings) -> None:
        self.geometry = geometry
        self.settings = settings
        self.lighting = FLAT if settings.shading == "flat" else LIGHTING[settings.lighting]
        #: the lighting of a map's cortex (a scene coloured per vertex); regions keep :attr:`lighting`
        self.map_lighting = for_maps(self.lighting)
        self._batches: dict[str, Any] = {}
        self._meshes: dict[str, tuple[Any, np.ndarray, np.ndarray]] = {}
        self._fronts: deque[_Aim] = deque()  # the views holding front faces, oldest first
        self._aims: dict[View, _Aim] = {}
        self._palette_key: bytes | None = None
        self._palette_tex: Any = None
        self._hi: Any = None
        self._hi_color: Any = None
        self._hi_depth: Any = None
        self._lines = tract_lines.TractLines(settings.width, settings.height)
        self._lo: Any = None
        self._lo_tex: Any = None
        self._resolve: Any = None
        self._quad: Any = None
        self._edges: edge_aa.EdgeAA | None = None
        self._glass: glass_layers.GlassLayers | None = None
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

        gpu_shaders.part_shader()  # compiled now; the parts' batches on first use (_batch)
        s = self.settings
        self.factor = f = self._factor()
        edges = f == 1 and s.quality in EDGE_AA
        self._resolve = gpu_shaders.resolve_shader(f, edges)
        self._quad = batch_for_shader(self._resolve, "TRIS", {"pos": [(-1, -1), (3, -1), (-1, 3)]})
        # Linear light in 16-bit integers: as exact as half floats for 0-1 and cheaper to write.
        size = (int(s.width * f), int(s.height * f))
        self._hi_color = gpu.types.GPUTexture(size, format=HI_FORMAT)
        self._hi_depth = gpu.types.GPUTexture(size, format="DEPTH_COMPONENT32F")  # read by tract_lines
        self._hi = gpu.types.GPUFrameBuffer(depth_slot=self._hi_depth, color_slots=self._hi_color)
        self._glass = glass_layers.GlassLayers(*size, self._hi_depth)
        if edges:
            self._edges = edge_aa.EdgeAA(s.width, s.height, self._hi_depth)
        # The resolve writes linear light; the sRGB target encodes it (cheaper than pow() per pixel).
        self._lo_tex = gpu.types.GPUTexture((s.width, s.height), format="SRGB8_A8")
        self._lo = gpu.types.GPUFrameBuffer(color_slots=self._lo_tex)

    def _batch(self, part: PartGeometry) -> Any:
        """The part's indexed batch, uploaded when a view first shows it (in a GPU context).

        Views of one hemisphere never pay for the other's upload (~40 ms of start-up).
        """
        batch = self._batches.get(part.name)
        if batch is None:
            import gpu

            order, triangles, normals = draw_order(part)
            attrs = {"pos": part.vertices[order], "nrm": part.normals[order],
                     "pal": part.palette_index[order].astype(np.float32), "sulc": part.sulc[order],
                     "ao": self._occlusion(part)[order]}
            fmt = gpu.types.GPUVertFormat()
            for name, _ in gpu_shaders.part_shader().attrs_info_get():
                fmt.attr_add(id=name, comp_type="F32", len=3 if name in ("pos", "nrm") else 1,
                             fetch_mode="FLOAT")
            vbo = gpu.types.GPUVertBuf(fmt, len(order))
            for name, values in attrs.items():
                vbo.attr_fill(name, np.ascontiguousarray(values, np.float32))
            self._meshes[part.name] = (vbo, normals, triangles, order)
            batch = self._batches[part.name] = gpu.types.GPUBatch(
                type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(type="TRIS", seq=triangles))
        return batch

    def _front(self, part: PartGeometry, aim: _Aim, back: bool = False) -> Any:
        """The part's batch of the triangles that face the camera in `aim` (kept with the view),
        or with `back` of those turned away (the glass's far side).

        The rasteriser culls the others anyway, but only after shading their vertices and
        setting them up: llvmpipe draws a cortex about a third faster without them. Facing is
        the sign of the triangle's area on screen, as the rasteriser decides it.
        """
        key = f"{part.name} back" if back else part.name
        batch = aim.front.get(key)
        if batch is None:
            import gpu

            if not aim.front:
                self._fronts.append(aim)
                if len(self._fronts) > MAX_FRONT_VIEWS:
                    self._fronts.popleft().front.clear()
            self._batch(part)
            vbo, normals, triangles, order = self._meshes[part.name]
            seq = triangles[facing(normals, np.asarray(aim.mvp, np.float64), back)]
            if aim.cut(part):  # nor those the cut removes whole (fragments would be discarded one by one)
                seq = cutaway.left_whole(seq, part.vertices[order], aim.planes)
            batch = aim.front[key] = gpu.types.GPUBatch(
                type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(type="TRIS", seq=seq))
        return batch

    def _occlusion(self, part: PartGeometry) -> np.ndarray:
        """The part's baked occlusion as the shader uses it: 1 at and above ``occlusion_open``, float32."""
        if part.occlusion is None:
            return np.ones(len(part.vertices), np.float32)
        return np.clip(part.occlusion / self.lighting.occlusion_open, 0.0, 1.0).astype(np.float32)

    def render(self, palette_rgb: np.ndarray, view: View) -> np.ndarray:
        """Draw one image; `palette_rgb` is sRGB 0-1, shape (n_slots, 3). Returns RGBA uint8 (h, w, 4)."""
        aim = self._aim(view)
        return in_gpu_context(lambda: self._draw(np.asarray(palette_rgb, np.float32), aim, view))

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
            width = gpu_shaders.PALETTE_WIDTH
            rows = max(1, -(-len(rgb) // width))
            rgba = np.ones((rows * width, 4), np.float32)
            rgba[:len(rgb), :3] = srgb_to_linear(rgb)
            buf = gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel())
            self._palette_tex = gpu.types.GPUTexture((width, rows), format="RGBA32F", data=buf)
            self._palette_key = key
        return self._palette_tex

    def profile(self, palette_rgb: np.ndarray, view: View) -> dict[str, float]:
        """Seconds each step of one image takes, each waited for (``benchmarks/bench_render.py --profile``).

        Returns
        -------
        dict of str to float
            ``palette``, ``clear``, ``draw <part>`` per opaque part, ``glass`` (its sides, drawn
            into the view's layer), ``glass layer`` (put over), ``resolve`` and ``read-back``;
            waiting for each step to finish (a 1-pixel read) removes the overlap of an ordinary image.
        """
        import gpu

        times: dict[str, float] = {}
        aim = self._aim(view)

        def mark(step: str) -> None:
            fb = gpu.state.active_framebuffer_get()
            fb.read_color(0, 0, 1, 1, 4, 0, "UBYTE", data=gpu.types.Buffer("UBYTE", 4))
            now = time.perf_counter()
            times[step] = now - times.pop("_t")
            times["_t"] = now

        def job() -> None:
            times["_t"] = time.perf_counter()
            self._draw(np.asarray(palette_rgb, np.float32), aim, view, mark)

        in_gpu_context(job)
        times.pop("_t")
        return times

    def _draw(self, rgb: np.ndarray, aim: _Aim, view: View,
              mark: Callable[[str], None] | None = None) -> np.ndarray:
        import gpu

        mark = mark or (lambda step: None)
        tex = self._palette(rgb)
        mark("palette")
        # tract parts are drawn as lines at output resolution (tract_lines), between the glass's sides
        tracts = [p for p in aim.visible if p.kind == "tract" and p.centrelines is not None]
        glass = self._glass_pass(rgb, aim, view, tex, mark)
        with self._hi.bind():
            top = self._draw_parts(aim, tex, mark, tracts, glass)
        if tracts:
            self._lines.draw_over(tracts, view, aim, tex, self.lighting, self._hi,
                                  lambda: self._draw_opaque(aim, tex, tracts), mark,
                                  self._hi_depth if self.factor == 1 else None)
            with self._hi.bind():
                top = glass(("BACK",))
        over = on_top(aim.visible)
        fresh = self._edges is not None and not self._edges.kept(view)
        # a cut part's edges are not where its silhouette was: anti-aliased are the parts left whole
        edges = None if self._edges is None else self._edges.texture(
            [p for p in aim.visible if p.name not in {q.name for q in over} and not aim.cut(p)], view, aim)
        if edges is not None:
            mark("edges")
        if over:  # drawn over the rest and the glass (put over here), each pixel in its own colour
            with self._hi.bind():
                if top is not None:
                    glass_layers.GlassLayers.over(top, mark)
                top = None
                gpu.state.active_framebuffer_get().clear(depth=1.0)
                self._draw_opaque(aim, tex, tracts, mark, over)
            if fresh and self._edges is not None:
                self._edges.add(over, view, aim)
        with self._lo.bind():
            # the resolve writes every pixel: no clear
            s, resolve = self.settings, self._resolve
            if top is not None:
                resolve = gpu_shaders.resolve_shader(self.factor, edges is not None, glass=True)
            resolve.bind()
            resolve.uniform_sampler("image", self._hi_color)  # samplers first: see _bind_part_shader
            if edges is not None:
                resolve.uniform_sampler("edges", edges)
            if top is not None:  # the glass's last layer, put over the image here
                resolve.uniform_sampler("glass", top)
            resolve.uniform_int("out_height", s.height)
            self._quad.draw(resolve)
            mark("resolve")
            buf = gpu.types.Buffer("UBYTE", s.width * s.height * 4)
            self._lo.read_color(0, 0, s.width, s.height, 4, 0, "UBYTE", data=buf)
            mark("read-back")
        # a view of the Buffer's memory (kept alive by the array), no copy
        return np.frombuffer(buf, dtype=np.uint8).reshape(s.height, s.width, 4)

    def _draw_parts(self, aim: _Aim, tex: Any, mark: Callable[[str], None],
                    tracts: list[PartGeometry], glass: Callable[[tuple[str, ...]], Any]) -> Any:
        """Clear the supersampled buffer, draw the opaque parts, then the glass (`glass`: :meth:`_glass_pass`;
        its result returned); with `tracts` (drawn afterwards as lines), only the far side of the glass."""
        import gpu

        s = self.settings
        bg = s.background
        clear = (0.0, 0.0, 0.0, 0.0) if bg is None else (*srgb_to_linear(np.asarray(bg)).tolist(), 1.0)
        gpu.state.active_framebuffer_get().clear(color=clear, depth=1.0)
        mark("clear")
        shader = self._draw_opaque(aim, tex, tracts, mark)
        if self._draw_outlines(aim, [p for p in aim.visible if p.kind != "glass" and not aim.cut(p)], shader,
                               tex):
            mark("outlines")
        # the far side first, then the near side over it (after the tracts, when there are)
        return glass(("FRONT",) if tracts else ("FRONT", "BACK"))

    def _glass_pass(self, rgb: np.ndarray, aim: _Aim, view: View, tex: Any,
                    mark: Callable[[str], None]) -> Callable[[tuple[str, ...]], Any]:
        """What draws the glass sides `culled` (:meth:`_draw_glass`) in this image: through the view's
        layers (:meth:`.glass_layers.GlassLayers.passes`), or without, into the bound buffer (None)."""
        glass, s, layers = [p for p in aim.visible if p.kind == "glass"], self.settings, self._glass
        outlined = s.outline_width > 0 and any(outlines.has_lines(p) for p in glass)

        def draw(culled: tuple[str, ...]) -> None:
            self._bind_part_shader(aim, tex)
            self._draw_glass(aim, tex, culled, mark)

        if (layers is None or not layers.enabled or not layers.worth(glass)
                or not (s.glass_opacity > 0 or outlined)):
            return draw
        colours = layers.colours(rgb, glass)
        # the depth of the borders' pass on the glass is read by the view's edge buffer when it is drawn
        fresh = outlined and self._edges is not None and not self._edges.kept(view)
        return layers.passes(view, colours, draw, mark, fresh)

    def _draw_opaque(self, aim: _Aim, tex: Any, tracts: list[PartGeometry],
                     mark: Callable[[str], None] | None = None,
                     only: list[PartGeometry] | None = None) -> Any:
        """The visible parts but the glass, `tracts` and those drawn on top (:func:`.aim.on_top`; `only`:
        these parts alone), lit, with depth; returns the bound shader."""
        import gpu

        shader = self._bind_part_shader(aim, tex)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.state.blend_set("NONE")
        # Parts are closed surfaces: faces turned away are always hidden behind others.
        gpu.state.face_culling_set(CULL_OPAQUE)
        shader.uniform_int("mode", gpu_shaders.MODE_LIT)
        skip = {t.name for t in tracts} | {p.name for p in on_top(aim.visible)}
        clipped = aim.n_clip > 0
        for p in aim.visible if only is None else only:
            if only is not None or (p.kind != "glass" and p.name not in skip):
                if clipped != aim.cut(p):  # parts left whole: the plain shader (no discard: early depth)
                    clipped = aim.cut(p)
                    shader = self._bind_part_shader(aim, tex, clipped)
                    shader.uniform_int("mode", gpu_shaders.MODE_LIT)
                mapped = p.kind == "cortex" and bool(self.geometry.vertex_slots)
                # a flat map is a 2-D picture: unlit, its colours exact
                light = FLAT if p.kind == "flat" else self.map_lighting if mapped else self.lighting
                for name, value in (("ambient", light.ambient), ("key", light.key if light.lit else 0.0),
                                    ("fill", light.fill if light.lit else 0.0),
                                    ("ao_direct", light.occlusion_direct), ("contrast", light.contrast),
                                    ("sulc_strength", light.sulc if p.kind == "cortex" else 0.0),
                                    ("ao_strength", light.occlusion),
                                    ("rim", light.rim if p.kind == "subcortical" else 0.0)):
                    shader.uniform_float(name, value)
                if clipped:
                    shader.uniform_int("clip_on", 1)
                self._front(p, aim).draw(shader)
                if aim.cut(p):  # its cut face, closed (cutaway)
                    cutaway.draw_cap(self._front(p, aim, back=True), shader,
                                     (gpu_shaders.MODE_CAP, gpu_shaders.MODE_LIT), CULL_OPAQUE)
                if mark is not None:
                    mark(f"draw {p.name}")
        return shader

    def _bind_part_shader(self, aim: _Aim, tex: Any, clipped: bool | None = None) -> Any:
        """Bind the part shader with the view's and the lighting's constants; returns it. `clipped`: its
        variant that cuts (default: for a view with cutaway planes)."""
        s, light = self.settings, self.lighting
        clipped = aim.n_clip > 0 if clipped is None else clipped
        shader = gpu_shaders.part_shader(clipped)
        shader.bind()
        # Samplers before push constants: bpy 5.3 drops an integer push constant set before a
        # sampler of the same shader (the resolve's row count read 0 and every image came out empty).
        shader.uniform_sampler("palette", tex)
        if clipped:
            cutaway.bind_clip(shader, aim.clips, aim.n_clip, srgb_to_linear)
        for name, value in (("mvp", aim.mvp), ("back", aim.back), ("key_dir", aim.key_dir),
                            ("fill_dir", aim.fill_dir), ("ambient", light.ambient),
                            ("key", light.key if light.lit else 0.0),
                            ("fill", light.fill if light.lit else 0.0),
                            ("glass_alpha", float(s.glass_opacity)), ("glass_edge", GLASS_EDGE),
                            ("glass_rim", GLASS_RIM if light.lit else 0.0),
                            ("ao_direct", light.occlusion_direct), ("contrast", light.contrast)):
            shader.uniform_float(name, value)
        return shader

    def _draw_glass(self, aim: _Aim, tex: Any, culled: tuple[str, ...], mark: Callable[[str], None]) -> None:
        """The glass parts, blended, with each face culling of `culled` in turn, and their borders.

        Culling ``FRONT`` draws the far side, ``BACK`` the near side (and the borders, on it).
        """
        import gpu

        s = self.settings
        shader = gpu_shaders.part_shader(aim.n_clip > 0)
        glass = [p for p in aim.visible if p.kind == "glass"]
        if glass and s.glass_opacity > 0:
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("ALPHA_PREMULT")
            shader.uniform_int("mode", gpu_shaders.MODE_GLASS)
            shader.uniform_float("sulc_strength", 0.0)
            shader.uniform_float("ao_strength", 0.0)
            shader.uniform_float("rim", 0.0)
            if aim.n_clip:
                shader.uniform_int("clip_on", 1)
            for cull in culled:
                gpu.state.face_culling_set(cull)
                for p in glass:  # only the triangles the culling keeps (see _front)
                    self._front(p, aim, back=cull == "FRONT").draw(shader)
            mark({"FRONT": "glass, far side", "BACK": "glass, near side"}.get("".join(culled), "glass"))
            gpu.state.blend_set("NONE")
            gpu.state.depth_mask_set(True)
        if "BACK" in culled and any(outlines.has_lines(p) for p in glass) and s.outline_width > 0 \
                and not aim.n_clip:  # a cut glass's borders would float over what the cut removed
            # A cortex drawn as glass (``--cortex glass``) keeps its borders, on its near side only:
            # its front faces go into the depth buffer alone, then the lines are depth-tested on them.
            gpu.state.color_mask_set(False, False, False, False)
            gpu.state.face_culling_set("BACK")
            depth = gpu_shaders.depth_shader()
            depth.bind()
            depth.uniform_float("mvp", aim.mvp)
            for p in glass:
                self._front(p, aim).draw(depth)
            gpu.state.color_mask_set(True, True, True, True)
            self._draw_outlines(aim, glass, shader, tex)
            mark("glass outlines")
        gpu.state.face_culling_set("NONE")
        gpu.state.depth_test_set("NONE")

    def _draw_outlines(self, aim: _Aim, parts: list[PartGeometry], part_shader: Any, tex: Any) -> bool:
        """The parts' region borders (:func:`brainpainter_blender.outlines.draw_outlines`), then
        `part_shader` bound again with its palette texture; False: none to draw."""
        import gpu

        if not outlines.draw_outlines(self._batches, parts, aim.mvp, self.settings, self.factor):
            return False
        gpu.state.face_culling_set(CULL_OPAQUE)
        part_shader.bind()
        part_shader.uniform_sampler("palette", tex)  # bound again, before any integer constant
        return True

    def close(self) -> None:
        """Free the batches, textures and offscreen buffers (in a GPU context)."""
        if self._hi is None and not self._batches:
            return

        def drop() -> None:
            self._hi = self._hi_color = self._hi_depth = None
            self._lo = self._lo_tex = self._quad = self._palette_tex = None
            self._lines.close()
            if self._glass is not None:
                self._glass.close()
            if self._edges is not None:
                self._edges.close()
                self._edges = None
            self._batches.clear()
            self._meshes.clear()
            self._aims.clear()
            self._fronts.clear()

        in_gpu_context(drop)
