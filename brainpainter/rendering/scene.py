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

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.template import SURFACES, Template
from brainpainter.errors import BrainPainterError, choice_error
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
__all__ = ["LIGHTINGS", "QUALITIES", "RGB", "SHADINGS", "SULC_LIGHTINGS", "BlankRenderError",
           "RenderSettings", "Renderer", "Scene", "nothing_drawn"]

if TYPE_CHECKING:
    from brainpainter.connectome.model import Connectome
    from brainpainter.maps.outlines import Contours
    from brainpainter.rendering.geometry import Palette, SceneGeometry
    from brainpainter.tracts.model import Tracts

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
    contours : Contours, optional
        A second map's iso-lines, drawn with the region borders at ``settings.outline_width``
        pixels (a per-vertex scene only).
    layers : tuple of PartsLayer
        What adds its own parts and palette keys (:class:`brainpainter.layers.kinds.PartsLayer`), in the
        order they are drawn: white-matter bundles as tubes
        (:class:`~brainpainter.rendering.tract_parts.TractLayer`; keys ``tract:NAME``, ``tract:NAME:i``),
        a connectome's nodes and edges as lit spheres and cylinders inside the glass cortex
        (:class:`~brainpainter.rendering.connectome_layers.ConnectomeLayer`; ``node:i``, ``edge:k``),
        a volume's supra-threshold clusters as lit surfaces
        (:class:`~brainpainter.rendering.blob_layers.BlobLayer`; ``blob:0`` ...), plugin layers
        (``--layer KIND:FILE``).
    """

    template: Template
    labels: str
    surface: str = "pial"
    hidden: frozenset[str] = field(default_factory=frozenset)
    settings: RenderSettings = field(default_factory=RenderSettings)
    medial_wall_color: RGB = (0.72, 0.72, 0.72)
    coloring: str = "regions"
    contours: Contours | None = None
    layers: tuple[Any, ...] = ()

    def __post_init__(self) -> None:
        if self.surface not in SURFACES:
            raise choice_error("surface", self.surface, SURFACES)
        if self.coloring not in COLORINGS:
            raise choice_error("coloring", self.coloring, COLORINGS)

    @property
    def tracts(self) -> Tracts | None:
        """The bundles of its tracts layer, if it has one (what an exporter or a renderer may read)."""
        return next((layer.tracts for layer in self.layers if layer.kind == "tracts"), None)

    @property
    def connectome(self) -> Connectome | None:
        """The connectome of its connectome layer, if it has one (its nodes' labels are drawn)."""
        return next((layer.connectome for layer in self.layers if layer.kind == "connectome"), None)

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

    Optional attribute ``draws_tubes: bool`` (absent: True): whether it draws a
    ``tract`` part's tubes (its triangles, built when first read) or only its
    ``centrelines``; the conformance suite holds a renderer to it.
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


class BlankRenderError(BrainPainterError):
    """A renderer returned an image in which nothing was drawn although the view shows geometry."""

    @classmethod
    def of(cls, view: View, renderer: str,
           hint: str = "report the version at the project's issue tracker") -> BlankRenderError:
        """The error for `view`, naming `renderer` and its library's version, ending with `hint`."""
        return cls(f"{renderer} drew nothing in view {view.name!r} although the view shows geometry "
                   f"(every pixel is background): {hint}.")


def nothing_drawn(pixels: NDArray[Any], background: RGB | None) -> bool:
    """Whether every pixel of an image is the background (or transparent): nothing was drawn.

    A view always shows geometry (:meth:`SceneGeometry.visible` refuses one that
    does not, and the camera frames what it shows), so such an image means the
    renderer failed silently (an untested version of its library): a renderer
    raises :class:`BlankRenderError` then, never returns the image. About half a
    millisecond for a 1200x900 image.

    Parameters
    ----------
    pixels : ndarray of uint8, shape (height, width, 4)
        RGBA, as :meth:`Renderer.render` returns it.
    background : (r, g, b) in 0-1, or None
        The render's background (``RenderSettings.background``); None: transparent.
    """
    rgba = np.ascontiguousarray(pixels, dtype=np.uint8)
    if rgba.ndim != 3 or rgba.shape[-1] != 4 or not rgba.size:
        return False
    packed = rgba.view(np.uint32)
    if background is None:
        alpha = np.frombuffer(bytes((0, 0, 0, 255)), np.uint32)[0]
        return not bool((packed & alpha).any())
    empty = bytes((*(round(float(c) * 255) for c in background), 255))
    return not bool((packed != np.frombuffer(empty, np.uint32)[0]).any())
