"""Flat maps: HCP's Colin flat fsLR 32k sheets, and fsaverage data brought onto them.

The views ``flat-left``, ``flat-right`` and ``flat`` draw the cortex on the
flat maps HCP ships (``colin.cerebral.{L,R}.flat.32k_fs_LR.surf.gii``, with
their cuts), built once by ``tools/build_fslr_resampling.py`` into
``brainpainter/data/fslr-flat.npz`` (HCP's notice in
``fslr-fsaverage.LICENSE.txt``). The sheets lie in the plane z = 0, in
millimetres, the left one left of the right one (x < 0), anterior up (+y).

Each sheet vertex is an fsLR 32k vertex: an fsLR 32k map is drawn on it as
it is (no resampling). fsaverage data reaches it through the fsLR sphere
deformed to fsaverage: values by barycentric interpolation in the fsaverage
triangle the vertex lies in (the weighted mean of the finite values), labels
from the vertex of largest weight.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.maps.resolution import N_FSAVERAGE, fsaverage_faces, map_mesh, own_vertex_count

if TYPE_CHECKING:
    from brainpainter.maps.inputs import VertexMaps

#: Vertices per hemisphere of a flat sheet (fsLR 32k).
N_FLAT = 32492


@dataclass(frozen=True)
class FlatSheet:
    """One hemisphere's flat map.

    Attributes
    ----------
    hemi : {"lh", "rh"}
    vertices : ndarray of float32, shape (32492, 3)
        Millimetres, z = 0; vertices of no triangle (in the cuts) are kept (fsLR's numbering).
    faces : ndarray of int64, shape (n_faces, 3)
        Counter-clockwise seen from +z.
    fsaverage : ndarray of int64, shape (32492, 3)
        The fsaverage triangle each vertex lies in.
    weights : ndarray of float32, shape (32492, 3)
        Its barycentric weights (rows sum to 1).
    """

    hemi: str
    vertices: NDArray[Any]
    faces: NDArray[Any]
    fsaverage: NDArray[Any]
    weights: NDArray[Any]

    @property
    def nearest(self) -> NDArray[Any]:
        """The fsaverage vertex of largest weight of each sheet vertex, int64 (32492,)."""
        out: NDArray[Any] = self.fsaverage[np.arange(len(self.fsaverage)), self.weights.argmax(axis=1)]
        return out

    @property
    def used(self) -> NDArray[Any]:
        """The vertices of some triangle (the sheet without its cuts), int64 (m,)."""
        out: NDArray[Any] = np.unique(self.faces)
        return out


@cache
def flat_sheet(hemi: str) -> FlatSheet:
    """The flat map of hemisphere `hemi`, loaded once (read-only arrays)."""
    with resources.files("brainpainter").joinpath("data/fslr-flat.npz").open("rb") as fh:
        with np.load(fh) as z:
            xy = z[f"{hemi}_xy"].astype(np.float32) * np.float32(z["xy_scale"])
            sheet = FlatSheet(hemi, np.column_stack([xy, np.zeros(len(xy), np.float32)]),
                              z[f"{hemi}_faces"].astype(np.int64), z[f"{hemi}_fsaverage"].astype(np.int64),
                              z[f"{hemi}_fsaverage_weights"].astype(np.float32) / np.float32(65535))
    for array in (sheet.vertices, sheet.faces, sheet.fsaverage, sheet.weights):
        array.flags.writeable = False
    return sheet


def to_flat(values: NDArray[Any], hemi: str, categorical: bool = False) -> NDArray[Any]:
    """fsaverage values of hemisphere `hemi` on its flat sheet.

    Parameters
    ----------
    values : ndarray, shape (163842,)
        NaN = no value.
    categorical : bool
        Labels: each sheet vertex takes the value of its nearest fsaverage vertex.

    Returns
    -------
    ndarray of float32, shape (32492,)
        The weighted mean of the finite values of the vertex's fsaverage triangle; NaN where it has none.
    """
    sheet = flat_sheet(hemi)
    v = np.asarray(values, np.float32)
    if categorical:
        out: NDArray[Any] = v[sheet.nearest]
        return out
    corner = v[sheet.fsaverage]  # (32492, 3)
    ok = np.isfinite(corner)
    weight = np.where(ok, sheet.weights, 0.0).sum(axis=1)
    total = np.where(ok, sheet.weights * np.where(ok, corner, 0.0), 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean: NDArray[Any] = np.where(weight > 0, total / weight, np.nan).astype(np.float32)
    return mean


def flat_values(maps: VertexMaps, hemi: str, image: int) -> NDArray[Any]:
    """Image `image` of hemisphere `hemi` of `maps` on its flat sheet, float32 (32492,).

    An fsLR 32k map as it is (NaN outside HCP's cortex, as when resampled); any
    other through fsaverage (:func:`to_flat`).
    """
    values = maps.values[hemi][image]
    if maps.space == "fsLR" and len(values) == N_FLAT:
        from brainpainter.maps.fslr import cortex_roi

        own: NDArray[Any] = np.where(cortex_roi(hemi, "32k"), values, np.float32(np.nan)).astype(np.float32)
        return own
    return to_flat(maps.on_fsaverage(hemi, image), hemi, maps.categories is not None)


def check_flat(template: Any, labels: str, what: str = "flat views") -> None:
    """Refuse flat views of a template whose cortex is not made from fsaverage.

    Raises
    ------
    BrainPainterError
        Naming the template and the views it can draw.
    """
    for hemi in ("lh", "rh"):
        if own_vertex_count(template, hemi) is not None:
            raise BrainPainterError(
                f"{what} draw fsaverage's cortex on HCP's flat fsLR maps; template {template.name!r} is "
                "made from another surface (your own or a subject's): draw it in the 3-D views "
                "(lateral-left, medial-left, ...), or leave out --lh-surface/--rh-surface and --template.")
        try:
            map_mesh(template, labels, hemi)
        except BrainPainterError:
            raise BrainPainterError(
                f"{what} draw fsaverage's cortex on HCP's flat fsLR maps; template {template.name!r} is not "
                "made from fsaverage: draw it in the 3-D views (lateral-left, medial-left, ...), or use "
                "the default template (--template fsaverage).") from None


def fsaverage_labels(template: Any, labels: str, hemi: str) -> NDArray[Any]:
    """The label of every fsaverage vertex in label set `labels`, int64 (163842,).

    Indices into the label set's names (``template.cortex(labels, hemi).label_names``);
    a vertex the template's (decimated) mesh leaves out takes the label of a
    neighbour on fsaverage's mesh that has one.
    """
    from brainpainter.maps.outlines import mesh_labels

    check_flat(template, labels)
    mesh = map_mesh(template, labels, hemi)
    per_vertex = mesh_labels(template, labels, hemi, mesh)
    if per_vertex is None:
        raise BrainPainterError(f"template {template.name!r} has no per-vertex labels for {labels!r}, so its "
                                "regions cannot be drawn on the flat maps.")
    sv = np.asarray(mesh.source_vertex, np.int64)
    out = np.full(N_FSAVERAGE, -1, np.int64)
    out[sv[sv >= 0]] = np.asarray(per_vertex, np.int64)[sv >= 0]
    faces = fsaverage_faces()
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    while (out < 0).any():
        todo = (out[edges[:, 0]] < 0) & (out[edges[:, 1]] >= 0)
        if not todo.any():
            out[out < 0] = 0
            break
        out[edges[todo, 0]] = out[edges[todo, 1]]
    return out


def flat_labels(template: Any, labels: str, hemi: str) -> NDArray[Any]:
    """The label of each sheet vertex in label set `labels` (its nearest fsaverage vertex's), (32492,)."""
    out: NDArray[Any] = fsaverage_labels(template, labels, hemi)[flat_sheet(hemi).nearest]
    return out


def face_labels(faces: NDArray[Any], vertex_label: NDArray[Any]) -> NDArray[Any]:
    """One label per triangle from its vertices' labels: the label two of them share, else the first's."""
    lab = np.asarray(vertex_label)[np.asarray(faces, np.int64)]
    out: NDArray[Any] = np.where(lab[:, 1] == lab[:, 2], lab[:, 1], lab[:, 0])
    return out
