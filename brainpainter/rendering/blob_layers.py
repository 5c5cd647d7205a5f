"""A volume's blobs as a layer: their values on a scale of their own, and the colour of each value level.

The scale is made from ``--blobs-*`` (or, for blobs drawn alone, the plain ``--cmap``/``--vmin``/...);
given no range it spans the threshold to the peak (``viridis``; clusters of both signs: ``RdBu_r``
from -peak to +peak, centred at 0), so the bar starts where the blobs do.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from brainpainter.color.scale import ScaleOptions
from brainpainter.maps.autoscale import choose_scale
from brainpainter.maps.clusters import Blobs
from brainpainter.rendering.blob_parts import blob_keys, blob_parts
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.parts import PartGeometry
from brainpainter.rendering.settings import RGB


def load_blobs(options: Options) -> Blobs | None:
    """The clusters of ``--volume-surface`` above ``--threshold`` (None: no volume given)."""
    from brainpainter.maps.clusters import find_blobs

    scene = options.scene
    if scene.volume_surface is None:
        return None
    return find_blobs(scene.volume_surface, options.maps.threshold, float(scene.min_cluster_mm3))


def blob_kinds(blobs: Blobs | None) -> tuple[str, ...]:
    """The layers blobs draw: ``("blobs",)``, or none without them."""
    return () if blobs is None else ("blobs",)


def blob_layer(options: Options, blobs: Blobs, first: bool) -> Layer:
    """The blobs' layer; `first`: they are the run's first layer (drawn alone), so the plain scale
    options are theirs too."""
    plain = ScaleOptions(nan_color=options.scale.nan_color, missing_color=options.scale.missing_color)
    own = options.layers.scale_options("blobs", options.scale, first) or plain
    values = blobs.values
    if own.vmin is None and own.vmax is None and own.center is None:  # from the threshold to the peak
        top, signs = max(abs(c.peak) for c in blobs.clusters), {c.sign for c in blobs.clusters}
        lo, hi = ((-top, top) if len(signs) == 2 else (blobs.threshold, top) if 1 in signs
                  else (-top, -blobs.threshold))
        own = replace(own, vmin=lo, vmax=hi, center=0.0 if len(signs) == 2 else None)
    chosen_options, chosen = choose_scale(own, values)
    scale = replace(chosen_options.scale(values), chosen=chosen)
    label = options.layers.label("blobs")
    if label is None:
        source = options.scene.volume_surface
        label = Path(source).name if isinstance(source, str | Path) else blobs.source
    return Layer("blobs", scale, 1.0, label)


def blob_colors(blobs: Blobs, layers: tuple[Layer, ...]) -> dict[str, RGB]:
    """The colour of each blob level's key (``blob:i``) on the blobs' layer's scale."""
    scale = next(layer.scale for layer in layers if layer.kind == "blobs")
    rgb = scale(blobs.levels)
    return {k: (float(c[0]), float(c[1]), float(c[2])) for k, c in zip(blob_keys(len(rgb)), rgb, strict=True)}


@dataclass(frozen=True)
class BlobLayer:
    """The blobs drawn, as any drawn layer (:class:`brainpainter.layers.kinds.DrawnLayer`): their part,
    their value levels' colours on `own`'s scale, their layer and their manifest entry."""

    blobs: Blobs
    own: Layer
    kind: str = "blobs"

    def parts(self, template: Any, slots_for: Callable[..., Any]) -> list[PartGeometry]:
        """Their one part, kind ``blob`` (:func:`~brainpainter.rendering.blob_parts.blob_parts`)."""
        return blob_parts(self.blobs, template, slots_for)

    def colors(self, row: int) -> dict[str, RGB]:
        """Each value level's colour (the same in every image)."""
        return blob_colors(self.blobs, (self.own,))

    def layer(self) -> Layer:
        """Their layer (made with the run's others: :func:`blob_layer`)."""
        return self.own

    def summary(self) -> dict[str, Any]:
        """The manifest's ``blobs``: the clusters drawn."""
        return self.blobs.summary()

    def digest(self) -> str:
        """A digest of the blobs drawn (the web's painters are keyed by it)."""
        return str(self.blobs.digest())


def drawn_blobs(blobs: Blobs | None, layers: tuple[Layer, ...]) -> tuple[BlobLayer, ...]:
    """The blobs as a drawn layer (with their layer among `layers`); none without blobs."""
    if blobs is None:
        return ()
    return (BlobLayer(blobs, next(layer for layer in layers if layer.kind == "blobs")),)
