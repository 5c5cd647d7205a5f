"""Sulcal depth per vertex, 0 (crown of a gyrus) to 1 (deep in a sulcus), for optional darkening.

From the template's ``sulc`` (or ``curv``) when it ships one, else from the mesh alone
(:func:`convexity`); :class:`~brainpainter.rendering.geometry.SceneGeometry` stores it per part.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template


def convexity(vertices: NDArray[Any], faces: NDArray[Any], iterations: int = 60) -> NDArray[Any]:
    """Sulcal depth from the mesh alone: how far each vertex lies inside a smoothed copy.

    The surface is smoothed by `iterations` steps of uniform Laplacian
    averaging (a few millimetres on a template mesh, about a gyrus wide); the
    displacement of each vertex from its smoothed position along the normal
    is positive on gyral crowns and negative in sulci, like FreeSurfer's
    ``sulc`` with the opposite sign.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    iterations : int

    Returns
    -------
    ndarray of float32, shape (n_vertices,)
        0 on the outer 30 % (crowns), rising to 1 at the deepest 3 % of sulci.
    """
    from scipy import sparse

    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(v)
    if not len(f):
        return np.zeros(n, np.float32)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    adj = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    adj.data[:] = 1.0
    degree = np.asarray(adj.sum(axis=1)).ravel()
    step = sparse.diags(1.0 / np.maximum(degree, 1)) @ adj
    smooth = v.copy()
    for _ in range(iterations):
        smooth = step @ smooth
    d = np.einsum("ij,ij->i", v - smooth, vertex_normals(v, f).astype(np.float64))
    return _depth_0_1(-d)


def _depth_0_1(depth: NDArray[Any]) -> NDArray[Any]:
    """Map a sulcal-depth measure (larger = deeper) to 0-1 by its 30th and 97th percentiles."""
    lo, hi = np.percentile(depth, [30, 97])
    out: NDArray[Any] = np.clip((depth - lo) / max(hi - lo, 1e-9), 0.0, 1.0).astype(np.float32)
    return out


def template_sulc(template: Template, labels: str, hemi: str, cm: Any) -> NDArray[Any] | None:
    """A per-vertex ``sulc`` (or ``curv``) array the template ships, if any (normalised to 0-1 depth)."""
    raw = getattr(cm, "sulc", None)
    if raw is None:
        entry = template.manifest["labels"][labels]["cortex"][hemi]
        z = template._npz(entry["file"]) if "base" not in entry else {}
        raw = z.get("sulc")
    if raw is None or len(raw) != len(cm.source_vertex):
        return None
    return _depth_0_1(np.asarray(raw, dtype=np.float64))  # FreeSurfer's sulc: sulci positive


def part_sulc(template: Template, labels: str, hemi: str, cm: Any, verts: NDArray[Any],
              with_sulc: bool) -> NDArray[Any]:
    """Sulcal depth per vertex of a cortex part: the template's, else convexity; zeros when unused."""
    if not with_sulc:
        return np.zeros(len(verts), np.float32)
    sulc = template_sulc(template, labels, hemi, cm)
    return sulc if sulc is not None else convexity(cm.vertices.get("pial", verts), cm.faces)
