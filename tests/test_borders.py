"""Region borders as line segments (rendering/borders.py) and where a scene carries them."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.borders import LIFT_MM, face_borders, vertex_borders
from brainpainter.rendering.settings import DEFAULT_OUTLINE_WIDTH, RenderSettings, outlined

# a unit square of two triangles sharing the edge (1, 2), facing +z
SQUARE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
FACES = np.array([[0, 1, 2], [1, 3, 2]])
UP = np.tile([0.0, 0.0, 1.0], (4, 1))


def test_face_borders_are_the_edges_between_two_labels():
    seg = face_borders(SQUARE, FACES, np.array([0, 1]), UP)
    assert seg.shape == (1, 2, 3) and seg.dtype == np.float32
    assert sorted(map(tuple, seg[0, :, :2].tolist())) == [(0.0, 1.0), (1.0, 0.0)]   # the shared edge
    assert np.allclose(seg[..., 2], LIFT_MM)                                          # lifted off the surface
    assert len(face_borders(SQUARE, FACES, np.array([4, 4]), UP)) == 0


def test_vertex_borders_join_the_midpoints_of_mixed_edges():
    seg = vertex_borders(SQUARE, FACES, np.array([0, 0, 1, 1]), UP)  # y = 0 | y = 1
    assert seg.shape == (2, 2, 3)
    assert np.allclose(seg[..., 1], 0.5)                             # the line y = 0.5 ...
    assert np.allclose(np.sort(seg[..., 0].ravel()), [0, 0.5, 0.5, 1])  # ... across the square
    three = vertex_borders(SQUARE, FACES, np.array([0, 1, 2, 2]), UP)
    assert len(three) == 1 + 3                                       # centre to the three midpoints
    assert len(vertex_borders(SQUARE, FACES, np.zeros(4), UP)) == 0


def test_outline_settings():
    assert RenderSettings().outline_width == 0 and "outline_width" not in RenderSettings().to_dict()
    drawn = outlined(RenderSettings(), "dk")
    assert drawn.outline_width == DEFAULT_OUTLINE_WIDTH and drawn.to_dict()["outline_color"]
    assert outlined(RenderSettings(outline_width=3), "dk").outline_width == 3
    assert outlined(RenderSettings(), None).outline_width == 0
    assert RenderSettings(outline_color="white").outline_color == (1.0, 1.0, 1.0)
    for bad in (-1, 21, float("nan"), "wide"):
        with pytest.raises(BrainPainterError, match="outline width must be"):
            RenderSettings(outline_width=bad)


@pytest.mark.integration
def test_a_scene_with_outlines_carries_border_segments_on_its_cortex():
    from brainpainter.rendering.painter import load_scene

    plain = load_scene("dk")[1].geometry
    lined = load_scene("dk", settings=RenderSettings(outline_width=2))[1].geometry
    assert all(p.outline is None for p in plain.parts)
    cortex = {p.name: p for p in lined.parts if p.kind == "cortex"}
    assert set(cortex) == {"cortex-lh", "cortex-rh"}
    for part in cortex.values():
        assert part.outline is not None and part.outline.shape[1:] == (2, 3) and len(part.outline) > 1000
        lo, hi = part.vertices.min(axis=0) - 1, part.vertices.max(axis=0) + 1
        assert np.all((part.outline >= lo) & (part.outline <= hi))  # on the hemisphere
    assert all(p.outline is None for p in lined.parts if p.kind != "cortex")
