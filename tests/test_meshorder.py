"""The Blender plugin's mesh order for llvmpipe's vertex cache (brainpainter_blender.meshorder)."""

from __future__ import annotations

import numpy as np
import trimesh

from brainpainter_blender import meshorder


def _shuffled_sphere(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere with its vertices and triangles in random order, shapes (n, 3) and (m, 3)."""
    ico = trimesh.creation.icosphere(subdivisions=4, radius=50.0)
    rng = np.random.default_rng(seed)
    perm = rng.permutation(len(ico.vertices))
    inverse = np.empty_like(perm)
    inverse[perm] = np.arange(len(perm))
    vertices = np.asarray(ico.vertices, np.float32)[perm]
    triangles = inverse[np.asarray(ico.faces)][rng.permutation(len(ico.faces))]
    return vertices, triangles


def _oriented(vertices: np.ndarray, triangles: np.ndarray) -> set[tuple]:
    """Each triangle as its corner positions, rotated to start at the smallest corner (keeps winding)."""
    out = set()
    for tri in vertices[triangles].round(4).tolist():
        k = min(range(3), key=lambda i: tri[i])
        out.add(tuple(map(tuple, tri[k:] + tri[:k])))
    return out


def test_reorder_keeps_every_triangle_and_its_winding():
    vertices, triangles = _shuffled_sphere()
    order, new = meshorder.cache_friendly(vertices, triangles)
    assert new.dtype == np.int32 and new.shape == triangles.shape
    assert sorted(order.tolist()) == list(range(len(vertices)))  # a permutation of the vertices
    assert _oriented(vertices[order], new) == _oriented(vertices, triangles)


def test_reorder_cuts_vertex_shadings_of_a_scattered_mesh():
    vertices, triangles = _shuffled_sphere()
    before = meshorder.shadings_per_triangle(triangles)
    _, new = meshorder.cache_friendly(vertices, triangles)
    after = meshorder.shadings_per_triangle(new)
    # each triangle refers to 3 vertices: ~3 shadings in random order; a closed mesh has ~0.5 per triangle
    assert before > 2.0, before
    assert after < 0.8, after


def test_morton_codes_follow_space():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], np.float32)
    codes = meshorder.morton_codes(points)
    assert codes[0] == 0 and codes[4] == codes.max() == 2 ** (3 * meshorder.BITS) - 1
    assert codes[1] < codes[2] < codes[3]  # x is the lowest bit, then y, then z
