"""What a view draws and from where, computed once per view (:class:`Aim`), and which of its parts are drawn
on top of all others (a connectome's nodes and edges: :func:`on_top`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from brainpainter.rendering.framing import view_projection
from brainpainter.rendering.geometry import PartGeometry, SceneGeometry
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import View
from brainpainter_blender.gpu_lighting import Lighting

#: Kinds of parts drawn over every other part and the glass, each pixel in its own colour (issue 44): a
#: connectome's nodes and edges. Under the glass cortex an edge was paler than its colour bar and in the
#: midline gap (no glass over it) saturated, so a dorsal view showed a dark-red "spine" that is not in
#: the data; over an opaque cortex in its values' colours they were hidden.
ON_TOP = ("node", "edge")


def on_top(parts: list[PartGeometry]) -> list[PartGeometry]:
    """The parts of `parts` drawn on top (:data:`ON_TOP`), in their order."""
    return [p for p in parts if p.kind in ON_TOP]


@dataclass(frozen=True)
class Aim:
    """A view's parts and camera uniforms (``mathutils`` values, world space)."""

    visible: list[PartGeometry]
    mvp: Any
    back: Any
    key_dir: Any
    fill_dir: Any
    #: per part, its batch of the triangles facing the camera; per glass part also of those turned
    #: away (:meth:`~brainpainter_blender.gpu_draw.GpuDraw._front`)
    front: dict[str, Any] = field(default_factory=dict)


def aim_for(geometry: SceneGeometry, view: View, settings: RenderSettings, light: Lighting) -> Aim:
    """The parts `view` shows, its view-projection matrix and the camera-fixed light directions."""
    from mathutils import Matrix, Vector

    aspect = settings.width / settings.height
    pose = geometry.camera(view, aspect)
    cam = pose.rotation  # columns: right, up, back (camera space -> world)

    def world(d: tuple[float, float, float]) -> Vector:
        v = cam @ np.asarray(d, float)
        return Vector((v / np.linalg.norm(v)).tolist())

    return Aim(geometry.visible(view), Matrix(view_projection(pose, aspect).tolist()),
                world((0.0, 0.0, 1.0)), world(light.key_dir), world(light.fill_dir))
