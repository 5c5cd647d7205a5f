"""Cycles path: build Blender objects once from core's geometry (``scene.geometry``).

Each part (cortex of each hemisphere, subcortical structures, glass hulls)
becomes one mesh object with one material per palette slot it uses and
per-polygon material indices, so recolouring an image only changes material
colours. Normals are core's (smooth across region borders, where core stores
a vertex once per region). Hidden regions have no faces in the geometry.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from brainpainter.rendering.geometry import PartGeometry
from brainpainter.rendering.scene import Scene
from brainpainter_blender import materials


@dataclass
class Part:
    """One Blender object and what it shows.

    Attributes
    ----------
    obj : bpy.types.Object
    kind : {"cortex", "subcortical", "glass", "tract"}
    hemi : str or None
    slots : list of (int, bpy.types.Material)
        Palette slot of every material slot, in slot order (empty for glass).
    name : str
        The geometry part's name (``PartGeometry.name``).
    """

    obj: object
    kind: str
    hemi: str | None
    slots: list[tuple[int, object]] = field(default_factory=list)
    name: str = ""


def mesh_object(bpy, name: str, vertices: np.ndarray, faces: np.ndarray,
                material_index: np.ndarray | None, mats: list, collection,
                normals: np.ndarray | None = None):
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
    normals : ndarray of float, shape (n_vertices, 3), optional
        Custom vertex normals; smooth shading either way.
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
    mesh.shade_smooth()
    if normals is not None and n_faces:
        mesh.normals_split_custom_set_from_vertices(np.asarray(normals, dtype=np.float64).tolist())
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def _part_object(bpy, tag: str, part: PartGeometry, glass_mat, collection) -> Part:
    """An object for one geometry part; opaque parts get one material per palette slot used."""
    tri = part.triangles.astype(np.int64)
    name = f"{tag}:{part.name}"
    if part.kind == "glass":
        obj = mesh_object(bpy, name, part.vertices, tri, None, [glass_mat], collection, part.normals)
        # In Cycles the glass neither shadows nor reflects onto the structures inside.
        obj.visible_shadow = obj.visible_diffuse = obj.visible_glossy = False
        return Part(obj, part.kind, part.hemi, [], part.name)
    face_slot = part.palette_index[tri[:, 0]]
    used, index = np.unique(face_slot, return_inverse=True)
    slots = [(int(s), materials.new_region_material(bpy, f"{tag}:slot{int(s)}")) for s in used]
    obj = mesh_object(bpy, name, part.vertices, tri, index, [m for _, m in slots], collection,
                      part.normals)
    return Part(obj, part.kind, part.hemi, slots, part.name)


def build(bpy, scene: Scene, tag: str, collection) -> list[Part]:
    """Every part of ``scene.geometry`` as an object linked into `collection`, hidden from render.

    Parameters
    ----------
    bpy : module
    scene : brainpainter.rendering.scene.Scene
    tag : str
        Prefix of datablock names (unique per renderer).
    collection : bpy.types.Collection

    Returns
    -------
    list of Part
    """
    glass_mat = materials.new_glass_material(bpy, f"{tag}:glass", scene.settings.glass_opacity)
    parts = [_part_object(bpy, tag, p, glass_mat, collection) for p in scene.geometry.parts]
    for part in parts:
        part.obj.hide_render = True
    return parts
