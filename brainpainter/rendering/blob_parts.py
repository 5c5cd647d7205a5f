"""A volume's blobs (:class:`~brainpainter.maps.clusters.Blobs`) as one scene part of kind ``blob``.

The blobs' surface, placed in the template's coordinates (MNI152 to the template's MNI305 for
fsaverage, :func:`brainpainter.atlas.volumes.space_transform`), is drawn as any opaque lit part.
Its colours are :data:`~brainpainter.maps.clusters.N_LEVELS` palette slots (keys ``blob:0`` ...),
one per value level (:attr:`Blobs.levels`); each vertex takes its value's level, so an image
recolours the blobs as it recolours regions, and a renderer interpolates between vertices.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.rendering.parts import PartGeometry
from brainpainter.rendering.settings import RGB

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template
    from brainpainter.maps.clusters import Blobs

#: Colour of a blob level the palette gives none (sRGB).
BLOB_COLOR: RGB = (0.9, 0.3, 0.1)
BLOB_KEY = "blob:"

SlotsFor = Callable[[list[str], "int | RGB", frozenset[str]], NDArray[Any]]


def blob_keys(n: int) -> list[str]:
    """Palette keys of `n` blob levels (``blob:0`` ...)."""
    return [f"{BLOB_KEY}{i}" for i in range(n)]


def template_points(points: NDArray[Any], template: Template) -> NDArray[np.float64]:
    """MNI152 points (shape (n, 3)) in the template's coordinates, shape (n, 3)."""
    from brainpainter.atlas.volumes import space_transform

    m = space_transform("MNI152NLin2009cAsym", template)
    out: NDArray[np.float64] = np.asarray(points, float) @ m[:3, :3].T + m[:3, 3]
    return out


def blob_parts(blobs: Blobs | None, template: Template, slots_for: SlotsFor) -> list[PartGeometry]:
    """The part of `blobs` (kind ``blob``, name ``blobs``, of no hemisphere); None: no parts."""
    if blobs is None:
        return []
    slots = slots_for(blob_keys(len(blobs.levels)), BLOB_COLOR, frozenset())
    verts = template_points(blobs.vertices, template)
    normals = vertex_normals(verts, blobs.triangles)
    pal = np.asarray(slots, np.int32)[blobs.level_of()]
    v32 = verts.astype(np.float32)
    return [PartGeometry("blobs", "blob", None, v32, normals.astype(np.float32),
                         np.asarray(blobs.triangles, np.uint32), pal, np.zeros(len(verts), np.float32),
                         verts)]
