"""The glass drawn once per view and glass colours into a layer, put over each image (default draw path).

Every pass of the glass is blended with premultiplied alpha (``dst' = src + (1 - src.a) * dst``),
its borders by their coverage (``dst' = a * c + (1 - a) * dst``, the alpha channel as the
premultiplied one), all depth-tested against the opaque parts' depth without changing what is
drawn there. A sequence of such blends is affine in what lies under it: over any ``dst`` it gives
``G.rgb + (1 - G.a) * dst``, per pixel, where ``G`` is what the same passes draw over a cleared
(0, 0, 0, 0) buffer holding the opaque parts' depth. Within one
:class:`~brainpainter_blender.gpu_draw.GpuDraw` the geometry is fixed, so the opaque parts' depth
is the view's; ``G`` depends on the view and the glass's colours (the palette at the glass parts'
slots) alone. So a view's glass is drawn into its layer (an RGBA16 texture the size of the
supersampled buffer, :data:`MAX_LAYER_PIXELS` of them kept) and each image puts the layer over its
opaque parts in one pass: a connectome series or a table's rows over the same views (the nodes'
and edges' or the regions' colours changing, the glass's not) draw the glass's 300,000 triangles
only once a view. With tract lines between the glass's far and near sides, each side is a layer.

Every image goes through a layer, the first of a view too (drawn into the layer, then put over
the image), so an image's pixels do not depend on the images drawn before it: ``--jobs`` writes
the serial run's bytes.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.geometry import PartGeometry

#: Pixels of the glass layers kept (RGBA16, 8 bytes each: 69 MB): 8 views of 1200x900, or 4 with tracts.
MAX_LAYER_PIXELS = 8 * 1200 * 900
#: The most layers a view has (the far and near sides, with tract lines between them).
LAYERS_PER_VIEW = 2
#: Glass of fewer triangles is drawn per image (the subcortical views' hull, ~6,000: as cheap as
#: putting a layer over the image, and a region render's memory does not grow by a layer for it).
MIN_TRIANGLES = 50_000


@dataclass
class _Layer:
    """A kept layer: its texture and the glass colours it was drawn in."""

    texture: Any
    colours: NDArray[Any]


class GlassLayers:
    """The glass layers of the views last drawn (see the module docstring).

    Parameters
    ----------
    width, height : int
        Of the supersampled buffer the layers are put over.
    depth : gpu.types.GPUTexture
        That buffer's depth (the opaque parts' depth when a layer is drawn).
    """

    def __init__(self, width: int, height: int, depth: Any) -> None:
        self.width, self.height = int(width), int(height)
        self._depth = depth
        self._slots: dict[tuple[str, ...], NDArray[Any]] = {}
        self._layers: OrderedDict[Hashable, _Layer] = OrderedDict()
        #: layers drawn (not put over from a kept one) since the renderer started
        self.drawn = 0

    @property
    def enabled(self) -> bool:
        """Whether a view's layers fit in :data:`MAX_LAYER_PIXELS` (else the glass is drawn per image)."""
        return LAYERS_PER_VIEW * self.width * self.height <= MAX_LAYER_PIXELS

    @staticmethod
    def worth(parts: list[PartGeometry]) -> bool:
        """Whether the glass `parts` have enough triangles to be kept in layers (:data:`MIN_TRIANGLES`)."""
        return sum(len(p.triangles) for p in parts) >= MIN_TRIANGLES

    def colours(self, rgb: NDArray[Any], parts: list[PartGeometry]) -> NDArray[Any]:
        """The colours of the glass `parts` in the palette `rgb` (sRGB, shape (n_slots, 3)), shape (n, 3)."""
        names = tuple(p.name for p in parts)
        slots = self._slots.get(names)
        if slots is None:
            slots = self._slots[names] = np.unique(np.concatenate([p.palette_index for p in parts]))
        if len(slots) and slots[-1] - slots[0] + 1 == len(slots):  # a map's: a view, not a copy
            return np.asarray(rgb[slots[0]:slots[-1] + 1])
        return np.asarray(rgb[slots])

    def passes(self, view: Hashable, colours: NDArray[Any], draw: Callable[[tuple[str, ...]], None],
               mark: Callable[[str], None], fresh: bool = False) -> Callable[[tuple[str, ...]], Any]:
        """What draws the glass sides `culled` (``draw(culled)``) of `view` in an image through their
        layer (:meth:`layer`): the far side's, under tract lines, put over the bound framebuffer
        (returns None); a layer with the near side, the last drawn, returned for the resolve to put
        over the image."""

        def layered(culled: tuple[str, ...]) -> Any:
            texture = self.layer((view, culled), colours, lambda: draw(culled), fresh)
            if "BACK" in culled:
                return texture
            self.over(texture, mark)
            return None

        return layered

    def layer(self, key: Hashable, colours: NDArray[Any], draw: Callable[[], None],
              fresh: bool = False) -> Any:
        """The texture of the layer of `key`, drawn first with `draw` when not kept in `colours`
        (:meth:`colours`) or when `fresh`.

        `draw` draws the glass passes into the bound framebuffer (its depth the opaque parts').
        """
        layer = self._layers.get(key)
        if layer is None or fresh or not np.array_equal(layer.colours, colours):
            layer = self._draw(key, np.array(colours), draw)
        self._layers.move_to_end(key)
        return layer.texture

    @staticmethod
    def over(texture: Any, mark: Callable[[str], None]) -> None:
        """Put a layer over the bound framebuffer (blended, premultiplied)."""
        import gpu

        from brainpainter_blender import gpu_shaders

        gpu.state.blend_set("ALPHA_PREMULT")
        gpu_shaders.draw_box("over", (-1.0, -1.0, 1.0, 1.0), {"layer": texture})
        gpu.state.blend_set("NONE")
        mark("glass layer")

    def _draw(self, key: Hashable, colours: NDArray[Any], draw: Callable[[], None]) -> _Layer:
        """Draw the layer of `key` (into the texture of the one it replaces, or of the oldest dropped)."""
        import gpu

        layer = self._layers.pop(key, None)
        while layer is None and len(self._layers) >= MAX_LAYER_PIXELS // (self.width * self.height):
            layer = self._layers.popitem(last=False)[1]  # its texture is drawn over
        texture = (gpu.types.GPUTexture((self.width, self.height), format="RGBA16") if layer is None
                   else layer.texture)
        fb = gpu.types.GPUFrameBuffer(depth_slot=self._depth, color_slots=texture)
        with fb.bind():
            fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            draw()
        self.drawn += 1
        self._layers[key] = _Layer(texture, colours)
        return self._layers[key]

    def close(self) -> None:
        """Drop the layers (call in a GPU context)."""
        self._depth = None
        self._layers.clear()
        self._slots.clear()

