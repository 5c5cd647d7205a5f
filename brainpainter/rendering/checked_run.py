"""A checked run (:class:`Run`): its images, colour scales, views, settings and options, and the colours
of each image, read off its layers. :func:`brainpainter.rendering.run.prepare_run` makes one; render,
figure, movie, plot, export and the web API paint it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from brainpainter.color.scale import ColourScale
from brainpainter.connectome.model import Connectome
from brainpainter.layers.kinds import RGB, DrawnLayer, PartsLayer
from brainpainter.layers.over import FirstLayer, OverLayer
from brainpainter.maps.clusters import Blobs
from brainpainter.maps.outlines import Contours
from brainpainter.rendering.composition import scene_layers
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.painter import Painter
from brainpainter.rendering.parallel import Item
from brainpainter.rendering.settings import RenderSettings
from brainpainter.rendering.views import View
from brainpainter.tracts.values import TractValues


@dataclass
class Run:
    """A checked run: its images, colour scales, views, settings and options, and the colours of each image.

    `base` is the first layer's colours (:class:`~brainpainter.layers.regions.RegionValues` of a region
    table, :class:`~brainpainter.layers.vertex_map.MapColors` of a map): what colours the cortex and
    the structures; `over` the layers drawn over it (:func:`brainpainter.layers.over.over_layers`).
    `layers` are every layer's scale, opacity and label (:mod:`brainpainter.rendering.layers`), `scale`
    the first's. `table` gives the image names (``images``), the atlas and the input's summary.
    """

    table: Any
    scale: ColourScale
    views: list[View]
    settings: RenderSettings
    options: Options
    base: FirstLayer
    over: tuple[OverLayer, ...] = ()
    layers: tuple[Layer, ...] = ()
    tract_values: TractValues | None = None
    contours: Contours | None = None  # a second map's iso-lines (--contour)
    connectome: Connectome | None = None
    blobs: Blobs | None = None  # a volume's clusters as surfaces (--volume-surface)
    drawn: tuple[DrawnLayer, ...] = ()  # what adds its own parts: the blobs, plugin layers (--layer)

    @property
    def coloring(self) -> str:
        """How the painter colours the cortex: ``"regions"`` (per region) or ``"vertices"`` (a map)."""
        return self.base.coloring

    def scale_of(self, kind: str) -> ColourScale:
        """The colour scale of layer `kind` (``"regions"``, ``"tracts"``); the run's scale if it has none."""
        return next((layer.scale for layer in self.layers if layer.kind == kind), self.scale)

    def painter(self) -> Painter:
        """A new (not loaded) painter for this run's atlas, scene options and image settings."""
        scene = self.options.scene
        return Painter(self.table.atlas, scene.template, scene.surface, scene.hide, self.settings,
                       scene.renderer, coloring=self.coloring, contours=self.contours,
                       layers=self.scene_layers())

    def scene_layers(self) -> tuple[PartsLayer, ...]:
        """What the run adds to the scene, in the order drawn (:func:`~brainpainter.rendering.composition.
        scene_layers`): the tracts, a connectome, the blobs, plugin layers."""
        return scene_layers(self.options, self.tract_values, self.connectome, self.drawn)

    def items(self, rows: Sequence[int]) -> list[tuple[int, View]]:
        """The images of `rows`: ``(row, view)`` for every row and view, row by row."""
        return [(i, view) for i in rows for view in self.views]

    def colors(self, i: int) -> Mapping[str, RGB]:
        """The colours of image `i`: the first layer's, then each layer over it."""
        over: dict[str, RGB] = {}
        for layer in self.over:
            over.update(layer.colors(i))
        return self.base.colors(i, over)

    def blend(self, a: int, b: int, weight: float) -> Mapping[str, RGB]:
        """Images `a` and `b` blended, ``(1 - weight) * a + weight * b`` (a movie's frame)."""
        over: dict[str, RGB] = {}
        for layer in self.over:
            over.update(layer.blend(a, b, weight))
        return self.base.blend(a, b, weight, over)

    def item(self, i: int, view: View, metadata: Mapping[str, str] | None = None) -> Item:
        """The image of row `i` from `view`, as a painter task."""
        return Item(self.colors(i), view, metadata, self.table.images[i])
