"""Render options of the web API: the core option classes' names, defaults and help, checked by them.

:class:`RenderOptions` has ``brainpainter render``'s options (Python names:
``nan_color``, ``glass_opacity``...; ``size`` is ``WIDTHxHEIGHT``;
``transparent`` replaces the background), with the defaults, choices and help
of :class:`brainpainter.rendering.options.Options`. :func:`prepare` turns an uploaded
table and options into a :class:`~brainpainter.rendering.run.Run` through
:func:`brainpainter.rendering.run.prepare_run`, exactly as the CLI does, plus the
checks a server adds (no paths, size limits). Nothing here imports bpy.
"""

from __future__ import annotations

import io
import typing
from collections import Counter
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, FiniteFloat, PositiveFloat, create_model

from brainpainter.color.scale import ScaleOptions
from brainpainter.errors import BrainPainterError
from brainpainter.maps.options import MapOptions
from brainpainter.rendering.layers import LayerOptions
from brainpainter.rendering.options import SceneOptions, option_names
from brainpainter.rendering.settings import RenderSettings, parse_size
from brainpainter.table.options import TableOptions as ReadOptions
from brainpainter.web.connectomes import CONNECTOME_FIELDS, connectome_fields
from brainpainter.web.layer_uploads import layer_maps
from brainpainter.web.tracts import MAX_WEB_STREAMLINES

if TYPE_CHECKING:
    from brainpainter.rendering.checked_run import Run
    from brainpainter.web.tracts import TractFiles

#: The options of tracts (given to a run only with tractograms).
TRACT_FIELDS = ("tracts", "tracts_space", "tracts_affine", "max_streamlines", "tract_radius", "tract_value")
#: The options that name another upload drawn as a layer of the main one (a map over a table, tracts, a
#: contour map's iso-lines).
LAYER_UPLOADS = ("map", "tracts", "contour", "connectome")
#: Categories of a label map's key a check report lists (the figure names at most 60).
MAX_KEY_LISTED = 256

#: Suffixes an uploaded file name may have (only used to sniff the format; never a path).
UPLOAD_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", ".xlsx", ".xlsm", ".xls")


def core(cls: type, name: str) -> Any:
    """A pydantic field with the default and help of field `name` of the core options class `cls`."""
    f = next(f for f in fields(cls) if f.name == name)
    default = f.metadata.get("cli_default", f.default)
    if isinstance(default, tuple):
        return Field(default_factory=lambda: list(default), description=f.metadata.get("help") or None)
    return Field(default, description=f.metadata.get("help") or None)


def one_of(cls: type, name: str) -> AfterValidator:
    """A validator: the value must be one of the choices of field `name` of `cls`."""
    choices = next(f for f in fields(cls) if f.name == name).metadata["choices"]

    def check(value: str) -> str:
        if value not in choices:
            raise ValueError(f"must be one of {list(choices)}; {value!r} was given")
        return value

    return AfterValidator(check)


class TableOptions(BaseModel):
    """How the table is read: ``brainpainter check``'s input options.

    See :class:`brainpainter.table.options.TableOptions`.
    """

    model_config = ConfigDict(extra="forbid")

    atlas: str | None = Field(None, description="dk, destrieux, dkt (alias tourville) or a plugin atlas; "
                                                "inferred from the region names when not given.")
    image_column: str | None = core(ReadOptions, "image_column")
    value: str | None = core(ReadOptions, "value")
    region_column: str | None = core(ReadOptions, "region_column")
    strict: bool = core(ReadOptions, "strict")


def _layer_fields() -> dict[str, Any]:
    """Each layer's own colour options (``regions_cmap``, ``map_vmin``, ``map_alpha``, ``tracts_label``...):
    the fields of :class:`~brainpainter.rendering.layers.LayerOptions`, with their defaults and help."""
    hints = typing.get_type_hints(LayerOptions)
    kinds: dict[Any, Any] = {float | None: FiniteFloat | None, float: FiniteFloat,
                             str | None: Annotated[str | None, Field(max_length=200)]}
    return {name: (kinds[hints[name]], core(LayerOptions, name)) for name in option_names(LayerOptions)}


