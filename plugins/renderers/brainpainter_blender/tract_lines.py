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
the tubes were. Per image with tracts (:meth:`GpuDraw._draw`):

1. the opaque parts and the far side of the glass are drawn supersampled, as
   without tracts;
2. the tracts' layer: an output-sized buffer, transparent, holding the lines
   drawn farthest streamline first (sorted once per view), blended, and
   depth-tested against the opaque parts (drawn again, into its depth alone);
3. that layer is put over the supersampled buffer, within the tracts' box,
   then the near side of the glass is drawn over both, and the resolve follows.

The layer depends only on the view and the tracts' colours, so it is kept
(up to :data:`MAX_LAYER_PIXELS`): the rows of a table that change the regions'
colours and not the bundles' (direction colours, a cortical table with the
tracts) draw the lines once per view.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from brainpainter.rendering.geometry import PartGeometry
from brainpainter.tracts.tubes import tangents

#: Views whose sorted line order is kept (a movie's orbit has one per frame).
MAX_CACHED_VIEWS = 64
#: Pixels of the tract layers kept (views x tract colourings; 8 bytes a pixel): 8 of 1200x900.
MAX_LAYER_PIXELS = 8 * 1200 * 900
#: Margin of the tracts' box beyond their projected points, in pixels (the line's fringe and more).
BOX_MARGIN_PX = 4.0


def raster_width(half_width: float) -> int:
    """GL line width (pixels) that holds a line of `half_width` and its fringe at any angle.

    A wide GL line is widened along the minor axis only, so across a diagonal it is
    ``cos(45 degrees)`` as wide; the fringe ends half a pixel beyond the line.
    """
    return max(1, math.ceil(2.0 * math.sqrt(2.0) * (half_width + 0.5)))


