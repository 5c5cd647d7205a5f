"""Cutaways in the default draw path: a view's clip planes (:mod:`brainpainter.rendering.clip`) as the
clipped part shader's uniforms, and the cut face drawn closed.

A clipped view draws with :func:`~brainpainter_blender.gpu_shaders.part_shader` ``(clip=True)``: each
fragment of a cortex or glass part on the removed side of every plane is discarded. A cut cortex part
is then drawn again with only its faces turned away from the camera, in ``MODE_CAP``: where the cut
opens the surface, its inside shows, in :data:`~brainpainter.rendering.clip.CAP_COLOR` lit as the
nearest cutting plane (a closed surface seen from inside is its far wall; depth-tested as any part,
so what lies inside, in front of that wall, stays in view).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from brainpainter.rendering.clip import CAP_COLOR, MAX_PLANES
from brainpainter.rendering.views import View


def clip_uniforms(view: View) -> tuple[Any, int]:
    """The clipped shader's ``clips`` (a ``mathutils.Matrix``, columns ``a, b, c, d`` of each plane) and
    ``n_clip`` of `view`; ``(None, 0)`` without planes."""
    if not view.clip:
        return None, 0
    from mathutils import Matrix

    clips = np.zeros((4, MAX_PLANES))
    for i, plane in enumerate(view.clip):
        clips[:, i] = plane.plane  # in template coordinates: RAS for every template drawn so far
    return Matrix(clips.tolist()), len(view.clip)


def left_whole(triangles: Any, vertices: Any, planes: Any) -> Any:
    """`triangles` (shape (n, 3)) without those whose three `vertices` (shape (n_vertices, 3)) the
    `planes` remove: the removed region (on the named side of every plane) is convex, so such a
    triangle lies wholly in it."""
    from brainpainter.rendering.clip import removed

    gone = removed(np.asarray(vertices, np.float64), planes)
    return triangles[~gone[triangles].all(axis=1)]


def bind_clip(shader: Any, clips: Any, n_clip: int, to_linear: Callable[[Any], Any]) -> None:
    """Set the clipped shader's planes, the cut face's colour (linear light), and no part cut yet."""
    shader.uniform_float("clips", clips)
    shader.uniform_int("n_clip", n_clip)
    shader.uniform_int("clip_on", 0)
    shader.uniform_float("cap_rgb", [float(c) for c in to_linear(np.asarray(CAP_COLOR))])


def draw_cap(back_faces: Any, shader: Any, modes: tuple[int, int], cull: str) -> None:
    """Draw `back_faces` (a part's batch of faces turned away) in the cap mode, then restore the lit
    mode and the face culling `cull`; `modes`: (cap, lit)."""
    import gpu

    gpu.state.face_culling_set("FRONT")
    shader.uniform_int("mode", modes[0])
    back_faces.draw(shader)
    shader.uniform_int("mode", modes[1])
    gpu.state.face_culling_set(cull)
