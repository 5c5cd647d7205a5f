"""A connectome's nodes and edges as scene parts: lit spheres and cylinders, instanced from one mesh each.

Every node is the same unit icosphere scaled by its radius and moved to its position, every edge
the same open unit cylinder stretched from one node to the other: a part is one indexed mesh of all
instances (numpy broadcasting, no Python loop per node or edge), drawn as any opaque part. Each node
and each edge has a palette slot of its own (keys ``node:i``, ``edge:k``, k in the order of
:meth:`~brainpainter.connectome.model.Connectome.edges`), so an image recolours them as it recolours
regions.

A node's radius comes from its value (:data:`NODE_RADIUS`, the values' range mapped linearly onto it);
an edge's from its absolute weight (:data:`EDGE_RADIUS`, 0 to the largest ``|weight|``).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.model import edge_keys, node_keys
from brainpainter.rendering.parts import PartGeometry
from brainpainter.rendering.settings import RGB

if TYPE_CHECKING:
    from brainpainter.connectome.model import Connectome

#: Smallest and largest node radius, millimetres (the lowest and highest node value).
NODE_RADIUS = (2.0, 6.0)
#: Radius of every node when the nodes have no values, millimetres.
PLAIN_NODE_RADIUS = 3.0
#: Edge radius at weight 0 and at the largest |weight|, millimetres.
EDGE_RADIUS = (0.25, 1.0)
#: Subdivisions of the nodes' icosphere (2: 162 vertices, 320 triangles; 1: 42, 80), by the most nodes
#: drawn so (level of detail: 1,000 nodes of 320 triangles are 320,000 triangles, most of a cortex).
SPHERE_SUBDIVISIONS = ((500, 2), (None, 1))
#: Sides of an edge's cylinder: seen across, 8 sides are 92-100 % as wide as a round tube (12: 97-100 %),
#: and an edge costs llvmpipe per long, thin side it draws (798 edges of 12 sides: ~28 CPU ms of a
#: 1200x900 image; of 8: ~13).
CYLINDER_SIDES = 8
#: Colour of nodes without a value or category (sRGB).
NODE_COLOR: RGB = (0.25, 0.25, 0.30)

SlotsFor = Callable[[list[str], "int | RGB", frozenset[str]], NDArray[Any]]


def node_radii(values: NDArray[Any] | None, n: int) -> NDArray[np.float64]:
    """Radius of each node in mm, shape (n,): its value's place in their range, on :data:`NODE_RADIUS`.

    No values: :data:`PLAIN_NODE_RADIUS` each; NaN: the smallest radius; equal values: the middle.
    """
    lo, hi = NODE_RADIUS
    if values is None:
        return np.full(n, PLAIN_NODE_RADIUS)
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if not finite.size:
        return np.full(n, lo)
    vmin, vmax = float(finite.min()), float(finite.max())
    t = np.full(n, 0.5) if vmax <= vmin else (v - vmin) / (vmax - vmin)
    return np.where(np.isfinite(v), lo + np.clip(t, 0.0, 1.0) * (hi - lo), lo)


def edge_radii(weights: NDArray[Any]) -> NDArray[np.float64]:
    """Radius of each edge in mm, shape (E,): ``|weight|`` from 0 to the largest, on :data:`EDGE_RADIUS`."""
    lo, hi = EDGE_RADIUS
    w = np.abs(np.asarray(weights, dtype=float))
    top = float(w.max()) if w.size else 0.0
    radii: NDArray[np.float64] = lo + (w / top if top > 0 else np.zeros_like(w)) * (hi - lo)
    return radii


def sphere_subdivisions(n: int) -> int:
    """Subdivisions of the icosphere of `n` nodes (:data:`SPHERE_SUBDIVISIONS`)."""
    return next(k for most, k in SPHERE_SUBDIVISIONS if most is None or n <= most)


@cache
def unit_sphere(subdivisions: int = 2) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The icosphere every node is drawn with: vertices (unit length, also the normals) and triangles."""
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    vertices = np.asarray(mesh.vertices, dtype=float)
    return vertices / np.linalg.norm(vertices, axis=1, keepdims=True), np.asarray(mesh.faces, np.int64)