if TYPE_CHECKING:
    _WithLayers = TableOptions
else:  # the table's options and each layer's, then render's own
    _WithLayers = create_model("_WithLayers", __base__=TableOptions, **_layer_fields(), **connectome_fields())


class RenderOptions(_WithLayers):
    """The options of ``brainpainter render``, with the defaults and help of the core option classes.

    See :class:`brainpainter.rendering.options.Options`; ``size`` is
    ``WIDTHxHEIGHT`` and ``transparent`` replaces the background, as in the CLI. Each layer's
    colour options (``regions_*``, ``map_*``, ``tracts_*``) are those of
    :class:`~brainpainter.rendering.layers.LayerOptions`; ``map`` and ``tracts`` name other uploads
    drawn with the table.
    """

    views: str | None = core(SceneOptions, "views")  # None: the run's own (a table's, a map's)
    surface: Annotated[str, one_of(SceneOptions, "surface")] = core(SceneOptions, "surface")
    gradient: str | None = core(ScaleOptions, "gradient")
    cmap: str | None = core(ScaleOptions, "cmap")
    vmin: FiniteFloat | None = core(ScaleOptions, "vmin")  # the CLI refuses inf and nan too
    vmax: FiniteFloat | None = core(ScaleOptions, "vmax")
    center: FiniteFloat | None = core(ScaleOptions, "center")
    nan_color: str = core(ScaleOptions, "nan_color")
    missing_color: str = core(ScaleOptions, "missing_color")
    hide: list[str] = core(SceneOptions, "hide")
    background: str = core(RenderSettings, "background")
    transparent: bool = Field(False, description="Transparent background.")
    size: str | None = Field(None, max_length=40, description=(
        f"Size of each rendered view, WIDTHxHEIGHT pixels (default {RenderSettings().size}; an atlas of "
        "another shape, such as the mouse, reshapes it to as many pixels)."))
    quality: Annotated[str, one_of(RenderSettings, "quality")] = core(RenderSettings, "quality")
    shading: Annotated[str, one_of(RenderSettings, "shading")] = core(RenderSettings, "shading")
    lighting: Annotated[str, one_of(RenderSettings, "lighting")] = core(RenderSettings, "lighting")
    glass_opacity: FiniteFloat = core(RenderSettings, "glass_opacity")
    underlay: Annotated[str, one_of(MapOptions, "underlay")] = core(MapOptions, "underlay")
    threshold: FiniteFloat | None = core(MapOptions, "threshold")
    outline: str | None = core(MapOptions, "outline")
    outline_threshold: bool = core(MapOptions, "outline_threshold")
    outline_width: FiniteFloat = Field(core(RenderSettings, "outline_width").default, ge=0, le=20,
                                       description=core(RenderSettings, "outline_width").description)
    outline_color: str = core(RenderSettings, "outline_color")
    outline_style: Annotated[str, one_of(RenderSettings, "outline_style")] = core(RenderSettings,
                                                                                  "outline_style")
    contour_width: FiniteFloat = Field(0.0, ge=0, le=20, description=core(RenderSettings,
                                                                          "contour_width").description)
    contour_color: str | None = Field(None, max_length=40, description=core(RenderSettings,
                                                                            "contour_color").description)
    contour_style: Annotated[str, one_of(RenderSettings, "contour_style")] = core(RenderSettings,
                                                                                  "contour_style")
    cortex: Annotated[str, one_of(RenderSettings, "cortex")] = core(RenderSettings, "cortex")
    volume_surface: bool = Field(False, description=(
        "Draw a volume upload as blobs: its clusters above threshold (both signs) as smooth lit surfaces "
        "inside the glass brain, on a scale of their own (as --volume-surface FILE --threshold T), instead "
        "of its projection onto the cortex."))
    min_cluster_mm3: FiniteFloat = Field(0.0, ge=0, le=1e9,
                                         description=core(SceneOptions, "min_cluster_mm3").description)
    clip: list[Annotated[str, Field(max_length=40)]] = Field([], max_length=6, description=core(
        SceneOptions, "clip").description)
    map: str | None = Field(None, pattern="^[0-9a-f]{32}$", description=(
        "Upload id of a map (POST /api/uploads: a surface map, a volume or a CIFTI file) drawn over the "
        "table's region colours, as --lh/--rh (or --volume) beside INPUT; map_alpha is its opacity."))
    contour: str | None = Field(None, pattern="^[0-9a-f]{32}$", description=(
        "Upload id of a map of one image (a cluster mask, a p-map) whose iso-lines are drawn over the map, "
        "as --contour."))
    contour_levels: str | None = Field(None, max_length=200,
                                       description=core(MapOptions, "contour_levels").description)
    tracts: str | None = Field(None, pattern="^[0-9a-f]{32}$", description=(
        "Upload id of tractograms (POST /api/tracts) drawn with the table, as --tracts (with the upload's "
        "table of bundle values, if it had one, as --tract-values)."))
    tracts_space: Annotated[str, one_of(SceneOptions, "tracts_space")] = core(SceneOptions, "tracts_space")
    tracts_affine: str | None = Field(None, max_length=2000, description=(
        "A 4x4 matrix applied to the tractograms' coordinates first, as --tracts-affine: 16 numbers, row "
        "after row (or 4 lines of 4; 12 numbers: the first 3 rows)."))
    max_streamlines: int = Field(core(SceneOptions, "max_streamlines").default, ge=1, le=MAX_WEB_STREAMLINES,
                                 description=core(SceneOptions, "max_streamlines").description)
    tract_radius: PositiveFloat | None = core(SceneOptions, "tract_radius")
    tract_value: str | None = Field(None, max_length=200,
                                    description=core(SceneOptions, "tract_value").description)
    connectome: str | None = Field(None, pattern="^[0-9a-f]{32}$", description=(
        "Upload id of a connectome (POST /api/connectomes: a matrix, its nodes, node values and "
        "categories) drawn with the table as nodes and edges, as --connectome (--nodes, ...)."))

    def table_kwargs(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in option_names(ReadOptions)}

    def run_kwargs(self, tracts: TractFiles | None = None,
                   connectome: dict[str, str] | None = None) -> dict[str, Any]:
        """Keyword arguments of ``prepare_run`` (without `data`, `atlas` and `hide`).

        `tracts`: the files of the ``tracts`` upload on disk (:func:`brainpainter.web.tracts.materialise`),
        given as the CLI's ``--tracts``, ``--tract-values`` and ``--tracts-affine``; `connectome`: the
        files of a connectome upload (:func:`brainpainter.web.connectomes.materialise`), given with the
        connectome's options.
        """
        values = self.model_dump(exclude={"atlas", "size", "transparent", "hide", "volume_surface",
                                          *LAYER_UPLOADS, *TRACT_FIELDS, *CONNECTOME_FIELDS})
        if connectome is not None:
            values.update(connectome, **self.model_dump(include=set(CONNECTOME_FIELDS)))
        if self.size:  # none: the default size, which an atlas of another shape reshapes (as on the CLI)
            values["width"], values["height"] = parse_size(self.size)
        if self.transparent:
            values["background"] = None
        if tracts is not None:
            values.update(
                tracts=[str(tracts.bundles)], tracts_space=self.tracts_space,
                max_streamlines=self.max_streamlines,
                tract_radius=self.tract_radius, tract_value=self.tract_value or None,
                tract_values=None if tracts.values is None else str(tracts.values),
                tracts_affine=None if not (self.tracts_affine or "").strip() else str(
                    tracts.affine_file(self.tracts_affine or "")))
        return values

    def layers_given(self) -> bool:
        """Whether any layer's own colour option (``regions_cmap``, ``map_alpha``, ...) was given."""
        return bool(self.model_dump(include=set(option_names(LayerOptions)), exclude_defaults=True))

    def hide_tokens(self) -> list[str]:
        return [h.strip() for item in self.hide for h in item.split(",") if h.strip()]


