"""Ambient occlusion baked per vertex: how much of the sky each vertex of a mesh sees.

Baked once, when a template is built (``tools/brainpainter_builder``), and
stored in the template (``ao_{surface}`` in cortex files, ``ao`` in
``subcortical.npz``), so it costs nothing when an image is drawn: the draw
path multiplies the lighting by it, and the bottom of a sulcus is darker than
a crown in every colour.

The bake needs no ray tracer: for each of `n_directions` directions spread
evenly over the sphere (a Fibonacci lattice), points sampled densely on the
mesh's faces (:func:`surface_points`) are projected orthographically into a depth map with
`cell`-millimetre pixels, each pixel keeping its point nearest the sky in that
direction. A vertex sees the sky in that direction when nothing in its pixel
lies more than `bias` millimetres above it (plus the rise of a flat surface
across one pixel, so that a slope does not shade itself). Occlusion is the
cosine-weighted fraction of the directions above the vertex's tangent plane
that it sees (1 = open sky, 0 = fully enclosed), what a path tracer's ambient
occlusion with rays of unlimited length gives, up to the depth maps'
resolution.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals

#: Directions sampled over the sphere (about half lie above any vertex's tangent plane).
N_DIRECTIONS = 96
#: Depth-map pixel, mm (the occluders are sampled on the faces at most this far apart).
CELL_MM = 1.0
#: A point this far (mm) above a vertex in its pixel occludes it (tangent slopes within a pixel do not).
BIAS_MM = 0.8


def sphere_directions(n: int) -> NDArray[Any]:
    """`n` unit vectors spread evenly over the sphere (Fibonacci lattice), shape (n, 3)."""
    i = np.arange(n, dtype=np.float64) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = i * np.pi * (3.0 - np.sqrt(5.0))
    out: NDArray[Any] = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    return out


def surface_points(vertices: NDArray[Any], faces: NDArray[Any], spacing: float) -> NDArray[Any]:
    """The vertices first, then points on every face at most about `spacing` apart, shape (n, 3).

    Each face gets a barycentric grid of ``k`` steps per edge (``k`` = longest
    edge / `spacing`, rounded up, at most 16; its centroid when ``k`` is 1),
    so a depth map of `spacing` pixels has no holes.
    """
    v, f = np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64)
    tri = v[f]
    longest = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    steps = np.clip(np.ceil(longest / spacing), 1, 16).astype(np.int64)
    out = [v]
    for k in np.unique(steps):
        if k == 1:
            bary = np.full((1, 3), 1.0 / 3.0)
        else:
            ij = np.array([(i, j) for i in range(k + 1) for j in range(k + 1 - i)], dtype=np.float64)
            bary = np.column_stack([ij, k - ij.sum(axis=1)]) / k
            bary = bary[(bary < 1.0).all(axis=1)]  # the corners are the vertices
        out.append(np.einsum("pk,fkc->fpc", bary, tri[steps == k]).reshape(-1, 3))
    return np.vstack(out)


def ambient_occlusion(vertices: NDArray[Any], faces: NDArray[Any], *, n_directions: int = N_DIRECTIONS,
                      cell: float = CELL_MM, bias: float = BIAS_MM) -> NDArray[Any]:
    """Per-vertex ambient occlusion of a closed (or open) triangle mesh.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
        Millimetres.
    faces : ndarray of int, shape (n_faces, 3)
        Counter-clockwise seen from outside.
    n_directions : int
        Directions over the whole sphere.
    cell : float
        Depth-map pixel, mm.
    bias : float
        Height (mm) above a vertex from which a point in its pixel occludes it.

    Returns
    -------
    ndarray of float32, shape (n_vertices,)
        1 where a vertex sees the whole sky above it, towards 0 deep in a fold.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(v)
    if n == 0 or len(f) == 0:
        return np.ones(n, np.float32)
    normals = vertex_normals(v, f, np.float64)
    points = surface_points(v, f, cell)
    centre = (points.min(axis=0) + points.max(axis=0)) / 2.0
    # pixels a depth map spans, whatever the direction: the points lie within this many cells of the centre
    reach = int(np.ceil(float(np.linalg.norm(points - centre, axis=1).max()) / cell)) + 2
    side = 2 * reach + 1
    seen = np.zeros(n)
    weight = np.zeros(n)
    for d in sphere_directions(n_directions):
        cos = normals @ d
        up = cos > 0.0
        if not up.any():
            continue
        # a basis (a, b) of the plane the depth map lies in, and the height along d
        a = np.cross(d, (1.0, 0.0, 0.0) if abs(d[0]) < 0.9 else (0.0, 1.0, 0.0))
        a /= np.linalg.norm(a)
        basis = np.column_stack([a, np.cross(d, a), d])
        projected = points @ basis
        # pixels are whole cells of the plane's own coordinates, numbered from the centre's (0 .. side-1)
        ij = np.floor(projected[:, :2] / cell).astype(np.int64) - (np.floor(centre @ basis[:, :2] / cell)
                                                                   .astype(np.int64) - reach)
        pixel = ij[:, 0] * side + ij[:, 1]
        height = projected[:, 2]
        top = np.full(side * side, -np.inf)
        np.maximum.at(top, pixel, height)
        c = cos[up]
        # a flat surface tilted from the map rises by up to cell * tan(tilt) within one pixel
        slack = bias + cell * np.sqrt(1.0 - c * c) / np.maximum(c, 0.05)
        visible = height[:n][up] >= top[pixel[:n][up]] - slack
        seen[up] += cos[up] * visible
        weight[up] += cos[up]
    out: NDArray[Any] = np.where(weight > 0, seen / np.where(weight > 0, weight, 1.0), 1.0).astype(np.float32)
    return out


def occlusion_of_shown(vertices: NDArray[Any], faces: NDArray[Any], shown: NDArray[Any],
                       baked: NDArray[Any]) -> NDArray[Any]:
    """Occlusion of a mesh some of whose faces are hidden: what the bake gives the faces shown alone.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    shown : ndarray of bool, shape (n_faces,)
        The faces drawn; the others occlude nothing.
    baked : ndarray of float32, shape (n_vertices,)
        The occlusion baked with every face (kept for the vertices of hidden faces only).

    Returns
    -------
    ndarray of float32, shape (n_vertices,)
    """
    shown = np.asarray(shown, dtype=bool)
    f = np.asarray(faces, dtype=np.int64)[shown]
    used, inverse = np.unique(f, return_inverse=True)
    out: NDArray[Any] = np.array(baked, dtype=np.float32, copy=True)
    if len(used) and not shown.all():  # all shown: what was baked
        out[used] = ambient_occlusion(np.asarray(vertices)[used], inverse.reshape(-1, 3))
    return out


def to_uint8(occlusion: NDArray[Any]) -> NDArray[Any]:
    """Occlusion 0-1 as stored in a template: uint8, 255 = open sky (a third the size of float32, zipped)."""
    out: NDArray[Any] = np.rint(np.clip(occlusion, 0.0, 1.0) * 255.0).astype(np.uint8)
    return out


def from_stored(stored: NDArray[Any]) -> NDArray[Any]:
    """A stored occlusion array (uint8 0-255, or float 0-1) as float32 0-1."""
    a = np.asarray(stored)
    out: NDArray[Any] = (a.astype(np.float32) / 255.0 if a.dtype == np.uint8 else a.astype(np.float32))
    return out
