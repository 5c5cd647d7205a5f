"""The tracts layer's colours: each bundle (or bundle node of a profile) on the tracts' own scale."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from brainpainter.color.scale import ColourScale
from brainpainter.layers.kinds import RGB
from brainpainter.table.rows import interpolate
from brainpainter.tracts.values import MISSING_TRACT_KEY, TractValues


def tract_colors(values: Mapping[str, float], scale: ColourScale) -> dict[str, RGB]:
    """Colour of each bundle (or bundle node) key for one image; NaN: the scale's NaN colour; the bundles
    drawn without a value (:data:`~brainpainter.tracts.values.MISSING_TRACT_KEY`): missing colour."""
    keys = list(values)
    m = scale.missing_color
    missing: dict[str, RGB] = {MISSING_TRACT_KEY: (float(m[0]), float(m[1]), float(m[2]))}
    if not keys:
        return missing
    rgb = scale(np.array([values[k] for k in keys], dtype=float))
    return {k: (float(c[0]), float(c[1]), float(c[2])) for k, c in zip(keys, rgb, strict=True)} | missing


@dataclass(frozen=True)
class TractColors:
    """The colours of the bundle values of a run's images (`images`: the run's image names, by row)."""

    values: TractValues
    images: Sequence[str]
    scale: ColourScale

    def colors(self, row: int) -> dict[str, RGB]:
        """Each bundle's colour in image `row`."""
        return tract_colors(self.values.row(self.images[row]), self.scale)

    def blend(self, a: int, b: int, weight: float) -> dict[str, RGB]:
        """Rows `a` and `b`'s bundle values blended (a movie's frame between key frames)."""
        ra, rb = (self.values.row(self.images[k]) for k in (a, b))
        blended = interpolate(np.array(list(ra.values())), np.array(list(rb.values())), weight)
        return tract_colors(dict(zip(ra, blended.tolist(), strict=True)), self.scale)