def table_stream(data: bytes, name: str) -> io.BytesIO:
    """The uploaded bytes as a named stream for the readers: `name` is only a label, never opened."""
    stream = io.BytesIO(data)
    stream.name = name
    return stream


def upload_name(name: str | None) -> str:
    """A display name for an upload (``table.csv``): letters, digits and ``._-`` only; known suffix kept."""
    from pathlib import PurePosixPath

    from brainpainter.io.output import safe_name

    raw = (name or "table.csv").replace("\\", "/")
    base = PurePosixPath(raw).name or "table.csv"
    suffix = PurePosixPath(base).suffix.lower()
    stem = safe_name(PurePosixPath(base).stem)[:60] or "table"
    return stem + (suffix if suffix in UPLOAD_SUFFIXES else "")


@dataclass
class Prepared:
    """A checked run plus what the server needs to render it."""

    run: Run
    options: RenderOptions
    hidden: list[str]
    file_names: list[str]
    kwargs: dict[str, Any] = field(default_factory=dict)
    tract_table: Path | None = None

    @property
    def coloring(self) -> str:
        """``"vertices"`` for a map run (its painter draws a per-vertex scene), else ``"regions"``."""
        return str(self.run.coloring)

    def painter_args(self) -> dict[str, Any]:
        """The contours and scene layers of the run's painter (as
        :meth:`brainpainter.rendering.checked_run.Run.painter` gives them)."""
        return {"contours": self.run.contours, "layers": self.run.scene_layers()}


