"""Which nodes of a connectome are labelled on its images (``--node-labels``, ``--node-labels-top K``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.model import Connectome


def node_strength(connectome: Connectome) -> NDArray[np.float64]:
    """Each node's strength, shape (N,) float64: the sum of ``|weight|`` of its drawn edges."""
    source, target, weight = connectome.edges()
    strength = np.zeros(connectome.n_nodes)
    np.add.at(strength, source, np.abs(weight))
    np.add.at(strength, target, np.abs(weight))
    return strength


def labelled_nodes(connectome: Connectome, top: int | None = None) -> tuple[int, ...]:
    """The nodes whose labels are drawn, in node order: every node with a label text, or the `top` of them
    by node value (NaN last; equal values by strength), or by strength (:func:`node_strength`) where
    there are no values.

    Parameters
    ----------
    connectome : Connectome
    top : int, optional
        How many (None: all).

    Returns
    -------
    tuple of int
        Node indices, increasing.
    """
    texts = connectome.label_texts()
    named = np.array([i for i, text in enumerate(texts) if text.strip()], dtype=np.intp)
    if top is None or top >= len(named):
        return tuple(int(i) for i in named)
    chosen = ranked(connectome, named)[:int(top)]
    return tuple(int(i) for i in np.sort(chosen))


def ranked(connectome: Connectome, nodes: NDArray[np.intp]) -> NDArray[np.intp]:
    """`nodes`, shape (K,), from the first to the last to label: by node value (NaN last), equal values by
    strength; without values by strength (:func:`node_strength`); ties in node order."""
    strength = node_strength(connectome)[nodes]
    values = strength if connectome.node_values is None else np.asarray(connectome.node_values, float)[nodes]
    values = np.where(np.isfinite(values), values, -np.inf)
    order: NDArray[np.intp] = nodes[np.lexsort((-strength, -values))]
    return order
