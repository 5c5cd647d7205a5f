"""Cortical meshes: one hemisphere split into regions, decimated without cracks.

How region boundaries stay exact
--------------------------------
Every triangle of the FreeSurfer surface goes to exactly one region
(:func:`assign_face_labels`: the label most of its three vertices carry; if
all three differ, the label of its lowest-numbered vertex). Regions are
therefore a partition of one closed mesh: neighbours share their boundary
vertices and the union of all regions has no open edge.

Decimation (:func:`decimate`) runs MeshLab's quadric edge collapse on the
pial surface with only the *region-interior* part selected: faces that touch
a region-boundary edge are left unselected, and MeshLab only moves or removes
vertices whose incident faces are all selected. Boundary vertices therefore
survive untouched, every collapse happens inside one region (so face labels
stay valid), and the boundary polylines are the full-resolution ones. With
``optimalplacement=False`` a collapse keeps one of the two original
vertices, so each surviving vertex is an original FreeSurfer vertex; its
index (carried through MeshLab as vertex quality) is ``source_vertex``, and
the white and inflated surfaces take the same topology with their own
positions at those indices. All of this is checked after every decimation.

Smooth borders
--------------
Faces whose three vertices do not share one label (the faces a region
boundary runs through) are locked as well, so they reach the template
unchanged, and the template stores every vertex's label (``vertex_label``)
beside the whole-face labels. When the template is loaded, core splits
those faces along a smoothed boundary
(:func:`brainpainter.atlas.mesh.split_mesh`, the same code that splits
custom label sets), so borders no longer step along triangles.

Folds
-----
FreeSurfer's fsaverage pial and white surfaces cross themselves in a few
places; after decimation every surface is freed of self-intersections by
local smoothing (:func:`.clean.remove_self_intersections`), which moves a
few hundred vertices by up to a few millimetres and changes no face.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshing import edge_use_counts
from brainpainter.errors import BrainPainterError

#: Added to the face quality of locked faces (a flag MeshLab's selection reads).
_LOCK = float(2**20)


@dataclass(frozen=True)
class LabelledSurface:
    """One hemisphere, one label set, all surfaces, in one topology.

    Attributes
    ----------
    faces : ndarray of int32, shape (n_faces, 3)
    face_label : ndarray of int16, shape (n_faces,)
        Index into `names`.
    names : tuple of str
        Colour-table names (regions and non-regions such as ``"unknown"``).
    colors : ndarray of uint8, shape (n_names, 3)
        Colour-table colours.
    vertices : dict[str, Any] of str to ndarray of float32, shape (n_vertices, 3)
        Positions per surface (``"pial"``, ``"white"``, ``"inflated"``).
    source_vertex : ndarray of int32, shape (n_vertices,)
        Index of each vertex in the full-resolution surface.
    n_source_faces : int
        Face count before decimation.
    vertex_label : ndarray of int16, shape (n_vertices,)
        Index into `names` per vertex (the full-resolution vertex's label).
    boundary_t : ndarray of float32, shape (n_crossing_edges,)
        Where the border crosses each label-crossing edge
        (:func:`brainpainter.atlas.mesh.smooth_crossings`), stored so that
        loading the template only has to split.
    sulc : ndarray of float32, shape (n_vertices,), or None
        Sulcal depth per vertex, when given.
    self_intersections : dict[str, Any] of str to (int, int)
        Per surface: self-intersecting faces before and after cleaning.
    """

    faces: NDArray[Any]
    face_label: NDArray[Any]
    names: tuple[str, ...]
    colors: NDArray[Any]
    vertices: dict[str, NDArray[Any]]
    source_vertex: NDArray[Any]
    n_source_faces: int
    vertex_label: NDArray[Any]
    boundary_t: NDArray[Any]
    sulc: NDArray[Any] | None = None
    self_intersections: dict[str, tuple[int, int]] | None = None


def assign_face_labels(faces: NDArray[Any], vertex_labels: NDArray[Any]) -> NDArray[Any]:
    """Give every triangle one label: the majority of its vertex labels.

    Parameters
    ----------
    faces : ndarray of int, shape (n_faces, 3)
    vertex_labels : ndarray of int, shape (n_vertices,)

    Returns
    -------
    face_label : ndarray of int64, shape (n_faces,)
        The label shared by at least two of the face's vertices; when all three
        differ, the label of the face's lowest-numbered vertex (deterministic and
        independent of the order in which a face lists its vertices).
    """
    faces = np.asarray(faces, dtype=np.int64)
    lab = np.asarray(vertex_labels, dtype=np.int64)[faces]
    a, b, c = lab[:, 0], lab[:, 1], lab[:, 2]
    lowest = lab[np.arange(len(faces)), np.argmin(faces, axis=1)]
    return np.where((a == b) | (a == c), a, np.where(b == c, b, lowest))


def boundary_vertex_mask(faces: NDArray[Any], face_label: NDArray[Any], n_vertices: int) -> NDArray[Any]:
    """Vertices whose incident faces carry more than one label, shape (n_vertices,)."""
    faces = np.asarray(faces, dtype=np.int64)
    face_label = np.asarray(face_label, dtype=np.int64)
    lo = np.full(n_vertices, np.iinfo(np.int64).max)
    hi = np.full(n_vertices, np.iinfo(np.int64).min)
    for k in range(3):
        np.minimum.at(lo, faces[:, k], face_label)
        np.maximum.at(hi, faces[:, k], face_label)
    boundary: NDArray[np.bool_] = (lo != hi) & (hi >= lo)
    return boundary


def open_edge_count(faces: NDArray[Any]) -> int:
    """Number of edges used by exactly one face (0 for a closed surface)."""
    return int(np.count_nonzero(edge_use_counts(faces) == 1))


def decimate(vertices: NDArray[Any], faces: NDArray[Any], face_label: NDArray[Any],
             target_faces: int, vertex_labels: NDArray[Any] | None = None) -> tuple[
                 NDArray[Any], NDArray[Any], NDArray[Any]]:
    """Quadric decimation that keeps every region boundary vertex in place.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
        Positions that drive the decimation error (the pial surface).
    faces : ndarray of int, shape (n_faces, 3)
    face_label : ndarray of int, shape (n_faces,)
        Non-negative region label of every face.
    target_faces : int
        Wanted face count of the whole mesh. Faces along region boundaries are
        kept, so the result can have more faces than asked when boundaries
        alone need them.
    vertex_labels : ndarray of int, shape (n_vertices,), optional
        Per-vertex labels: faces whose vertices differ are kept unchanged too.

    Returns
    -------
    faces : ndarray of int64, shape (m, 3)
        Indices into `source_vertex`.
    face_label : ndarray of int64, shape (m,)
    source_vertex : ndarray of int64, shape (k,)
        Increasing indices into `vertices` of the kept vertices.
    """
    from brainpainter.atlas.meshing import import_pymeshlab

    pymeshlab = import_pymeshlab()

    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    face_label = np.asarray(face_label, dtype=np.int64)
    n_vertices = len(vertices)
    boundary = boundary_vertex_mask(faces, face_label, n_vertices)
    # Faces along a boundary edge (two boundary vertices) are left out of the
    # selection; every boundary vertex lies on such an edge, so it is locked.
    locked = np.count_nonzero(boundary[faces], axis=1) >= 2
    if vertex_labels is not None:
        lab = np.asarray(vertex_labels, dtype=np.int64)[faces]
        locked |= (lab[:, 0] != lab[:, 1]) | (lab[:, 1] != lab[:, 2])
    quality = face_label.astype(np.float64) + np.where(locked, _LOCK, 0.0)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(
        vertex_matrix=vertices, face_matrix=faces.astype(np.int32),
        v_scalar_array=np.arange(n_vertices, dtype=np.float64), f_scalar_array=quality))
    ms.compute_selection_by_condition_per_face(condselect=f"fq < {_LOCK / 2:.1f}")
    n_locked = int(np.count_nonzero(locked))
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=max(int(target_faces) - n_locked, 1),  # counts the selected faces only
        selected=True, optimalplacement=False, preservenormal=True, preservetopology=True,
        planarquadric=True, qualitythr=0.3, autoclean=True)
    mesh = ms.current_mesh()
    if not mesh.is_compact():
        mesh.compact()
    out_faces = np.asarray(mesh.face_matrix(), dtype=np.int64)
    src_f = np.asarray(mesh.vertex_scalar_array(), dtype=np.float64)
    out_label = np.asarray(mesh.face_scalar_array(), dtype=np.float64) % _LOCK
    source = np.rint(src_f).astype(np.int64)
    # The claims in the module docstring, checked on every run.
    if (not np.array_equal(source, src_f) or len(np.unique(source)) != len(source)
            or source.min(initial=0) < 0 or source.max(initial=0) >= n_vertices):
        raise BrainPainterError("decimation lost track of the original vertex indices")
    if not np.array_equal(np.asarray(mesh.vertex_matrix()), vertices[source]):
        raise BrainPainterError("decimation moved a vertex off its original position")
    if not np.isin(np.flatnonzero(boundary), source).all():
        raise BrainPainterError("decimation removed a region-boundary vertex")
    # Renumber so that vertices come in increasing source order (deterministic).
    order = np.argsort(source, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank[out_faces], np.rint(out_label).astype(np.int64), source[order]


def canonical_faces(faces: NDArray[Any], face_label: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
    """Sort faces by label, then by vertex, each rotated to start at its lowest vertex.

    Rotation keeps the winding; the order makes each region a contiguous run
    of faces and makes the files compress better and byte-identical per build.
    """
    faces = np.asarray(faces, dtype=np.int64)
    rot = np.argmin(faces, axis=1)
    idx = np.arange(len(faces))
    faces = np.stack([faces[idx, (rot + k) % 3] for k in range(3)], axis=1)
    order = np.lexsort((faces[:, 2], faces[:, 1], faces[:, 0], face_label))
    return faces[order], np.asarray(face_label)[order]


def build_labelled_surface(surfaces: dict[str, tuple[NDArray[Any], NDArray[Any]]],
                           vertex_labels: NDArray[Any], names: tuple[str, ...], ctab: NDArray[Any],
                           target_faces: int | None,
                           offsets: dict[str, NDArray[Any]] | None = None,
                           sulc: NDArray[Any] | None = None,
                           clean: bool = True) -> LabelledSurface:
    """Split one hemisphere by one label set and decimate it on the pial surface.

    Parameters
    ----------
    surfaces : dict[str, Any] of str to (vertices (n, 3), faces (m, 3))
        Full-resolution surfaces of one hemisphere; must include ``"pial"``
        and all must share the pial faces.
    vertex_labels : ndarray of int, shape (n,)
        Index into `names` per vertex.
    names : tuple of str
    ctab : ndarray of int, shape (len(names), >=3)
    target_faces : int or None
        Faces wanted per hemisphere; None keeps full resolution.
    offsets : dict[str, Any] of str to ndarray, shape (3,), optional
        Translation added to a surface (the inflated hemisphere offset).
    sulc : ndarray of float, shape (n,), optional
        Sulcal depth per full-resolution vertex (``surf/?h.sulc``).
    clean : bool
        Remove self-intersections of every surface (:mod:`.clean`).
    """
    from brainpainter.atlas.mesh import smooth_crossings
    from brainpainter_builder.clean import remove_self_intersections

    pial_v, faces = surfaces["pial"]
    vertex_labels = np.asarray(vertex_labels)
    labels = assign_face_labels(faces, vertex_labels)
    if target_faces is not None and target_faces < len(faces):
        out_faces, out_label, source = decimate(pial_v, faces, labels, target_faces, vertex_labels)
    else:
        out_faces, out_label, source = faces, labels, np.arange(len(pial_v), dtype=np.int64)
    out_faces, out_label = canonical_faces(out_faces, out_label)
    offsets = offsets or {}
    vertices = {}
    crossings = {}
    for name, (v, _) in surfaces.items():
        pos = v[source].astype(np.float64)
        if clean:
            cleaned = remove_self_intersections(pos, out_faces)
            pos, crossings[name] = cleaned.vertices, (cleaned.before, cleaned.after)
        vertices[name] = (pos + np.asarray(offsets.get(name, 0.0), dtype=np.float64)).astype(np.float32)
    return LabelledSurface(
        faces=out_faces.astype(np.int32),
        face_label=out_label.astype(np.int16),
        names=tuple(names),
        colors=np.asarray(ctab, dtype=np.int64)[:, :3].clip(0, 255).astype(np.uint8),
        vertices=vertices,
        source_vertex=source.astype(np.int32),
        n_source_faces=len(faces),
        vertex_label=vertex_labels[source].astype(np.int16),
        boundary_t=smooth_crossings(out_faces, vertex_labels[source]).astype(np.float32),
        sulc=None if sulc is None else np.asarray(sulc, dtype=np.float32)[source],
        self_intersections=crossings if clean else None,
    )


def inflated_offsets(lh_inflated: NDArray[Any], rh_inflated: NDArray[Any],
                     gap: float = 10.0) -> dict[str, NDArray[Any]]:
    """x translations that put the inflated hemispheres side by side.

    The left hemisphere ends at ``x = -gap / 2`` and the right one starts at
    ``x = +gap / 2``, so they never overlap when drawn together.

    Returns
    -------
    dict of {"lh", "rh"} to ndarray of float64, shape (3,)
    """
    return {
        "lh": np.array([-gap / 2 - float(np.max(lh_inflated[:, 0])), 0.0, 0.0]),
        "rh": np.array([gap / 2 - float(np.min(rh_inflated[:, 0])), 0.0, 0.0]),
    }
