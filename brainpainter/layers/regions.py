"""The regions layer: a table's value per atlas region, each image one row, coloured on the layer's scale."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from brainpainter.atlas.model import Atlas
from brainpainter.color.scale import ColourScale
from brainpainter.layers.kinds import RGB
from brainpainter.table.region_table import RegionTable
from brainpainter.table.rows import interpolate


def region_colors(values: Mapping[str, float], atlas: Atlas, scale: ColourScale) -> dict[str, RGB]:
    """Colour of every atlas region for one image.

    Parameters
    ----------
    values : mapping of region key to float
        NaN = empty cell (``scale.nan_color``); keys absent = no data
        (``scale.missing_color``).
    """
    values = atlas.expand(values)  # a group member without a value takes the group's
    keys = [k for k in atlas.keys if k in values]
    colors: dict[str, RGB] = {k: scale.missing_color for k in atlas.keys}
    if keys:
        rgb = scale(np.array([values[k] for k in keys], dtype=float))
        colors.update({k: (float(c[0]), float(c[1]), float(c[2])) for k, c in zip(keys, rgb, strict=True)})
    return atlas.expand(colors)  # a group's colour goes to each of its member regions


@dataclass(frozen=True)
class RegionValues:
    """The colours of a region table's images: the cortex and structures coloured per region.

    A run's first layer (:attr:`brainpainter.rendering.run.Run.base`); tracts or a connectome
    alone draw an empty table's (every region the missing colour).
    """

    table: RegionTable
    scale: ColourScale
    #: How the painter colours the cortex: one colour per region.
    coloring: ClassVar[str] = "regions"

    def colors(self, row: int, over: Mapping[str, RGB]) -> dict[str, RGB]:
        """The region colours of image `row`, with `over` (the layers drawn over it) added."""
        return self.blend(row, row, 0.0, over)  # a key frame: its own values

    def blend(self, a: int, b: int, weight: float, over: Mapping[str, RGB]) -> dict[str, RGB]:
        """Rows `a` and `b` blended, ``(1 - weight) * a + weight * b`` (a movie's frame), with `over`."""
        values = interpolate(self.table.values[a], self.table.values[b], weight)
        return region_colors(dict(zip(self.table.regions, values.tolist(), strict=True)), self.table.atlas,
                             self.scale) | dict(over)
