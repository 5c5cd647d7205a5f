"""Outlines over a map: cluster borders (``--outline-threshold``), the label lookups of ``--outline``,
and the iso-lines of a second map (``--contour``: :class:`Contours`).

An atlas's region borders (``--outline ATLAS``) are drawn as lines of constant pixel
width through the scene model (:mod:`brainpainter.rendering.borders`,
``PartGeometry.outline``). The borders of the supra-threshold areas change with
every image, so they are drawn per vertex, in the map's own colours: a vertex on
the border takes the outline colour and the renderer's interpolation across
triangles turns the marked vertices into a line about one mesh edge wide. Only one
side of each border is marked (the vertex whose label is the smaller).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Outline colour (sRGB).
OUTLINE_COLOR = (0.05, 0.05, 0.05)


@dataclass(frozen=True)
class Contours:
    """Iso-lines of a second map (``--contour``), drawn at constant pixel width as ``--outline``'s borders.

    Attributes
    ----------
    values : dict of str to ndarray of float32, shape (163842,)
        The map on fsaverage, per hemisphere it covers.
    levels : tuple of float
        The values whose iso-lines are drawn (a mask's edge: 0.5; a p-map: 0.05).
    regions : bool
        Whether the atlas's region borders (``--outline``) are drawn too.
    """

    values: dict[str, NDArray[Any]] = field(repr=False)
    levels: tuple[float, ...]
    regions: bool = False


def mesh_edges(faces: NDArray[Any]) -> NDArray[Any]:
    """Unique undirected edges of a triangle mesh, int64 (m, 2), smaller index first."""
    f = np.asarray(faces, np.int64)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    e.sort(axis=1)
    if not len(e):
        empty: NDArray[Any] = e.reshape(0, 2)
        return empty
    # one int64 key per edge, ordered as the rows (a, b): a 1-D unique is ~50x faster than axis=0
    n = int(e.max()) + 1
    key = np.unique(e[:, 0] * n + e[:, 1])
    unique: NDArray[Any] = np.stack([key // n, key % n], axis=1)
    return unique


def border_vertices(labels: NDArray[Any], edges: NDArray[Any]) -> NDArray[Any]:
    """Vertices on a border between two labels (one side only: the smaller label), bool (n,).

    Parameters
    ----------
    labels : ndarray, shape (n,)
        A label (or a 0/1 mask) per vertex.
    edges : ndarray of int, shape (m, 2)
    """
    lab = np.asarray(labels)
    a, b = lab[edges[:, 0]], lab[edges[:, 1]]
    differ = a != b
    mark = np.zeros(len(lab), bool)
    low = np.where(a < b, edges[:, 0], edges[:, 1])[differ]
    mark[low] = True
    return mark


def mesh_labels(template: Any, labels: str, hemi: str, mesh: Any) -> NDArray[Any] | None:
    """The label of each vertex of `mesh` (the map mesh of label set `labels`), or None if unknown."""
    from brainpainter.atlas.mesh import labels_at_vertices

    entry = template.manifest["labels"][labels]["cortex"].get(hemi)
    if entry is None:
        return None
    z = template._npz(entry["file"])
    if "base" not in entry and "vertex_label" in z and len(z["vertex_label"]) == len(mesh.source_vertex):
        return np.asarray(z["vertex_label"])
    if "source_label" in z:
        return np.asarray(labels_at_vertices(z["source_label"], mesh))
    if "vertex_label" in z and len(z["vertex_label"]) == len(mesh.source_vertex):
        return np.asarray(z["vertex_label"])
    return None
