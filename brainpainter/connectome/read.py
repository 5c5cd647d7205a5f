"""The connectome resolver: a matrix, an atlas or a nodes file, and per-node vectors, to a "
":class:`Connectome`.

Weights: the diagonal is ignored; 0 and empty cells are no edge (as in
BrainNet Viewer and nilearn); NaN off the diagonal is dropped with a warning.
An undirected connectome is made symmetric from whichever triangle holds each
edge (a matrix that gives both, differently, warns and keeps the upper one).
"""

from __future__ import annotations

import os
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.model import SPACES, Atlas
from brainpainter.atlas.template import Template
from brainpainter.connectome.matrix import Matrix, read_matrix
from brainpainter.connectome.model import Connectome
from brainpainter.connectome.nodefiles import NodeTable, node_cells, node_texts, node_values, read_nodes
from brainpainter.connectome.order import matched_keys, ordered_keys
from brainpainter.errors import BrainPainterError, choice_error


def read_connectome(matrix: Any, atlas: Atlas | str | None = None, *,
                    nodes: str | os.PathLike[str] | None = None, node_values: Any = None,
                    node_categories: Any = None, node_labels: Any = None,
                    directed: bool = False, space: str = "template", template: Template | str = "fsaverage",
                    surface: str = "pial", atlas_given: bool = True) -> Connectome:
    """Read a connectivity matrix and place its nodes.

    Parameters
    ----------
    matrix : path-like or array-like, (N, N)
        CSV/TSV/text (with or without names in the first row and column), BrainNet Viewer ``.edge``,
        ``.npy``, ``.mat``, CIFTI ``.pconn.nii``, or the weights (:mod:`brainpainter.connectome.matrix`).
    atlas : Atlas or str, optional
        Without `nodes`: the nodes are its regions, by the matrix's names or in the atlas's node order
        (:mod:`brainpainter.connectome.order`), at their centroids
        (:mod:`brainpainter.connectome.centroids`).
    nodes : path-like, optional
        A coordinates table (``name,x,y,z``) or a BrainNet Viewer ``.node`` file, one node per row of
        the matrix (reordered by name where both have names).
    node_values, node_categories, node_labels : str, path-like or sequence, optional
        A column of `nodes`, a file of one entry per node, or the entries. A ``.node`` file's
        ``size``, ``color`` and ``label`` columns are the default ones. A text that is not a column
        is opened as a file: a caller that takes the text from someone else (a web form) passes the
        path of what they uploaded, never their text.
    directed : bool
        ``weights[i, j]`` is the edge from node i to node j only.
    space : str
        Space of the nodes file's coordinates (:data:`brainpainter.atlas.model.SPACES`); MNI152 is
        mapped into the template as tracts are.
    template : Template or str
        The template the nodes are placed in.
    surface : {"pial", "white", "inflated"}
        Surface the atlas centroids are taken from.
    atlas_given : bool
        False where `atlas` is a default the user did not choose: a matrix without names is then refused
        (naming the atlases that take its size) unless that atlas alone takes it.

    Returns
    -------
    Connectome

    Raises
    ------
    BrainPainterError
        Bad input (see the module docstrings); every message is one line.
    """
    if space not in SPACES:
        raise choice_error("the nodes' space (--space)", space, SPACES)
    m = read_matrix(matrix)
    n = m.weights.shape[0]
    atlas, table, names, positions = _nodes(m, atlas, nodes, space, template, surface, atlas_given)
    key_of = None
    if table is None and atlas is not None:
        from brainpainter.table.names import NameResolver

        key_of = NameResolver.for_atlas(atlas).resolve

    def cells(given: Any, column: str, what: str) -> list[Any] | None:
        return node_cells(_given(given, table, column), n, what, table, names, key_of)

    values = cells(node_values, "size", "node values")
    categories = cells(node_categories, "color", "node categories")
    labels = cells(node_labels, "label", "node labels")
    return Connectome(
        names=tuple(names), positions=np.asarray(positions, dtype=np.float64),
        weights=edge_weights(m.weights, directed, m.source), directed=bool(directed),
        node_values=None if values is None else node_values_of(values, _given(node_values, table, "size")),
        node_categories=None if categories is None else node_texts(categories, numbers=True),
        node_labels=None if labels is None else node_texts(labels),
    )


