"""Tract parts drawn as lit, anti-aliased lines at output resolution, by the default draw path.

Tubes a few pixels wide, drawn into the supersampled buffer, cost llvmpipe 4-6x a
region image: its rasteriser walks every 4x4 block that a long, thin triangle
crosses, in a buffer of four times the pixels (``benchmarks/profile_tracts.py``).
So the default draw path draws a tract part's centrelines
(:class:`brainpainter.rendering.parts.Centrelines`) instead of its tubes: one
GL line per segment, at output resolution, as wide as the tube plus a pixel of
fringe. The fragment shader finds each pixel's distance from the centreline,
which gives both its coverage (anti-aliasing without supersampling) and the
normal of a round tube at that point, lit by the same camera-fixed lights as
the tubes were.

The lines are drawn once per view, without their colours, into the view's
tracts' layer (:data:`MAX_LAYER_PIXELS` of them are kept): farthest streamline
first (sorted), blended, depth-tested against the opaque parts (drawn again,
into the layer's depth alone). The layer holds, per output pixel, the light
and coverage of all the lines there (premultiplied) and the palette slots of
the nearest line covering half of it (the two ends of its segment and how far
along). Each image then colours the layer from its own palette and puts it
over the supersampled buffer, between the glass's far and near sides
(:meth:`GpuDraw._draw`): a table whose rows change the bundles' values draws
no line again, only a view not seen before does. Where lines of different
colours share a pixel, its colour is the nearer line's (the coverage stays
exact).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.geometry import PartGeometry
from brainpainter.tracts.tubes import tangents

#: Pixels of the tract layers kept (one per view; 24 bytes a pixel): 4 views of 1200x900.
MAX_LAYER_PIXELS = 4 * 1200 * 900
#: Margin of the tracts' box beyond their projected points, in pixels (the line's fringe and more).
BOX_MARGIN_PX = 4.0
#: Palette slots a layer can hold exactly (float32 integers).
MAX_SLOT = 2**24


def raster_width(half_width: float) -> int:
    """GL line width (pixels) that holds a line of `half_width` and its fringe at any angle.

    A wide GL line is widened along the minor axis only, so across a diagonal it is
    ``cos(45 degrees)`` as wide; the fringe ends half a pixel beyond the line.
    """
    return max(1, math.ceil(2.0 * math.sqrt(2.0) * (half_width + 0.5)))


@dataclass(frozen=True)
class _Layer:
    """A view's tracts' layer: light and coverage (RGBA16), slots (RGBA32F), box (NDC)."""

    shade: Any
    slots: Any
    box: tuple[float, float, float, float]


class TractLines:
    """The tracts' layers of the views last drawn, the output-sized buffers they share, the lines' vertices.

    Parameters
    ----------
    width, height : int
        Of the output image.
    """

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = int(width), int(height)
        self._depth: Any = None
        self._layers: OrderedDict[Any, _Layer] = OrderedDict()
        self._buffers: dict[str, Any] = {}
        self._framebuffers: dict[str, Any] = {}
        self._textures: dict[str, Any] = {}

    def _vertices(self, part: PartGeometry) -> Any:
        """The part's centreline points as a vertex buffer (uploaded once)."""
        vbo = self._buffers.get(part.name)
        if vbo is None:
            import gpu

            from brainpainter_blender import gpu_shaders

            c = part.centrelines
            assert c is not None
            if c.slots.size and int(c.slots.max()) >= MAX_SLOT:
                raise BrainPainterError(f"tracts: the scene has {int(c.slots.max()) + 1:,} palette slots, "
                                        f"the tract lines hold at most {MAX_SLOT:,}; colour the cortex by "
                                        "region (no vertex map) or draw fewer bundle nodes")
            fmt = gpu.types.GPUVertFormat()
            for name, _ in gpu_shaders.line_shader().attrs_info_get():
                fmt.attr_add(id=name, comp_type="F32", len=3 if name in ("pos", "tang") else 1,
                             fetch_mode="FLOAT")
            n, m = c.slots.shape
            vbo = self._buffers[part.name] = gpu.types.GPUVertBuf(fmt, n * m)
            vbo.attr_fill("pos", np.ascontiguousarray(c.points.reshape(-1, 3), np.float32))
            vbo.attr_fill("tang", tangents(c.points).reshape(-1, 3).astype(np.float32))
            vbo.attr_fill("pal", c.slots.reshape(-1).astype(np.float32))
            cap = np.zeros((n, m), np.float32)
            cap[:, 0], cap[:, -1] = -1.0, 1.0  # the ends reach out (see gpu_shaders)
            vbo.attr_fill("cap", cap.reshape(-1))
            vbo.attr_fill("odd", (np.arange(n * m) % 2).astype(np.float32))
        return vbo

    def _sorted(self, part: PartGeometry, back: np.ndarray) -> Any:
        """The part's segments as a line batch, farthest streamline first (`back`: towards the viewer)."""
        import gpu

        c = part.centrelines
        assert c is not None
        n, m = c.slots.shape
        toward_viewer = (c.points.reshape(-1, 3) @ back).reshape(n, m).mean(axis=1)
        order = np.argsort(toward_viewer, kind="stable")
        first = (order[:, None] * m + np.arange(m - 1)[None, :]).reshape(-1)
        pairs = np.stack([first, first + 1], axis=-1).astype(np.uint32)
        ibo = gpu.types.GPUIndexBuf(type="LINES", seq=pairs)
        return gpu.types.GPUBatch(type="LINES", buf=self._vertices(part), elem=ibo)

    def _box(self, parts: list[PartGeometry], aim: Any) -> tuple[float, float, float, float]:
        """The tracts' extent in normalised device coordinates (x0, y0, x1, y1), with a margin."""
        mvp = np.asarray(aim.mvp, np.float64)
        lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
        for p in parts:
            assert p.centrelines is not None
            ndc = p.centrelines.points.reshape(-1, 3) @ mvp[:2, :3].T + mvp[:2, 3]
            lo, hi = np.minimum(lo, ndc.min(axis=0)), np.maximum(hi, ndc.max(axis=0))
        size = np.array([self.width, self.height])
        margin = BOX_MARGIN_PX + self._half_width(parts, aim)
        # on whole output pixels, so a supersampled pass over the box reads only pixels the
        # output-sized passes over it wrote
        lo = np.clip(np.floor((lo + 1.0) / 2.0 * size - margin), 0, size) / size * 2.0 - 1.0
        hi = np.clip(np.ceil((hi + 1.0) / 2.0 * size + margin), 0, size) / size * 2.0 - 1.0
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def _half_width(self, parts: list[PartGeometry], aim: Any) -> float:
        """Half the lines' width in output pixels: the tubes' radius at the view's scale."""
        scale = np.asarray(aim.mvp, np.float64)[0, :3]  # NDC per millimetre along the image's x
        radius = max(float(p.centrelines.radius) for p in parts if p.centrelines is not None)
        return radius * float(np.linalg.norm(scale)) * self.width / 2.0

    def draw_over(self, parts: list[PartGeometry], view: Any, aim: Any, palette: Any, lighting: Any,
                  supersampled: Any, draw_opaque: Callable[[], None], mark: Callable[[str], None],
                  depth: Any = None) -> None:
        """Colour the view's tracts' layer (drawn first when not kept) and put it over `supersampled`.

        Parameters
        ----------
        parts : list of PartGeometry
            Tract parts (with :attr:`~PartGeometry.centrelines`).
        view : View
            Key of the kept layers.
        aim : brainpainter_blender.aim.Aim
            The view's matrix and camera axes.
        palette : gpu.types.GPUTexture
            The image's palette (linear colours, as the part shader reads it).
        lighting : brainpainter_blender.gpu_lighting.Lighting
        supersampled : gpu.types.GPUFrameBuffer
            The supersampled buffer (its size a multiple of the output's).
        draw_opaque : callable
            Draws the view's opaque parts into the bound framebuffer's depth alone (the
            lines' occluders).
        mark : callable
            Called with the name of each step done (see ``GpuDraw.profile``).
        depth : gpu.types.GPUTexture, optional
            The opaque parts' depth at output resolution, when `supersampled` is not
            supersampled: the lines are depth-tested against it instead of drawing the
            opaque parts again (`draw_opaque` is not called).
        """
        import gpu

        from brainpainter_blender import gpu_shaders

        layer = self._layers.get(view)
        if layer is None:
            spare = None
            while len(self._layers) >= max(1, MAX_LAYER_PIXELS // (self.width * self.height)):
                spare = self._layers.popitem(last=False)[1]  # its textures are drawn over
            layer = self._layers[view] = self._draw_layer(parts, aim, lighting, draw_opaque, mark, spare,
                                                          depth)
        self._layers.move_to_end(view)
        with self._scratch("coloured").bind():
            gpu_shaders.draw_box("colour", layer.box, {"shade": layer.shade, "slots": layer.slots,
                                                 "palette": palette})
        with supersampled.bind():
            factor = supersampled.viewport_get()[2] // self.width
            gpu.state.blend_set("ALPHA_PREMULT")
            gpu_shaders.draw_box("over", layer.box, {"layer": self._textures["coloured"]}, factor)
            gpu.state.blend_set("NONE")
            mark("tract layer")

    def _scratch(self, name: str) -> Any:
        """An output-sized framebuffer shared by all views: ``coloured`` (RGBA16) or ``slots`` (RGBA32F)."""
        fb = self._framebuffers.get(name)
        if fb is None:
            import gpu

            fmt = {"coloured": "RGBA16", "slots": "RGBA32F"}[name]
            tex = self._textures[name] = gpu.types.GPUTexture((self.width, self.height), format=fmt)
            fb = self._framebuffers[name] = gpu.types.GPUFrameBuffer(color_slots=tex)
        return fb

    def _draw_layer(self, parts: list[PartGeometry], aim: Any, lighting: Any,
                    draw_opaque: Callable[[], None], mark: Callable[[str], None],
                    spare: _Layer | None = None, depth: Any = None) -> _Layer:
        """A view's layer (in `spare`'s textures): cleared, the opaque parts' depth (or `depth`, theirs
        already drawn, left as it is), then the lines."""
        import gpu

        from brainpainter_blender import gpu_shaders

        size = (self.width, self.height)
        if self._depth is None and depth is None:
            self._depth = gpu.types.GPUTexture(size, format="DEPTH_COMPONENT32F")
        if spare is None:
            shade = gpu.types.GPUTexture(size, format="RGBA16")
            slots = gpu.types.GPUTexture(size, format="RGBA32F")
        else:
            shade, slots = spare.shade, spare.slots
        self._scratch("slots")
        fb = gpu.types.GPUFrameBuffer(depth_slot=self._depth if depth is None else depth,
                                      color_slots=(shade, self._textures["slots"]))
        back = np.asarray(aim.back, np.float64)
        batches = [self._sorted(p, back) for p in parts]
        with fb.bind():
            if depth is None:
                fb.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
                gpu.state.color_mask_set(False, False, False, False)
                draw_opaque()
                gpu.state.color_mask_set(True, True, True, True)
                mark("tract depth")
            else:
                fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            shader = gpu_shaders.line_shader()
            shader.bind()
            half = self._half_width(parts, aim)
            for name, value in (("mvp", aim.mvp), ("viewport", (float(self.width), float(self.height))),
                                ("half_width", half), ("key_dir", _unit(lighting.key_dir)),
                                ("fill_dir", _unit(lighting.fill_dir)), ("ambient", lighting.ambient),
                                ("key", lighting.key if lighting.lit else 0.0),
                                ("fill", lighting.fill if lighting.lit else 0.0),
                                ("contrast", lighting.contrast)):
                shader.uniform_float(name, value)
            gpu.state.face_culling_set("NONE")
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("ALPHA_PREMULT")
            gpu.state.line_width_set(float(raster_width(half)))
            for batch in batches:
                batch.draw(shader)
            gpu.state.line_width_set(1.0)
            gpu.state.blend_set("NONE")
            gpu.state.depth_mask_set(True)
            gpu.state.depth_test_set("NONE")
            mark("tracts")
        box = self._box(parts, aim)
        fill = gpu.types.GPUFrameBuffer(color_slots=slots)
        with fill.bind():
            gpu_shaders.draw_box("fill", box, {"slots": self._textures["slots"]})
            mark("tract fill")
        return _Layer(shade, slots, box)

    def close(self) -> None:
        """Drop the buffers and batches (call in a GPU context)."""
        self._depth = None
        for cache in (self._layers, self._buffers, self._framebuffers, self._textures):
            cache.clear()


def _unit(d: tuple[float, float, float]) -> tuple[float, float, float]:
    v = np.asarray(d, np.float64)
    v = v / np.linalg.norm(v)
    return (float(v[0]), float(v[1]), float(v[2]))