@cache
def unit_cylinder() -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The open cylinder every edge is drawn with: ring points ``(cos a, sin a, t)`` (t 0 and 1), triangles.

    Returns
    -------
    ring : ndarray, shape (2 * CYLINDER_SIDES, 3)
        Columns: cosine and sine of the side's angle, and 0 (start) or 1 (end).
    triangles : ndarray of int, shape (2 * CYLINDER_SIDES, 3)
        Counter-clockwise seen from outside.
    """
    k = CYLINDER_SIDES
    angle = 2 * np.pi * np.arange(k) / k
    ring = np.concatenate([np.column_stack([np.cos(angle), np.sin(angle), np.full(k, t)])
                           for t in (0.0, 1.0)])
    a = np.arange(k)
    b = (a + 1) % k
    triangles = np.concatenate([np.column_stack([a, b, a + k]), np.column_stack([b, b + k, a + k])])
    return ring, triangles


def _instances(unit_vertices: NDArray[Any], unit_triangles: NDArray[Any], vertices: NDArray[Any],
               normals: NDArray[Any], slots: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any],
                                                                      NDArray[Any], NDArray[Any]]:
    """Instances of one unit mesh as one indexed mesh; `vertices`, `normals`: shape (n, m, 3), slots (n,)."""
    n, m = len(vertices), len(unit_vertices)
    triangles = (unit_triangles[None] + (np.arange(n) * m)[:, None, None]).reshape(-1, 3)
    return (vertices.reshape(-1, 3).astype(np.float32), normals.reshape(-1, 3).astype(np.float32),
            triangles.astype(np.uint32), np.repeat(np.asarray(slots, np.int32), m))


def sphere_mesh(centres: NDArray[Any], radii: NDArray[Any], slots: NDArray[Any]) -> tuple[NDArray[Any], ...]:
    """Node spheres: one instance of :func:`unit_sphere` per centre, shape (n, 3), radius (n,), slot (n,).

    Returns
    -------
    vertices, normals : ndarray of float32, shape (n * 162, 3) (42 for more than 500 nodes)
    triangles : ndarray of uint32, shape (n * 320, 3) (80)
    palette_index : ndarray of int32, shape (n * 162,)
    """
    unit, triangles = unit_sphere(sphere_subdivisions(len(centres)))
    centres = np.asarray(centres, dtype=float)
    vertices = centres[:, None, :] + np.asarray(radii, dtype=float)[:, None, None] * unit[None]
    return _instances(unit, triangles, vertices, np.broadcast_to(unit, vertices.shape), slots)


def cylinder_mesh(starts: NDArray[Any], ends: NDArray[Any], radii: NDArray[Any],
                  slots: NDArray[Any]) -> tuple[NDArray[Any], ...]:
    """Edge cylinders from `starts` to `ends` (E, 3), radius (E,), slot (E,), like :func:`sphere_mesh`."""
    ring, triangles = unit_cylinder()
    a, b = np.asarray(starts, dtype=float), np.asarray(ends, dtype=float)
    axis = b - a
    length = np.linalg.norm(axis, axis=1, keepdims=True)
    d = np.where(length > 0, axis / np.where(length > 0, length, 1.0), [0.0, 0.0, 1.0])
    # two unit vectors across each edge: from the coordinate axis least along it
    helper = np.eye(3)[np.argmin(np.abs(d), axis=1)]
    u = np.cross(d, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(d, u)
    out = ring[None, :, 0:1] * u[:, None, :] + ring[None, :, 1:2] * v[:, None, :]  # (E, 2k, 3)
    vertices = a[:, None, :] + ring[None, :, 2:3] * axis[:, None, :] \
        + np.asarray(radii, dtype=float)[:, None, None] * out
    return _instances(ring, triangles, vertices, out, slots)


def node_hemis(positions: NDArray[Any]) -> NDArray[np.str_]:
    """The hemisphere of each node, ``lh`` (x < 0, RAS) or ``rh``, shape (n,)."""
    return np.where(np.asarray(positions, dtype=float)[:, 0] < 0, "lh", "rh")


def connectome_parts(connectome: Connectome | None, slots_for: SlotsFor) -> list[PartGeometry]:
    """The parts of a connectome: nodes (kind ``node``) and edges (kind ``edge``), by hemisphere.

    Parameters
    ----------
    connectome : Connectome, optional
        None: no parts.
    slots_for : callable
        ``slots_for(keys, default_colour, hidden)``: the palette slot of each key, made on first use.

    Returns
    -------
    list of PartGeometry
        ``nodes-lh`` and ``nodes-rh`` (:func:`node_hemis`), ``edges-lh`` and ``edges-rh`` (both ends in
        that hemisphere) and ``edges`` (between the hemispheres, hemisphere None), those that have any:
        a lateral view draws its hemisphere's (:data:`brainpainter.rendering.framing.CONNECTOME_KINDS`).
    """
    parts: list[PartGeometry] = []
    if connectome is None:
        return parts
    positions = np.asarray(connectome.positions, dtype=float)
    n = connectome.n_nodes
    hemi = node_hemis(positions)
    keys = node_keys(n)
    radii = node_radii(connectome.node_values, n)
    for side in ("lh", "rh"):
        mine = np.flatnonzero(hemi == side)
        if len(mine):
            slots = slots_for([keys[i] for i in mine], NODE_COLOR, frozenset())
            verts, normals, tris, pal = sphere_mesh(positions[mine], radii[mine], slots)
            parts.append(PartGeometry(f"nodes-{side}", "node", side, verts, normals, tris, pal,
                                      np.zeros(len(verts), np.float32), verts))
    source, target, weight = connectome.edges()
    keys, radii = edge_keys(len(weight)), edge_radii(weight)
    side_of = np.where(hemi[source] == hemi[target], hemi[source], "")
    for side in ("lh", "rh", ""):
        mine = np.flatnonzero(side_of == side)
        if len(mine):
            slots = slots_for([keys[k] for k in mine], NODE_COLOR, frozenset())
            a, b = source[mine], target[mine]
            verts, normals, tris, pal = cylinder_mesh(positions[a], positions[b], radii[mine], slots)
            parts.append(PartGeometry(f"edges-{side}" if side else "edges", "edge", side or None, verts,
                                      normals, tris, pal, np.zeros(len(verts), np.float32),
                                      positions[np.r_[a, b]]))
    return parts
