"""Render options of the web API: the CLI's names and defaults, checked by the CLI's own code.

:class:`RenderOptions` mirrors ``brainpainter render``'s options (Python
names: ``nan_color``, ``glass_opacity``...; ``size`` is ``WIDTHxHEIGHT``;
``transparent`` replaces the background). :func:`prepare` turns an uploaded
table and options into a :class:`~brainpainter.rendering.painter.Run` through
:func:`brainpainter.rendering.painter.prepare_run`, exactly as the CLI does, plus the
checks a server adds (no paths, size limits). Nothing here imports bpy.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from brainpainter.cli.options import DEFAULT_SIZE, DEFAULT_VIEWS, parse_size
from brainpainter.errors import BrainPainterError

#: Suffixes an uploaded file name may have (only used to sniff the format; never a path).
UPLOAD_SUFFIXES = (".csv", ".tsv", ".tab", ".txt", ".dat", ".xlsx", ".xlsm", ".xls")


class TableOptions(BaseModel):
    """How the table is read (``brainpainter check``'s input options)."""

    model_config = ConfigDict(extra="forbid")

    atlas: str | None = Field(None, description="dk, destrieux, dkt (alias tourville) or a plugin atlas; "
                                                "inferred from the region names when not given.")
    image_column: str | None = Field(None, description="Column with image names.")
    value: str | None = Field(None, description="Long tables: the column with the values.")
    region_column: str | None = Field(None, description="Long tables: the column with region names.")
    strict: bool = Field(False, description="Names that match no region are an error.")


class RenderOptions(TableOptions):
    """The options of ``brainpainter render`` with the same names and defaults."""

    views: str = Field(DEFAULT_VIEWS, description="Comma-separated views, 'all', or camera:AZ:EL[:ZOOM].")
    surface: Literal["pial", "white", "inflated"] = "pial"
    gradient: str | None = Field(None, description="Control colours, e.g. white,yellow,orange,red "
                                                   "(the default). Values 0..N-1.")
    cmap: str | None = Field(None, description="A matplotlib colour map instead of a gradient.")
    vmin: float | None = Field(None, description="Value at the first colour.")
    vmax: float | None = Field(None, description="Value at the last colour.")
    center: float | None = Field(None, description="Diverging: value at the middle colour.")
    nan_color: str = Field("#8c8c8c", description="Colour of empty cells.")
    missing_color: str = Field("#d0d0d0", description="Colour of regions with no column.")
    hide: list[str] = Field(default_factory=list, description="Regions or groups not drawn (cerebellum, "
                                                               "ventricles, brainstem, ventraldc).")
    background: str = Field("white", description="Background colour.")
    transparent: bool = Field(False, description="Transparent background.")
    size: str = Field(DEFAULT_SIZE, description="Size of each rendered view, WIDTHxHEIGHT pixels.")
    quality: Literal["fast", "default", "high"] = "default"
    shading: Literal["default", "flat"] = "default"
    lighting: Literal["studio", "soft", "flat-studio"] = "studio"
    glass_opacity: float = 0.12

    def table_kwargs(self) -> dict[str, Any]:
        return {"image_column": self.image_column, "value": self.value,
                "region_column": self.region_column, "strict": self.strict}

    def run_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of ``prepare_run`` (without `data` and `atlas`)."""
        width, height = parse_size(self.size)
        return {
            "views": self.views, "gradient": self.gradient, "cmap": self.cmap, "vmin": self.vmin,
            "vmax": self.vmax, "center": self.center, "nan_color": self.nan_color,
            "missing_color": self.missing_color,
            "background": None if self.transparent else self.background,
            "width": width, "height": height, "quality": self.quality, "shading": self.shading,
            "lighting": self.lighting, "glass_opacity": self.glass_opacity, **self.table_kwargs(),
        }

    def hide_tokens(self) -> list[str]:
        return [h.strip() for item in self.hide for h in item.split(",") if h.strip()]


def table_stream(data: bytes, name: str) -> io.BytesIO:
    """The uploaded bytes as a named stream for the readers: `name` is only a label, never opened."""
    stream = io.BytesIO(data)
    stream.name = name  # type: ignore[attr-defined]
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

    run: Any  # brainpainter.rendering.painter.Run
    options: RenderOptions
    hidden: list[str]
    file_names: list[str]


def prepare(data: bytes, name: str, options: RenderOptions, *, max_images: int | None = None,
            max_pixels: int | None = None) -> Prepared:
    """Check `options` against the uploaded table exactly as ``brainpainter render`` would.

    Parameters
    ----------
    data : bytes
        The uploaded table file.
    name : str
        Its display name (from :func:`upload_name`).
    options : RenderOptions
    max_images : int, optional
        Largest rows x views.
    max_pixels : int, optional
        Largest width x height of one view.

    Raises
    ------
    BrainPainterError
        The CLI's one-line message for the first problem.
    """
    from brainpainter.io.output import safe_name
    from brainpainter.rendering.painter import prepare_run, resolve_hidden

    kwargs = options.run_kwargs()
    if max_pixels is not None and kwargs["width"] * kwargs["height"] > max_pixels:
        raise BrainPainterError(
            f"size {options.size} is {kwargs['width'] * kwargs['height']} pixels; this server renders at "
            f"most {max_pixels} pixels per view. Choose a smaller size."
        )
    run = prepare_run(table_stream(data, name), options.atlas, **kwargs)
    hidden = options.hide_tokens()
    resolve_hidden(hidden, run.table.atlas)
    n = len(run.table.images) * len(run.views)
    if max_images is not None and n > max_images:
        raise BrainPainterError(
            f"{len(run.table.images)} row(s) x {len(run.views)} view(s) = {n} images; this server renders at "
            f"most {max_images} per job. Choose fewer views or split the table."
        )
    names = [safe_name(i) for i in run.table.images]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise BrainPainterError(
            f"image names {clash[:3]} become the same file name after removing unsafe characters; "
            "make the image names differ in letters or digits."
        )
    return Prepared(run, options, hidden, names)
