"""One drawable part of a scene (:class:`PartGeometry`) and how a mesh becomes one.

:class:`~brainpainter.rendering.geometry.SceneGeometry` builds every part of a scene
from these; the palette slots ``0, 1, 2`` are fixed (medial wall, neutral grey, glass).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.mesh_edges import EdgeTable
from brainpainter.rendering.mesh_memo import kept_vertex_normals

#: Colour of subcortical structures that have no colour in the mapping (sRGB).
NEUTRAL_GREY = (0.8, 0.8, 0.8)
#: Colour of the glass brain (sRGB).
GLASS_COLOR = (0.78, 0.80, 0.84)
MEDIAL_SLOT, NEUTRAL_SLOT, GLASS_SLOT = 0, 1, 2
N_FIXED_SLOTS = 3


@dataclass(frozen=True)
class Centrelines:
    """A ``tract`` part's streamlines, for renderers that draw lines (often finer than its tubes).

    Attributes
    ----------
    points : ndarray of float32, shape (n_streamlines, n_points, 3)
        RAS millimetres, along the tubes' centres.
    slots : ndarray of int32, shape (n_streamlines, n_points)
        Palette slot of each point (the colour is interpolated between points).
    radius : float
        Of the tubes, millimetres: a line is drawn ``2 * radius`` wide.
    """

    points: NDArray[Any]
    slots: NDArray[Any]
    radius: float


@dataclass(frozen=True)
class PartGeometry:
    """One drawable part of a scene, indexed, ready for a vertex buffer.

    Renderers upload it once, when the scene loads.

    Attributes
    ----------
    name : str
        ``cortex-lh``, ``cortex-rh``, ``subcortical``, ``glass-lh``, ``glass-rh``,
        ``tracts-lh``, ``tracts-rh``, ``tracts``, ``nodes``, ``edges``.
    kind : {"cortex", "subcortical", "glass", "tract", "node", "edge"}
    hemi : {"lh", "rh"} or None
    vertices : ndarray of float32, shape (n_vertices, 3)
        RAS millimetres.
    normals : ndarray of float32, shape (n_vertices, 3)
        Unit, outward, area-weighted over the surface's faces.
    triangles : ndarray of uint32, shape (n_triangles, 3)
        Counter-clockwise seen from outside.
    palette_index : ndarray of int32, shape (n_vertices,)
        Palette slot of each vertex (equal on the three vertices of a triangle).
    sulc : ndarray of float32, shape (n_vertices,)
        Sulcal depth 0 (crown of a gyrus) to 1 (deep in a sulcus), for
        optional darkening; zeros where unknown, off the cortex, and when the
        scene's lighting does not use it (:data:`brainpainter.rendering.scene.SULC_LIGHTINGS`).
    hull : ndarray of float, shape (n_points, 3)
        Points whose projections bound the part (here its vertices: projecting
        them costs about a millisecond, less than a convex hull, whose import
        alone costs a second at start-up).
    occlusion : ndarray of float32, shape (n_vertices,), or None
        Ambient occlusion baked into the template (1 = open sky, towards 0
        deep in a fold; :mod:`brainpainter.atlas.occlusion`), for the
        renderer's shading; None when the template has none (old templates,
        the glass) or the shading is flat.
    outline : ndarray of float32, shape (m, 2, 3), or None
        Region borders on the part as line segments (RAS millimetres, lifted off the
        surface; :mod:`brainpainter.rendering.borders`), drawn as lines
        ``RenderSettings.outline_width`` pixels wide in the outline colour; None: no outline.
    contour : ndarray of float32, shape (k, 2, 3), or None
        A second map's iso-lines on the part (``--contour``), drawn in the contour's own colour, width
        and style (:meth:`RenderSettings.line`); None: none.
    centrelines : Centrelines or None
        A ``tract`` part's streamlines; a renderer draws either them, as lines of the
        tubes' width, or the tubes (the triangles); None for every other kind.
    edges : EdgeTable or None
        The mesh's edges (:func:`brainpainter.rendering.mesh_edges.edge_table` of its vertices,
        triangles and slots) where they were kept with the part
        (:mod:`brainpainter.rendering.part_cache`); None: a renderer that needs them builds them.
    """

    name: str
    kind: str
    hemi: str | None
    vertices: NDArray[Any]
    normals: NDArray[Any]
    triangles: NDArray[Any]
    palette_index: NDArray[Any]
    sulc: NDArray[Any]
    hull: NDArray[Any]
    occlusion: NDArray[Any] | None = None
    outline: NDArray[Any] | None = None
    centrelines: Centrelines | None = None
    edges: EdgeTable | None = None
    contour: NDArray[Any] | None = None


@dataclass(frozen=True)
class PendingPart:
    """A part not built yet: its name, kind and hemisphere, whether it has faces to draw (False: all
    its regions are hidden, or it built to nothing) and how to build it (None when nothing is left)."""

    name: str
    kind: str
    hemi: str | None
    drawn: bool
    build: Callable[[], PartGeometry | None]


def split_by_label(vertices: NDArray[Any], faces: NDArray[Any], face_slot: NDArray[Any],
                   extra: tuple[NDArray[Any], ...] = ()) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any],
                                                              tuple[NDArray[Any], ...]]:
    """One vertex per (vertex, slot) pair used by `faces`: the indexed mesh a renderer draws.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    face_slot : ndarray of int, shape (n_faces,)
        Palette slot of each face.
    extra : tuple of ndarray, each shape (n_vertices, ...)
        Per-vertex arrays (normals, sulc) carried to the new vertices.

    Returns
    -------
    vertices : ndarray, shape (n_new, 3)
    triangles : ndarray of uint32, shape (n_faces, 3)
    palette_index : ndarray of int32, shape (n_new,)
    extra : tuple of ndarray, each shape (n_new, ...)
    """
    f = np.asarray(faces, dtype=np.int64)
    slot = np.asarray(face_slot, dtype=np.int64)
    n_slots = int(slot.max()) + 1 if len(slot) else 1
    pair = f * n_slots + slot[:, None]
    unique, inverse = np.unique(pair.ravel(), return_inverse=True)
    src, pal = unique // n_slots, unique % n_slots
    return (np.asarray(vertices)[src], inverse.reshape(-1, 3).astype(np.uint32),
            pal.astype(np.int32), tuple(np.asarray(e)[src] for e in extra))


#: Palette slots at most: a renderer's palette is a 2-D texture (the Blender renderer's: 4096 texels
#: a row) whose rows GPUs limit to 16384 (llvmpipe included); a scene needing more is refused with advice.
MAX_SLOTS = 4096 * 16_384


def build_part(name: str, kind: str, hemi: str | None, verts: NDArray[Any], faces: NDArray[Any],
          face_slot: NDArray[Any], sulc: NDArray[Any], *, first_slot: int | None = None,
          ao: NDArray[Any] | None = None, occlusion: bool = True,
          outline: NDArray[Any] | None = None, contour: NDArray[Any] | None = None) -> PartGeometry | None:
    """One part from its mesh and per-face slots (faces of slot -1 are hidden); None when nothing is left.

    With `first_slot` (a per-vertex scene) the mesh is kept as stored and vertex ``i`` gets slot
    ``first_slot + i``; else it is split by slot (:func:`split_by_label`). `ao` (baked occlusion per
    vertex) is dropped when `occlusion` is false (flat shading) or its length does not fit.
    `outline` (border segments, shape (m, 2, 3)) and `contour` (iso-lines, (k, 2, 3)) are kept as given.
    """
    keep = face_slot >= 0
    faces, face_slot = np.asarray(faces)[keep], face_slot[keep]
    if not len(faces):
        return None
    normals = kept_vertex_normals(verts, faces)
    if not occlusion or ao is None or len(ao) != len(verts):
        ao = None  # flat colours stay exact; a template without occlusion draws without it
    per_vertex: tuple[NDArray[Any], ...] = (normals, sulc) if ao is None else (normals, sulc, ao)
    extra: tuple[NDArray[Any], ...]
    if first_slot is not None:
        v, tri, extra = verts, np.asarray(faces, np.uint32), per_vertex
        pal = (first_slot + np.arange(len(verts))).astype(np.int32)
    else:
        v, tri, pal, extra = split_by_label(verts, faces, face_slot, per_vertex)
    return PartGeometry(name, kind, hemi, v.astype(np.float32), extra[0].astype(np.float32),
                        tri, pal, extra[1].astype(np.float32), v,
                        None if ao is None else extra[2].astype(np.float32), outline, contour=contour)


def check_slots(n: int) -> None:
    """Refuse a scene of more palette slots than a palette texture holds (:data:`MAX_SLOTS`)."""
    if n > MAX_SLOTS:
        raise BrainPainterError(
            f"the scene needs {n:,} palette slots (regions, vertices, bundles and along-tract nodes); at "
            f"most {MAX_SLOTS:,} fit a palette texture; give profiles with fewer nodes or fewer bundles.")
