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
from brainpainter.maps.resolution import LEVELS, fsaverage_faces, to_fsaverage

MIN_FINITE_WEIGHT = 0.5     # a vertex keeps a value when finite samples carry this share of its weight
FINE_STEPS = 2              # sheet-mean steps on fsaverage before it goes on on fsaverage6
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
def _neighbour_mean(hemi: str, level: int = 7) -> tuple[Any, float]:
    """The operator that replaces a value by the mean of its vertex and its neighbours on the
    family member of `level` (7: fsaverage; sparse, shape (n, n)), and that surface's RMS edge
    length (mm)."""
    import scipy.sparse as sp

    points = fsaverage_mni152()[hemi][:LEVELS[level]]
    f = fsaverage_faces(level)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])   # each edge once each way
    n = len(points)
    adjacency = sp.csr_matrix((np.ones(len(edges), np.float32), (edges[:, 0], edges[:, 1])), shape=(n, n))
    adjacency = adjacency + sp.identity(n, np.float32, format="csr")
    step = sp.diags(1.0 / np.asarray(adjacency.sum(axis=1), np.float32).ravel()) @ adjacency
    length = float(np.sqrt(np.mean(np.sum((points[edges[:, 0]] - points[edges[:, 1]]) ** 2, axis=1))))
    return step.tocsr(), length


def sheet_steps(hemi: str, radius: float) -> tuple[int, int]:
    """Neighbour-averaging steps on fsaverage, then on fsaverage6, whose samples lie `radius` mm
    (RMS) from the vertex along the sheet.

    A step keeps a vertex with weight 1/7 and moves to each of its ~6 neighbours (one edge, ``e``
    mm) with 1/7, so ``k`` steps spread over ``e * sqrt(6 k / 7)`` mm RMS. After
    :data:`FINE_STEPS` steps on fsaverage the spread goes on on fsaverage6 (a quarter of the
    vertices, edges twice as long: 1/16 of the work for the same spread), then back by linear
    interpolation (:func:`brainpainter.maps.resolution.to_fsaverage`).
    """
    _, fine = _neighbour_mean(hemi)
    steps = max(1, round((radius / fine) ** 2 * 7.0 / 6.0))
    if steps <= FINE_STEPS + 2:
        return steps, 0
    _, coarse = _neighbour_mean(hemi, 6)
    rest = radius ** 2 - FINE_STEPS * fine ** 2 * 6.0 / 7.0
    return FINE_STEPS, max(1, round(rest / coarse ** 2 * 7.0 / 6.0))


def _spread(columns: NDArray[np.float32], hemi: str, radius: float) -> NDArray[np.float32]:
    """`columns`, shape (163842, c), each averaged over the sheet (:func:`sheet_steps`)."""
    fine_steps, coarse_steps = sheet_steps(hemi, radius)
    step, _ = _neighbour_mean(hemi)
    for _ in range(fine_steps):
        columns = step @ columns
    if coarse_steps:
        step, _ = _neighbour_mean(hemi, 6)
        columns = columns[:LEVELS[6]]
        for _ in range(coarse_steps):
            columns = step @ columns
        columns = to_fsaverage(np.ascontiguousarray(columns.T)).T
    return columns


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
    finite = np.isfinite(values)
    k = len(values)
    if finite.all():     # no weights to carry: each step keeps the sum of weights at 1
        return np.ascontiguousarray(_spread(np.ascontiguousarray(values.T, np.float32), hemi, radius).T)
    both = np.concatenate([np.where(finite, values, np.float32(0)), finite]).T.astype(np.float32)
    both = _spread(both, hemi, radius)       # the values and their weights, spread together
    total, weight = both[:, :k], both[:, k:]
    enough = (weight >= MIN_FINITE_WEIGHT) & finite.T
    out: NDArray[np.float32] = np.full(total.shape, np.nan, np.float32)
    out[enough] = total[enough] / weight[enough]
    return np.ascontiguousarray(out.T)
