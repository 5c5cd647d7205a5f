"""What is computed from a part's mesh alone, kept in this process (:data:`MESH_MEMO`).

A map's cortex part is built again for every figure, since its colours follow the map, but its
mesh is the template's, the same every time: its vertex normals (~10 ms per hemisphere), its edge
table (:mod:`brainpainter.rendering.mesh_edges`, ~0.1 s per hemisphere of a figure before) and a
renderer's vertex order (``brainpainter_blender.meshorder``, ~15 ms) come out the same. They are
kept under the SHA-256 of the arrays they are computed from (:func:`brainpainter.io.memo.array_key`,
~3 ms a hemisphere), so a mesh that differs in one bit is computed anew. A region scene's cortex
part keeps its edge table in the user's cache instead (:mod:`brainpainter.rendering.part_cache`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.io.memo import Memo, array_key
from brainpainter.rendering.mesh_edges import EdgeTable, edge_table

T = TypeVar("T")

#: Results computed from meshes in this process (a map's two cortex hemispheres: ~25 MB).
MESH_MEMO = Memo(max_bytes=192 * 1024 * 1024)


def mesh_result(name: str, arrays: tuple[NDArray[Any], ...], compute: Callable[[], T]) -> T:
    """``compute()``, kept under `name` and the SHA-256 of `arrays` (all it may depend on); read-only."""
    return MESH_MEMO.get((name, array_key(*arrays)), compute)


def kept_vertex_normals(vertices: NDArray[Any], faces: NDArray[Any]) -> NDArray[Any]:
    """:func:`~brainpainter.atlas.mesh.vertex_normals` (float32), kept (read-only)."""
    return mesh_result("vertex normals", (vertices, faces), lambda: vertex_normals(vertices, faces))


def kept_edge_table(vertices: NDArray[Any], triangles: NDArray[Any],
                    palette_index: NDArray[Any]) -> EdgeTable:
    """:func:`~brainpainter.rendering.mesh_edges.edge_table`, kept (read-only)."""
    return mesh_result("edge table", (vertices, triangles, palette_index),
                       lambda: edge_table(vertices, triangles, palette_index))
