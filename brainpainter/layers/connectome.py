"""A connectome's colours: each edge on the edges' scale, each node by its category or value (issue 43:
the layer's own module; the scales are chosen in :mod:`brainpainter.rendering.connectome_layers`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.model import Connectome, edge_keys, node_keys
from brainpainter.layers.kinds import RGB


def connectome_colors(connectome: Connectome, layers: Sequence[Any],
                      image: float | tuple[int, int, float] | None = None) -> dict[str, RGB]:
    """The colour of each node (``node:i``) and edge (``edge:k``) key, by the connectome's layers.

    `image`: of a series of matrices, the image (or a movie's ``(a, b, weight)`` between two) whose edge
    weights are drawn (:meth:`~brainpainter.connectome.series.EdgeSeries.at`).
    """
    out: dict[str, RGB] = {}
    by_kind = {layer.kind: layer.scale for layer in layers}
    if "edges" in by_kind:
        weights = (connectome.edges()[2] if connectome.series is None or image is None
                   else connectome.series.at(image))
        out.update(_keyed(edge_keys(len(weights)), by_kind["edges"](weights)))
    nodes = by_kind.get("nodes")
    if nodes is not None and nodes.categories and connectome.node_categories is not None:
        rgb = dict(nodes.categories)
        out.update(zip(node_keys(connectome.n_nodes), (rgb[c] for c in connectome.node_categories),
                       strict=True))
    elif nodes is not None and connectome.node_values is not None:
        out.update(_keyed(node_keys(connectome.n_nodes), nodes(np.asarray(connectome.node_values, float))))
    return out


def _keyed(keys: list[str], rgb: NDArray[Any]) -> dict[str, RGB]:
    return {k: (float(c[0]), float(c[1]), float(c[2])) for k, c in zip(keys, rgb, strict=True)}


@dataclass(frozen=True)
class ConnectomeColors:
    """The colours of a connectome's nodes and edges by its layers (`layers`: a run's, read by kind)."""

    connectome: Connectome
    layers: Sequence[Any]

    def colors(self, row: int) -> dict[str, RGB]:
        """The colours of image `row` (of a series of matrices: that matrix's edge weights)."""
        return connectome_colors(self.connectome, self.layers, row)

    def blend(self, a: int, b: int, weight: float) -> dict[str, RGB]:
        """Images `a` and `b`'s edge weights blended (a movie's frame between key frames)."""
        return connectome_colors(self.connectome, self.layers, (a, b, weight))
