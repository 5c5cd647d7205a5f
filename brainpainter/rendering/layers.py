"""Layers: each kind of data drawn (regions, a map, tracts, a connectome's nodes and edges) on its own scale.

A :class:`Layer` is one kind of data's colour scale, opacity and colour-bar label; a run's
layers are ordered, the first being its main input (a region table, a map, or tract values
alone). :class:`LayerOptions` holds the options of each kind (``--regions-cmap``,
``--map-vmin``, ``--tracts-vmax``, ``--map-alpha``, ...), one definition from which the CLI
is made (:mod:`brainpainter.rendering.options`). The plain ``--cmap``/``--vmin``/``--vmax``
are the first layer's; a later layer given options of its own (or a label) gets a scale of its own
(:meth:`LayerOptions.scale_options`), one given none shares the first layer's scale.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any, TypedDict

from brainpainter.color.scale import ColourScale, ScaleOptions
from brainpainter.errors import BrainPainterError, within

#: The kinds of data a layer draws, in the order of their options.
LAYER_KINDS = ("regions", "map", "tracts", "nodes", "edges", "blobs")
#: The colour-scale options each layer has (the fields of :class:`ScaleOptions` that make its colours).
SCALE_FIELDS = ("gradient", "cmap", "vmin", "vmax", "center")
_WHAT = {"regions": "Region values", "map": "The map", "tracts": "Tract values",
         "nodes": "Node values", "edges": "Edge weights", "blobs": "Blob values"}
_GIVE = {"regions": "give a region table as INPUT", "map": "give a map (--lh/--rh or --volume)",
         "tracts": "give tract values (--tract-values, or bundle columns in INPUT, with --tracts)",
         "nodes": "give a connectome (--connectome) with --node-values or --node-categories",
         "edges": "give a connectome (--connectome)",
         "blobs": "give a volume's clusters (--volume-surface FILE --threshold T)"}


@dataclass(frozen=True)
class Layer:
    """One kind of data drawn, with its colour scale.

    Attributes
    ----------
    kind : {"regions", "map", "tracts", "nodes", "edges", "blobs"}
    scale : ColourScale
        A categorical layer's (node categories) carries them (``scale.categories``).
    opacity : float
        0-1: how much of the layer covers the layers below it.
    label : str
        Its colour bar's label (a file's name where none was given).
    own_scale : bool
        Whether its scale is its own; False: it shares the first layer's (one colour bar).
    """

    kind: str
    scale: ColourScale
    opacity: float = 1.0
    label: str = ""
    own_scale: bool = True

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (the manifest's ``layers``)."""
        return {"kind": self.kind, "label": self.label, "opacity": self.opacity,
                "scale": self.scale.to_dict()}


def colorbar_layers(layers: tuple[Layer, ...]) -> list[Layer]:
    """The layers that need a colour bar of their own: the first, and every later one with its own scale."""
    return [layer for k, layer in enumerate(layers) if k == 0 or layer.own_scale]


def without_regions(layers: Sequence[Layer]) -> bool:
    """Whether the first layer is a connectome's edges or a volume's blobs drawn alone: no region
    values, so a figure, movie or plot shows no region swatch (no data, not measured)."""
    return bool(layers) and layers[0].kind in ("edges", "blobs")


def first_bar_label(layers: tuple[Layer, ...], label: str | None, own: str | None) -> str | None:
    """The first colour bar's label: `label` (``--label``), else its layer's own (`own`: ``--map-label``,
    a Scene layer's ``label=``), else beside other bars its layer's (its file's name); None: none."""
    if label is not None or own is not None:
        return label if label is not None else own
    return layers[0].label if len(colorbar_layers(layers)) > 1 else None


class LayerKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`LayerOptions`."""

    regions_gradient: str | None
    regions_cmap: str | None
    regions_vmin: float | None
    regions_vmax: float | None
    regions_center: float | None
    regions_label: str | None
    map_gradient: str | None
    map_cmap: str | None
    map_vmin: float | None
    map_vmax: float | None
    map_center: float | None
    map_label: str | None
    map_alpha: float
    tracts_gradient: str | None
    tracts_cmap: str | None
    tracts_vmin: float | None
    tracts_vmax: float | None
    tracts_center: float | None
    tracts_label: str | None
    nodes_gradient: str | None
    nodes_cmap: str | None
    nodes_vmin: float | None
    nodes_vmax: float | None
    nodes_center: float | None
    nodes_label: str | None
    edges_gradient: str | None
    edges_cmap: str | None
    edges_vmin: float | None
    edges_vmax: float | None
    edges_center: float | None
    edges_label: str | None
    blobs_gradient: str | None
    blobs_cmap: str | None
    blobs_vmin: float | None
    blobs_vmax: float | None
    blobs_center: float | None
    blobs_label: str | None


def _scale_field(kind: str, name: str) -> Any:
    """A field of :class:`LayerOptions`: option `name` of :class:`ScaleOptions`, for layer `kind` only."""
    help_text = next(f for f in fields(ScaleOptions) if f.name == name).metadata["help"]
    return field(default=None, metadata={
        "help": f"{_WHAT[kind]} only: {help_text[0].lower()}{help_text[1:]}"})


def _label_field(kind: str) -> Any:
    return field(default=None, metadata={
        "help": f"Colour-bar label of {_WHAT[kind].lower()} (default: its file's name)."})


@dataclass(frozen=True)
class LayerOptions:
    """The colour options of each layer; those not given follow the plain ``--cmap``/``--vmin``/...

    Attributes
    ----------
    regions_gradient, regions_cmap, regions_vmin, regions_vmax, regions_center : optional
        The region values' scale (as :class:`ScaleOptions`).
    map_gradient, map_cmap, map_vmin, map_vmax, map_center : optional
        The map's scale.
    tracts_gradient, tracts_cmap, tracts_vmin, tracts_vmax, tracts_center : optional
        The tract values' scale.
    nodes_gradient, nodes_cmap, nodes_vmin, nodes_vmax, nodes_center : optional
        A connectome's node values' scale.
    edges_gradient, edges_cmap, edges_vmin, edges_vmax, edges_center : optional
        A connectome's edge weights' scale (default: diverging, ``RdBu_r`` centred at 0).
    blobs_gradient, blobs_cmap, blobs_vmin, blobs_vmax, blobs_center : optional
        A volume's blobs' scale (``--volume-surface``; default: automatic from the threshold to the peak).
    regions_label, map_label, tracts_label, nodes_label, edges_label, blobs_label : str, optional
        Each layer's colour-bar label.
    map_alpha : float
        Opacity of a map drawn over region colours, 0-1.
    """

    regions_gradient: str | None = _scale_field("regions", "gradient")
    regions_cmap: str | None = _scale_field("regions", "cmap")
    regions_vmin: float | None = _scale_field("regions", "vmin")
    regions_vmax: float | None = _scale_field("regions", "vmax")
    regions_center: float | None = _scale_field("regions", "center")
    regions_label: str | None = _label_field("regions")
    map_gradient: str | None = _scale_field("map", "gradient")
    map_cmap: str | None = _scale_field("map", "cmap")
    map_vmin: float | None = _scale_field("map", "vmin")
    map_vmax: float | None = _scale_field("map", "vmax")
    map_center: float | None = _scale_field("map", "center")
    map_label: str | None = _label_field("map")
    map_alpha: float = field(default=1.0, metadata={
        "help": "Opacity of a map drawn over region colours (INPUT with --lh/--rh), 0 to 1."})
    tracts_gradient: str | None = _scale_field("tracts", "gradient")
    tracts_cmap: str | None = _scale_field("tracts", "cmap")
    tracts_vmin: float | None = _scale_field("tracts", "vmin")
    tracts_vmax: float | None = _scale_field("tracts", "vmax")
    tracts_center: float | None = _scale_field("tracts", "center")
    tracts_label: str | None = _label_field("tracts")
    nodes_gradient: str | None = _scale_field("nodes", "gradient")
    nodes_cmap: str | None = _scale_field("nodes", "cmap")
    nodes_vmin: float | None = _scale_field("nodes", "vmin")
    nodes_vmax: float | None = _scale_field("nodes", "vmax")
    nodes_center: float | None = _scale_field("nodes", "center")
    nodes_label: str | None = _label_field("nodes")
    edges_gradient: str | None = _scale_field("edges", "gradient")
    edges_cmap: str | None = _scale_field("edges", "cmap")
    edges_vmin: float | None = _scale_field("edges", "vmin")
    edges_vmax: float | None = _scale_field("edges", "vmax")
    edges_center: float | None = _scale_field("edges", "center")
    edges_label: str | None = _label_field("edges")
    blobs_gradient: str | None = _scale_field("blobs", "gradient")
    blobs_cmap: str | None = _scale_field("blobs", "cmap")
    blobs_vmin: float | None = _scale_field("blobs", "vmin")
    blobs_vmax: float | None = _scale_field("blobs", "vmax")
    blobs_center: float | None = _scale_field("blobs", "center")
    blobs_label: str | None = _label_field("blobs")

    def __post_init__(self) -> None:
        if not within(self.map_alpha, 0.0, 1.0):
            raise BrainPainterError(f"--map-alpha must be a number from 0 (transparent) to 1 (opaque); "
                                    f"{self.map_alpha!r} was given.")
        for kind in LAYER_KINDS:
            own = self.given(kind)
            if own:
                try:
                    ScaleOptions(**own)  # a bad colour map or range fails now, before any data is read
                except BrainPainterError as exc:
                    raise BrainPainterError(f"--{kind}-* options: {exc}") from None

    def given(self, kind: str) -> dict[str, Any]:
        """The scale options given for layer `kind` (``{"cmap": "magma", "vmin": 0.3}``)."""
        return {name: value for name in SCALE_FIELDS
                if (value := getattr(self, f"{kind}_{name}")) is not None}

    def label(self, kind: str) -> str | None:
        """The colour-bar label given for layer `kind`."""
        label: str | None = getattr(self, f"{kind}_label")
        return label

    def check_drawn(self, kinds: Sequence[str]) -> None:
        """Refuse options of a layer the run does not draw (``--tracts-cmap`` and no tract values).

        Raises
        ------
        BrainPainterError
            Naming the first such option and what draws that layer.
        """
        for kind in LAYER_KINDS:
            if kind in kinds:
                continue
            names = [*self.given(kind), *(["label"] if self.label(kind) is not None else []),
                     *(["alpha"] if kind == "map" and float(self.map_alpha) != 1.0 else [])]
            if names:
                raise BrainPainterError(
                    f"--{kind}-{names[0]} colours {_WHAT[kind].lower()}, but this run draws none "
                    f"(it draws {', '.join(kinds) or 'nothing with values'}); {_GIVE[kind]}, or leave "
                    f"the --{kind}-* options out.")

    def scale_options(self, kind: str, base: ScaleOptions, first: bool) -> ScaleOptions | None:
        """The scale options of layer `kind`: `base` (the plain options) for the first layer, with its own.

        A later layer given none of its own shares the first layer's scale (None); given some, or a
        label (``--tracts-label FA``: a colour bar of its own to name), its scale is its own: its
        options, else the colour map or gradient of `base`, and its range from its own values.
        """
        own = self.given(kind)
        if not first and not own and self.label(kind) is None:
            return None
        if "cmap" in own or "gradient" in own:  # its own colour map replaces the plain one
            base = replace(base, cmap=None, gradient=None)
        if first:
            return replace(base, **own)
        inherited = {"gradient": base.gradient, "cmap": base.cmap, "nan_color": base.nan_color,
                     "missing_color": base.missing_color}
        return ScaleOptions(**{**inherited, **own})