def prepare(data: bytes, name: str, options: RenderOptions, *, max_images: int | None = None,
            max_pixels: int | None = None, tracts: bytes | None = None,
            data_dir: Path | None = None, map_upload: bytes | None = None,
            contour_upload: bytes | None = None, connectome_upload: bytes | None = None) -> Prepared:
    """Check `options` against the uploaded table (or map) exactly as ``brainpainter render`` would.

    Parameters
    ----------
    data : bytes
        The uploaded table, a map bundle (:mod:`brainpainter.web.maps`; a volume's: blobs with option
        ``volume_surface``), tractograms with a table of bundle values or a connectome (each alone).
    name : str
        Its display name (from :func:`upload_name`).
    options : RenderOptions
    max_images, max_pixels : int, optional
        Largest rows x views; largest width x height of one view.
    tracts : bytes, optional
        The tract bundle that option ``tracts`` names (drawn with the table).
    data_dir : Path, optional
        The server's data folder: a tract bundle's files are written under it (``incoming/``).
    map_upload, contour_upload, connectome_upload : bytes, optional
        The bundles of options ``map`` (over the table), ``contour`` (iso-lines over it), ``connectome``.

    Raises
    ------
    BrainPainterError
        The CLI's one-line message for the first problem.
    """
    from brainpainter.io.output import file_key, safe_name
    from brainpainter.rendering.painter import resolve_hidden
    from brainpainter.rendering.run import prepare_run
    from brainpainter.web.connectomes import connectome_files, is_connectome_bundle
    from brainpainter.web.maps import blob_kwargs, is_bundle, read_bundle
    from brainpainter.web.tracts import is_tract_bundle

    alone = is_tract_bundle(data)
    files = _tract_files(data, options, tracts, data_dir)
    kwargs = options.run_kwargs(files, connectome_files(data, options, connectome_upload, data_dir))
    kwargs.update(layer_maps(options, data, map_upload, contour_upload))
    default = RenderSettings()
    pixels = kwargs.get("width", default.width) * kwargs.get("height", default.height)
    if max_pixels is not None and pixels > max_pixels:
        raise BrainPainterError(
            f"size {options.size or default.size} is {pixels} pixels; this server renders at "
            f"most {max_pixels} pixels per view. Choose a smaller size."
        )
    tract_table = None
    if files is not None and alone:  # the tracts alone: their values table is the main table, as on the CLI
        if files.values is None:
            raise BrainPainterError(
                "tractograms alone are drawn with their table of bundle values; upload a region table and "
                "give the tractograms as option tracts, or upload them again with a values table (.csv).")
        tract_table = files.values
        kwargs["tract_values"] = None
        run = prepare_run(str(tract_table), options.atlas, **kwargs)
    elif options.volume_surface:  # a volume's blobs, as --volume-surface FILE (not projected onto the cortex)
        kwargs.update(blob_kwargs(data, options))
        run = prepare_run(None, options.atlas, **kwargs)
    elif is_bundle(data):  # a map: its files, read as the CLI reads --lh/--rh (tracts drawn with it)
        run = prepare_run(read_bundle(data), options.atlas, **kwargs)
    else:
        table = None if is_connectome_bundle(data) else table_stream(data, name)  # None: the connectome alone
        run = prepare_run(table, options.atlas, **kwargs)
    hidden = options.hide_tokens()
    resolve_hidden(hidden, run.table.atlas)
    n = len(run.table.images) * len(run.views)
    if max_images is not None and n > max_images:
        raise BrainPainterError(
            f"{len(run.table.images)} row(s) x {len(run.views)} view(s) = {n} images; this server renders at "
            f"most {max_images} per job. Choose fewer views or split the table."
        )
    names = [safe_name(i) for i in run.table.images]
    counts = Counter(file_key(n) for n in names)  # linear: tables may have many rows
    clash = sorted(n for n in set(names) if counts[file_key(n)] > 1)
    if clash:
        raise BrainPainterError(
            f"image names {clash[:3]} become the same file name after removing unsafe characters; "
            "make the image names differ in letters or digits."
        )
    return Prepared(run, options, hidden, names, kwargs, tract_table)


