"""The scene description handed from the core engine to a renderer.

The core maps values to colours; a renderer only sees a :class:`Scene`
(loaded once; ``scene.geometry`` holds its ready-to-draw parts) and, per
image, a :class:`~brainpainter.rendering.geometry.Palette` plus a
:class:`~brainpainter.rendering.views.View`. Renderers never parse input tables.

Region keys are BrainPainter's column names: ``"Left-insula"``,
``"Right-Hippocampus"``, ``"Brain-Stem"``; for a cortex label name ``n`` of
hemisphere ``h`` the key is ``HEMI_PREFIX[h] + n``; subcortical label names in
a template are already keys. Cortex labels with no colour in the mapping
(medial wall, ``unknown``) are drawn in ``Scene.medial_wall_color``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, Protocol

from numpy.typing import NDArray

from brainpainter.atlas.template import SURFACES, Template
from brainpainter.errors import choice_error
from brainpainter.rendering.settings import (
    LIGHTINGS,
    QUALITIES,
    RGB,
    SHADINGS,
    SULC_LIGHTINGS,
    RenderSettings,
)
from brainpainter.rendering.views import View

# RenderSettings and its choices live in brainpainter.rendering.settings; named here for renderers.
__all__ = ["LIGHTINGS", "QUALITIES", "RGB", "SHADINGS", "SULC_LIGHTINGS", "RenderSettings", "Renderer",
           "Scene"]

if TYPE_CHECKING:
    from brainpainter.rendering.geometry import Palette, SceneGeometry

#: How a scene's cortex is coloured: one colour per region, or one per vertex (a map).
COLORINGS = ("regions", "vertices")

@dataclass(frozen=True)
class Scene:
    """Everything loaded once per run.

    What a renderer draws is ``scene.geometry``, built from these on first use.

    Attributes
    ----------
    template : Template
    labels : str
        Label set of the template used for the cortex (an atlas's
        ``template_labels``).
    surface : {"pial", "white", "inflated"}
    hidden : frozenset of str
        Region keys not drawn at all.
    settings : RenderSettings
    medial_wall_color : tuple of float, shape (3,)
    coloring : {"regions", "vertices"}
        ``"vertices"``: a map; the cortex has one palette slot per vertex
        (:class:`~brainpainter.rendering.geometry.SceneGeometry`).
    """

    template: Template
    labels: str
    surface: str = "pial"
    hidden: frozenset[str] = field(default_factory=frozenset)
    settings: RenderSettings = field(default_factory=RenderSettings)
    medial_wall_color: RGB = (0.72, 0.72, 0.72)
    coloring: str = "regions"

    def __post_init__(self) -> None:
        if self.surface not in SURFACES:
            raise choice_error("surface", self.surface, SURFACES)
        if self.coloring not in COLORINGS:
            raise choice_error("coloring", self.coloring, COLORINGS)

    @cached_property
    def geometry(self) -> SceneGeometry:
        """Ready-to-draw parts and palette slots (:class:`~brainpainter.rendering.geometry.SceneGeometry`)."""
        from brainpainter.rendering.geometry import SceneGeometry

        return SceneGeometry(self)


class Renderer(Protocol):
    """What a ``brainpainter.renderers`` entry point must provide (see ``docs/renderers.md``).

    The entry point names a class; ``cls(scene)`` loads the scene once (the
    expensive part: upload ``scene.geometry``'s parts) and then ``render``
    only re-colours (a palette upload) and re-aims (the view's camera from
    ``scene.geometry.camera``). Check a renderer with
    :func:`brainpainter.testing.check_renderer`.
    """

    def __init__(self, scene: Scene) -> None: ...

    def render(self, palette: Palette, view: View) -> NDArray[Any]:
        """Render one image.

        Parameters
        ----------
        palette : brainpainter.rendering.geometry.Palette
            ``palette.rgb`` (float32, shape (n_slots, 3), sRGB 0-1) colours the
            per-vertex palette indices of ``scene.geometry``; the palette is also
            the mapping region key -> sRGB of the colours given.
        view : View
            ``scene.geometry.visible(view)`` and ``scene.geometry.camera(view, aspect)``
            say what to draw and from where.

        Returns
        -------
        ndarray of uint8, shape (height, width, 4)
            RGBA pixels, row 0 at the top, sRGB, straight (not premultiplied) alpha.
        """
        ...

    def close(self) -> None: ...
