"""Which triangles a view shows: front faces (those back-face culling keeps) or back faces, from
normals kept per mesh, so a new view costs one product per triangle (an orbit draws every frame
from a new view; the glass draws its far and near sides from separate index buffers).
"""

from __future__ import annotations

import numpy as np


def triangle_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The triangles' normals scaled by twice their areas (``(b - a) x (c - a)``), one row per axis.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    triangles : ndarray of int, shape (n_triangles, 3)

    Returns
    -------
    ndarray of float32, shape (3, n_triangles)
    """
    xyz = np.ascontiguousarray(np.asarray(vertices, np.float32).T)  # per axis: the gathers stay contiguous
    a, b, c = (xyz[:, triangles[:, i]] for i in range(3))
    e1, e2 = b - a, c - a
    return np.stack([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                     e1[0] * e2[1] - e1[1] * e2[0]])


def facing(normals: np.ndarray, mvp: np.ndarray, back: bool = False) -> np.ndarray:
    """Which triangles an orthographic `mvp` shows counter-clockwise (those that back-face culling
    keeps; edge-on ones too), or with `back` clockwise (those that front-face culling keeps).

    Parameters
    ----------
    normals : ndarray of float, shape (3, n_triangles)
        :func:`triangle_normals` of the mesh (kept between views: a new view costs one product
        per triangle).
    mvp : ndarray of float, shape (4, 4)
        Model-view-projection matrix (row-major, ``mvp @ [x, y, z, 1]``).
    back : bool
        The triangles turned away instead (edge-on ones too).

    Returns
    -------
    ndarray of bool, shape (n_triangles,)
    """
    # A triangle's signed area on screen, edges e1 and e2, x and y from the rows r1 and r2 of
    # mvp: (r1 . e1)(r2 . e2) - (r2 . e1)(r1 . e2) = (r1 x r2) . (e1 x e2). Elementwise: no BLAS thread.
    k = np.cross(mvp[0, :3], mvp[1, :3]).astype(np.float32)
    area = normals[0] * k[0] + normals[1] * k[1] + normals[2] * k[2]
    kept: np.ndarray = area <= 0 if back else area >= 0
    return kept


def front_faces(vertices: np.ndarray, triangles: np.ndarray, mvp: np.ndarray,
                back: bool = False) -> np.ndarray:
    """The triangles that :func:`facing` keeps.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    triangles : ndarray of int, shape (n_triangles, 3)
    mvp : ndarray of float, shape (4, 4)
    back : bool

    Returns
    -------
    ndarray, shape (n_kept, 3)
        The rows of `triangles` kept, in their order.
    """
    kept: np.ndarray = triangles[facing(triangle_normals(vertices, triangles), mvp, back)]
    return kept
