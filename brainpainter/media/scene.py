"""``brainpainter.Scene``: layers added one by one (a region table, a map, tracts, a contour, an outline),
drawn as the command line draws them.

A :class:`Scene` only translates its layers into the run's options (``regions_cmap``,
``map_alpha``, ``tracts``, ``tract_values``, ``contour``, ``outline``, ...) and calls the same
functions as the commands (:func:`brainpainter.render`, :func:`brainpainter.figure`, ``movie``,
``export``), so a scene renders the pixels of the command line with the same layers:

>>> scene = Scene(atlas="dk", surface="inflated")                            # doctest: +SKIP
>>> scene.add({"lh": thick_lh, "rh": thick_rh}, cmap="viridis", vmin=1.5, vmax=4, label="thickness")
>>> scene.add("cluster_mask.mgh", outline=True, color="black")
>>> scene.add("bundles/", values="fa.csv", cmap="magma", vmin=0.3, vmax=0.7, label="FA")
>>> scene.render(views=["lateral-left", "subcortical"], out="figs/")
>>> scene.figure("fig.pdf", views=["lateral-left", "lateral-right"])

The layers stack in the composition's order whatever the order they were added in: region
values, the map over them (by its ``alpha``), tracts, a connectome (its edges and nodes), a volume's
clusters as surfaces (``kind="volume-surface"``), then the lines (a contour, an atlas's outline).
Each kind is drawn once: a second layer of a kind already added is refused (two maps cannot be
stacked in one composition; draw them in two scenes). A new kind joins :data:`KINDS` (how it is
recognised and which options it becomes) and nothing else.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.rendering.layers import SCALE_FIELDS
from brainpainter.rendering.options import Options

if TYPE_CHECKING:  # pragma: no cover
    from brainpainter.atlas.model import Atlas
    from brainpainter.media.figure import FigureResult
    from brainpainter.media.movie import MovieResult
    from brainpainter.rendering.painter import RenderResult

__all__ = ["KINDS", "Kind", "Scene", "SceneLayer", "infer_kind"]

#: The scale keywords of :meth:`Scene.add` besides the colour scale's own (:data:`SCALE_FIELDS`).
LAYER_KEYWORDS = ("threshold", "alpha", "label")
#: The keywords of a line layer (a contour, an outline).
LINE_KEYWORDS = ("color", "width", "style", "levels")


@dataclass(frozen=True)
class SceneLayer:
    """One layer added to a :class:`Scene`: its kind, its data and the keywords it was added with."""

    kind: str
    data: Any
    keywords: Mapping[str, Any]

    def name(self) -> str:
        """What the layer was read from, for messages."""
        return str(self.data) if isinstance(self.data, str | Path) else type(self.data).__name__


@dataclass(frozen=True)
class Kind:
    """How one kind of layer becomes the run's options.

    Attributes
    ----------
    options : callable
        ``options(layer, input_taken)`` -> (INPUT or None, the run's keywords); `input_taken`: a
        region table is INPUT already (a map is then given as ``lh``/``rh``/``volume``).
    allowed : tuple of str
        The keywords of :meth:`Scene.add` it takes.
    first : bool
        It may be the run's INPUT (a region table, a map).
    """

    options: Callable[[SceneLayer, bool], tuple[Any, dict[str, Any]]]
    allowed: tuple[str, ...]
    first: bool = False


def _scale(kind: str, keywords: Mapping[str, Any]) -> dict[str, Any]:
    """A layer's scale keywords as its run options (``cmap`` of a map: ``map_cmap``)."""
    out = {f"{kind}_{name}": keywords[name] for name in (*SCALE_FIELDS, "label") if name in keywords}
    if "alpha" in keywords:
        out[f"{kind}_alpha"] = keywords["alpha"]
    if "threshold" in keywords:
        out["threshold"] = keywords["threshold"]
    return out


def _regions(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    return layer.data, _scale("regions", layer.keywords)


def _map(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    """A map is INPUT alone; under a region table it is ``lh``/``rh`` (a pair, a dict) or ``volume``."""
    options = _scale("map", layer.keywords)
    if not taken:
        return layer.data, options
    from brainpainter.maps.inputs import pair_of

    data = layer.data
    if hasattr(data, "data") and hasattr(data.data, "parts"):  # nilearn's SurfaceImage: its hemispheres
        data = dict(data.data.parts)
    if isinstance(data, Mapping):
        hemis = {"left": "lh", "right": "rh"}
        return None, {**options, **{hemis.get(str(k).lower(), str(k).lower()): v for k, v in data.items()}}
    if isinstance(data, str | Path):
        try:  # a hemisphere's file (its partner beside it); else a volume, as --volume
            return None, {**options, **{hemi: str(path) for hemi, path in pair_of(data).items()}}
        except BrainPainterError:
            pass
    return None, {**options, "volume": data}


def _tracts(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    data = layer.data
    files = (str(data),) if isinstance(data, str | Path) else tuple(str(p) for p in data)
    options: dict[str, Any] = {"tracts": files, **_scale("tracts", layer.keywords)}
    for name, option in (("values", "tract_values"), ("value", "tract_value")):
        if name in layer.keywords:
            options[option] = layer.keywords[name]
    return None, options


#: The connectome keywords of :meth:`Scene.add` besides its edges' scale: its nodes and which edges.
CONNECTOME_KEYWORDS = ("nodes", "node_values", "node_categories", "directed", "edge_threshold", "top_edges",
                       "edges_of", "nodes_space", "node_labels", "node_labels_top",
                       "node_labels_per_category",
                       *(f"nodes_{name}" for name in (*SCALE_FIELDS, "label")))


def _connectome(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    """A connectome (a matrix file or a Connectome): its edges' scale, its nodes' and its edges' options."""
    chosen = {k: v for k, v in layer.keywords.items() if k in CONNECTOME_KEYWORDS}
    return None, {"connectome": layer.data, **_scale("edges", layer.keywords), **chosen}


def _volume_surface(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    """A volume's clusters as surfaces (``--volume-surface``): its threshold, minimum size and scale."""
    size = layer.keywords.get("min_cluster_mm3")
    more = {"min_cluster_mm3": size} if size is not None else {}
    return None, {"volume_surface": layer.data, **_scale("blobs", layer.keywords), **more}


def _lines(layer: SceneLayer, kind: str) -> dict[str, Any]:
    """The line keywords (``color``, ``width``, ``style``) as the run's settings of line layer `kind`
    (``outline_color``, ``contour_width``, ...): each line layer is drawn in its own line."""
    return {f"{kind}_{k}": v for k, v in layer.keywords.items() if k in ("color", "width", "style")}


def _contour(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    data = layer.data
    given = ",".join(str(p) for p in data) if isinstance(data, tuple | list) else data
    levels = layer.keywords.get("levels")
    if isinstance(levels, Iterable) and not isinstance(levels, str):
        levels = ",".join(str(v) for v in levels)
    more = {"contour_levels": levels} if levels is not None else {}
    return None, {"contour": given, **_lines(layer, "contour"), **more}


def _outline(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
    return None, {"outline": str(layer.data), **_lines(layer, "outline")}


_SCALED = (*SCALE_FIELDS, "label")
#: Every kind of layer a scene draws, in the composition's order (a new kind joins here).
KINDS: dict[str, Kind] = {
    "regions": Kind(_regions, _SCALED, first=True),
    "map": Kind(_map, (*_SCALED, "alpha", "threshold"), first=True),
    "tracts": Kind(_tracts, (*_SCALED, "values", "value")),
    "connectome": Kind(_connectome, (*_SCALED, *CONNECTOME_KEYWORDS)),
    "volume-surface": Kind(_volume_surface, (*_SCALED, "threshold", "min_cluster_mm3")),
    "contour": Kind(_contour, ("levels", "color", "width", "style")),
    "outline": Kind(_outline, ("color", "width", "style")),
}


def _plugin_kind(name: str) -> Kind | None:
    """A plugin layer kind (``brainpainter.layers``, drawn by ``--layer KIND:FILE``) as a :class:`Kind`;
    None where `name` is no installed kind or a built-in one (drawn by its own options)."""
    from brainpainter.atlas.registry import layer_kinds
    from brainpainter.layers.kinds import kind_of

    if name not in layer_kinds.names() or kind_of(name).open is None:
        return None

    def options(layer: SceneLayer, taken: bool) -> tuple[Any, dict[str, Any]]:
        opts = tuple(f"{name}.{k}={v}" for k, v in layer.keywords.items())
        return None, {"layer": (f"{name}:{layer.data}",), "layer_opt": opts}

    return Kind(options, tuple(kind_of(name).options))


def kind_named(name: str) -> Kind:
    """The :class:`Kind` of a built-in kind (:data:`KINDS`) or an installed plugin's."""
    kind = KINDS.get(name) or _plugin_kind(name)
    if kind is None:
        from brainpainter.atlas.registry import layer_kinds

        plugins = [n for n in layer_kinds.names() if n not in KINDS and _plugin_kind(n) is not None]
        raise choice_error("kind", name, [*KINDS, *plugins])
    return kind


def _a(kind: str) -> str:
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def infer_kind(data: Any, outline: bool = False, values: Any = None) -> str:
    """The kind of `data`, as the command line reads it.

    ``outline=True``: an atlas's name is its outline, any other map a contour of it; tract values
    (`values`), a tractogram (``.trk``/``.tck``/``.trx``) or a folder of them: tracts; a
    :class:`~brainpainter.connectome.model.Connectome`: a connectome (a matrix file needs
    ``kind="connectome"``: a CSV could be a region table); a map
    (``{"lh": ..., "rh": ...}``, a map or CIFTI file, a volume): a map; else a region table.
    """
    from brainpainter.connectome.model import Connectome
    from brainpainter.layers.readers import is_map_data
    from brainpainter.maps.volume import is_volume
    from brainpainter.tracts.model import SUFFIXES

    if isinstance(data, Connectome):
        return "connectome"
    path = Path(data) if isinstance(data, str | Path) else None
    if outline:
        if isinstance(data, str) and path is not None and not path.exists() and not any(
                c in data for c in "/\\,."):
            return "outline"  # an atlas's name, not a file's
        return "contour"
    if values is not None or (path is not None and (path.is_dir() or path.name.lower().endswith(SUFFIXES))):
        return "tracts"
    if is_map_data(data) or is_volume(data):
        return "map"
    return "regions"


class Scene:
    """Layers drawn together, each with its own colour scale, as the command line draws them.

    Parameters
    ----------
    atlas : str or Atlas, optional
        As for :func:`brainpainter.render` (inferred from a region table's names when not given).
    **options
        The image and scene options of every render (``surface="inflated"``, ``width``,
        ``background``, ``shading``, ``template``, ``jobs``, ...), as for :func:`brainpainter.render`.
    """

    def __init__(self, atlas: Atlas | str | None = None, **options: Any) -> None:
        Options.of(options, "Scene")  # a bad option fails now, not at the first render
        self.atlas = atlas
        self.options = dict(options)
        self.layers: list[SceneLayer] = []

    def __repr__(self) -> str:
        return f"<Scene: {', '.join(f'{la.kind} {la.name()}' for la in self.layers) or 'no layers'}>"

    def add(self, data: Any, kind: str | None = None, *, outline: bool = False, **keywords: Any) -> Scene:
        """Add a layer; returns the scene (``scene.add(a).add(b)``).

        Parameters
        ----------
        data : path, DataFrame, dict, array mapping, volume, tractogram folder, or atlas name
            A region table; a map (``{"lh": ndarray (n,), "rh": ndarray (n,)}``, a map, CIFTI or
            volume file); tractograms (a folder, files); with ``outline=True`` a mask or p-map
            (a contour of it) or an atlas's name (its region borders).
        kind : {"regions", "map", "tracts", "connectome", "volume-surface", "contour", "outline"} or str
            Inferred as the command line infers it (:func:`infer_kind`) when not given; or an
            installed plugin's kind (``"foci"``: ``brainpainter layers`` lists them), whose
            options are its keywords (``--layer KIND:FILE``, ``--layer-opt``).
        outline : bool
            Draw `data` as lines: a map's iso-lines (``levels``, default 0.5), an atlas's borders.
        **keywords
            Its scale: ``cmap``, ``gradient``, ``vmin``, ``vmax``, ``center``, ``label``;
            ``alpha`` and ``threshold`` (a map); ``values`` (tract values: a table, or the
            bundle columns of the region table), ``value`` (its column); a connectome's nodes
            and edges (``nodes``, ``node_values``, ``node_categories``, ``top_edges``, ...,
            ``nodes_cmap``; its ``cmap``, ... are its edges'); a volume's clusters as surfaces
            (``kind="volume-surface"``: ``threshold``, ``min_cluster_mm3``, and its scale);
            ``color``, ``width`` and ``levels`` (lines).

        Raises
        ------
        BrainPainterError
            A kind not known, a keyword the kind does not take, or a second layer of a kind.
        """
        chosen = kind if kind is not None else infer_kind(data, outline, keywords.get("values"))
        allowed = kind_named(chosen).allowed
        wrong = sorted(set(keywords) - set(allowed))
        if wrong:
            raise BrainPainterError(f"{_a(chosen)} layer takes {list(allowed)}; {wrong[0]!r} "
                                    "was given. Leave it out, or give kind= if the layer is of another kind.")
        for layer in self.layers:
            if layer.kind == chosen:
                raise BrainPainterError(
                    f"the scene has {_a(chosen)} layer already ({layer.name()}); a composition draws one of "
                    f"each kind ({', '.join(KINDS)}), so {SceneLayer(chosen, data, {}).name()} cannot be "
                    "stacked on it. Draw it in a second Scene.")
        layer = SceneLayer(chosen, data, dict(keywords))
        self.run_options([*self.layers, layer])  # a bad colour map or range fails now
        self.layers.append(layer)
        return self

    def run_options(self, layers: list[SceneLayer] | None = None) -> tuple[Any, dict[str, Any]]:
        """The INPUT and keywords of the run that draws the layers (what the command line is given).

        Returns
        -------
        data : object or None
            The INPUT: the region table if any, else the map.
        options : dict
            The scene's options and each layer's (``regions_cmap``, ``map_alpha``, ``tracts``, ...).
        """
        layers = list(self.layers if layers is None else layers)
        order = [*KINDS, *(la.kind for la in layers if la.kind not in KINDS)]  # plugins' last, as added
        layers.sort(key=lambda la: order.index(la.kind))
        data, options = None, dict(self.options)
        for layer in layers:
            given, more = kind_named(layer.kind).options(layer, data is not None)
            if given is not None:
                data = given
            for name in ("layer", "layer_opt"):  # plugin layers: each adds its --layer and --layer-opt
                if name in more:
                    more[name] = (*options.get(name, ()), *more[name])
            options.update(more)
        Options.of(options, "Scene")
        return data, options

    def _call(self, keywords: Mapping[str, Any]) -> tuple[Any, dict[str, Any]]:
        if not self.layers:
            raise BrainPainterError("the scene has no layers: add one (scene.add(table), scene.add(map), "
                                    "...) before drawing it.")
        data, options = self.run_options()
        return data, {**options, **{k: v for k, v in keywords.items() if v is not None}}

    def render(self, views: Any = None, out: str | Path | None = None, **keywords: Any) -> RenderResult:
        """Render every image from every view, as :func:`brainpainter.render` (``out``: PNGs, manifest)."""
        from brainpainter.rendering.run import render

        data, options = self._call({"views": views, **keywords})
        return render(data, self.atlas, out=out, **options)

    def figure(self, out: str | Path | None = None, views: Any = None, **keywords: Any) -> FigureResult:
        """A figure with one labelled colour bar per scaled layer, as :func:`brainpainter.figure`
        (``colorbar_position="right"``: the bars upright at the right)."""
        from brainpainter.media.figure import make_figure

        data, options = self._call({"views": views, **keywords})
        return make_figure(data, self.atlas, out=out, **options)

    def movie(self, out: str | Path, **keywords: Any) -> MovieResult:
        """A movie through the images (or turning around one), as :func:`brainpainter.movie`."""
        from brainpainter.media.movie import make_movie

        data, options = self._call(keywords)
        return make_movie(data, self.atlas, out=out, **options)

    def export(self, out: str | Path, **keywords: Any) -> Path:
        """One image as an interactive 3D brain (``.glb``/``.html``), as :func:`brainpainter.export`."""
        from brainpainter.media.export import export

        data, options = self._call(keywords)
        return export(data, out, atlas=self.atlas, **options)
