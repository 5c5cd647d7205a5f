"""Node positions of atlas regions: a point inside each region, from the template's meshes.

A region's centroid is the area-weighted mean of its mesh's triangles. The mean
of a curved sheet of cortex lies below it, often far from the region (a
C-shaped parcel's mean is outside it), so it is pulled towards the region's
nearest vertex until at most :data:`DEPTH` mm (at most a fifth of the region's
radius, for small brains) from it: a node sits in (or just beneath) its region.
A closed structure (subcortical and volume atlas meshes) keeps its mean where
the mean is inside it (winding number above one half).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.atlas.template import Template, load_template, template_for
from brainpainter.errors import BrainPainterError

#: Greatest distance (mm) of a node from the nearest vertex of its region.
DEPTH = 2.0
#: Of a region's RMS radius: the greatest distance in small brains (a mouse's regions).
DEPTH_OF_RADIUS = 0.2


def atlas_template(atlas: Atlas, template: Template | str = "fsaverage") -> Template:
    """The template `atlas` is drawn on, with the label set and volume meshes it brings."""
    if atlas.template_dir is not None and template == "fsaverage":
        template = str(atlas.template_dir)  # an atlas with a brain of its own (volume only)
    return template_for(atlas, template if isinstance(template, Template) else load_template(template))


def _label_faces(faces: NDArray[Any], face_label: NDArray[Any], names: Sequence[str],
                 prefix: str = "") -> dict[str, NDArray[Any]]:
    """Faces of each label, by ``prefix + name``."""
    order = np.argsort(face_label, kind="stable")
    labels = np.asarray(face_label)[order]
    cuts = np.searchsorted(labels, np.arange(len(names) + 1))
    return {prefix + name: faces[order[cuts[i]:cuts[i + 1]]] for i, name in enumerate(names)
            if cuts[i + 1] > cuts[i]}


def _winding(point: NDArray[Any], tri: NDArray[Any]) -> float:
    """Generalised winding number of `point` for triangles `tri` (F, 3, 3): 1 inside a closed mesh."""
    a, b, c = (tri[:, k] - point for k in range(3))
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    div = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la
           + np.einsum("ij,ij->i", c, a) * lb)
    return float(np.arctan2(det, div).sum() / (2 * np.pi))


def centroid(vertices: NDArray[Any], faces: NDArray[Any], closed: bool = False) -> NDArray[np.float64]:
    """A point in a region: its mean, pulled to within the allowed depth of its nearest vertex.

    Parameters
    ----------
    vertices : ndarray, (n_vertices, 3)
    faces : ndarray of int, (n_faces, 3)
        The region's triangles (indices into `vertices`).
    closed : bool
        A closed structure: a mean inside it is kept.

    Returns
    -------
    ndarray, (3,) float64
    """
    tri = np.asarray(vertices, dtype=np.float64)[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    centres = tri.mean(axis=1)
    weight = area if area.sum() > 0 else np.ones(len(area))
    mean: NDArray[np.float64] = (centres * weight[:, None]).sum(axis=0) / weight.sum()
    if closed and _winding(mean, tri) > 0.5:
        return mean
    points = tri.reshape(-1, 3)
    offsets = points - mean
    nearest = points[int(np.argmin(np.einsum("ij,ij->i", offsets, offsets)))]
    radius = float(np.sqrt(np.einsum("ij,ij->i", offsets, offsets).mean()))
    depth = min(DEPTH, DEPTH_OF_RADIUS * radius)
    gap = float(np.linalg.norm(mean - nearest))
    if gap <= depth:
        return mean
    pulled: NDArray[np.float64] = nearest + (mean - nearest) * (depth / gap)
    return pulled


def region_centroids(atlas: Atlas, keys: Sequence[str], template: Template | str = "fsaverage",
                     surface: str = "pial") -> NDArray[np.float64]:
    """A point inside each region of `keys` (:func:`centroid`), in the template's coordinates.

    Parameters
    ----------
    atlas : Atlas
    keys : sequence of str, (N,)
        Region keys of `atlas`; a region group (a BrainGlobe parent) is its members together.
    template : Template or str
        The template the nodes are drawn in (an atlas with a brain of its own: that one).
    surface : {"pial", "white", "inflated"}
        Cortical surface the regions are taken from.

    Returns
    -------
    ndarray, (N, 3) float64

    Raises
    ------
    BrainPainterError
        A region without a mesh in the template.
    """
    tpl = atlas_template(atlas, template)
    cortex: dict[str, tuple[NDArray[Any], NDArray[Any]]] = {}
    for hemi, prefix in (("lh", "Left-"), ("rh", "Right-")):
        if not atlas.cortical(hemi):
            continue
        mesh = tpl.cortex(atlas.template_labels, hemi)
        verts = mesh.vertices[surface] if surface in mesh.vertices else next(iter(mesh.vertices.values()))
        for key, faces in _label_faces(mesh.faces, mesh.face_label, mesh.label_names, prefix).items():
            cortex[key] = (verts, faces)
    closed: dict[str, tuple[NDArray[Any], NDArray[Any]]] = {}
    if tpl.manifest.get("subcortical") and atlas.subcortical():
        sub = tpl.subcortical()
        for key, faces in _label_faces(sub.faces, sub.face_label, sub.label_names).items():
            closed[key] = (sub.vertices, faces)
    out = np.zeros((len(keys), 3))
    for i, key in enumerate(keys):
        members = [m for m in atlas.member_keys(key) if m in cortex or m in closed]
        if not members:
            raise BrainPainterError(
                f"region {key!r} of atlas {atlas.name!r} has no mesh in template {tpl.name!r}, so its "
                "node has no place; give the nodes' coordinates in a nodes file (name,x,y,z), or leave the "
                "region out of the matrix.")
        parts = [cortex.get(m) or closed[m] for m in members]
        verts = parts[0][0]
        if all(p[0] is verts for p in parts):
            out[i] = centroid(verts, np.concatenate([p[1] for p in parts]), closed=members[0] in closed)
        else:  # a group of cortical and subcortical regions: one vertex array of them all
            stacked = np.concatenate([p[0][p[1]].reshape(-1, 3) for p in parts])
            out[i] = centroid(stacked, np.arange(len(stacked)).reshape(-1, 3))
    return out
