"""The command line and the Python call that make a page's images again, from its upload and options.

:func:`reproduce` turns an upload (a table, a map, a volume, tractograms) and
its :class:`~brainpainter.web.options.RenderOptions` into the equivalent
``brainpainter render`` command and ``brainpainter.render(...)`` call. Both
are made from the same list of options that differ from their defaults
(:func:`changed`), whose names and defaults are those of the core option
classes (``RenderOptions`` is made from them, as the CLI's flags are:
``nan_color`` is ``--nan-color``). File names are the client's own (made
safe), never a server path; the files are the user's copies of what they
uploaded. Nothing here imports bpy.
"""

from __future__ import annotations

import re
import shlex
from pathlib import PurePosixPath
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from brainpainter.web.connectomes import CONNECTOME_FIELDS
from brainpainter.web.options import LAYER_UPLOADS, TRACT_FIELDS, RenderOptions

#: Options that apply to per-vertex maps only (left out of a table's command).
MAP_ONLY = ("underlay", "threshold", "outline_threshold")
#: Colour options, compared as colours (``white`` is ``#ffffff``).
COLOURS = ("nan_color", "missing_color", "background", "outline_color")
#: The output folder the command and the call write to.
OUT = "brainpainter-out"
#: Characters a terminal acts on (C0, DEL, C1): never verbatim in a command to copy.
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")
#: The file the command reads the tracts' affine from (the page's affine field, saved as text).
AFFINE = "affine.txt"


def _same(name: str, value: Any, default: Any) -> bool:
    """Whether option `name` has its default (colours compared as sRGB)."""
    if name in COLOURS and isinstance(value, str) and isinstance(default, str):
        from brainpainter.color.rgb import to_rgb
        from brainpainter.errors import BrainPainterError

        try:
            return all(round(a * 255) == round(b * 255)
                       for a, b in zip(to_rgb(value), to_rgb(default), strict=True))
        except BrainPainterError:
            return False
    return bool(value == default)


def changed(options: RenderOptions, *, kind: str, tracts: bool,
            connectome: bool = False) -> list[tuple[str, Any]]:
    """The options that differ from their defaults, as ``(name, value)`` in the options' order.

    Parameters
    ----------
    options : RenderOptions
    kind : {"table", "map", "tracts"}
        What is drawn (map options are left out of a table's command; a table with a map over it: map).
    tracts : bool
        Whether tracts are drawn (tract options are left out otherwise).
    connectome : bool
        Whether a connectome is drawn (its edge options are left out otherwise).

    Notes
    -----
    ``views`` given is always kept (the page's views are the ones drawn); ``hide`` is its tokens;
    the affine is the file :data:`AFFINE`.
    """
    out: list[tuple[str, Any]] = []
    for name, info in RenderOptions.model_fields.items():
        value = getattr(options, name)
        if name in LAYER_UPLOADS or name == "volume_surface" or (name in TRACT_FIELDS and not tracts) or (
                name in MAP_ONLY and kind != "map") or (name in CONNECTOME_FIELDS and not connectome):
            continue
        if name == "hide":
            value = options.hide_tokens()
        if name == "tracts_affine" and value is not None:
            value = AFFINE if value.strip() else None
        if name == "background" and options.transparent:
            continue
        if name == "views" and value is not None:
            out.append((name, value))
            continue
        if not _same(name, value, info.get_default(call_default_factory=True)):
            out.append((name, value))
    return out


def inputs(data: bytes, name: str) -> tuple[str, list[str], list[tuple[str, str]]]:
    """What was uploaded: ``(kind, positional inputs, input options)``, by the client's file names.

    Returns
    -------
    kind : {"table", "map", "tracts", "connectome"}
    positional : list of str
        The table (or the tracts' values table, tracts alone; or a CIFTI file; none for a connectome
        alone).
    options : list of (str, str)
        ``("lh", name)``, ``("rh", name)``, ``("volume", name)`` of a map.
    """
    from brainpainter.web.connectomes import is_connectome_bundle
    from brainpainter.web.maps import bundle_header, is_bundle
    from brainpainter.web.tracts import is_tract_bundle, report_of

    if is_connectome_bundle(data):
        return "connectome", [], []
    if is_tract_bundle(data):
        values = report_of(data).get("values") or {}
        return "tracts", [values["file"]] if values.get("file") else [], []
    if is_bundle(data):
        source = str(bundle_header(data)[0].get("source", ""))
        pairs = [part.strip().split("=", 1) for part in source.split(",") if "=" in part]
        cifti = [v for k, v in pairs if k == "cifti"]  # one CIFTI file is INPUT, as on the command line
        return "map", cifti[:1], [(k, v) for k, v in pairs if k in ("lh", "rh", "volume")]
    return "table", [name], []


