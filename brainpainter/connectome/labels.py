"""Which nodes of a connectome are labelled on its images (``--node-labels``, ``--node-labels-top K``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError


def node_strength(connectome: Connectome) -> NDArray[np.float64]:
    """Each node's strength, shape (N,) float64: the sum of ``|weight|`` of its drawn edges."""
    source, target, weight = connectome.edges()
    strength = np.zeros(connectome.n_nodes)
    np.add.at(strength, source, np.abs(weight))
    np.add.at(strength, target, np.abs(weight))
    return strength


def labelled_nodes(connectome: Connectome, top: int | None = None,
                   per_category: bool = False) -> tuple[int, ...]:
    """The nodes whose labels are drawn, in node order: every node with a label text, or the `top` of them
    by node value (NaN last; equal values by strength), or by strength (:func:`node_strength`) where
    there are no values; with `per_category`, the `top` of each node category.

    Parameters
    ----------
    connectome : Connectome
    top : int, optional
        How many (None: all), in all or (`per_category`) in each category.
    per_category : bool
        Rank within each of ``connectome.node_categories`` (so every network is named).

    Returns
    -------
    tuple of int
        Node indices, increasing.

    Raises
    ------
    BrainPainterError
        `per_category` for nodes without categories.
    """
    texts = connectome.label_texts()
    named = np.array([i for i, text in enumerate(texts) if text.strip()], dtype=np.intp)
    if per_category and connectome.node_categories is None:
        raise BrainPainterError("--node-labels-per-category ranks the labelled nodes within each node "
                                "category, but the nodes have none; give --node-categories, or leave it out.")
    if top is None:
        return tuple(int(i) for i in named)
    if not per_category:
        return tuple(int(i) for i in np.sort(ranked(connectome, named)[:int(top)]))
    assert connectome.node_categories is not None
    category = np.asarray(connectome.node_categories, dtype=object)
    chosen = [ranked(connectome, named[category[named] == c])[:int(top)]
              for c in dict.fromkeys(category[named])]
    return tuple(int(i) for i in np.sort(np.concatenate(chosen))) if chosen else ()


def ranked(connectome: Connectome, nodes: NDArray[np.intp]) -> NDArray[np.intp]:
    """`nodes`, shape (K,), from the first to the last to label: by node value (NaN last), equal values by
    strength; without values by strength (:func:`node_strength`); ties in node order."""
    strength = node_strength(connectome)[nodes]
    values = strength if connectome.node_values is None else np.asarray(connectome.node_values, float)[nodes]
    values = np.where(np.isfinite(values), values, -np.inf)
    order: NDArray[np.intp] = nodes[np.lexsort((-strength, -values))]
    return order
