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


def has_lines(part: PartGeometry) -> bool:
    """Whether `part` has lines to draw (region borders or a contour)."""
    return part.outline is not None or part.contour is not None


def draw_outlines(batches: dict[str, Any], parts: list[PartGeometry], mvp: Any, settings: RenderSettings,
                  factor: int) -> bool:
    """Draw the border segments and the contours of `parts` (those that have them) into the bound
    framebuffer: the borders in the outline's line, then the contours in theirs
    (:meth:`RenderSettings.line`: colour, width; dashes are in the segments).

    Parameters
    ----------
    batches : dict
        The renderer's batch cache; each part's line batch is made once, as ``outline:<name>`` (and
        ``contour:<name>``).
    parts : list of PartGeometry
    mvp : mathutils.Matrix
        The view's model-view-projection matrix.
    settings : RenderSettings
        ``outline_width`` (output pixels; 0: no lines) and each line layer's colour and width.
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

    layers = [(kind, [(p.name, segments) for p in parts
                      if (segments := getattr(p, kind)) is not None and len(segments)])
              for kind in ("outline", "contour")]
    if not any(drawn for _, drawn in layers) or settings.outline_width <= 0:
        return False
    shader = gpu.shader.from_builtin("POLYLINE_UNIFORM_COLOR")
    shader.bind()
    shader.uniform_float("viewportSize", (settings.width * factor, settings.height * factor))
    gpu.state.face_culling_set("NONE")
    # the shader's own anti-aliasing (coverage as alpha), blended: written as it is, the alpha left
    # holes along the lines in an opaque image
    shader.uniform_bool("lineSmooth", True)
    gpu.state.blend_set("ALPHA")
    with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
        gpu.matrix.load_matrix(Matrix.Identity(4))
        gpu.matrix.load_projection_matrix(mvp)
        for kind, drawn in layers:
            color, width, _ = settings.line(kind)
            shader.uniform_float("lineWidth", width * factor)
            shader.uniform_float("color", (*srgb_to_linear(color), 1.0))
            for name, segments in drawn:
                key = f"{kind}:{name}"
                if key not in batches:
                    batches[key] = batch_for_shader(
                        shader, "LINES", {"pos": np.ascontiguousarray(segments.reshape(-1, 3), np.float32)})
                batches[key].draw(shader)
    gpu.state.blend_set("NONE")
    return True