def tract_inputs(tracts: bytes, alone: bool) -> list[tuple[str, str]]:
    """``--tracts`` (a zip: its folder, unzipped; a zip of subject folders: the subject's) and
    ``--tract-values`` (with a table; tracts alone, their values table is the input)."""
    from brainpainter.web.tracts import report_of

    report = report_of(tracts)
    out: list[tuple[str, str]] = []
    for f in report.get("files", []):
        path = PurePosixPath(f)
        if path.suffix.lower() == ".zip":
            out.append(("tracts", str(path.with_suffix("") / report["subject"]) if report.get("subject")
                        else str(path.with_suffix("")) + "/"))
        elif f != (report.get("values") or {}).get("file"):
            out.append(("tracts", f))
    values = report.get("values") or {}
    if values.get("file") and not alone:
        out.append(("tract_values", values["file"]))
    return out


def connectome_inputs(connectome: bytes) -> list[tuple[str, str]]:
    """``--connectome`` and, where uploaded, ``--nodes``, ``--node-values``, ``--node-categories``: the
    files by the client's names (made safe)."""
    from brainpainter.web.connectomes import ROLES, report_of

    files = report_of(connectome)["files"]
    return [("connectome" if role == "matrix" else role, files[role]) for role in ROLES if role in files]


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _cli_value(value: Any) -> str:
    return shell_word(repr(value) if isinstance(value, float) else str(value))


def shell_word(text: str) -> str:
    """`text` as one shell word: quoted (:func:`shlex.quote`), or, where it holds a control character (ESC,
    CR, a bracketed-paste end), as bash's ``$'...'`` with each such character escaped, so the copied
    command holds none of them and the shell still gives the program `text` exactly."""
    if not _CONTROL.search(text):
        return shlex.quote(text)
    escaped = text.replace("\\", "\\\\").replace("'", "\\'")
    return "$'" + _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 128
                               else f"\\u{ord(m.group()):04x}", escaped) + "'"


def command_line(positional: list[str], pairs: list[tuple[str, Any]], command: str = "render",
                 out: str = OUT) -> str:
    """``brainpainter render INPUT -o OUT --flag value ...`` (booleans as bare flags, lists repeated)."""
    words = ["brainpainter", command, *(shell_word(p) for p in positional), "-o", shell_word(out)]
    for name, value in pairs:
        if value is True:
            words.append(_flag(name))
        elif isinstance(value, list):
            words += [w for item in value for w in (_flag(name), _cli_value(item))]
        else:
            words += [_flag(name), _cli_value(value)]
    return " ".join(words)


def python_call(positional: list[str], pairs: list[tuple[str, Any]], command: str = "render",
                out: str = OUT) -> str:
    """``brainpainter.render(INPUT, out=OUT, name=value, ...)``: ``size`` as ``width``/``height``,
    ``transparent`` as ``background=None``, as :meth:`RenderOptions.run_kwargs` gives them."""
    from brainpainter.rendering.settings import parse_size

    args = [repr(p) for p in positional] + [f"out={out!r}"]
    for name, value in pairs:
        if name == "size":
            width, height = parse_size(value)
            args += [f"width={width}", f"height={height}"]
        elif name == "transparent":
            args.append("background=None")
        else:
            args.append(f"{name}={value!r}")
    return f"import brainpainter\n\nbrainpainter.{command}(" + ", ".join(args) + ")\n"


def media_options(kind: str, params: dict[str, Any]) -> tuple[str, list[tuple[str, Any]]]:
    """The output file and the options of a figure or movie job (`params`: :class:`FigureParams` or
    :class:`MovieParams` fields) that differ from ``brainpainter figure``'s or ``movie``'s defaults; an
    export job's format and row (`params`: ``image``, the row's name, and ``title``)."""
    from brainpainter.io.output import safe_name
    from brainpainter.web.options import FigureParams, MovieParams

    if kind == "export":
        image = str(params.get("image", ""))
        more = [("title", params["title"])] if params.get("title") else []
        return f"{safe_name(image)}.html", [("format", "html"), ("row", image), *more]

    model: Any = FigureParams if kind == "figure" else MovieParams
    given = model(**{k: v for k, v in params.items() if k in model.model_fields})  # not the server's limits
    out = f"{kind}.{given.format}"
    pairs = [(n, getattr(given, n)) for n, info in model.model_fields.items()
             if n != "format" and getattr(given, n) != info.get_default(call_default_factory=True)]
    return out, pairs


