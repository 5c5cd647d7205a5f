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
from typing import TYPE_CHECKING, Protocol

import numpy as np

from brainpainter.atlas.template import SURFACES, Template
from brainpainter.errors import choice_error
from brainpainter.rendering.views import View

if TYPE_CHECKING:
    from brainpainter.rendering.geometry import Palette, SceneGeometry

RGB = tuple[float, float, float]
QUALITIES = ("fast", "default", "high")
SHADINGS = ("default", "flat")
LIGHTINGS = ("studio", "soft", "flat-studio", "sulc")
#: Lighting presets that darken sulci (they need the cortex's sulcal depth).
SULC_LIGHTINGS = ("flat-studio", "sulc")


@dataclass(frozen=True)
class RenderSettings:
    """Image settings shared by every image of a run.

    Attributes
    ----------
    width, height : int
        Pixels; default 1200 x 900 as the original BrainPainter.
    background : tuple of float, shape (3,), or None
        sRGB 0-1; ``None`` renders a transparent background.
    quality : {"fast", "default", "high"}
        ``fast``: no anti-aliasing; ``default``: 2x2 supersampling; ``high``:
        path tracing (Cycles), or 3x3 supersampling for flat shading.
    shading : {"default", "flat"}
        ``flat`` draws exact, unlit colours.
    lighting : {"studio", "soft", "flat-studio", "sulc"}
        Lighting preset for default shading: ``studio`` key + fill + ambient
        light that follow the camera; ``soft`` more ambient, flatter; ``sulc``
        studio plus a slight darkening of sulci (sulcal depth);
        ``flat-studio`` unlit colours darkened in sulci.
    glass_opacity : float
        Opacity of the glass brain, 0-1.
    """

    width: int = 1200
    height: int = 900
    background: RGB | None = (1.0, 1.0, 1.0)
    quality: str = "default"
    shading: str = "default"
    lighting: str = "studio"
    glass_opacity: float = 0.12

    def __post_init__(self) -> None:
        if self.quality not in QUALITIES:
            raise choice_error("quality", self.quality, QUALITIES)
        if self.shading not in SHADINGS:
            raise choice_error("shading", self.shading, SHADINGS)
        if self.lighting not in LIGHTINGS:
            raise choice_error("lighting", self.lighting, LIGHTINGS)

    def to_dict(self) -> dict:
        return {
            "width": self.width, "height": self.height,
            "background": None if self.background is None else list(self.background),
            "quality": self.quality, "shading": self.shading,
            "lighting": self.lighting, "glass_opacity": self.glass_opacity,
        }


@dataclass(frozen=True)
class Scene:
    """Everything loaded once per run.

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
    """

    template: Template
    labels: str
    surface: str = "pial"
    hidden: frozenset[str] = field(default_factory=frozenset)
    settings: RenderSettings = field(default_factory=RenderSettings)
    medial_wall_color: RGB = (0.72, 0.72, 0.72)

    def __post_init__(self) -> None:
        if self.surface not in SURFACES:
            raise choice_error("surface", self.surface, SURFACES)

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

    def render(self, palette: Palette, view: View) -> np.ndarray:
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
