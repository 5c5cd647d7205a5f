"""The edges of a part's mesh (:class:`EdgeTable`), where a view's colour can jump.

The default draw path anti-aliases them (``brainpainter_blender.edge_aa``); a region scene's
cortex part keeps its table beside its arrays in the user's cache
(:mod:`brainpainter.rendering.part_cache`): building it costs about 0.1 s per hemisphere.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class EdgeTable:
    """The edges of one part's mesh.

    Attributes
    ----------
    ends : ndarray of int, shape (n_edges, 2)
        Vertex indices of each edge's two ends.
    faces : ndarray of int32, shape (n_edges, 2)
        The edge's two triangles; ``-1`` as the second for an open boundary.
    border : ndarray of bool, shape (n_edges,)
        The two triangles have different palette slots (a region border).
    normals : ndarray of float32, shape (n_triangles, 3)
        Each triangle's normal (unnormalised, outward).
    """

    ends: NDArray[Any]
    faces: NDArray[Any]
    border: NDArray[Any]
    normals: NDArray[Any]


def edge_table(vertices: NDArray[Any], triangles: NDArray[Any], palette_index: NDArray[Any]) -> EdgeTable:
    """The edges of a mesh whose vertices are split along region borders.

    Vertices at the same position count as one, so the two triangles of a
    border edge (each on its own copy of the edge's vertices) are neighbours.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    triangles : ndarray of int, shape (n_triangles, 3)
    palette_index : ndarray of int, shape (n_vertices,)
        Palette slot per vertex; triangles whose three slots differ (a map's
        cortex) make no borders, only silhouettes.
    """
    v = np.ascontiguousarray(vertices, np.float32)
    tri = np.asarray(triangles, np.int64)
    # one id per position (the split's copies share their coordinates bit for bit)
    bits = v.view(np.int32)
    by_position = np.lexsort((bits[:, 2], bits[:, 1], bits[:, 0]))
    step = np.any(np.diff(bits[by_position], axis=0) != 0, axis=1)
    same = np.empty(len(v), np.int64)
    same[by_position] = np.concatenate([[0], np.cumsum(step)])
    ends = tri[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    a, b = same[ends[:, 0]], same[ends[:, 1]]
    key = np.minimum(a, b) * (int(same.max()) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    key = key[order]
    face = order // 3
    paired = np.zeros(len(key), bool)
    paired[:-1] = key[:-1] == key[1:]
    paired[1:] &= ~paired[:-1]  # a third triangle on an edge (non-manifold) starts a new pair
    first = np.flatnonzero(paired)
    single = np.ones(len(key), bool)
    single[first] = single[first + 1] = False
    alone = np.flatnonzero(single)
    keep = np.concatenate([first, alone])
    faces = np.stack([face[keep], np.concatenate([face[first + 1], np.full(len(alone), -1)])],
                     axis=1).astype(np.int32)
    slots = np.asarray(palette_index)[tri]
    uniform = bool(np.all(slots == slots[:, :1]))
    border = np.zeros(len(keep), bool)
    if uniform:
        border[:len(first)] = slots[faces[:len(first), 0], 0] != slots[faces[:len(first), 1], 0]
    p = v[tri]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return EdgeTable(ends[order[keep]], faces, border, normals)
