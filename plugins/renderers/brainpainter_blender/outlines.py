"""Region borders drawn as lines of constant pixel width (``--outline``), by the default draw path.

Blender's polyline shader widens each segment to a quad in screen space, so the width is
constant in output pixels (times the supersampling factor, so the resolve keeps it), and
anti-aliases it (its coverage as alpha, blended); the depth test hides the borders behind
the surface in front of them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from brainpainter.rendering.geometry import PartGeometry
from brainpainter.rendering.scene import RenderSettings
from brainpainter_blender.materials import srgb_to_linear


def draw_outlines(batches: dict[str, Any], parts: list[PartGeometry], mvp: Any, settings: RenderSettings,
                  factor: int) -> bool:
    """Draw the border segments of `parts` (those that have them) into the bound framebuffer.

    Parameters
    ----------
    batches : dict
        The renderer's batch cache; each part's line batch is made once, as ``outline:<name>``.
    parts : list of PartGeometry
    mvp : mathutils.Matrix
        The view's model-view-projection matrix.
    settings : RenderSettings
        ``outline_width`` (output pixels) and ``outline_color`` (sRGB).
    factor : int
        Supersampling factor of the framebuffer.

    Returns
    -------
    bool
        False when there was nothing to draw (no segments, or width 0). Face culling is left off.
    """
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix

    parts = [p for p in parts if p.outline is not None and len(p.outline)]
    if not parts or settings.outline_width <= 0:
        return False
    shader = gpu.shader.from_builtin("POLYLINE_UNIFORM_COLOR")
    shader.bind()
    shader.uniform_float("viewportSize", (settings.width * factor, settings.height * factor))
    shader.uniform_float("lineWidth", settings.outline_width * factor)
    shader.uniform_float("color", (*srgb_to_linear(settings.outline_color), 1.0))
    gpu.state.face_culling_set("NONE")
    # the shader's own anti-aliasing (coverage as alpha), blended: written as it is, the alpha left
    # holes along the lines in an opaque image
    shader.uniform_bool("lineSmooth", True)
    gpu.state.blend_set("ALPHA")
    with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
        gpu.matrix.load_matrix(Matrix.Identity(4))
        gpu.matrix.load_projection_matrix(mvp)
        for p in parts:
            key = f"outline:{p.name}"
            if key not in batches:
                assert p.outline is not None
                batches[key] = batch_for_shader(
                    shader, "LINES", {"pos": np.ascontiguousarray(p.outline.reshape(-1, 3), np.float32)})
            batches[key].draw(shader)
    gpu.state.blend_set("NONE")
    return True
