"""Build Blender objects from a template once: cortex, subcortical structures, glass.

Each hemisphere's cortex is one mesh object with one material slot per
region and per-polygon material indices from the template's ``face_label``,
so neighbouring regions share vertices (no cracks) and recolouring an image
only changes material colours. Faces of hidden regions are dropped here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from brainpainter.atlas import HEMI_PREFIX
from brainpainter.scene import Scene
from brainpainter.template import HEMIS
from brainpainter_blender import materials


@dataclass
class Part:
    """One Blender object and what it shows.

    Attributes
    ----------
    obj : bpy.types.Object
    kind : {"cortex", "subcortical", "glass"}
    hemi : str or None
    slots : list of (str, bpy.types.Material)
        Region key of every material slot, in slot order (empty for glass).
    """

    obj: object
    kind: str
    hemi: str | None
    slots: list[tuple[str, object]] = field(default_factory=list)


def mesh_object(bpy, name: str, vertices: np.ndarray, faces: np.ndarray,
                material_index: np.ndarray | None, mats: list, collection,
                smooth: bool = True):
    """A triangle-mesh object built with ``foreach_set`` (fast for 10^5 faces).

    Parameters
    ----------
    bpy : module
    name : str
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    material_index : ndarray of int, shape (n_faces,), or None
        Slot of each face in `mats`.
    mats : list of bpy.types.Material
    collection : bpy.types.Collection
        Where the object is linked.
    smooth : bool
        Smooth (vertex-normal) shading.
    """
    faces = np.ascontiguousarray(faces, dtype=np.int32)
    n_faces = len(faces)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, dtype=np.float32).ravel())
    mesh.loops.add(3 * n_faces)
    mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(n_faces)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n_faces, 3, dtype=np.int32))
    for mat in mats:
        mesh.materials.append(mat)
    if material_index is not None and n_faces:
        mesh.polygons.foreach_set("material_index", np.ascontiguousarray(material_index, np.int32))
    mesh.update(calc_edges=True)
    if smooth:
        mesh.shade_smooth()
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def _labelled_part(bpy, tag: str, kind: str, hemi: str | None, vertices: np.ndarray,
                   faces: np.ndarray, face_label: np.ndarray, keys: list[str],
                   hidden: frozenset[str], collection) -> Part | None:
    """An object for labelled faces, one material per label actually used."""
    keep = np.array([k not in hidden for k in keys], dtype=bool)
    face_label = np.asarray(face_label, dtype=np.int64)
    mask = keep[face_label] if len(keys) else np.zeros(len(faces), bool)
    faces, face_label = faces[mask], face_label[mask]
    if not len(faces):
        return None
    used = np.unique(face_label)
    slot_of = np.full(len(keys), -1, dtype=np.int64)
    slot_of[used] = np.arange(len(used))
    slots = [(keys[i], materials.new_region_material(bpy, f"{tag}:{keys[i]}")) for i in used]
    name = f"{tag}:{kind}" + (f"-{hemi}" if hemi else "")
    obj = mesh_object(bpy, name, vertices, faces, slot_of[face_label],
                      [m for _, m in slots], collection)
    return Part(obj, kind, hemi, slots)


def build(bpy, scene: Scene, tag: str, collection) -> list[Part]:
    """Every object of `scene`, linked into `collection`, all hidden from render.

    Parameters
    ----------
    bpy : module
    scene : brainpainter.scene.Scene
    tag : str
        Prefix of datablock names (unique per renderer).
    collection : bpy.types.Collection

    Returns
    -------
    list of Part
    """
    template, hidden = scene.template, frozenset(scene.hidden)
    parts: list[Part] = []
    for hemi in HEMIS:
        cm = template.cortex(scene.labels, hemi)
        if scene.surface not in cm.vertices:
            from brainpainter.errors import choice_error

            raise choice_error("surface", scene.surface, list(cm.vertices),
                               f"Template {template.name!r} lacks it.")
        keys = [HEMI_PREFIX[hemi] + n for n in cm.label_names]
        part = _labelled_part(bpy, tag, "cortex", hemi, cm.vertices[scene.surface], cm.faces,
                              cm.face_label, keys, hidden, collection)
        if part is not None:
            parts.append(part)
    if template.manifest.get("subcortical"):
        sub = template.subcortical()
        part = _labelled_part(bpy, tag, "subcortical", None, sub.vertices, sub.faces,
                              sub.face_label, list(sub.label_names), hidden, collection)
        if part is not None:
            parts.append(part)
    glass_mat = materials.new_glass_material(bpy, f"{tag}:glass", scene.settings.glass_opacity)
    for hemi in HEMIS:
        if hemi not in template.manifest.get("glass", {}):
            continue
        verts, faces = template.glass(hemi)
        obj = mesh_object(bpy, f"{tag}:glass-{hemi}", verts, faces, None, [glass_mat], collection)
        # In Cycles the glass neither shadows nor reflects onto the structures inside.
        obj.visible_shadow = obj.visible_diffuse = obj.visible_glossy = False
        parts.append(Part(obj, "glass", hemi, []))
    for part in parts:
        part.obj.hide_render = True
    return parts