def _nodes(m: Matrix, atlas: Atlas | str | None, nodes: str | os.PathLike[str] | None, space: str,
           template: Template | str, surface: str, atlas_given: bool = True
           ) -> tuple[Atlas | None, NodeTable | None, tuple[str, ...], NDArray[np.float64]]:
    """The atlas (loaded), the nodes file (in the matrix's order), the node names and positions."""
    if isinstance(atlas, str):
        from brainpainter.atlas.registry import get_atlas

        atlas = get_atlas(atlas)
    if nodes is not None:
        table = read_nodes(nodes)
        order = _node_rows(m, table)
        names = tuple(table.names[i] for i in order)
        positions = _placed(table.positions[order], space, atlas, template)
        columns = {k: [v[i] for i in order] for k, v in table.columns.items()}
        return atlas, NodeTable(names, positions, columns, table.source), names, positions
    if atlas is None:
        raise BrainPainterError(
            f"connectome matrix {m.source!r}: its nodes need a place; give an atlas (its regions' "
            "centroids) or a nodes file (name,x,y,z, or a BrainNet Viewer .node).")
    from brainpainter.connectome.centroids import region_centroids

    names = (matched_keys(m.names, atlas, m.source) if m.names is not None
             else ordered_keys(atlas, m.weights, m.source, atlas_given,
                               lambda a, keys: region_centroids(a, keys, template, surface)))
    return atlas, None, names, region_centroids(atlas, names, template, surface)


def _given(given: Any, table: NodeTable | None, column: str) -> Any:
    """`given`, or a BrainNet Viewer ``.node`` file's own `column` where it fills it."""
    if given is None and table is not None and table.is_brainnet and any(table.columns[column]):
        return column
    return given


def node_values_of(cells: list[Any], given: Any) -> NDArray[np.float64]:
    """`cells` as numbers, named in messages by what was `given` (a column, a file or values)."""
    return node_values(cells, str(given) if isinstance(given, str | os.PathLike) else "given")


def _node_rows(m: Matrix, table: NodeTable) -> list[int]:
    """Row of `table` for each node of the matrix: by name where the matrix names its nodes."""
    n = m.weights.shape[0]
    if len(table.names) != n:
        raise BrainPainterError(
            f"nodes file {table.source!r} has {len(table.names)} nodes but connectome matrix "
            f"{m.source!r} has {n} rows; give one node per row of the matrix, in its order.")
    if m.names is None:
        return list(range(n))
    where = {name.lower(): i for i, name in enumerate(table.names)}
    missing = [name for name in m.names if name.lower() not in where]
    if missing:
        from brainpainter.errors import nearest

        close = nearest(missing[0], table.names)
        raise BrainPainterError(
            f"connectome matrix {m.source!r} names {len(missing)} node(s) that nodes file "
            f"{table.source!r} lacks, e.g. {missing[0]!r}"
            + (f" (did you mean {close[0]!r}?)" if close else "") + "; give the same node names in both.")
    return [where[name.lower()] for name in m.names]


def _placed(positions: NDArray[np.float64], space: str, atlas: Atlas | None,
            template: Template | str) -> NDArray[np.float64]:
    """Coordinates in `space` mapped into the template's (as tracts are)."""
    if space == "template":
        return positions
    from brainpainter.atlas.volumes import space_transform
    from brainpainter.connectome.centroids import atlas_template

    if atlas is not None:
        tpl = atlas_template(atlas, template)
    else:
        from brainpainter.atlas.template import load_template

        tpl = template if isinstance(template, Template) else load_template(template)
    affine = space_transform(space, tpl)
    mapped: NDArray[np.float64] = positions @ affine[:3, :3].T + affine[:3, 3]
    return mapped


def edge_weights(weights: NDArray[np.float64], directed: bool, source: str) -> NDArray[np.float64]:
    """The weights as a :class:`Connectome` holds them: NaN for no edge and on the diagonal.

    Parameters
    ----------
    weights : ndarray, (N, N)
    directed : bool
        Undirected: made symmetric, each edge from the triangle that holds it.
    source : str
        For the warnings.

    Returns
    -------
    ndarray, (N, N) float64
    """
    w = np.array(weights, dtype=np.float64)
    off = ~np.eye(len(w), dtype=bool)
    dropped = int((np.isnan(w) & off).sum())
    if dropped:
        warnings.warn(f"connectome matrix {source!r}: {dropped} NaN weight(s) off the diagonal were "
                      "dropped (no edge); give 0 or leave the cell empty where there is no edge.",
                      UserWarning, stacklevel=3)
    w[w == 0] = np.nan
    np.fill_diagonal(w, np.nan)
    if directed:
        return w
    upper, lower = np.triu(w), np.triu(w.T)  # lower triangle seen from above
    upper[np.tril(np.ones_like(w, dtype=bool))] = np.nan
    lower[np.tril(np.ones_like(w, dtype=bool))] = np.nan
    both = np.isfinite(upper) & np.isfinite(lower)
    differ = int((both & ~np.isclose(upper, lower, rtol=1e-6, atol=0)).sum())
    if differ:
        warnings.warn(f"connectome matrix {source!r} is not symmetric ({differ} pairs differ); the "
                      "upper triangle is drawn. Give --directed to draw both directions.", UserWarning,
                      stacklevel=3)
    sym = np.where(np.isfinite(upper), upper, lower)
    out: NDArray[np.float64] = np.where(np.isfinite(sym), sym, sym.T)
    return out
