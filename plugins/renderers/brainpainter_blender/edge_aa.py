"""Anti-aliasing of the parts' edges at output resolution, by the default draw path.

Supersampling 2x2 made llvmpipe rasterise four times the pixels for the few
that lie on an edge. Instead, the parts are drawn once at output resolution
and the edges where colour jumps are found from the geometry, per view: the
region borders (edges whose two triangles have different palette slots), the
silhouettes (one triangle facing the camera, the other not) and the open
boundaries of each mesh. Each such edge is drawn as a line, depth-tested
against the parts, into an output-sized edge buffer; its fragment shader finds
how far the pixel's centre lies from the edge along the line's minor axis and
writes which neighbour lies across the edge and how much of the pixel the other
side covers (``0.5 - distance``). The resolve mixes each such pixel with that
neighbour (geometric post-process anti-aliasing, as in Humus's GPAA): the
coverage of a straight edge is exact, with no blur inside the regions.

The edge table of a part (edge ends, the two triangles, whether it is a
region border) is built once, on the first view that shows it, and kept in the
process for the next run of the same mesh (a map's figures:
:mod:`brainpainter.rendering.mesh_memo`); a view's edges
are an index buffer into one vertex buffer of two vertices per edge. Lines one
pixel wide suffice: a line rasterised along its major axis covers, in each
column (row), the pixel whose centre is nearest to it, the one pixel there
that the edge crosses nearer than half a pixel.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.geometry import PartGeometry
from brainpainter.rendering.mesh_edges import EdgeTable
from brainpainter.rendering.mesh_edges import edge_table as edge_table  # tests import it from here
from brainpainter.rendering.mesh_memo import kept_edge_table

#: Pixels of the edge buffers kept (one per view; 4 bytes a pixel): 4 views of 1200x900.
MAX_BUFFER_PIXELS = 4 * 1200 * 900
#: How far an edge's line is moved towards the camera for the depth test (millimetres): the
#: surface seen at a pixel's centre next to a silhouette can be nearer than the edge itself.
DEPTH_BIAS_MM = 0.6


def visible_edges(table: EdgeTable, back: NDArray[Any]) -> NDArray[Any]:
    """Indices of the edges where colour can jump in a view whose camera looks along ``-back``.

    Parameters
    ----------
    table : EdgeTable
    back : ndarray of float, shape (3,)
        Unit vector from the scene towards the (orthographic) camera.

    Returns
    -------
    ndarray of int64, shape (n,)
        Silhouettes, region borders and open boundaries with a triangle facing the camera.
    """
    facing = np.append(table.normals @ np.asarray(back, np.float32) > 0, False)  # [-1]: none
    front0, front1 = facing[table.faces[:, 0]], facing[table.faces[:, 1]]
    # open boundaries: front1 is False, so they count when their triangle faces the camera
    return np.flatnonzero((front0 != front1) | (table.border & front0))


class EdgeAA:
    """The edge buffers of the views last drawn and the parts' edges (see the module docstring).

    A view's edge buffer depends on the geometry and the view alone, not on the
    image's colours: it is drawn on a view's first image and kept
    (:data:`MAX_BUFFER_PIXELS` of them), so a table's rows over the same views
    pay only the resolve's extra fetch.

    Parameters
    ----------
    width, height : int
        Of the output image (the buffer the parts are drawn into).
    depth : gpu.types.GPUTexture
        That buffer's depth.
    """

    def __init__(self, width: int, height: int, depth: Any) -> None:
        self.width, self.height = int(width), int(height)
        self._depth = depth
        self._tables: dict[str, EdgeTable] = {}
        self._vertices: dict[str, Any] = {}
        self._buffers: OrderedDict[Any, Any] = OrderedDict()

    def _table(self, part: PartGeometry) -> EdgeTable:
        table = self._tables.get(part.name)
        if table is None:
            table = part.edges  # kept with the part (a region scene's cortex, read from the cache)
            if table is None:
                table = kept_edge_table(part.vertices, part.triangles, part.palette_index)
            self._tables[part.name] = table
        return table

    def _batch(self, part: PartGeometry, back: NDArray[Any]) -> Any:
        """The part's edges seen from `back` as a line batch; None: none."""
        import gpu

        from brainpainter_blender import gpu_shaders

        table = self._table(part)
        vbo = self._vertices.get(part.name)
        if vbo is None:
            fmt = gpu.types.GPUVertFormat()
            for name, _ in gpu_shaders.edge_shader().attrs_info_get():
                fmt.attr_add(id=name, comp_type="F32", len=3, fetch_mode="FLOAT")
            pos = np.asarray(part.vertices, np.float32)[table.ends]  # (n_edges, 2, 3)
            vbo = self._vertices[part.name] = gpu.types.GPUVertBuf(fmt, 2 * len(table.ends))
            vbo.attr_fill("pos", pos.reshape(-1, 3))
            vbo.attr_fill("other", pos[:, ::-1].reshape(-1, 3))
        edges = visible_edges(table, back)
        if not len(edges):
            return None
        pairs = np.stack([2 * edges, 2 * edges + 1], axis=1).astype(np.uint32)
        return gpu.types.GPUBatch(type="LINES", buf=vbo, elem=gpu.types.GPUIndexBuf(type="LINES", seq=pairs))

    def texture(self, parts: list[PartGeometry], view: Any, aim: Any) -> Any:
        """The edge buffer of `view` (drawn now if not kept; the parts' depth must be in `depth`)."""
        texture = self._buffers.get(view)
        if texture is None:
            spare = None
            while len(self._buffers) >= max(1, MAX_BUFFER_PIXELS // (self.width * self.height)):
                spare = self._buffers.popitem(last=False)[1]  # drawn over
            texture = self._buffers[view] = self._draw(parts, aim, spare)
        self._buffers.move_to_end(view)
        return texture

    def add(self, parts: list[PartGeometry], view: Any, aim: Any) -> None:
        """Draw the edges of `parts` too into the kept buffer of `view` (the depth now theirs: parts drawn
        on top of the others, :func:`brainpainter_blender.aim.on_top`)."""
        self._draw(parts, aim, self._buffers[view], clear=False)

    def kept(self, view: Any) -> bool:
        """Whether the edge buffer of `view` is kept (else the view's next image draws it)."""
        return view in self._buffers

    def _draw(self, parts: list[PartGeometry], aim: Any, texture: Any = None, clear: bool = True) -> Any:
        """Draw the edges of `parts` seen in `aim` into `texture` (a new one if None), cleared first (unless
        not `clear`)."""
        import gpu

        from brainpainter_blender import gpu_shaders

        if texture is None:
            texture = gpu.types.GPUTexture((self.width, self.height), format="RGBA8")
        back = np.asarray(aim.back, np.float64)
        batches = [b for b in (self._batch(p, back) for p in parts if p.kind != "tract") if b is not None]
        fb = gpu.types.GPUFrameBuffer(depth_slot=self._depth, color_slots=texture)
        with fb.bind():
            if clear:
                fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            if not batches:
                return texture
            shader = gpu_shaders.edge_shader()
            shader.bind()
            mvp = np.asarray(aim.mvp, np.float64)
            shader.uniform_float("mvp", aim.mvp)
            shader.uniform_float("viewport", (float(self.width), float(self.height)))
            # orthographic: clip-space depth per millimetre along the view is |mvp[2, :3]|
            shader.uniform_float("bias", DEPTH_BIAS_MM * float(np.linalg.norm(mvp[2, :3])))
            gpu.state.face_culling_set("NONE")
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("NONE")
            for batch in batches:
                batch.draw(shader)
            gpu.state.depth_mask_set(True)
            gpu.state.depth_test_set("NONE")
        return texture

    def close(self) -> None:
        """Drop the buffers and batches (call in a GPU context)."""
        self._depth = None
        for cache in (self._vertices, self._buffers):
            cache.clear()
