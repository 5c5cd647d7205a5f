"""The connectome options of a run (``--connectome``, ``--nodes``, ``--top-edges``, ...), defined once.

The CLI's click options and the keywords of ``brainpainter.render`` (and of figure, movie, plot,
export) are made from these fields (:mod:`brainpainter.rendering.options`);
:meth:`ConnectomeOptions.load` reads what they name into a
:class:`~brainpainter.connectome.model.Connectome` with the edges to draw.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, TypedDict

from brainpainter.atlas.model import SPACES
from brainpainter.connectome.edges import (
    MAX_EDGES_DRAWN,
    kept_none,
    kept_none_text,
    parse_threshold,
    select_edges,
)
from brainpainter.connectome.labels import labelled_nodes
from brainpainter.connectome.model import Connectome
from brainpainter.errors import BrainPainterError, choice_error

if TYPE_CHECKING:
    from brainpainter.atlas.model import Atlas
    from brainpainter.atlas.template import Template
    from brainpainter.connectome.series import MatrixSeries

log = logging.getLogger(__name__)


class ConnectomeKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`ConnectomeOptions`."""

    connectome: Any
    nodes: Any
    node_values: Any
    node_categories: Any
    directed: bool
    edge_threshold: str | float | None
    top_edges: int | None
    edges_of: str | None
    nodes_space: str
    node_labels: bool
    node_labels_top: int | None
    node_labels_per_category: bool


