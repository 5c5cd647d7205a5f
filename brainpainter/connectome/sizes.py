"""Which atlases take a matrix without names of N rows, and whose node order its structure fits.

A matrix without names is placed by an atlas's node order
(:mod:`brainpainter.connectome.order`); several atlases take the same size
(Schaefer-400 in its 7- and 17-network orders, which are the same parcels in
different orders), so a matrix of the other order would be drawn with every
node in the wrong parcel, in silence. :func:`atlases_taking` names the
atlases of a size (installed, and the known plugins' not installed);
:func:`better_fit` says in which atlas's order the matrix's weights follow
the regions' places best (:func:`distance_fit`): real connectivity is stronger between near
regions, so the order the matrix was made in is the one that fits best.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import Atlas
from brainpainter.errors import BrainPainterError

#: Another atlas's fit must exceed the given atlas's by this factor to be named as the better one.
BETTER_FIT = 1.25
_SIZED_NAME = re.compile(r"^schaefer(\d+)_\d+n$")


def atlases_taking(n: int, node_order: Callable[[Atlas], tuple[tuple[str, ...], tuple[str, ...]]]
                   ) -> tuple[list[str], list[str]]:
    """Atlases that take a matrix without names of `n` rows.

    Parameters
    ----------
    n : int
    node_order : callable
        :func:`brainpainter.connectome.order.node_order`.

    Returns
    -------
    installed : list of str
        Installed atlases whose node order has `n` rows (a plugin that fails to load is skipped).
    elsewhere : list of str
        Atlases of the known plugins not installed whose name says they have `n` cortical regions.
    """
    from brainpainter.atlas import registry

    installed = []
    for name in registry.list_atlases():
        try:
            atlas = registry.get_atlas(name)
        except BrainPainterError:
            continue
        if n in {len(keys) for keys in node_order(atlas) if keys}:
            installed.append(name)
    elsewhere = [name for names in registry.KNOWN_ATLAS_PLUGINS.values() for name in names
                 if name not in installed and (hit := _SIZED_NAME.match(name)) and int(hit.group(1)) == n]
    return sorted(installed, key=_natural), elsewhere


def _natural(name: str) -> list[Any]:
    """``schaefer400_7n`` before ``schaefer400_17n``."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)]


def taking_text(n: int, installed: list[str], elsewhere: list[str]) -> str:
    """``atlases that take N rows: a, b (installed); c (pip install ...)``, or that none does."""
    from brainpainter.atlas.registry import KNOWN_ATLAS_PLUGINS

    parts = []
    if installed:
        parts.append(", ".join(installed[:8]) + (", ..." if len(installed) > 8 else ""))
    if elsewhere:
        dists = [d for d, names in KNOWN_ATLAS_PLUGINS.items() if set(names) & set(elsewhere)]
        parts.append(", ".join(elsewhere[:4]) + (", ..." if len(elsewhere) > 4 else "")
                     + f" (pip install {' '.join(dists)})")
    if not parts:
        return f"no atlas known here takes {n} rows"
    return f"the atlases that take {n} rows: " + "; ".join(parts)


def distance_fit(weights: NDArray[np.float64], positions: NDArray[np.float64]) -> float:
    """How well `weights` (N, N) follow the nodes' `positions` (N, 3): minus the correlation of each pair's
    weight with its distance (real connectivity is stronger between near regions, so the order a matrix
    was made in fits best; NaN weights and the diagonal left out)."""
    w = np.asarray(weights, dtype=np.float64)
    i, j = np.triu_indices(len(w), 1)
    distance = np.linalg.norm(positions[i] - positions[j], axis=1)
    keep = np.isfinite(w[i, j])
    if keep.sum() < 3 or np.ptp(w[i, j][keep]) == 0:
        return 0.0
    return float(-np.corrcoef(w[i, j][keep], distance[keep])[0, 1])


def better_fit(weights: NDArray[np.float64], atlas: Atlas, candidates: list[str],
               node_order: Callable[[Atlas], tuple[tuple[str, ...], tuple[str, ...]]],
               place: Callable[[Atlas, tuple[str, ...]], NDArray[np.float64]]
               ) -> tuple[str, float, float] | None:
    """Another of `candidates` in whose node order `weights` follow the regions' places clearly better.

    Parameters
    ----------
    weights : ndarray, (N, N)
    atlas : Atlas
        The atlas the matrix is placed in.
    candidates : list of str
        Installed atlases that take N rows.
    node_order, place : callable
        :func:`brainpainter.connectome.order.node_order`; ``place(atlas, keys)``: the regions' centroids.

    Returns
    -------
    (name, its fit, the given atlas's fit), or None
        None where none fits better by :data:`BETTER_FIT` (:func:`distance_fit`).
    """
    from brainpainter.atlas.registry import get_atlas

    def fit(a: Atlas) -> float:
        keys = next(k for k in node_order(a) if len(k) == len(weights))
        try:
            return distance_fit(weights, place(a, keys))
        except BrainPainterError:  # a region without a place in this template
            return 0.0

    others = [name for name in candidates if name != atlas.name]
    if not others:
        return None
    own = fit(atlas)
    scored = sorted(((fit(get_atlas(name)), name) for name in others), reverse=True)
    best, name = scored[0]
    return (name, best, own) if best > 0.05 and best > max(own, 0.0) * BETTER_FIT else None
