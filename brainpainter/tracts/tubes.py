"""Streamlines as triangle tubes: what a renderer draws (a renderer only draws triangles).

Each resampled streamline of ``n_points`` points becomes ``n_points`` rings of
``sides`` vertices joined by quads (two triangles each), open at the ends;
normals point radially out, so a tube is lit like a cylinder. The rings'
frames are carried along each streamline by projection (a rotation-minimising
frame for smooth curves), so the tube does not twist.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Sides of a tube: 3 (a triangular prism whose smooth radial normals light it as a round tube; at the
#: default radius a tube is 3-5 pixels wide, where 6 sides look the same and cost twice the triangles).
SIDES = 3
#: Triangles of all tubes together, roughly: beyond it streamlines get fewer points (level of detail;
#: a software rasteriser's time per image grows with the triangles).
TRIANGLE_BUDGET = 250_000
#: Segments of all centrelines together, roughly (drawn as lines once per view: a movie's orbit pays
#: them every frame): 10,000 streamlines keep 11 points, where their tubes get 5; 3,000 keep all 32.
LINE_SEGMENT_BUDGET = 100_000
#: Fewest points per streamline the level of detail leaves.
MIN_POINTS = 5
#: Tube radius in millimetres.
RADIUS = 0.3


#: Up to this many streamlines keep the full radius; beyond, the radius shrinks as 1/sqrt(n).
FULL_RADIUS_STREAMLINES = 2_000
#: Thinnest automatic radius (mm): still 1-2 pixels wide at 1200 pixels across the brain.
MIN_RADIUS = 0.12


def auto_radius(n_streamlines: int) -> float:
    """Tube radius (mm) for `n_streamlines`: :data:`RADIUS` up to 2,000, then ``RADIUS * sqrt(2000 / n)``.

    Many tubes overlap: the pixels drawn (a software rasteriser's cost) grow with
    their total width, and thinner tubes keep a dense tractogram readable.
    """
    r = RADIUS * (FULL_RADIUS_STREAMLINES / max(n_streamlines, 1)) ** 0.5
    return float(min(RADIUS, max(MIN_RADIUS, r)))


def points_for(n_streamlines: int, n_points: int, sides: int = SIDES,
               budget: int = TRIANGLE_BUDGET) -> int:
    """Points per streamline so that all tubes stay near `budget` triangles (``MIN_POINTS`` to `n_points`).

    A tube of ``m`` points has ``(m - 1) * sides * 2`` triangles: with 3 sides, 1,000
    streamlines keep 32 points, 3,000 get 14, 10,000 get 5 (a point every 20-25 mm of
    a long association bundle: visibly polygonal up close, the price of the speed bar).
    """
    m = int(budget // max(1, n_streamlines * sides * 2)) + 1
    return max(min(MIN_POINTS, n_points), min(n_points, m))


def line_points_for(n_streamlines: int, n_points: int, budget: int = LINE_SEGMENT_BUDGET) -> int:
    """Points per streamline so that all centrelines keep near `budget` segments (at least ``MIN_POINTS``)."""
    m = int(budget // max(1, n_streamlines)) + 1
    return max(min(MIN_POINTS, n_points), min(n_points, m))


def tangents(lines: NDArray[Any]) -> NDArray[Any]:
    """Unit tangents, shape (n_streamlines, n_points, 3), float64 (central differences)."""
    t = np.gradient(np.asarray(lines, dtype=np.float64), axis=1)
    norm = np.linalg.norm(t, axis=2, keepdims=True)
    out: NDArray[Any] = t / np.where(norm > 0, norm, 1.0)
    return out


def _frames(t: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
    """Normal and binormal per point, shape (n, m, 3) each, carried along by projection."""
    m = t.shape[1]
    normal = np.empty_like(t)
    axes = np.eye(3)
    seed = axes[np.argmin(np.abs(t[:, 0]), axis=1)]  # the axis least aligned with the first tangent
    cur = np.cross(t[:, 0], seed)
    for i in range(m):
        if i:
            cur = normal[:, i - 1] - np.einsum("ij,ij->i", normal[:, i - 1], t[:, i])[:, None] * t[:, i]
        length = np.linalg.norm(cur, axis=1)
        bad = length < 1e-6  # a kink of 90 degrees or a zero tangent: start afresh
        if np.any(bad):
            cur[bad] = np.cross(t[bad, i], axes[np.argmin(np.abs(t[bad, i]), axis=1)])
            length[bad] = np.linalg.norm(cur[bad], axis=1)
        normal[:, i] = cur / np.where(length > 0, length, 1.0)[:, None]
    return normal, np.cross(t, normal)


def tube_mesh(lines: NDArray[Any], radius: float = RADIUS,
              sides: int = SIDES) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """Tubes around streamlines.

    Parameters
    ----------
    lines : ndarray of float, shape (n_streamlines, n_points, 3)
    radius : float
        Millimetres.
    sides : int
        At least 3.

    Returns
    -------
    vertices : ndarray of float32, shape (n_streamlines * n_points * sides, 3)
        Vertex ``(s * n_points + i) * sides + j`` is side `j` of point `i` of streamline `s`.
    normals : ndarray of float32, same shape
        Unit, radial.
    triangles : ndarray of uint32, shape (n_streamlines * (n_points - 1) * sides * 2, 3)
        Counter-clockwise seen from outside.
    """
    pts = np.asarray(lines, dtype=np.float64)
    n_lines, m, _ = pts.shape
    t = tangents(pts)
    normal, binormal = _frames(t)
    theta = 2.0 * np.pi * np.arange(sides) / sides
    radial = (np.cos(theta)[None, None, :, None] * normal[:, :, None, :]
              + np.sin(theta)[None, None, :, None] * binormal[:, :, None, :])  # (n, m, sides, 3)
    verts = pts[:, :, None, :] + radius * radial
    # one streamline's quads, then offset per streamline
    i, j = np.meshgrid(np.arange(m - 1), np.arange(sides), indexing="ij")
    a = i * sides + j
    b = i * sides + (j + 1) % sides
    c, d = a + sides, b + sides
    one = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    offsets = (np.arange(n_lines, dtype=np.int64) * m * sides)[:, None, None]
    tris = (one[None] + offsets).reshape(-1, 3).astype(np.uint32)
    return (verts.reshape(-1, 3).astype(np.float32), radial.reshape(-1, 3).astype(np.float32), tris)
