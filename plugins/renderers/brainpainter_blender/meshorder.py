"""Triangle and vertex order for a software rasteriser's vertex cache.

Mesa's llvmpipe shades the vertices of an indexed draw in chunks through a
small cache keyed by vertex index: a vertex is shaded again whenever its
triangles lie far apart in the index buffer. The bundled cortex meshes have
their border-splitting triangles and vertices appended at the end, so about
1.6 vertex shadings per triangle. Numbering the vertices along a Morton
(Z-order) curve and sorting the triangles by their first vertex brings that
to about 0.7 (~25 ms per hemisphere, once per mesh in a process: :func:`draw_order`). The
picture does not change: the same triangles, drawn with a depth test.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from brainpainter.rendering.mesh_memo import mesh_result
from brainpainter_blender.facing import triangle_normals

#: Bits per axis of the Morton code (1024 cells per axis: far finer than a cache's reach).
BITS = 10


def _spread(q: np.ndarray) -> np.ndarray:
    """Insert two zero bits after every bit of 10-bit integers (``abc`` -> ``a00b00c``)."""
    q = q.astype(np.uint32)
    q = (q | (q << 16)) & 0x030000FF
    q = (q | (q << 8)) & 0x0300F00F
    q = (q | (q << 4)) & 0x030C30C3
    return (q | (q << 2)) & 0x09249249


def morton_codes(points: np.ndarray) -> np.ndarray:
    """Morton (Z-order) code of each point in its bounding box, `BITS` bits per axis.

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)

    Returns
    -------
    ndarray of uint32, shape (n,)
    """
    low = points.min(axis=0)
    span = np.maximum(points.max(axis=0) - low, 1e-12)
    q = ((points - low) / span * (2**BITS - 1)).astype(np.uint32)
    return _spread(q[:, 0]) | (_spread(q[:, 1]) << 1) | (_spread(q[:, 2]) << 2)


def cache_friendly(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reorder a mesh for the vertex cache: vertices along a Morton curve, triangles by first vertex.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    triangles : ndarray of int, shape (n_triangles, 3)

    Returns
    -------
    vertex_order : ndarray of int, shape (n_vertices,)
        Old index of each new vertex (index every per-vertex array with it).
    new_triangles : ndarray of int32, shape (n_triangles, 3)
        The same triangles (same winding), renumbered and sorted by their
        lowest new vertex index.
    """
    vertex_order = np.argsort(morton_codes(vertices), kind="stable")
    new_index = np.empty(len(vertices), np.int32)
    new_index[vertex_order] = np.arange(len(vertices), dtype=np.int32)
    tris = new_index[triangles]
    return vertex_order, tris[np.argsort(tris.min(axis=1), kind="stable")]


def shadings_per_triangle(triangles: np.ndarray, cache: int = 256) -> float:
    """Vertex shadings per triangle with a direct-mapped cache of `cache` entries (a model of llvmpipe's).

    Parameters
    ----------
    triangles : ndarray of int, shape (n_triangles, 3)
    cache : int

    Returns
    -------
    float
        1.5 or more for a scattered order; about 0.5-0.7 for a good one.
    """
    slots = [-1] * cache
    misses = 0
    for i in triangles.ravel().tolist():
        if slots[i % cache] != i:
            slots[i % cache] = i
            misses += 1
    return misses / max(len(triangles), 1)


def draw_order(part: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A part's :func:`cache_friendly` order and its triangles' normals in that order, kept in the
    process for the next run of the same mesh (:mod:`brainpainter.rendering.mesh_memo`).

    Parameters
    ----------
    part : brainpainter.rendering.geometry.PartGeometry

    Returns
    -------
    vertex_order : ndarray of int, shape (n_vertices,)
    triangles : ndarray of int32, shape (n_triangles, 3)
    normals : ndarray of float32, shape (3, n_triangles)
        :func:`~brainpainter_blender.facing.triangle_normals` of the reordered mesh.
    """
    def compute() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        order, triangles = cache_friendly(part.vertices, part.triangles)
        return order, triangles, triangle_normals(part.vertices[order], triangles)
    return mesh_result("draw order", (part.vertices, part.triangles), compute)
