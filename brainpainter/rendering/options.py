"""The options of a run, defined once: what is drawn, the colour scale, the image, the table, the workers.

Each group is a frozen dataclass, checked when it is made, in the lowest layer
that owns it:

========================  ==========================================================  ============
group                     options                                                     defined in
========================  ==========================================================  ============
:class:`SceneOptions`     views, template, surface, hide, renderer, atlas_config      here
:class:`ScaleOptions`     gradient, cmap, vmin, vmax, center, nan_color,              color.scale
                          missing_color
:class:`RenderSettings`   width, height, background, quality, shading, lighting,     rendering.settings
                          glass_opacity, outline_width
:class:`TableOptions`     image_column, value, region_column, strict                  table.options
:class:`MapOptions`       lh, rh, underlay, threshold                                 maps.options
:class:`LayerOptions`     each layer's scale: regions_cmap, map_vmin, tracts_vmax,    rendering.layers
                          map_alpha, nodes_cmap, edges_center, ...
:class:`RunnerOptions`    jobs, client, scheduler                                     here
========================  ==========================================================  ============

and :class:`~brainpainter.connectome.options.ConnectomeOptions` (connectome, nodes, node_values,
node_categories, directed, edge_threshold, top_edges, edges_of; ``connectome.options``).

The public functions (``brainpainter.render``, ``figure``, ``movie``,
``plot``, ``export``) take these options as flat keywords
(``render(table, cmap="viridis", width=800)``), typed by :class:`RenderKwargs`;
:meth:`Options.of` sorts them into the groups. The CLI's click options and the
web API's fields are generated from the same fields (defaults, choices, help).
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

from brainpainter.atlas.model import SPACES, SURFACES
from brainpainter.color.rgb import to_rgb
from brainpainter.color.scale import ScaleKwargs, ScaleOptions
from brainpainter.connectome.options import ConnectomeKwargs, ConnectomeOptions
from brainpainter.errors import BrainPainterError, choice_error, within
from brainpainter.layers.kinds import parse_layer, parse_layer_opts
from brainpainter.maps.options import MapKwargs, MapOptions
from brainpainter.rendering.clip import ClipPlane, parse_clips
from brainpainter.rendering.layers import LayerKwargs, LayerOptions
from brainpainter.rendering.settings import RenderSettings, SettingsKwargs
from brainpainter.rendering.views import PRESETS, parse_views
from brainpainter.table.options import TableKwargs, TableOptions
from brainpainter.tracts.model import DEFAULT_SPACE, MAX_STREAMLINES, TractSpec

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template

AUTO = "auto"
PIP_HINT = "pip install 'brainpainter[cluster]'"
#: The default views, as the CLI shows them.
DEFAULT_VIEWS = "lateral-left,medial-left,subcortical"


class SceneKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`SceneOptions`."""

    views: str | Sequence[str] | None
    template: Template | str
    surface: str
    hide: Iterable[str]
    renderer: str
    atlas_config: str | Path | None
    tracts: str | Sequence[str]
    tracts_space: str
    tracts_affine: str | Path | None
    max_streamlines: int
    tract_values: Any
    tract_value: str | None
    tract_radius: float | None
    volume_surface: Any
    min_cluster_mm3: float
    clip: str | Sequence[str] | None
    layer: str | Sequence[str]
    layer_opt: str | Sequence[str]


class RunnerKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`RunnerOptions`."""

    jobs: int | str
    client: Any
    scheduler: str | None


class RenderKwargs(SceneKwargs, ScaleKwargs, SettingsKwargs, TableKwargs, RunnerKwargs, MapKwargs,
                   LayerKwargs, ConnectomeKwargs, total=False):
    """Every option of a run as a flat keyword (see :class:`Options` for what each means)."""


@dataclass(frozen=True)
class SceneOptions:
    """What is drawn, and from where.

    Attributes
    ----------
    views : str or list of str, optional
        Default (None, not given): BrainPainter's ``lateral-left, medial-left, subcortical``
        (for an atlas without cortical regions ``subcortical, subcortical-dorsal``; for maps
        both hemispheres' lateral and medial views). Views given are drawn as given.
    template : str or Template
        Template name or folder.
    surface : {"pial", "white", "inflated"}
    hide : tuple of str
        Regions, hemisphere-free names or groups (``cerebellum``) not to draw.
    renderer : str
        Name in the ``brainpainter.renderers`` registry.
    atlas_config : path, optional
        Region-group TOML file (:mod:`brainpainter.atlas.config`) defining the
        atlas; given instead of an atlas.
    tracts : tuple of str
        Tractogram files (.trk, .tck, .trx) or folders of them, one file per
        bundle, drawn as tubes (:mod:`brainpainter.tracts`).
    tracts_space : str
        Space of the tractograms' coordinates (MNI152 is mapped onto the fsaverage template).
    tracts_affine : path, optional
        4x4 matrix (text file) applied to the tractograms' coordinates first.
    max_streamlines : int
        Streamlines drawn at most (a random subsample beyond; the run says so).
    tract_values : path or DataFrame, optional
        Values per bundle (columns named after bundles) or along-tract profiles
        (``bundle,node,value``); default: the main table's bundle columns, else direction colours.
    tract_value : str, optional
        The value column of a long profile table with several.
    tract_radius : float, optional
        Radius of the streamlines' tubes, millimetres; default by their number
        (0.3 mm up to 2,000 streamlines, thinner beyond, 0.13 mm at 10,000).
    volume_surface : path or nibabel image, optional
        An MNI152 volume whose clusters above ``threshold`` (``--threshold``, both signs) are drawn
        as lit surfaces inside the glass brain (:mod:`brainpainter.maps.clusters`).
    min_cluster_mm3 : float
        Its clusters smaller than this (cubic millimetres) are not drawn.
    clip : str or list of str, optional
        Cutaway planes (``"x<0"``, ``"x<0,z>20"``; :mod:`brainpainter.rendering.clip`) applied to every view.
    layer : tuple of str
        Plugin layers as ``KIND:FILE`` (``foci:peaks.csv``; :mod:`brainpainter.layers.kinds`).
    layer_opt : tuple of str
        Their options as ``KIND.NAME=VALUE`` (``foci.cmap=magma``).
    """

    views: str | Sequence[str] | None = field(default=None, metadata={
        "help": "Comma-separated views (" + ", ".join(PRESETS) + "), 'all', or camera:AZ:EL[:ZOOM]. "
                "Default: " + DEFAULT_VIEWS + "; maps: lateral and medial of both hemispheres (and "
                "subcortical for a volume). flat-left, flat-right, flat: HCP's flat maps."})
    template: Template | str = field(default="fsaverage", metadata={"help": "Template name or folder."})
    surface: str = field(default="pial", metadata={"choices": SURFACES, "help": "Cortical surface to draw."})
    hide: tuple[str, ...] = field(default=(), metadata={
        "help": "Regions or groups not drawn (cerebellum, ventricles, brainstem, ventraldc). Repeatable."})
    renderer: str = field(default="blender", metadata={
        "help": "Renderer plugin ('brainpainter plugins' lists them)."})
    atlas_config: str | Path | None = field(default=None, metadata={
        "help": "Region-group TOML file defining the atlas (instead of --atlas); see docs/atlases.md."})
    tracts: tuple[str, ...] = field(default=(), metadata={
        "help": "Tractograms (.trk, .tck, .trx) or folders of them, one file per bundle, drawn as tubes in "
                "the views; see docs/tracts.md. Repeatable."})
    tracts_space: str = field(default=DEFAULT_SPACE, metadata={
        "choices": SPACES,
        "help": "Space of the tractograms' coordinates (MNI152 is mapped to the fsaverage template, "
                "MNI305)."})
    tracts_affine: str | Path | None = field(default=None, metadata={
        "help": "A 4x4 matrix (text file, numpy or FSL) applied to the tractograms' coordinates first."})
    max_streamlines: int = field(default=MAX_STREAMLINES, metadata={
        "help": "Streamlines drawn at most, over all bundles (a random subsample beyond; the run says so)."})
    tract_values: Any = field(default=None, metadata={
        "help": "Table of values per bundle (columns AF_left, CST_right, ...) or along-tract profiles "
                "(bundle,node,value). Default: the bundle columns of the main table, else direction "
                "colours."})
    tract_value: str | None = field(default=None, metadata={
        "help": "Value column of a long profile table with several (pyAFQ: dti_fa)."})
    tract_radius: float | None = field(default=None, metadata={
        "help": "Radius of the streamline tubes in millimetres (default: 0.3 up to 2,000 streamlines, "
                "thinner beyond)."})

    volume_surface: Any = field(default=None, metadata={
        "help": "An MNI152 volume whose clusters above --threshold (both signs) are drawn as smooth lit "
                "surfaces inside the glass brain, on a colour scale of their own; see docs/maps-volumes.md."})
    min_cluster_mm3: float = field(default=0.0, metadata={
        "help": "Clusters of --volume-surface smaller than this many cubic millimetres are not drawn."})
    clip: Any = field(default=None, metadata={
        "help": "Cut the cortex and glass away where AXIS<MM or AXIS>MM (x right, y anterior, z superior), "
                "e.g. x<0; several planes (repeated or comma-separated) cut out a wedge. What lies inside "
                "stays whole and shows. Repeatable."})
    layer: tuple[str, ...] = field(default=(), metadata={
        "help": "A layer of an installed kind, KIND:FILE (e.g. foci:peaks.csv: MNI152 points drawn as "
                "spheres); 'brainpainter layers' lists the kinds and their options. Repeatable."})
    layer_opt: tuple[str, ...] = field(default=(), metadata={
        "help": "An option of a --layer, KIND.NAME=VALUE (e.g. foci.cmap=magma). Repeatable."})

    def __post_init__(self) -> None:
        if self.surface not in SURFACES:
            raise choice_error("surface", self.surface, SURFACES)
        object.__setattr__(self, "clip", tuple(str(p) for p in parse_clips(self.clip)))
        if not within(self.min_cluster_mm3, 0.0, 1e9):
            raise BrainPainterError(f"--min-cluster-mm3 must be a number of cubic millimetres >= 0; "
                                    f"{self.min_cluster_mm3!r} was given.")
        if self.volume_surface is None and float(self.min_cluster_mm3) != 0.0:
            raise BrainPainterError("--min-cluster-mm3 drops small clusters of --volume-surface, but no "
                                    "--volume-surface was given; give the volume, or leave it out.")
        for name in ("layer", "layer_opt"):
            given = getattr(self, name)
            object.__setattr__(self, name, (given,) if isinstance(given, str)
                               else tuple(str(g) for g in given))
        for given in self.layer:
            parse_layer(given)
        parse_layer_opts(self.layer_opt)
        hide = [self.hide] if isinstance(self.hide, str) else list(self.hide)
        object.__setattr__(self, "hide", tuple(str(h) for h in hide))
        if self.views is not None:
            parse_views(self.views if isinstance(self.views, str) else list(self.views))
        tracts = [self.tracts] if isinstance(self.tracts, str | Path) else list(self.tracts)
        object.__setattr__(self, "tracts", tuple(str(t) for t in tracts))
        if self.tracts:
            self.tract_spec()  # fail now on a missing file or a bad affine
        if self.tract_radius is not None and not 0.01 <= float(self.tract_radius) <= 10:
            raise BrainPainterError(f"--tract-radius must be 0.01 to 10 millimetres; {self.tract_radius} was "
                                    "given.")
        if not self.tracts and self.tract_values is not None:
            raise BrainPainterError("--tract-values colours bundles, but no --tracts were given; give the "
                                    "tractograms to draw with --tracts FILE_OR_FOLDER.")

    @property
    def clips(self) -> tuple[ClipPlane, ...]:
        """The ``clip`` planes (:mod:`brainpainter.rendering.clip`)."""
        return parse_clips(self.clip)

    def tract_spec(self) -> TractSpec | None:
        """What tractograms to load (None without ``tracts``)."""
        if not self.tracts:
            return None
        return TractSpec(tuple(self.tracts), self.tracts_space,
                         None if self.tracts_affine is None else str(self.tracts_affine),
                         int(self.max_streamlines))


# -- where a run renders ------------------------------------------------------------------
def cpu_count() -> int:
    """Cores this process may use (its CPU affinity where the system tells it)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def resolve_jobs(jobs: int | str | None) -> int:
    """The number of local worker processes for ``--jobs`` (``"auto"``: one per core).

    Raises
    ------
    BrainPainterError
        Not a positive whole number or ``"auto"``.
    """
    if jobs is None:
        return 1
    if isinstance(jobs, str):
        text = jobs.strip().lower()
        if text == AUTO:
            return cpu_count()
        if text.isdigit() and int(text) > 0:
            return int(text)
    elif isinstance(jobs, numbers.Integral) and not isinstance(jobs, bool) and int(jobs) > 0:
        return int(jobs)
    raise BrainPainterError(
        f"--jobs must be a positive whole number of processes or 'auto' (one per core, {cpu_count()} "
        f"here); {jobs!r} was given."
    )


def import_distributed() -> Any:
    """``dask.distributed``, or a one-line error with the pip command."""
    try:
        import distributed
    except ImportError:
        raise BrainPainterError(
            f"--scheduler (a Dask cluster) needs dask.distributed, which is not installed; {PIP_HINT}"
        ) from None
    return distributed


@dataclass(frozen=True)
class RunnerOptions:
    """Where the images are rendered (see :mod:`brainpainter.rendering.parallel`).

    Attributes
    ----------
    jobs : int or "auto"
        Worker processes on this machine (``"auto"``: one per core), each with
        a warm renderer; the output is byte-identical to ``jobs=1``.
    client : distributed.Client, optional
        Render on this Dask cluster instead.
    scheduler : str, optional
        A Dask scheduler address (``tcp://host:8786``) to connect to instead of `client`.
    """

    jobs: int | str = field(default=1, metadata={
        "help": "Render in N processes on this machine ('auto': one per core); output identical to one "
                "process."})
    client: Any = field(default=None, metadata={"cli": False})
    scheduler: str | None = field(default=None, metadata={
        "help": "Render on a Dask cluster, e.g. tcp://host:8786 (default: $BRAINPAINTER_SCHEDULER); needs "
                f"{PIP_HINT}."})

    def __post_init__(self) -> None:
        n = resolve_jobs(self.jobs)
        if self.client is not None or self.scheduler:
            if n > 1:
                raise BrainPainterError("give --jobs (processes on this machine) or --scheduler / client (a "
                                        f"Dask cluster), not both; --jobs {self.jobs} and a scheduler were "
                                        "given.")
            import_distributed()

    @property
    def n_jobs(self) -> int:
        """Local worker processes."""
        return resolve_jobs(self.jobs)

    @property
    def cluster(self) -> bool:
        """Whether a Dask cluster renders."""
        return self.client is not None or bool(self.scheduler)


# -- all of them ----------------------------------------------------------------------------
#: Option group -> its class, in the order they are checked (cheap checks first).
GROUPS: dict[str, type] = {"runner": RunnerOptions, "scale": ScaleOptions, "scene": SceneOptions,
                           "settings": RenderSettings, "table": TableOptions, "maps": MapOptions,
                           "layers": LayerOptions, "connectome": ConnectomeOptions}


def option_names(cls: type) -> list[str]:
    """The public keyword names of an option group (its dataclass fields)."""
    return [f.name for f in fields(cls) if f.init and not f.name.startswith("_")]


def take(options: dict[str, Any], cls: type) -> dict[str, Any]:
    """Remove the keywords of option group `cls` from `options` and return them."""
    return {name: options.pop(name) for name in option_names(cls) if name in options}


@dataclass(frozen=True)
class Options:
    """Every option of a run, by group; checked when made.

    Attributes
    ----------
    runner : RunnerOptions
        jobs, client, scheduler.
    scale : ScaleOptions
        gradient, cmap, vmin, vmax, center, nan_color, missing_color.
    scene : SceneOptions
        views, template, surface, hide, renderer, atlas_config.
    settings : RenderSettings
        width, height, background, quality, shading, lighting, glass_opacity, outline_width.
    table : TableOptions
        image_column, value, region_column, strict.
    maps : MapOptions
        lh, rh, underlay, threshold (per-vertex maps, :mod:`brainpainter.maps`).
    layers : LayerOptions
        Each layer's own colour options (``tracts_cmap``, ``map_vmin``, ``map_alpha``, ...).
    connectome : ConnectomeOptions
        The connectome drawn as nodes and edges (``connectome``, ``nodes``, ``top_edges``, ...).
    size_given : bool
        Whether the user gave ``width`` or ``height``; if not, an atlas with its own
        :attr:`~brainpainter.atlas.model.Atlas.image_aspect` reshapes the default size.
    """

    runner: RunnerOptions = field(default_factory=RunnerOptions)
    scale: ScaleOptions = field(default_factory=ScaleOptions)
    scene: SceneOptions = field(default_factory=SceneOptions)
    settings: RenderSettings = field(default_factory=RenderSettings)
    table: TableOptions = field(default_factory=TableOptions)
    maps: MapOptions = field(default_factory=MapOptions)
    layers: LayerOptions = field(default_factory=LayerOptions)
    connectome: ConnectomeOptions = field(default_factory=ConnectomeOptions)
    size_given: bool = field(default=True, compare=False)  # not an option: how the settings were made

    @classmethod
    def of(cls, options: Mapping[str, Any], caller: str = "render", **defaults: Any) -> Options:
        """Sort flat keywords (:class:`RenderKwargs`) into the groups and check them.

        Parameters
        ----------
        options : mapping of str to object
            The keywords the user gave.
        caller : str
            The public function, for the message about an unknown keyword.
        **defaults
            The caller's own defaults where they differ from the groups'
            (a movie's ``width=800``).

        Raises
        ------
        TypeError
            A keyword that is no option (as Python says for any function).
        """
        given = {**defaults, **options}
        known = {name for group in GROUPS.values() for name in option_names(group)}
        unknown = sorted(set(given) - known)
        if unknown:
            import difflib

            name = unknown[0]
            close = difflib.get_close_matches(name, sorted(known), n=1)
            hint = ("; the command line's --size WxH is width=W, height=H" if name == "size"
                    else f"; did you mean {close[0]!r}?" if close else "")
            raise TypeError(f"{caller}() got an unexpected keyword argument {name!r}{hint}")
        if given.get("background") is not None:
            given["background"] = to_rgb(given["background"])
        made = {key: group(**{n: given[n] for n in option_names(group) if n in given})
                for key, group in GROUPS.items()}
        return cls(**made, size_given="width" in options or "height" in options)

    def flat(self) -> dict[str, Any]:
        """The options as flat keywords again (``Options.of(o.flat()) == o``; the keywords always give
        the size, so the result has ``size_given``)."""
        return {name: getattr(getattr(self, key), name)
                for key, group in GROUPS.items() for name in option_names(group)}
