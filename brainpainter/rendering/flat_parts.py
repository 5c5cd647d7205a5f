"""The flat maps as parts of a scene: what flat views (``flat-left``, ``flat-right``, ``flat``) draw.

:attr:`brainpainter.rendering.geometry.SceneGeometry.flat_parts` builds them from
:mod:`brainpainter.maps.flat` when a flat view first draws them: parts of kind
``flat`` (``flat-lh``, ``flat-rh``) in the plane z = 0 (RAS, turned into the
template's coordinates), which renderers draw unlit, as they draw any opaque part.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.maps.flat import FlatSheet, check_flat, face_labels, flat_labels, flat_sheet, to_flat
from brainpainter.rendering.parts import MEDIAL_SLOT, PartGeometry, build_part


def flat_parts(scene: Any, slot_of: Mapping[str, int], vertex_slots: Mapping[str, tuple[int, int]],
               to_ras: NDArray[Any]) -> tuple[PartGeometry, ...]:
    """The flat maps of `scene` as parts of kind ``flat``.

    Per region, a triangle takes its vertices' region (each vertex its nearest
    fsaverage vertex's label in ``scene.labels``) and that region's slot in
    `slot_of` (hidden regions: not drawn; a label without a slot: the medial
    wall's). Per vertex (``flat-<hemi>`` in `vertex_slots`), sheet vertex ``i``
    has slot ``vertex_slots["flat-<hemi>"][0] + i``. Region borders
    (``--outline``) and ``--contour``'s iso-lines are drawn on them as on the cortex.

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
        verts = sheet.vertices @ to_ras  # the template's coordinates (the camera turns them back)
        names = [HEMI_PREFIX[hemi] + n for n in scene.template.cortex(scene.labels, hemi).label_names]
        per_vertex = f"flat-{hemi}" in vertex_slots
        outlined = scene.settings.outline_width > 0
        labels = (flat_labels(scene.template, scene.labels, hemi) if outlined or not per_vertex
                  else np.zeros(len(sheet.vertices), np.int64))  # a map's sheet needs labels for borders only
        label_of_face = face_labels(sheet.faces, labels)
        if per_vertex:
            face_slot = np.full(len(sheet.faces), MEDIAL_SLOT, np.int64)
        else:
            slot = [-1 if k in scene.hidden else slot_of.get(k, MEDIAL_SLOT) for k in names]
            face_slot = np.asarray(slot, np.int64)[label_of_face]
        outline = None
        if outlined:
            outline = _borders(scene, sheet, verts, labels, label_of_face, per_vertex, to_ras)
        part = build_part(f"flat-{hemi}", "flat", hemi, verts, sheet.faces, face_slot,
                          np.zeros(len(verts), np.float32), occlusion=False, outline=outline,
                          first_slot=vertex_slots[f"flat-{hemi}"][0] if per_vertex else None)
        if part is not None:
            drawn = np.unique(sheet.faces[face_slot >= 0])  # the hull: the sheet drawn, not its cuts
            parts.append(replace(part, hull=sheet.vertices[drawn] @ to_ras))
    return tuple(parts)


def _borders(scene: Any, sheet: FlatSheet, verts: NDArray[Any], labels: NDArray[Any],
             label_of_face: NDArray[Any], per_vertex: bool, to_ras: NDArray[Any]) -> NDArray[Any]:
    """Region borders and ``--contour``'s iso-lines on a flat sheet, lifted towards the camera (+z)."""
    from brainpainter.rendering.borders import face_borders, iso_lines, vertex_borders

    normals = np.tile(np.asarray([0.0, 0.0, 1.0]) @ to_ras, (len(verts), 1))
    if not per_vertex:
        return face_borders(verts, sheet.faces, label_of_face, normals)
    contours = getattr(scene, "contours", None)
    lines: list[NDArray[np.float32]] = []
    if contours is not None and sheet.hemi in contours.values:
        values = to_flat(contours.values[sheet.hemi], sheet.hemi)
        lines = [iso_lines(verts, sheet.faces, values, level, normals) for level in contours.levels]
    if contours is None or contours.regions:
        lines.append(vertex_borders(verts, sheet.faces, labels, normals))
    return np.concatenate(lines) if lines else np.zeros((0, 2, 3), np.float32)
