"""Region borders on a surface as line segments: what ``--outline`` draws at constant pixel width.

A renderer draws a part's :attr:`~brainpainter.rendering.parts.PartGeometry.outline`
segments as lines ``RenderSettings.outline_width`` pixels wide in every image, however
large the image and however near the camera (a border coloured into the mesh would be
one mesh edge wide: thin from afar, thick up close). The segments sit on the surface,
lifted a little along its normals so that the surface in front of them hides them and the
surface under them does not.

Two ways a border runs, as the colours run:

- a scene coloured per region (faces take their region's colour): the borders are the
  mesh edges between faces of two regions (:func:`face_borders`);
- a scene coloured per vertex (a map over an atlas): the colours change halfway along the
  edges between vertices of two labels, so the border joins those midpoints across each
  triangle (:func:`vertex_borders`, marching triangles).

A second map's iso-lines (``--contour``) are drawn the same way: :func:`iso_lines` joins the
points where the map crosses the level along each edge, interpolated linearly. Either line can be
dashed (:func:`dashed`: the segments chained into lines, every other stretch of them left out).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

#: A dashed line's dash and gap along the surface, millimetres (at 1200 x 900, about 20 and 13 pixels).
DASH_MM, GAP_MM = 3.0, 2.0
#: How near two segment ends are to be one point of a line, millimetres.
JOIN_MM = 1e-3
#: How far a border is lifted off the surface along its normals, millimetres (a fraction of a
#: voxel: enough to win the depth test against the surface it lies on, never to show through a fold).
LIFT_MM = 0.15


def face_borders(vertices: NDArray[Any], faces: NDArray[Any], face_label: NDArray[Any],
                 normals: NDArray[Any], lift: float = LIFT_MM) -> NDArray[np.float32]:
    """The mesh edges between faces of different labels, shape (m, 2, 3).

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (f, 3)
    face_label : ndarray, shape (f,)
        A label per face (faces of label -1 are not drawn; their borders with drawn faces are).
    normals : ndarray of float, shape (n, 3)
        Unit vertex normals.
    lift : float
        Millimetres off the surface.
    """
    f = np.asarray(faces, np.int64)
    label = np.asarray(face_label)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    owner = np.tile(np.arange(len(f)), 3)
    edges.sort(axis=1)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, owner = edges[order], owner[order]
    # an interior edge appears twice in a row (its two faces); keep those whose faces differ
    pair = np.all(edges[1:] == edges[:-1], axis=1)
    first = np.nonzero(pair)[0]
    differ = label[owner[first]] != label[owner[first + 1]]
    both = (label[owner[first]] >= 0) | (label[owner[first + 1]] >= 0)
    chosen = edges[first[differ & both]]
    v, n = np.asarray(vertices, float), np.asarray(normals, float)
    return _segments(v[chosen[:, 0]], n[chosen[:, 0]], v[chosen[:, 1]], n[chosen[:, 1]], lift)


def vertex_borders(vertices: NDArray[Any], faces: NDArray[Any], vertex_label: NDArray[Any],
                   normals: NDArray[Any], lift: float = LIFT_MM) -> NDArray[np.float32]:
    """The lines between vertices of different labels, through the midpoints of the edges, (m, 2, 3).

    A triangle with two labels gets the segment joining the midpoints of its two mixed
    edges; one with three labels gets three, from its centre to each edge's midpoint.

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (f, 3)
    vertex_label : ndarray, shape (n,)
    normals : ndarray of float, shape (n, 3)
    lift : float
        Millimetres off the surface.
    """
    v, n = np.asarray(vertices, float), np.asarray(normals, float)
    f = np.asarray(faces, np.int64)
    lab = np.asarray(vertex_label)[f]
    same = np.stack([lab[:, 1] == lab[:, 2], lab[:, 2] == lab[:, 0], lab[:, 0] == lab[:, 1]], axis=1)
    n_same = same.sum(axis=1)
    # two labels: exactly one edge is uniform; the corner opposite it is the odd one
    two = np.nonzero(n_same == 1)[0]
    odd = np.argmax(same[two], axis=1)                       # edge k is opposite corner k
    c, b0, b1 = f[two, odd], f[two, (odd + 1) % 3], f[two, (odd + 2) % 3]
    seg_two = _segments((v[c] + v[b0]) / 2, n[c] + n[b0], (v[c] + v[b1]) / 2, n[c] + n[b1], lift)
    # three labels: centre to each edge's midpoint
    three = f[n_same == 0]
    centre = v[three].mean(axis=1)
    centre_n = n[three].mean(axis=1)
    seg_three = [_segments(centre, centre_n, (v[three[:, a]] + v[three[:, b]]) / 2,
                           n[three[:, a]] + n[three[:, b]], lift) for a, b in ((0, 1), (1, 2), (2, 0))]
    out: NDArray[np.float32] = np.concatenate([seg_two, *seg_three])
    return out


def iso_lines(vertices: NDArray[Any], faces: NDArray[Any], values: NDArray[Any], level: float,
              normals: NDArray[Any], lift: float = LIFT_MM) -> NDArray[np.float32]:
    """Where `values` crosses `level` on the surface, as segments, (m, 2, 3) (marching triangles).

    A triangle with corners on both sides of the level (``values >= level``; NaN counts as below)
    gets the segment joining the two points where its mixed edges cross the level, placed by
    linear interpolation (the edge's middle where a value is not finite). Closed regions give
    closed lines.

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (f, 3)
    values : ndarray of float, shape (n,)
    level : float
    normals : ndarray of float, shape (n, 3)
    lift : float
        Millimetres off the surface.
    """
    v, n = np.asarray(vertices, float), np.asarray(normals, float)
    f = np.asarray(faces, np.int64)
    val = np.asarray(values, float)
    above = np.where(np.isnan(val), False, val >= level)[f]
    mixed = np.nonzero(above.any(axis=1) & ~above.all(axis=1))[0]
    a = above[mixed]
    odd = np.where(a[:, 0] == a[:, 1], 2, np.where(a[:, 0] == a[:, 2], 1, 0))  # the corner alone on its side
    c, b0, b1 = f[mixed, odd], f[mixed, (odd + 1) % 3], f[mixed, (odd + 2) % 3]

    def crossing(p: NDArray[Any], q: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (level - val[p]) / (val[q] - val[p])
        t = np.clip(np.where(np.isfinite(t), t, 0.5), 0.0, 1.0)[:, None]
        return v[p] + t * (v[q] - v[p]), n[p] + n[q]

    return _segments(*crossing(c, b0), *crossing(c, b1), lift)


def _lift(points: NDArray[Any], normals: NDArray[Any], lift: float) -> NDArray[Any]:
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    out: NDArray[Any] = points + lift * normals / np.where(length > 0, length, 1.0)
    return out


def _segments(p: NDArray[Any], pn: NDArray[Any], q: NDArray[Any], qn: NDArray[Any],
              lift: float) -> NDArray[np.float32]:
    """Segments p -> q, each end lifted along its normal, float32 (m, 2, 3)."""
    out: NDArray[np.float32] = np.stack([_lift(p, pn, lift), _lift(q, qn, lift)], axis=1).astype(np.float32)
    return out


def dashed(segments: NDArray[Any], dash: float = DASH_MM, gap: float = GAP_MM) -> NDArray[np.float32]:
    """The dashes of line `segments`, shape (m, 2, 3): chained end to end into lines, the segments whose
    middle lies in a dash (the first `dash` mm of every ``dash + gap`` along its line) kept, shape (k, 2, 3).

    A line starts anew at each segment not reached from another (its dashes then start there).
    """
    seg = np.asarray(segments, np.float32).reshape(-1, 2, 3)
    m = len(seg)
    if not m:
        return seg
    _, point = np.unique(np.round(seg.reshape(-1, 3) / JOIN_MM).astype(np.int64), axis=0, return_inverse=True)
    point = point.reshape(m, 2)
    at: dict[int, list[int]] = {}
    for s, (p, q) in enumerate(point.tolist()):
        at.setdefault(p, []).append(s)
        at.setdefault(q, []).append(s)
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).astype(float)
    middle = np.full(m, np.nan)
    for first in range(m):
        s, end, along = first, int(point[first, 1]), 0.0
        while s >= 0 and np.isnan(middle[s]):
            middle[s] = along + length[s] / 2
            along += length[s]
            nxt = [t for t in at[end] if np.isnan(middle[t])]
            s = nxt[0] if nxt else -1
            if s >= 0:
                end = int(point[s, 1] if point[s, 0] == end else point[s, 0])
    return seg[np.mod(middle, dash + gap) < dash]