class TractLines:
    """The output-sized buffer the tracts are drawn into, and their line batches.

    Parameters
    ----------
    width, height : int
        Of the output image.
    """

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = int(width), int(height)
        self._depth: Any = None
        self._layers: OrderedDict[Any, tuple[Any, Any]] = OrderedDict()
        self._buffers: dict[str, Any] = {}
        self._slots: dict[str, np.ndarray] = {}
        self._batches: dict[Any, dict[str, Any]] = {}
        self._boxes: dict[Any, tuple[float, float, float, float]] = {}

    def _vertices(self, part: PartGeometry) -> Any:
        """The part's centreline points as a vertex buffer (uploaded once)."""
        vbo = self._buffers.get(part.name)
        if vbo is None:
            import gpu

            from brainpainter_blender import gpu_shaders

            c = part.centrelines
            assert c is not None
            fmt = gpu.types.GPUVertFormat()
            for name, _ in gpu_shaders.line_shader().attrs_info_get():
                fmt.attr_add(id=name, comp_type="F32", len=3 if name in ("pos", "tang") else 1,
                             fetch_mode="FLOAT")
            vbo = self._buffers[part.name] = gpu.types.GPUVertBuf(fmt, c.slots.size)
            vbo.attr_fill("pos", np.ascontiguousarray(c.points.reshape(-1, 3), np.float32))
            vbo.attr_fill("tang", tangents(c.points).reshape(-1, 3).astype(np.float32))
            vbo.attr_fill("pal", c.slots.reshape(-1).astype(np.float32))
            cap = np.zeros(c.slots.shape, np.float32)
            cap[:, 0], cap[:, -1] = -1.0, 1.0  # the ends reach out (see gpu_shaders)
            vbo.attr_fill("cap", cap.reshape(-1))
        return vbo

    def _view(self, parts: list[PartGeometry], view: Any, aim: Any) -> dict[str, Any]:
        """Each part's segments, farthest streamline first from `view`, and the tracts' box (once a view)."""
        per_view = self._batches.get(view)
        if per_view is None:
            if len(self._batches) >= MAX_CACHED_VIEWS:
                self._batches.clear()
                self._boxes.clear()
            per_view = self._batches[view] = {}
            mvp = np.asarray(aim.mvp, np.float64)
            back = np.asarray(aim.back, np.float64)
            lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
            for p in parts:
                per_view[p.name] = self._sorted(p, back)
                assert p.centrelines is not None
                ndc = p.centrelines.points.reshape(-1, 3) @ mvp[:2, :3].T + mvp[:2, 3]
                lo, hi = np.minimum(lo, ndc.min(axis=0)), np.maximum(hi, ndc.max(axis=0))
            pixels = BOX_MARGIN_PX + self._half_width(parts, aim)
            margin = 2.0 * pixels / np.array([self.width, self.height])
            lo, hi = np.clip(lo - margin, -1.0, 1.0), np.clip(hi + margin, -1.0, 1.0)
            self._boxes[view] = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
        return per_view

    def _sorted(self, part: PartGeometry, back: np.ndarray) -> Any:
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

    def _half_width(self, parts: list[PartGeometry], aim: Any) -> float:
        """Half the lines' width in output pixels: the tubes' radius at the view's scale."""
        scale = np.asarray(aim.mvp, np.float64)[0, :3]  # NDC per millimetre along the image's x
        radius = max(float(p.centrelines.radius) for p in parts if p.centrelines is not None)
        return radius * float(np.linalg.norm(scale)) * self.width / 2.0

    def _colour_key(self, parts: list[PartGeometry], palette_rgb: np.ndarray) -> bytes:
        """The palette colours the tracts use (their layer is drawn again when these change)."""
        keys = []
        for p in parts:
            slots = self._slots.get(p.name)
            if slots is None:
                assert p.centrelines is not None
                slots = self._slots[p.name] = np.unique(p.centrelines.slots)
            keys.append(np.asarray(palette_rgb)[slots].tobytes())
        return b"|".join(keys)

    def draw_over(self, parts: list[PartGeometry], view: Any, aim: Any, palette: tuple[Any, np.ndarray],
                  lighting: Any, supersampled: Any, draw_opaque: Callable[[], None],
                  mark: Callable[[str], None]) -> None:
        """Put the tracts' layer over the framebuffer `supersampled` (drawn first when not kept).

        Parameters
        ----------
        parts : list of PartGeometry
            Tract parts (with :attr:`~PartGeometry.centrelines`).
        view : View
            Key of the sorted line order and of the kept layers.
        aim : brainpainter_blender.gpu_draw._Aim
            The view's matrix and camera axes.
        palette : tuple
            The palette texture and its sRGB colours, shape (n_slots, 3).
        lighting : brainpainter_blender.gpu_draw.Lighting
        supersampled : gpu.types.GPUFrameBuffer
            The supersampled buffer (its size a multiple of the output's).
        draw_opaque : callable
            Draws the view's opaque parts into the bound framebuffer's depth alone (the
            lines' occluders).
        mark : callable
            Called with the name of each step done (see ``GpuDraw.profile``).
        """
        import gpu

        from brainpainter_blender import gpu_shaders

        batches = self._view(parts, view, aim)
        key = (view, self._colour_key(parts, palette[1]))
        layer = self._layers.get(key)
        if layer is None:
            layer = self._draw_layer(parts, [batches[p.name] for p in parts], aim, palette[0], lighting,
                                     draw_opaque, mark)
            while len(self._layers) >= max(1, MAX_LAYER_PIXELS // (self.width * self.height)):
                self._layers.popitem(last=False)
            self._layers[key] = layer
        self._layers.move_to_end(key)
        with supersampled.bind():
            factor = supersampled.viewport_get()[2] // self.width
            over = gpu_shaders.over_shader(factor)
            over.bind()
            over.uniform_sampler("layer", layer[1])
            over.uniform_float("box", self._boxes[view])
            gpu.state.blend_set("ALPHA_PREMULT")
            gpu.state.depth_test_set("NONE")
            gpu.state.face_culling_set("NONE")
            _unit_square().draw(over)
            gpu.state.blend_set("NONE")
            mark("tract layer")

    def _draw_layer(self, parts: list[PartGeometry], batches: list[Any], aim: Any, palette: Any,
                    lighting: Any, draw_opaque: Callable[[], None],
                    mark: Callable[[str], None]) -> tuple[Any, Any]:
        """A new layer: transparent, the opaque parts' depth, then the lines."""
        import gpu

        from brainpainter_blender import gpu_shaders

        if self._depth is None:
            self._depth = gpu.types.GPUTexture((self.width, self.height), format="DEPTH_COMPONENT32F")
        color = gpu.types.GPUTexture((self.width, self.height), format="RGBA16")
        fb = gpu.types.GPUFrameBuffer(depth_slot=self._depth, color_slots=color)
        with fb.bind():
            fb.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            gpu.state.color_mask_set(False, False, False, False)
            draw_opaque()
            gpu.state.color_mask_set(True, True, True, True)
            mark("tract depth")
            shader = gpu_shaders.line_shader()
            shader.bind()
            shader.uniform_sampler("palette", palette)  # samplers before push constants (see GpuDraw)
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
        return fb, color

    def close(self) -> None:
        """Drop the buffers and batches (call in a GPU context)."""
        self._depth = None
        for cache in (self._layers, self._buffers, self._slots, self._batches, self._boxes):
            cache.clear()


_square: dict[str, Any] = {}


def _unit_square() -> Any:
    """Two triangles over the unit square (``pos``), made once per process."""
    if "batch" not in _square:
        from gpu_extras.batch import batch_for_shader

        from brainpainter_blender import gpu_shaders

        _square["batch"] = batch_for_shader(gpu_shaders.over_shader(1), "TRIS",
                                            {"pos": [(0, 0), (1, 0), (1, 1), (0, 0), (1, 1), (0, 1)]})
    return _square["batch"]


def _unit(d: tuple[float, float, float]) -> tuple[float, float, float]:
    v = np.asarray(d, np.float64)
    v = v / np.linalg.norm(v)
    return (float(v[0]), float(v[1]), float(v[2]))