def _tract_files(data: bytes, options: RenderOptions, tracts: bytes | None,
                 data_dir: Path | None) -> TractFiles | None:
    """The files on disk of the tracts of a run: the upload itself (tracts alone) or option ``tracts``."""
    import tempfile

    from brainpainter.web.tracts import is_tract_bundle, materialise

    if is_tract_bundle(data):
        if tracts is not None and tracts != data:
            raise BrainPainterError("the upload is tractograms already; give option tracts only with a "
                                    "region table (or leave it out to draw the tracts alone).")
        tracts = data
    elif options.tracts is not None and (tracts is None or not is_tract_bundle(tracts)):
        raise BrainPainterError("option tracts names no tract upload (it expired, or is a table); upload the "
                                "tractograms again (POST /api/tracts) and give its upload_id.")
    root = data_dir if data_dir is not None else Path(tempfile.gettempdir()) / "brainpainter-web"
    return None if tracts is None else materialise(tracts, root)


# -- figure and movie options of a job: the CLI's defaults (core option classes) ----------------------
def _figure_options() -> type:
    from brainpainter.media.layout import FigureOptions

    return FigureOptions


def _movie_options() -> type:
    from brainpainter.media.movie import MovieOptions

    return MovieOptions


class FigureParams(BaseModel):
    """``figure`` job options, with ``brainpainter figure``'s defaults (render size: option ``size``)."""

    model_config = ConfigDict(extra="forbid")
    format: Literal["pdf", "png"] = "pdf"
    grid: bool = core(_figure_options(), "grid")
    title: str | None = Field(None, max_length=200)
    label: str | None = Field(None, max_length=200)
    dpi: float = Field(core(_figure_options(), "dpi").default, ge=50, le=600,
                       description="Resolution of PNG output (dots per inch).")
    fig_width: float | None = Field(None, gt=0, le=40,
                                    description="Figure width in inches (default: from the layout).")
    font_size: float = Field(core(_figure_options(), "font_size").default, ge=1, le=72,
                             description="Text size in points.")
    slices: list[Annotated[str, Field(max_length=200)]] = Field([], max_length=24, description=(
        "A volume upload's slice panels: AXIS=MM[,MM...] (x, y, z; MNI mm), e.g. z=-20,0,20,40."))
    projections: str | None = Field(None, max_length=40, description="Glass-brain panels: xyz, z, ...")
    convention: Literal["neurological", "radiological"] = "neurological"


class ExportParams(BaseModel):
    """``export`` job options: one row as an interactive 3D page (``brainpainter export --format html``)."""

    model_config = ConfigDict(extra="forbid")
    row: int = Field(0, ge=0, description="Row (0-based) exported.")
    title: str | None = Field(None, max_length=200,
                              description="The page's heading (default: the row's name).")


