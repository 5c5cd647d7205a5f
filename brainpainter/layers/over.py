"""The layers drawn over a run's first layer (tracts, a connectome, the blobs and plugin layers), each
giving its colours of one image or of a movie's frame between two (:class:`OverLayer`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from brainpainter.connectome.model import Connectome
from brainpainter.layers.connectome import ConnectomeColors
from brainpainter.layers.kinds import RGB, DrawnLayer
from brainpainter.layers.tracts import TractColors
from brainpainter.tracts.values import TractValues


class OverLayer(Protocol):
    """A layer drawn over the first: the colours of its palette keys."""

    def colors(self, row: int) -> Mapping[str, RGB]:
        """Its colours in image `row`."""

    def blend(self, a: int, b: int, weight: float) -> Mapping[str, RGB]:
        """Its colours between images `a` and `b` (a movie's frame, ``weight`` 0-1 of the way)."""


class FirstLayer(Protocol):
    """A run's first layer (regions or a map): the colours of the cortex and the structures."""

    @property
    def coloring(self) -> str:
        """How the painter colours the cortex: ``"regions"`` or ``"vertices"``."""

    def colors(self, row: int, over: Mapping[str, RGB]) -> Mapping[str, RGB]:
        """Its colours in image `row`, with `over` (the colours of the layers over it) added."""

    def blend(self, a: int, b: int, weight: float, over: Mapping[str, RGB]) -> Mapping[str, RGB]:
        """Its colours between images `a` and `b`, with `over` added."""


@dataclass(frozen=True)
class KeyFrameColors:
    """A drawn layer (:class:`~brainpainter.layers.kinds.DrawnLayer`: the blobs, a plugin's): its colours
    are its image's; a movie's frame between two images shows those of the first."""

    layer: DrawnLayer

    def colors(self, row: int) -> Mapping[str, RGB]:
        return self.layer.colors(row)

    def blend(self, a: int, b: int, weight: float) -> Mapping[str, RGB]:
        return self.layer.colors(a)


def over_layers(layers: Sequence[Any], images: Sequence[str], tract_values: TractValues | None = None,
                connectome: Connectome | None = None,
                drawn: Sequence[DrawnLayer] = ()) -> tuple[OverLayer, ...]:
    """The layers drawn over a run's first, in the order they are painted: the tracts on their scale
    (the first layer's where they have none), the connectome, then each drawn layer.

    Parameters
    ----------
    layers : sequence of Layer
        The run's layers (:class:`~brainpainter.rendering.layers.Layer`), read by kind.
    images : sequence of str
        The run's image names, by row (the tract values' rows are found by name).
    """
    out: list[OverLayer] = []
    if tract_values is not None:
        scale = next((layer.scale for layer in layers if layer.kind == "tracts"), layers[0].scale)
        out.append(TractColors(tract_values, images, scale))
    if connectome is not None:
        out.append(ConnectomeColors(connectome, layers))
    return (*out, *(KeyFrameColors(layer) for layer in drawn))
