"""Remove self-intersections (folds) from a surface without changing its triangles.

FreeSurfer's fsaverage pial and white surfaces cross themselves in a few
places (119 faces of ``lh.pial``, mostly in the precentral and fusiform
gyri); decimation keeps them. Rendered, such a fold shows as a bright
sliver or a pinhole. :func:`remove_self_intersections` finds the faces
that intersect another face of the same surface (MeshLab's
``compute_selection_by_self_intersections_per_face``, through pymeshlab),
and smooths only the vertices around them (umbrella / Laplacian steps, the
rest of the surface held fixed), widening the patch until no face
intersects another. Only positions change: faces, labels and
``source_vertex`` stay, so every surface of a hemisphere keeps one topology.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshing import count_self_intersections, self_intersecting_faces
from brainpainter.errors import BrainPainterError

__all__ = ["Cleaned", "count_self_intersections", "remove_self_intersections"]


@dataclass(frozen=True)
class Cleaned:
    """Result of :func:`remove_self_intersections`.

    Attributes
    ----------
    vertices : ndarray of float64, shape (n, 3)
    before, after : int
        Self-intersecting faces before and after.
    moved : int
        Vertices that moved.
    """

    vertices: NDArray[Any]
    before: int
    after: int
    moved: int


def _neighbours(faces: NDArray[Any], n: int) -> Any:
    from scipy import sparse

    ij = np.asarray(faces, dtype=np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    adj = sparse.csr_matrix((np.ones(2 * len(ij)), (np.r_[ij[:, 0], ij[:, 1]], np.r_[ij[:, 1], ij[:, 0]])),
                            shape=(n, n))
    adj.data[:] = 1.0
    return adj


def remove_self_intersections(vertices: NDArray[Any], faces: NDArray[Any], *, rings: int = 2,
                              steps: int = 4, max_rounds: int = 40) -> Cleaned:
    """Smooth the surface around its self-intersections until there are none.

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (m, 3)
    rings : int
        Neighbour rings around the intersecting faces smoothed in the first
        round; one more ring every third round.
    steps : int
        Umbrella smoothing steps per round (each moves a vertex half way to
        the mean of its neighbours).
    max_rounds : int
        Rounds before giving up.

    Returns
    -------
    Cleaned

    Raises
    ------
    BrainPainterError
        When intersections remain after `max_rounds` rounds.
    """
    v = np.asarray(vertices, dtype=np.float64).copy()
    faces = np.asarray(faces, dtype=np.int64)
    n = len(v)
    bad = self_intersecting_faces(v, faces)
    before = int(np.count_nonzero(bad))
    if before == 0:
        return Cleaned(v, 0, 0, 0)
    adj = _neighbours(faces, n)
    degree = np.asarray(adj.sum(axis=1)).ravel()
    degree[degree == 0] = 1.0
    moved = np.zeros(n, dtype=bool)
    patch = np.zeros(n, dtype=bool)
    for round_ in range(max_rounds):
        seed = np.zeros(n, dtype=bool)
        seed[faces[bad].ravel()] = True
        patch |= seed  # a patch only grows: vertices smoothed once stay in it
        for _ in range(rings + round_ // 3):
            patch |= (adj @ patch.astype(np.float64)) > 0
        for _ in range(steps):
            mean = (adj @ v) / degree[:, None]
            v[patch] += 0.5 * (mean[patch] - v[patch])
        moved |= patch
        bad = self_intersecting_faces(v, faces)
        if not bad.any():
            return Cleaned(v, before, 0, int(np.count_nonzero(moved)))
    raise BrainPainterError(f"{int(np.count_nonzero(bad))} self-intersecting faces remain after "
                            f"{max_rounds} smoothing rounds (of {before})")

