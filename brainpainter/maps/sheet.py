"""The cortical sheet in MNI152: fsaverage's mesh at its registration-fusion positions.

A volume sampled at one point per vertex (``point``) follows the grey-matter ribbon only as
well as the registration-fusion surface does: that surface is an average over 1490 subjects,
so it weaves in and out of a given template's ribbon by a millimetre or two, and a thin
probability sheet sampled on it breaks into spots a few millimetres apart, low on many crowns.
Averaging over the sheet around each vertex (``ribbon``: :func:`sheet_mean`) or along its
normal (``line``, nilearn's ``vol_to_surf`` default: :func:`line_points`) reads the ribbon
instead of a surface through it.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.maps.regfusion import fsaverage_mni152
from brainpainter.maps.resolution import fsaverage_faces

MIN_FINITE_WEIGHT = 0.5     # a vertex keeps a value when finite samples carry this share of its weight
LINE_POINTS = 10                # samples along a vertex's normal (as nilearn's kind="line")
#: Depths (mm, outwards) of the ``ribbon`` samples: the registration-fusion positions lie in the lower
#: part of the grey matter (ICBM 2009 grey-matter probability peaks 1-2 mm outwards of them on
#: crowns, walls and fundi alike; white-matter probability at the positions 0.26-0.38).
RIBBON_DEPTHS = (0.0, 1.0, 2.0)


@cache
def normals(hemi: str) -> NDArray[np.float64]:
    """Outward unit normals of the registration-fusion surface, shape (163842, 3)."""
    points = fsaverage_mni152()[hemi]
    faces = fsaverage_faces()
    corners = points[faces]
    volume = float(np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum())
    out: NDArray[np.float64] = vertex_normals(points, faces if volume > 0 else faces[:, ::-1], np.float64)
    out.flags.writeable = False
    return out


def depths(projection: str, radius: float) -> NDArray[np.float64]:
    """Offsets (mm) along the outward normal at which `projection` samples a vertex: ``line``,
    :data:`LINE_POINTS` from ``-radius`` to ``+radius``; ``ribbon``, :data:`RIBBON_DEPTHS`."""
    if projection == "line":
        return np.linspace(-radius, radius, LINE_POINTS)
    return np.asarray(RIBBON_DEPTHS if projection == "ribbon" else (0.0,), np.float64)


def along_normals(hemi: str, offsets: NDArray[np.float64]) -> NDArray[np.float64]:
    """Every vertex's position moved `offsets` mm along its outward normal.

    Returns
    -------
    ndarray, shape (len(offsets), 163842, 3)
        MNI152 mm.
    """
    steps = np.asarray(offsets, np.float64)[:, None, None]
    out: NDArray[np.float64] = fsaverage_mni152()[hemi][None] + steps * normals(hemi)[None]
    return out


@cache
def _neighbour_mean(hemi: str) -> tuple[Any, float]:
    """The operator that replaces a value by the mean of its vertex and its neighbours (sparse,
    shape (163842, 163842)), and the surface's RMS edge length (mm)."""
    import scipy.sparse as sp

    points = fsaverage_mni152()[hemi]
    f = fsaverage_faces()
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])   # each edge once each way
    n = len(points)
    adjacency = sp.csr_matrix((np.ones(len(edges), np.float32), (edges[:, 0], edges[:, 1])), shape=(n, n))
    adjacency = adjacency + sp.identity(n, np.float32, format="csr")
    step = sp.diags(1.0 / np.asarray(adjacency.sum(axis=1), np.float32).ravel()) @ adjacency
    length = float(np.sqrt(np.mean(np.sum((points[edges[:, 0]] - points[edges[:, 1]]) ** 2, axis=1))))
    return step.tocsr(), length


def sheet_steps(hemi: str, radius: float) -> int:
    """Neighbour-averaging steps whose samples lie `radius` mm (RMS) from the vertex on the sheet.

    A step keeps a vertex with weight 1/7 and moves to each of its ~6 neighbours (one edge, ``e``
    mm) with 1/7, so ``k`` steps spread over ``e * sqrt(6 k / 7)`` mm RMS.
    """
    _, length = _neighbour_mean(hemi)
    return max(1, round((radius / length) ** 2 * 7.0 / 6.0))


def sheet_mean(values: NDArray[np.float32], hemi: str, radius: float) -> NDArray[np.float32]:
    """Each vertex's mean over the cortical sheet within about `radius` mm around it.

    Parameters
    ----------
    values : ndarray of float32, shape (k, 163842)
        Point samples (k volumes); NaN where there is none.
    hemi : {"lh", "rh"}
    radius : float
        RMS distance (mm) along the surface of the samples that make a vertex's value.

    Returns
    -------
    ndarray of float32, shape (k, 163842)
        NaN where the vertex's own sample is NaN, or where finite samples carry less than half
        of its weight.
    """
    step, _ = _neighbour_mean(hemi)
    finite = np.isfinite(values)
    k = len(values)
    both = np.concatenate([np.where(finite, values, np.float32(0)), finite]).T.astype(np.float32)
    for _ in range(sheet_steps(hemi, radius)):
        both = step @ both           # the values and their weights, spread together
    total, weight = both[:, :k], both[:, k:]
    enough = (weight >= MIN_FINITE_WEIGHT) & finite.T
    out: NDArray[np.float32] = np.full(total.shape, np.nan, np.float32)
    out[enough] = total[enough] / weight[enough]
    return np.ascontiguousarray(out.T)
