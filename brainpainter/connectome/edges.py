"""Which edges are drawn: a threshold on |weight|, the K strongest, the edges of one node.

The three combine, in this order: ``edges_of`` keeps the edges of one node;
``threshold`` then keeps those with ``|weight| >= threshold`` (a number), or
the strongest ``100 - p`` % of them (a percentile ``"p%"``, as nilearn's
``edge_threshold="95%"``; counted, so ``"95%"`` keeps round(5 % of E) edges);
``top`` then keeps the K strongest; last, at most :data:`MAX_EDGES_DRAWN` are kept
(the strongest), so a dense matrix of a thousand nodes (half a million edges) draws
in seconds and bounded memory instead of minutes and gigabytes; the connectome's
``edges_left_out`` says how many the cap left out (the manifest's note). The edges counted are those
:meth:`Connectome.edges` gives: the upper triangle of an undirected connectome,
every off-diagonal weight of a directed one. Ties go to the earlier edge (row
by row).
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError, nearest

#: Most edges drawn of one connectome (the strongest by |weight|); more are left out, with a note.
MAX_EDGES_DRAWN = 5000
_PERCENT = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*%\s*$")


def parse_threshold(threshold: Any) -> tuple[str, float]:
    """``("percentile", p)`` for ``"95%"``, ``("value", t)`` for a number (or its text).

    Raises
    ------
    BrainPainterError
        Not a number >= 0 nor a percentage from 0 to 100.
    """
    text = str(threshold).strip()
    hit = _PERCENT.match(text)
    if hit and 0 <= float(hit.group(1)) <= 100:
        return "percentile", float(hit.group(1))
    if not hit and not isinstance(threshold, bool):
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if math.isfinite(value) and value >= 0:
            return "value", value
    raise BrainPainterError(
        "the edge threshold must be a number >= 0 (kept: |weight| >= it) or a percentage from 0% to "
        f"100% (e.g. '95%': the strongest 5 % of the edges); {text[:40]!r} was given.")


def _strongest(weight: NDArray[np.float64], k: int) -> NDArray[np.intp]:
    """Indices of the `k` largest |weight| (ties: the earlier first)."""
    order = np.argsort(-np.abs(weight), kind="stable")
    return np.sort(order[:k])


def select_edges(conn: Connectome, *, threshold: Any = None, top: int | None = None,
                 edges_of: str | None = None, max_edges: int = MAX_EDGES_DRAWN) -> Connectome:
    """`conn` with only the chosen edges.

    Parameters
    ----------
    conn : Connectome
    threshold : float, str or None
        A number (keep ``|weight| >= threshold``) or a percentile ``"95%"`` (keep the strongest 5 %).
    top : int or None
        Keep the `top` strongest by |weight|.
    edges_of : str or None
        A node name: keep only its edges (case-insensitive).
    max_edges : int
        Keep at most this many (the strongest) of those chosen; ``edges_left_out`` counts the others.

    Returns
    -------
    Connectome
        The same nodes; NaN the weights of the edges not chosen.

    Raises
    ------
    BrainPainterError
        A bad threshold or `top`, or `edges_of` not among the nodes.
    """
    source, target, weight = conn.edges()
    keep = np.arange(len(weight))
    if edges_of is not None:
        node = _node_index(conn, edges_of)
        keep = keep[(source[keep] == node) | (target[keep] == node)]
    if threshold is not None:
        kind, value = parse_threshold(threshold)
        if kind == "value":
            keep = keep[np.abs(weight[keep]) >= value]
        else:
            keep = keep[_strongest(weight[keep], round(len(keep) * (100 - value) / 100))]
    if top is not None:
        if isinstance(top, bool) or not isinstance(top, int | np.integer) or top < 0:
            raise BrainPainterError(f"the number of top edges must be a whole number >= 0; {top!r} was "
                                    "given.")
        keep = keep[_strongest(weight[keep], int(top))]
    left_out = max(0, len(keep) - max_edges)
    if left_out:
        keep = keep[_strongest(weight[keep], max_edges)]
    weights = np.full_like(conn.weights, np.nan)
    weights[source[keep], target[keep]] = weight[keep]
    if not conn.directed:
        weights[target[keep], source[keep]] = weight[keep]
    return dataclasses.replace(conn, weights=weights, edges_left_out=left_out)


def kept_none(conn: Connectome, chosen: Connectome, threshold: Any) -> float | None:
    """The largest |weight| of `conn` where `threshold` left `chosen` no edge of the edges it had; else None.

    A threshold that keeps nothing is mostly a slip (``99`` for ``99%``): the image would show the nodes
    only, so the caller says so with this number.
    """
    if threshold is None or len(chosen.edges()[2]):
        return None
    weight = conn.edges()[2]
    return float(np.abs(weight).max()) if len(weight) else None


def kept_none_text(threshold: Any, largest: float, what: str, whose: str = "its") -> str:
    """``--edge-threshold 99 keeps no edge of WHAT: its largest |weight| is 0.91`` (a message's start)."""
    return (f"--edge-threshold {str(threshold).strip()[:40]} keeps no edge of {what}: {whose} largest "
            f"|weight| is {largest:.4g}")


def _node_index(conn: Connectome, name: str) -> int:
    lower = [n.lower() for n in conn.names]
    text = str(name).strip()
    if text.lower() in lower:
        return lower.index(text.lower())
    close = nearest(text, conn.names, n=3)
    shown = list(conn.names[:8]) + (["..."] if conn.n_nodes > 8 else [])
    raise BrainPainterError(
        f"--edges-of {text[:60]!r} is not a node of the connectome (its {conn.n_nodes} nodes are {shown})"
        + (f"; did you mean {close[0]!r}?" if close else "; give one of its node names."))
