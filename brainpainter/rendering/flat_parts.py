"""The flat maps as parts of a scene: what flat views (``flat-left``, ``flat-right``, ``flat``) draw.

:attr:`brainpainter.rendering.geometry.SceneGeometry.flat_parts` builds them from
:mod:`brainpainter.maps.flat` when a flat view first draws them: parts of kind
``flat`` (``flat-lh``, ``flat-rh``) in the plane z = 0 (RAS, turned into the
template's coordinates), which renderers draw unlit, as they draw any opaque part; around
each sheet a thin grey rim (``flat-lh-rim``, ``flat-rh-rim``: :func:`rim`), so that a region drawn in
the background's colour keeps its edge.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.maps.flat import FlatSheet, check_flat, face_labels, flat_labels, flat_sheet, to_flat
from brainpainter.rendering.parts import MEDIAL_SLOT, NEUTRAL_SLOT, PartGeometry, build_part

#: Width of the grey rim around each flat sheet, millimetres of the sheet (about a pixel at the default size).
RIM_MM = 1.2


def flat_parts(scene: Any, slot_of: Mapping[str, int], vertex_slots: Mapping[str, tuple[int, int]],
               to_ras: NDArray[Any]) -> tuple[PartGeometry, ...]:
    """The flat maps of `scene` as parts of kind ``flat``.

    Per region, a triangle takes its vertices' region (each vertex its nearest
    fsaverage vertex's label in ``scene.labels``) and that region's slot in
    `slot_of` (a label without a slot: the medial wall's). Per vertex
    (``flat-<hemi>`` in `vertex_slots`), sheet vertex ``i`` has slot
    ``vertex_slots["flat-<hemi>"][0] + i``. Either way the triangles of hidden
    regions (``--hide``) are not drawn. Region borders (``--outline``) and
    ``--contour``'s iso-lines are drawn on them as on the cortex; each sheet is
    followed by its grey rim (:func:`rim`, slot ``NEUTRAL_SLOT``).

    Parameters
    ----------
    scene : brainpainter.rendering.scene.Scene
    slot_of : mapping of str to int
        Palette slot of each region key.
    vertex_slots : mapping of str to (int, int)
        A per-vertex scene's first slot and count per part (``flat-lh``: 32492 slots).
    to_ras : ndarray of float, shape (3, 3)
        The template's rotation to RAS.

    Raises
    ------
    BrainPainterError
        For a template not made from fsaverage (:func:`brainpainter.maps.flat.check_flat`).
    """
    from brainpainter.atlas.model import HEMI_PREFIX

    check_flat(scene.template, scene.labels)
    parts: list[PartGeometry] = []
    for hemi in ("lh", "rh"):
        sheet = flat_sheet(hemi)
        names = [HEMI_PREFIX[hemi] + n for n in scene.template.cortex(scene.labels, hemi).label_names]
        per_vertex = f"flat-{hemi}" in vertex_slots
        outlined = scene.settings.outline_width > 0
        hidden = np.asarray([k in scene.hidden for k in names], bool)
        needs_labels = outlined or hidden.any() or not per_vertex  # a map: for borders and --hide only
        labels = (flat_labels(scene.template, scene.labels, hemi) if needs_labels
                  else np.zeros(len(sheet.vertices), np.int64))
        if per_vertex:  # vertex i of the sheet is slot first + i
            sheet_vertices, faces = sheet.vertices, sheet.faces
            label_of_face = face_labels(faces, labels)
            face_slot = np.where(hidden[label_of_face], -1, MEDIAL_SLOT).astype(np.int64)
        else:  # regions meet half-way between vertices of two labels
            sheet_vertices, faces, label_of_face = split_at_borders(sheet.vertices, sheet.faces, labels)
            slot = [-1 if k in scene.hidden else slot_of.get(k, MEDIAL_SLOT) for k in names]
            face_slot = np.asarray(slot, np.int64)[label_of_face]
        verts = sheet_vertices @ to_ras  # the template's coordinates (the camera turns them back)
        outline = contour = None
        if outlined:
            outline, contour = _borders(scene, sheet, verts, faces, labels, label_of_face, per_vertex, to_ras)
        part = build_part(f"flat-{hemi}", "flat", hemi, verts, faces, face_slot,
                          np.zeros(len(verts), np.float32), occlusion=False, outline=outline, contour=contour,
                          first_slot=vertex_slots[f"flat-{hemi}"][0] if per_vertex else None)
        if part is not None:
            drawn = np.unique(faces[face_slot >= 0])  # the hull: the sheet drawn, not its cuts
            parts.append(replace(part, hull=sheet_vertices[drawn] @ to_ras))
        rim_vertices, rim_faces = rim(sheet.vertices, sheet.faces, RIM_MM)
        edge = build_part(f"flat-{hemi}-rim", "flat", hemi, rim_vertices @ to_ras, rim_faces,
                          np.full(len(rim_faces), NEUTRAL_SLOT, np.int64),
                          np.zeros(len(rim_vertices), np.float32), occlusion=False)
        if edge is not None:
            parts.append(replace(edge, hull=rim_vertices @ to_ras))
    return tuple(parts)


def rim(vertices: NDArray[Any], faces: NDArray[Any], width: float) -> tuple[NDArray[Any], NDArray[Any]]:
    """A band of `width` just outside the boundary of a flat mesh (its outer edge and its cuts).

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
        In the plane z = 0.
    faces : ndarray of int, shape (m, 3)
        Counter-clockwise seen from +z.
    width : float

    Returns
    -------
    vertices : ndarray of float32, shape (2 k, 3)
        The k boundary vertices, then each moved outwards, mitred so that the band is `width` wide
        along its edges.
    faces : ndarray of int64, shape (2 b, 3)
        Two triangles per boundary edge, counter-clockwise seen from +z.
    """
    f = np.asarray(faces, np.int64)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])  # interior on the left of a -> b
    key = np.sort(edges, axis=1)
    _, inverse, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = edges[count[inverse.ravel()] == 1]
    if not len(boundary):
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int64)
    ring, local = np.unique(boundary, return_inverse=True)
    local = local.reshape(-1, 2)
    xy = np.asarray(vertices, np.float64)[ring, :2]
    d = xy[local[:, 1]] - xy[local[:, 0]]
    outward = np.column_stack([d[:, 1], -d[:, 0]]) / np.maximum(np.linalg.norm(d, axis=1), 1e-12)[:, None]
    mean = np.zeros_like(xy)
    np.add.at(mean, local[:, 0], outward)
    np.add.at(mean, local[:, 1], outward)
    mean /= np.bincount(local.ravel(), minlength=len(ring))[:, None]
    # a mitred corner: the band `width` wide along both edges (at most twice that at a sharp corner)
    outer = xy + width * mean / np.maximum((mean ** 2).sum(axis=1), 0.25)[:, None]
    k = len(ring)
    a, b = local[:, 0], local[:, 1]
    band = np.concatenate([np.stack([b, a, a + k], 1), np.stack([b, a + k, b + k], 1)])
    flat = np.zeros((2 * k, 3), np.float32)
    flat[:, :2] = np.concatenate([xy, outer])
    return flat, band


def split_at_borders(vertices: NDArray[Any], faces: NDArray[Any], vertex_label: NDArray[Any]
                     ) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """Triangles whose vertices have two or three labels, split through their edges' midpoints (and
    centroid), so that each piece has one label and the regions meet half-way between vertices (not
    along a zigzag of whole triangles).

    Parameters
    ----------
    vertices : ndarray of float, shape (n, 3)
    faces : ndarray of int, shape (m, 3)
        Counter-clockwise; the pieces keep the winding.
    vertex_label : ndarray of int, shape (n,)

    Returns
    -------
    vertices : ndarray of float32, shape (n + k, 3)
        The midpoints of the edges between two labels and the centroids of three-label triangles after
        the given vertices (whose indices stay).
    faces : ndarray of int64, shape (m', 3)
    face_label : ndarray of int64, shape (m',)
    """
    v, f = np.asarray(vertices, np.float32), np.asarray(faces, np.int64)
    lab = np.asarray(vertex_label)[f]
    same = np.stack([lab[:, 0] == lab[:, 1], lab[:, 1] == lab[:, 2], lab[:, 2] == lab[:, 0]], axis=1)
    n_same = same.sum(axis=1)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    key = edges[:, 0] * len(v) + edges[:, 1]
    cut = np.unique(key[np.asarray(vertex_label)[edges[:, 0]] != np.asarray(vertex_label)[edges[:, 1]]])

    def mid(a: NDArray[Any], b: NDArray[Any]) -> NDArray[Any]:
        out: NDArray[Any] = len(v) + np.searchsorted(cut, np.minimum(a, b) * len(v) + np.maximum(a, b))
        return out

    mids = (v[cut // len(v)] + v[cut % len(v)]) / 2
    pieces, labels = [f[n_same == 3]], [lab[n_same == 3, 0]]
    two = f[n_same == 1]
    rot = np.argmax(same[n_same == 1], axis=1)  # the pair (0,1), (1,2) or (2,0): the odd vertex follows it
    idx = np.stack([rot, (rot + 1) % 3, (rot + 2) % 3], axis=1)
    p, q, r = (np.take_along_axis(two, idx[:, [k]], axis=1)[:, 0] for k in range(3))
    mqr, mrp = mid(q, r), mid(r, p)
    pieces += [np.stack([p, q, mqr], 1), np.stack([p, mqr, mrp], 1), np.stack([mrp, mqr, r], 1)]
    labels += [lab[n_same == 1][np.arange(len(two)), rot]] * 2 + [np.asarray(vertex_label)[r]]
    three = f[n_same == 0]
    g = len(v) + len(cut) + np.arange(len(three))
    a, b, c = three.T
    mab, mbc, mca = mid(a, b), mid(b, c), mid(c, a)
    for corner, m_in, m_out in ((a, mab, mca), (b, mbc, mab), (c, mca, mbc)):
        pieces += [np.stack([corner, m_in, g], 1), np.stack([corner, g, m_out], 1)]
        labels += [np.asarray(vertex_label)[corner]] * 2
    centroids = v[three].mean(axis=1)
    return (np.concatenate([v, mids.astype(np.float32), centroids.astype(np.float32)]),
            np.concatenate(pieces), np.concatenate(labels).astype(np.int64))


def _borders(scene: Any, sheet: FlatSheet, verts: NDArray[Any], faces: NDArray[Any], labels: NDArray[Any],
             label_of_face: NDArray[Any], per_vertex: bool,
             to_ras: NDArray[Any]) -> tuple[NDArray[Any] | None, NDArray[Any] | None]:
    """Region borders and ``--contour``'s iso-lines on a flat sheet (`verts`, `faces`: as drawn), lifted
    towards the camera (+z), each in its own line style (dashed where asked)."""
    from brainpainter.rendering.borders import dashed, face_borders, iso_lines, vertex_borders

    normals = np.tile(np.asarray([0.0, 0.0, 1.0]) @ to_ras, (len(verts), 1))
    s = scene.settings
    if not per_vertex:
        regions = face_borders(verts, faces, label_of_face, normals)
        return (dashed(regions) if s.outline_style == "dashed" else regions), None
    contours = getattr(scene, "contours", None)
    contour = None
    if contours is not None:
        lines = ([iso_lines(verts, sheet.faces, to_flat(contours.values[sheet.hemi], sheet.hemi), level,
                            normals) for level in contours.levels] if sheet.hemi in contours.values else [])
        contour = np.concatenate(lines) if lines else np.zeros((0, 2, 3), np.float32)
        contour = dashed(contour) if s.contour_style == "dashed" else contour
        if not contours.regions:
            return None, contour
    regions = vertex_borders(verts, sheet.faces, labels, normals)
    return (dashed(regions) if s.outline_style == "dashed" else regions), contour