def reproduce(data: bytes, name: str, options: RenderOptions, tracts: bytes | None = None,
              kind: str = "images", params: dict[str, Any] | None = None, *,
              map_upload: bytes | None = None, contour_upload: bytes | None = None,
              connectome_upload: bytes | None = None, preview: tuple[str | None, str] | None = None
              ) -> dict[str, str]:
    """The command and the Python call that make the images of `options` from the upload `data` (named
    `name`): ``brainpainter render``, or ``figure`` / ``movie`` for those jobs (`kind`, with their
    `params`).

    Parameters
    ----------
    data : bytes
        The stored upload (a table, a map bundle, or a tract bundle: the tracts alone).
    name : str
        Its display name (:func:`brainpainter.web.options.upload_name`).
    options : RenderOptions
    tracts : bytes, optional
        The tract bundle option ``tracts`` names (drawn with the table).
    kind : {"images", "figure", "movie", "export"}
        The job the command makes (images: ``brainpainter render``).
    params : dict, optional
        A figure's or movie's options.
    map_upload : bytes, optional
        The map bundle option ``map`` names (drawn over the table: its ``--lh``/``--rh`` or ``--volume``).
    contour_upload : bytes, optional
        The map bundle option ``contour`` names (``--contour``).
    connectome_upload : bytes, optional
        The connectome bundle option ``connectome`` names (``--connectome``, ``--nodes``, ...).
    preview : (str or None, str), optional
        The page's preview, ``(image, view)``: the command draws that image from that view only
        (``--rows IMAGE --views VIEW``; no image: the view only).

    Returns
    -------
    dict
        ``command`` (one shell line) and ``python`` (a snippet), with the files under the client's names.
    """
    upload, positional, given = inputs(data, name)
    if options.volume_surface:  # the volume drawn as blobs: --volume-surface FILE
        given = [("volume_surface" if k == "volume" else k, v) for k, v in given]
    drawn = data if upload == "tracts" else tracts
    pairs: list[tuple[str, Any]] = list(given)
    if map_upload is not None:  # a map over the table: its files as --lh/--rh or --volume
        upload = "map"
        pairs += inputs(map_upload, "")[2]
    if contour_upload is not None:  # --contour FILE, or LH,RH
        pairs.append(("contour", ",".join(v for _, v in inputs(contour_upload, "")[2])))
    if drawn is not None:
        merged: dict[str, list[str]] = {}
        for key, value in tract_inputs(drawn, upload == "tracts"):
            merged.setdefault(key, []).append(value)
        pairs += [(k, v if k == "tracts" else v[0]) for k, v in merged.items()]
    network = data if upload == "connectome" else connectome_upload
    if network is not None:
        pairs += connectome_inputs(network)
    pairs += changed(options, kind=upload, tracts=drawn is not None, connectome=network is not None)
    command, out = "render", OUT
    if preview is not None:
        image, view = preview
        pairs = [(k, v) for k, v in pairs if k != "views"] + ([("rows", image)] if image else []) + [
            ("views", view)]
    if kind == "export":  # an export draws no image: no views, size or quality
        from brainpainter.media.export import EXPORT_OPTIONS

        keep = ("atlas", *EXPORT_OPTIONS)  # as the CLI's export command takes them
        pairs = [(k, v) for k, v in pairs if k in keep]
    if kind in ("figure", "movie", "export"):
        command = kind
        out, more = media_options(kind, params or {})
        pairs += more
    return {"command": command_line(positional, pairs, command, out),
            "python": python_call(positional, pairs, command, out)}


class PreviewShown(BaseModel):
    """The image and view the page's preview shows (``/api/check``: the command that draws it)."""

    model_config = ConfigDict(extra="forbid")
    row: str | None = Field(None, max_length=500, description="The image's name (a table's row).")
    view: str = Field(..., max_length=100, description="A view name or camera:AZ:EL[:ZOOM].")