class MovieParams(BaseModel):
    """``movie`` job options, with ``brainpainter movie``'s defaults."""

    model_config = ConfigDict(extra="forbid")
    format: Literal["mp4", "gif"] = "mp4"
    frames_per_step: int = Field(core(_movie_options(), "frames_per_step").default, ge=1, le=120,
                                 description="Frames from one key frame (row) to the next.")
    easing: Literal["linear", "smooth"] = core(_movie_options(), "easing")
    hold: int = Field(core(_movie_options(), "hold").default, ge=0, le=120,
                      description="Extra frames showing each key frame still.")
    fps: float = Field(core(_movie_options(), "fps").default, ge=1, le=60, description="Frames per second.")
    clip_sweep: str | None = Field(None, max_length=8,
                                   description=core(_movie_options(), "clip_sweep").description)
    title: str | None = Field(None, max_length=200)
    label: str | None = Field(None, max_length=200)

    def n_frames(self, n_keys: int) -> int:
        """Frames of a movie through `n_keys` key frames (the job's progress total)."""
        from brainpainter.media.timeline import plan_frames

        return len(plan_frames(list(range(n_keys)), self.frames_per_step, self.easing, self.hold))


def map_check(data: bytes, name: str, options: RenderOptions, data_dir: Path | None = None,
              **uploads: Any) -> dict[str, Any]:
    """The report of a map upload (:func:`brainpainter.web.maps.base_report`) with the colour scale of
    `options` (the page's colour bar; the threshold band is marked by ``threshold``) and its layers'
    (`uploads`: the tracts and contour drawn with it, as :func:`prepare` takes them)."""
    from brainpainter.web.maps import base_of

    report = base_of(data)
    run = prepare(data, name, options, data_dir=data_dir, **uploads).run
    report["values"]["scale"] = scale_report(run.scale)
    report["layers"] = layers_report(run)
    return report


def scale_report(scale: Any) -> dict[str, Any]:
    """A run's colour scale as the check report gives it (the page's colour bar: ``ramp``, ``ticks``; a
    label map's ``categories``, its key: ``name`` and ``color`` each, the first :data:`MAX_KEY_LISTED`,
    and ``n_categories``)."""
    from brainpainter.color.rgb import to_hex
    from brainpainter.table.report import colour_bar

    return {"name": scale.name, "vmin": scale.vmin, "vmax": scale.vmax, "center": scale.center,
            "threshold": getattr(scale, "threshold", None), **colour_bar(scale),
            "categories": [{"name": n, "color": to_hex(c)} for n, c in scale.categories[:MAX_KEY_LISTED]],
            "n_categories": len(scale.categories)}


def layers_report(run: Any) -> list[dict[str, Any]]:
    """The colour bars of a run: one per layer with a scale of its own (``kind``, ``label``, ``opacity``,
    ``scale`` as :func:`scale_report`), the first layer's first, as ``render``'s figures draw them."""
    from brainpainter.rendering.layers import colorbar_layers

    return [{"kind": layer.kind, "label": layer.label, "opacity": layer.opacity,
             "scale": scale_report(layer.scale)} for layer in colorbar_layers(run.layers)]


def table_layers(data: bytes, name: str, options: RenderOptions, data_dir: Path | None = None,
                 **uploads: Any) -> dict[str, Any]:
    """The colour scales of a table drawn with other layers (tracts, a map) or options of its own layer:
    ``scale``, the first layer's, and ``layers`` (:func:`layers_report`); `uploads`: :func:`prepare`'s."""
    run = prepare(data, name, options, data_dir=data_dir, **uploads).run
    return {"scale": scale_report(run.scale), "layers": layers_report(run)}


def tract_check(data: bytes, name: str, options: RenderOptions, *,
                data_dir: Path | None = None) -> dict[str, Any]:
    """The report of a tract upload drawn alone (:func:`brainpainter.web.tracts.tract_report`) with the
    colour scale of `options` over its values (the page's colour bar)."""
    from brainpainter.web.tracts import report_of

    report = report_of(data)
    run = prepare(data, name, options, data_dir=data_dir).run
    report["scale"] = scale_report(run.scale)
    report["layers"] = layers_report(run)
    return report

