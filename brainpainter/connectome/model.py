"""A connectome: nodes (names, positions, values, categories, labels) and the weights between them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

#: Palette keys of a connectome's parts: ``node:i``, ``edge:k``.
NODE_KEY, EDGE_KEY = "node:", "edge:"

def node_keys(n: int) -> list[str]:
    """Palette keys of `n` nodes (``node:0`` ...)."""
    return [f"{NODE_KEY}{i}" for i in range(n)]


def edge_keys(n: int) -> list[str]:
    """Palette keys of `n` edges (``edge:0`` ..., in the order of ``Connectome.edges()``)."""
    return [f"{EDGE_KEY}{k}" for k in range(n)]


#: Most characters of a node's label drawn on an image (a longer one ends with an ellipsis).
MAX_LABEL_CHARS = 60


def _label(text: str) -> str:
    """A node's label as drawn: control characters as spaces, at most :data:`MAX_LABEL_CHARS` characters."""
    shown = "".join(" " if ord(c) < 32 or 127 <= ord(c) < 160 else c for c in str(text)[:MAX_LABEL_CHARS + 1])
    return shown if len(shown) <= MAX_LABEL_CHARS else shown[:MAX_LABEL_CHARS - 1] + "\u2026"


class EdgeSeries(Protocol):
    """What a connectome drawn from a series of matrices knows of them
    (:class:`brainpainter.connectome.series.EdgeSeries`)."""

    @property
    def names(self) -> tuple[str, ...]:
        """The image of each matrix, (T,)."""

    @property
    def given(self) -> str:
        """What the series was given as, for messages."""

    @property
    def sample(self) -> NDArray[np.float64]:
        """Weights the edges' colour scale is chosen from, (S,)."""

    def __len__(self) -> int: ...

    def at(self, image: float | tuple[int, int, float]) -> NDArray[np.float64]:
        """The weights of the edges drawn (:meth:`Connectome.edges`'s order) in `image`, (E,)."""

    def summary(self) -> dict[str, Any]:
        """The manifest's ``series``."""


@dataclass(frozen=True)
class Connectome:
    """Nodes in the template's space and the weights of the edges between them.

    Attributes
    ----------
    names : tuple of str, (N,)
        Node names (region names of the atlas, or the names given).
    positions : ndarray, (N, 3) float64
        Node centres in the template's space (mm), the space the meshes are in.
    weights : ndarray, (N, N) float64
        Edge weights; NaN where there is no edge. Symmetric unless ``directed``;
        the diagonal is ignored.
    directed : bool
        Whether ``weights[i, j]`` is the edge from node i to node j only.
    node_values : ndarray, (N,) float64, or None
        One value per node (drawn as sphere size and/or colour); NaN where unknown.
    node_categories : tuple of str, (N,), or None
        A category per node (a network or module), drawn in categorical colours with a key.
    node_labels : tuple of str, (N,), or None
        Text of each node's label ("" for none; None: the node names).
    labelled : tuple of int
        The nodes whose labels are drawn on the images (``--node-labels``), in order; none by default.
    label_share : float, optional
        Height of the labels' text as a share of the image's (None: the renderer's default; a figure sets
        it so that its labels print at least 7 pt).
    series : EdgeSeries, optional
        A series of matrices, one per image (:mod:`brainpainter.connectome.series`): `weights` are then
        the edges drawn in every image at their largest ``|weight|``, and the series gives each image's.
    edges_left_out : int
        Edges chosen but not drawn: beyond :data:`brainpainter.connectome.edges.MAX_EDGES_DRAWN` (the
        strongest are drawn).
    """

    names: tuple[str, ...]
    positions: NDArray[np.float64]
    weights: NDArray[np.float64]
    directed: bool = False
    node_values: NDArray[np.float64] | None = None
    node_categories: tuple[str, ...] | None = None
    node_labels: tuple[str, ...] | None = None
    labelled: tuple[int, ...] = ()
    label_share: float | None = None
    series: EdgeSeries | None = None
    edges_left_out: int = 0

    @property
    def n_nodes(self) -> int:
        """Number of nodes N."""
        return len(self.names)

    def label_texts(self) -> tuple[str, ...]:
        """The label drawn of each node, (N,): its ``node_labels`` entry where given, else its name; at most
        :data:`MAX_LABEL_CHARS` characters (a longer one ends with an ellipsis), control characters as
        spaces."""
        texts = self.names if self.node_labels is None else self.node_labels
        return tuple(_label(text) for text in texts)

    def digest(self) -> str:
        """A SHA-256 of everything drawn (names, positions, weights, per-node vectors): equal connectomes,
        equal digests (a cached painter's key)."""
        import hashlib
        import pickle

        return hashlib.sha256(pickle.dumps(self)).hexdigest()

    def edges(self) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
        """The edges drawn: finite off-diagonal weights (the upper triangle unless ``directed``).

        Returns
        -------
        source, target : ndarray, (E,) intp
            Node indices of each edge's ends.
        weight : ndarray, (E,) float64
            Each edge's weight.
        """
        keep = np.isfinite(self.weights)
        np.fill_diagonal(keep, False)
        if not self.directed:
            keep = np.triu(keep)
        source, target = np.nonzero(keep)
        return source, target, self.weights[source, target]