@dataclass(frozen=True)
class ConnectomeOptions:
    """What connectome to draw, with which nodes, and which of its edges.

    Attributes
    ----------
    connectome : path or Connectome, optional
        A connectivity matrix (rows and columns in the atlas's region order, or named), or a
        :class:`Connectome` (Python); or a series of matrices, one per image
        (:mod:`brainpainter.connectome.series`).
    nodes : path, optional
        Node coordinates (``name,x,y,z`` in the template's space, or BrainNet Viewer ``.node``);
        default: the centroids of the atlas's regions.
    node_values : path or array, optional
        A value per node (sphere size and colour).
    node_categories : path or sequence, optional
        A network or module per node (categorical colours with a key).
    directed : bool
        The matrix's rows are the edges' sources (else the upper triangle is drawn).
    edge_threshold : str or float, optional
        Edges kept: ``|weight| >= 0.3``, or ``95%`` (the strongest 5 %).
    top_edges : int, optional
        The K strongest edges (by ``|weight|``) kept.
    edges_of : str, optional
        Only the edges of this node.
    nodes_space : str
        Space of the nodes file's coordinates (MNI152 is mapped into the template as tracts are).
    node_labels : bool
        Draw the nodes' labels (the connectome's ``node_labels``, else the node names) on the images.
    node_labels_top : int, optional
        Label only the K nodes of the largest node value (no values: the largest strength, the sum of
        the ``|weight|`` of their drawn edges); implies ``node_labels``.
    node_labels_per_category : bool
        ``node_labels_top`` ranks within each node category (the top K of every network).
    """

    connectome: Any = field(default=None, metadata={
        "help": "A connectivity matrix drawn as nodes and edges (CSV/TSV with or without names, .npy, .txt, "
                ".mat, CIFTI .pconn.nii, BrainNet Viewer .edge); several, one per image (a.csv,b.csv, a "
                "folder, a quoted glob, a T x N x N .npy): see docs/connectomes.md."})
    nodes: Any = field(default=None, metadata={
        "help": "Node coordinates (CSV name,x,y,z in the template's space, or BrainNet Viewer .node). "
                "Default: the centroids of the atlas's regions, in the matrix's order."})
    node_values: Any = field(default=None, metadata={
        "help": "A value per node: a file of one per node in the matrix's order, or a column of --nodes; "
                "drawn as sphere size (2-6 mm) and colour."})
    node_categories: Any = field(default=None, metadata={
        "help": "A network or module per node: a file of one per node in the matrix's order, or a column "
                "of --nodes; drawn in categorical colours with a key."})
    directed: bool = field(default=False, metadata={
        "help": "The matrix is directed (row = source); default: undirected, its upper triangle drawn."})
    edge_threshold: str | float | None = field(default=None, metadata={
        "help": "Edges drawn: |weight| at least this (0.3), or a percentile of |weight| (95%: the "
                "strongest 5 %)."})
    top_edges: int | None = field(default=None, metadata={
        "help": "Only the K strongest edges (by |weight|) are drawn (at most 5000 are drawn, the strongest, "
                "whatever is given)."})
    edges_of: str | None = field(default=None, metadata={
        "help": "Only the edges of this node (Left-precentral) are drawn."})
    nodes_space: str = field(default="template", metadata={
        "choices": SPACES, "help": "Space of the --nodes coordinates (MNI152 is mapped to the template)."})
    node_labels: bool = field(default=False, metadata={
        "help": "Draw the nodes' labels (a .node file's label column, else the node names) beside them."})
    node_labels_top: int | None = field(default=None, metadata={
        "help": "Label only the K nodes of the largest node value (no values: the largest strength, the "
                "sum of |weight| of their drawn edges); implies --node-labels."})
    node_labels_per_category: bool = field(default=False, metadata={
        "help": "With --node-labels-top K: the top K of each node category (network), so every network "
                "is named, not only the strongest."})

    def __post_init__(self) -> None:
        if self.connectome is None:
            given = [f"--{name.replace('_', '-')}" for name in ("nodes", "node_values", "node_categories",
                                                                "edge_threshold", "top_edges", "edges_of",
                                                                "node_labels_top", "directed", "node_labels",
                                                                "node_labels_per_category")
                     if getattr(self, name) not in (None, False)]
            if given:
                raise BrainPainterError(f"{given[0]} describes a connectome's nodes or edges, but no "
                                        "--connectome was given; give the matrix with --connectome FILE.")
        if self.nodes_space not in SPACES:
            raise choice_error("--nodes-space", self.nodes_space, SPACES)
        if self.edge_threshold is not None:
            parse_threshold(self.edge_threshold)  # a bad threshold fails before the matrix is read
        for name in ("top_edges", "node_labels_top"):
            count = getattr(self, name)
            if count is not None and (isinstance(count, bool) or int(count) < 0 or int(count) != count):
                raise BrainPainterError(f"--{name.replace('_', '-')} must be a whole number >= 0; {count!r} "
                                        "was given.")

    @property
    def given(self) -> bool:
        """Whether a connectome is drawn."""
        return self.connectome is not None

    def chosen(self, connectome: Connectome) -> Connectome:
        """`connectome` with only the edges drawn (``edge_threshold``, ``top_edges``, ``edges_of``; at most
        :data:`~brainpainter.connectome.edges.MAX_EDGES_DRAWN`, the strongest, whatever is given)."""
        return select_edges(connectome, threshold=self.edge_threshold, top=self.top_edges,
                            edges_of=self.edges_of)

    def _chosen_some(self, connectome: Connectome) -> Connectome:
        """:meth:`chosen`, refusing a threshold that keeps no edge of the matrix (the image would show the
        nodes only: mostly ``99`` meant as ``99%``)."""
        chosen = self.chosen(connectome)
        largest = kept_none(connectome, chosen, self.edge_threshold)
        if largest is not None:
            raise BrainPainterError(
                kept_none_text(self.edge_threshold, largest,
                               f"connectome matrix {str(self.connectome)[:80]!r}")
                + "; give a smaller threshold, or a percentage (e.g. '99%': the strongest 1 % of the edges).")
        return chosen

    def _series_chosen(self, series: MatrixSeries, read: Callable[[Any], Connectome]) -> Connectome:
        """The series' connectome; a threshold that keeps no edge of some matrices warns (naming them), of
        every matrix is refused."""
        from brainpainter.connectome.series import series_connectome

        empty: list[tuple[str, float]] = []

        def choose(connectome: Connectome) -> Connectome:
            chosen = self.chosen(connectome)
            largest = kept_none(connectome, chosen, self.edge_threshold)
            if largest is not None:
                empty.append((series.names[calls[0]], largest))
            calls[0] += 1
            return chosen

        calls = [0]
        connectome = series_connectome(series, read, choose)
        if not empty:
            return connectome
        largest = max(w for _, w in empty)
        what = f"{len(empty)} of the {len(series)} matrices of connectome series {series.source!r}"
        if len(empty) == len(series):
            raise BrainPainterError(kept_none_text(self.edge_threshold, largest, what, "their")
                                    + "; give a smaller threshold, or a percentage (e.g. '99%').")
        names = ", ".join(name for name, _ in empty[:5]) + (", ..." if len(empty) > 5 else "")
        warnings.warn(kept_none_text(self.edge_threshold, largest, what, "their")
                      + f" ({names}): those images show the nodes only.", UserWarning, stacklevel=2)
        return connectome

    def load(self, atlas: Atlas | None, template: Template | str = "fsaverage",
             surface: str = "pial", atlas_given: bool = True) -> Connectome | None:
        """The connectome to draw (None: none given), its nodes placed in `template`, its edges chosen.

        A matrix is read by :func:`~brainpainter.connectome.read.read_connectome` (nodes at the
        centroids of `atlas`'s regions on `surface`, or from ``nodes``); the edges drawn are chosen by
        :func:`~brainpainter.connectome.edges.select_edges`. A series of matrices (several files, a folder,
        a glob, a 3-D array: :func:`~brainpainter.connectome.series.matrix_series`) is read one matrix at a
        time into one connectome whose ``series`` colours each image
        (:func:`~brainpainter.connectome.series.series_connectome`).

        Raises
        ------
        BrainPainterError
            A file that cannot be read, names that match no region, a node file of another count, ...
        """
        if self.connectome is None:
            return None
        if isinstance(self.connectome, Connectome):
            given = [name for name in ("nodes", "node_values", "node_categories")
                     if getattr(self, name) is not None]
            if given:
                raise BrainPainterError(f"{given[0]}= describes the nodes of a matrix read from a file; a "
                                        "Connectome given carries its own (Connectome(node_values=...)).")
            connectome = self.chosen(self.connectome)
        else:
            from brainpainter.connectome.read import read_connectome
            from brainpainter.connectome.series import matrix_series

            def read(matrix: Any) -> Connectome:
                return read_connectome(
                    matrix, atlas, nodes=self.nodes, node_values=self.node_values,
                    node_categories=self.node_categories, directed=bool(self.directed),
                    space=self.nodes_space, template=template, surface=surface, atlas_given=atlas_given)

            series = matrix_series(self.connectome)
            connectome = (self._chosen_some(read(self.connectome)) if series is None
                          else self._series_chosen(series, read))
        if connectome.edges_left_out:
            log.warning("connectome: the strongest %d edges are drawn; %d more were chosen (at most %d are "
                        "drawn: give --top-edges or --edge-threshold)", MAX_EDGES_DRAWN,
                        connectome.edges_left_out, MAX_EDGES_DRAWN)
        if not self.node_labels and self.node_labels_top is None:
            return connectome
        return replace(connectome, labelled=labelled_nodes(connectome, self.node_labels_top,
                                                           self.node_labels_per_category))
