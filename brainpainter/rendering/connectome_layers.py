"""A connectome's two layers, edges and nodes, each on its own scale, and the colours they give each slot.

The edges' scale colours their weights: diverging, ``RdBu_r`` centred at 0, symmetric over the
largest ``|weight|`` drawn, unless ``--edges-*`` (or, for a connectome alone, the plain
``--cmap``/``--vmin``/...) say otherwise. The nodes are a layer when they have categories (a
categorical scale: its colour bar is their key) or values (a map's automatic scale,
:func:`brainpainter.maps.autoscale.choose_scale`, or ``--nodes-*``); without either they are drawn
in one neutral colour (:data:`~brainpainter.rendering.connectome_parts.NODE_COLOR`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from typing import Any

import numpy as np

from brainpainter.color.scale import ColourScale, ScaleOptions
from brainpainter.connectome.edges import MAX_EDGES_DRAWN
from brainpainter.connectome.model import Connectome
from brainpainter.maps.autoscale import choose_scale
from brainpainter.rendering.connectome_parts import connectome_parts
from brainpainter.rendering.layers import SCALE_FIELDS, Layer
from brainpainter.rendering.options import Options
from brainpainter.rendering.settings import RGB

#: The edges' default scale: diverging about a weight of 0.
EDGE_CENTER = 0.0
#: Categorical colour maps of node categories, by how many they hold at most (more: turbo, sampled).
CATEGORY_CMAPS = ((10, "tab10"), (20, "tab20"))


def connectome_kinds(connectome: Connectome | None) -> tuple[str, ...]:
    """The layers a connectome draws: ``edges``, and ``nodes`` when they have values or categories."""
    if connectome is None:
        return ()
    coloured = connectome.node_values is not None or connectome.node_categories is not None
    return ("edges", "nodes") if coloured else ("edges",)


def connectome_layers(options: Options, connectome: Connectome, first: bool) -> tuple[Layer, ...]:
    """The edge layer and (with node values or categories) the node layer of `connectome`.

    `first`: the edges are the run's first layer (a connectome alone), so the plain scale options
    (``--cmap``, ``--vmin``, ...) are theirs too.
    """
    plain = ScaleOptions(nan_color=options.scale.nan_color, missing_color=options.scale.missing_color)
    own = _own_options(options, "edges", first, plain)
    if all(getattr(own, name) is None for name in SCALE_FIELDS):
        own = replace(own, center=EDGE_CENTER)
    weights = connectome.edges()[2] if connectome.series is None else connectome.series.sample  # all images'
    edge_options, chosen = choose_scale(own, weights)
    edges = Layer("edges", replace(edge_options.scale(weights), chosen=chosen), 1.0,
                  _label(options, "edges", "edge weight"))
    if "nodes" not in connectome_kinds(connectome):
        return (edges,)
    if connectome.node_categories is not None:
        scale = category_scale(connectome.node_categories, plain)
        fallback = "network"
    else:
        assert connectome.node_values is not None
        values = np.asarray(connectome.node_values, dtype=float)
        node_options, chosen = choose_scale(_own_options(options, "nodes", False, plain), values)
        scale = replace(node_options.scale(values), chosen=chosen)
        fallback = "node value"
    return edges, Layer("nodes", scale, 1.0, _label(options, "nodes", fallback))


def _own_options(options: Options, kind: str, first: bool, plain: ScaleOptions) -> ScaleOptions:
    """Scale options of connectome layer `kind`: the plain ``--cmap``/``--vmin``/... with its own where it is
    the run's first layer, else its own ``--edges-*``/``--nodes-*`` alone.

    A connectome's layers after region values or a map always have a scale of their own (edge weights
    are not region values): the plain options are the first layer's, and a label (``--edges-label``)
    names a bar without taking them (``--cmap viridis --edges-label FC`` drew the edges in viridis over
    their own range instead of ``RdBu_r`` about 0).
    """
    if first:
        own = options.layers.scale_options(kind, options.scale, True)
        assert own is not None
        return own
    return replace(plain, **options.layers.given(kind))


def _label(options: Options, kind: str, fallback: str) -> str:
    """A connectome layer's colour-bar label: as given (``--edges-label FC``), else the layer's name
    (`fallback`: ``edge weight``, ``node value``, ``network``), never a file's name (issue 44: a bar named
    ``net400.txt`` or the matrix's file said where the numbers came from, not what they are)."""
    given = options.layers.label(kind)
    return given if given is not None else fallback


