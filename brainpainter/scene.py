"""The scene description handed from the core engine to a renderer.

The core maps values to colours; a renderer only sees a :class:`Scene`
(loaded once) and, per image, a mapping of region key to sRGB colour plus a
:class:`~brainpainter.views.View`. Renderers never parse input tables.

Region keys are BrainPainter's column names: ``"Left-insula"``,
``"Right-Hippocampus"``, ``"Brain-Stem"``; for a cortex label name ``n`` of
hemisphere ``h`` the key is ``HEMI_PREFIX[h] + n``; subcortical label names in
a template are already keys. Cortex labels with no colour in the mapping
(medial wall, ``unknown``) are drawn in ``Scene.medial_wall_color``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from brainpainter.errors import choice_error
from brainpainter.template import SURFACES, Template
from brainpainter.views import View

RGB = tuple[float, float, float]
QUALITIES = ("fast", "default", "high")
SHADINGS = ("default", "flat")
LIGHTINGS = ("studio", "soft", "flat-studio")


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
        Workbench without / with anti-aliasing; ``high`` = Cycles path tracing.
    shading : {"default", "flat"}
        ``flat`` draws exact, unlit colours.
    lighting : str
        Lighting preset for default shading.
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


class Renderer(Protocol):
    """What a ``brainpainter.renderers`` entry point must provide.

    The entry point names a class; ``cls(scene)`` loads the scene once (the
    expensive part) and then ``render`` only re-colours and re-aims it.
    """

    def __init__(self, scene: Scene) -> None: ...

    def render(self, colors: Mapping[str, RGB], view: View) -> np.ndarray:
        """Render one image.

        Parameters
        ----------
        colors : mapping of str to (r, g, b)
            sRGB 0-1 colour of every region key to colour.
        view : View

        Returns
        -------
        ndarray of uint8, shape (height, width, 4)
            RGBA pixels, row 0 at the top, sRGB.
        """
        ...

    def close(self) -> None: ...
