"""What a view draws and its camera's uniforms, computed once per view (:class:`Aim`), for the default
draw path (:mod:`brainpainter_blender.gpu_draw`), and which of its parts are drawn on top of all others (a
connectome's nodes and edges: :func:`on_top`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from brainpainter.rendering.clip import CLIPPED
from brainpainter.rendering.framing import view_projection
from brainpainter.rendering.geometry import PartGeometry, SceneGeometry
from brainpainter.rendering.scene import RenderSettings
from brainpainter.rendering.views import View
from brainpainter_blender import cutaway
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
    #: away (:meth:`GpuDraw._front`)
    front: dict[str, Any] = field(default_factory=dict)
    #: the view's cutaway planes as the clipped shader's ``clips`` (columns a, b, c, d), or None: none
    clips: Any = None
    n_clip: int = 0
    #: the view's planes (:class:`~brainpainter.rendering.clip.ClipPlane`)
    planes: tuple[Any, ...] = ()

    def cut(self, part: PartGeometry) -> bool:
        """Whether the view's planes cut `part` (its kind is cortex or glass)."""
        return self.n_clip > 0 and part.kind in CLIPPED


def aim_for(geometry: SceneGeometry, view: View, settings: RenderSettings, light: Lighting) -> Aim:
    """The parts `view` shows, its view-projection matrix and the camera-fixed light directions."""
    from mathutils import Matrix, Vector

    aspect = settings.width / settings.height
    pose = geometry.camera(view, aspect)
    cam = pose.rotation  # columns: right, up, back (camera space -> world)

    def world(d: tuple[float, float, float]) -> Vector:
        v = cam @ np.asarray(d, float)
        return Vector((v / np.linalg.norm(v)).tolist())

    clips, n_clip = cutaway.clip_uniforms(view)
    return Aim(geometry.visible(view), Matrix(view_projection(pose, aspect).tolist()),
               world((0.0, 0.0, 1.0)), world(light.key_dir), world(light.fill_dir), clips=clips,
               n_clip=n_clip, planes=view.clip)