def category_scale(categories: tuple[str, ...], plain: ScaleOptions) -> ColourScale:
    """A categorical scale of node `categories` (N,): one colour each, in order of first appearance.

    Categories that all name Yeo's networks (``Vis``, ``Default``, ``SalVentAttnB``, ``DMN``, ...:
    :func:`network_colors`) take Yeo's published colours; others those of ``tab10``/``tab20``/``turbo``.
    """
    import matplotlib

    names = list(dict.fromkeys(categories))
    n = len(names)
    cmap = next((name for most, name in CATEGORY_CMAPS if n <= most), "turbo")
    where = np.arange(n) if cmap != "turbo" else np.linspace(0.05, 0.95, n)  # a listed map: its i-th colour
    colors = np.asarray(matplotlib.colormaps[cmap](where), dtype=float)[:, :3]
    networks = network_colors()
    if all(name.strip().lower() in networks for name in names):  # Yeo's networks: their published colours
        colors = np.array([networks[name.strip().lower()] for name in names], dtype=float).reshape(n, 3)
    keyed = tuple((name, (float(c[0]), float(c[1]), float(c[2])))
                  for name, c in zip(names, colors, strict=True))
    base = replace(plain, cmap=cmap, vmin=0.0, vmax=float(max(n - 1, 1))).scale()
    return replace(base, colors=np.vstack([colors, colors[-1:]]), categories=keyed)


@cache
def network_colors() -> dict[str, RGB]:
    """Yeo et al. 2011's network colours by lower-case network name or alias (``data/network_colors.tsv``)."""
    from importlib import resources

    from brainpainter.color.rgb import to_rgb

    text = resources.files("brainpainter.data").joinpath("network_colors.tsv").read_text("utf-8")
    rows = [line.split("\t") for line in text.splitlines() if line and not line.startswith("#")][1:]
    out: dict[str, RGB] = {}
    for name, color, *aliases in rows:
        rgb = to_rgb(color)
        for key in [name, *"|".join(aliases).split("|")]:
            if key.strip():
                out[key.strip().lower()] = rgb
    return out


def connectome_summary(connectome: Connectome) -> dict[str, Any]:
    """The manifest's ``connectome``: its nodes (name, position, value, category, the label drawn) and the
    edges drawn; ``labelled``: the names of the nodes labelled on the images (when any is); ``series``: a
    series' matrices and each image's edges (:meth:`~brainpainter.connectome.series.EdgeSeries.summary`)."""
    values = connectome.node_values
    nodes = []
    for i, name in enumerate(connectome.names):
        node: dict[str, Any] = {"name": name,
                                "position": [round(float(x), 3) for x in connectome.positions[i]]}
        if values is not None:
            node["value"] = float(values[i]) if np.isfinite(values[i]) else None
        if connectome.node_categories is not None:
            node["category"] = connectome.node_categories[i]
        if i in connectome.labelled:
            node["label"] = connectome.label_texts()[i]
        nodes.append(node)
    weights = connectome.edges()[2]
    out: dict[str, Any] = {
        "n_nodes": connectome.n_nodes, "n_edges": len(weights), "directed": connectome.directed,
        "weight_range": [float(weights.min()), float(weights.max())] if len(weights) else None,
        "nodes": nodes}
    if connectome.edges_left_out:
        out["edges_left_out"] = connectome.edges_left_out
        chosen = len(weights) + connectome.edges_left_out
        out["note"] = (f"the strongest {len(weights)} of {chosen} edges are drawn (at most "
                       f"{MAX_EDGES_DRAWN}); choose fewer with --top-edges or --edge-threshold")
    if connectome.labelled:
        out["labelled"] = [connectome.names[i] for i in connectome.labelled]
    if connectome.series is not None:
        out["series"] = connectome.series.summary()
    return out


@dataclass(frozen=True)
class ConnectomeLayer:
    """A connectome as a scene layer (:class:`~brainpainter.layers.kinds.PartsLayer`): its nodes and edges
    (:func:`~brainpainter.rendering.connectome_parts.connectome_parts`), drawn inside the glass cortex."""

    connectome: Connectome
    kind: str = "connectome"

    def parts(self, template: Any, slots_for: Callable[..., Any]) -> list[Any]:
        """Its nodes' spheres and edges' cylinders, by hemisphere."""
        return connectome_parts(self.connectome, slots_for)

    def summary(self) -> dict[str, Any]:
        """The manifest's ``connectome`` (:func:`connectome_summary`)."""
        return connectome_summary(self.connectome)

    def digest(self) -> str:
        """A digest of its nodes and edges (the web's painters are keyed by it)."""
        return str(self.connectome.digest())
