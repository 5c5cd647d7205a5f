"""The other uploads a render draws with its main one, each a layer: tracts (option ``tracts``) and a
map over a region table (option ``map``).

Each is an upload of the same client, found by its id
(:func:`brainpainter.web.tract_routes.layer_uploads`), and a job keeps a
copy of each beside its ``input.bin`` (:meth:`LayerUploads.files`, :meth:`LayerUploads.read`), as
it keeps its main upload: what it draws never changes or expires while it waits.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: A job's copy of each layer upload its options name (beside ``input.bin``).
FILES = {"tracts": "tracts.bin", "map": "map.bin", "contour": "contour.bin", "connectome": "connectome.bin"}


@dataclass(frozen=True)
class LayerUploads:
    """The stored bytes of the uploads a render's options name (None: not named).

    Attributes
    ----------
    tracts : bytes, optional
        A tract bundle (:mod:`brainpainter.web.tracts`).
    map : bytes, optional
        A map bundle (:mod:`brainpainter.web.maps`), drawn over the table's region colours.
    contour : bytes, optional
        A map bundle whose iso-lines are drawn over the map (``--contour``).
    connectome : bytes, optional
        A connectome bundle (:mod:`brainpainter.web.connectomes`), drawn as nodes and edges.
    """

    tracts: bytes | None = None
    map: bytes | None = None
    contour: bytes | None = None
    connectome: bytes | None = None

    def kwargs(self) -> dict[str, Any]:
        """The keyword arguments of :func:`brainpainter.web.options.prepare` (and of previews, reports)."""
        return {"tracts": self.tracts, "map_upload": self.map, "contour_upload": self.contour,
                "connectome_upload": self.connectome}

    def files(self) -> dict[str, bytes] | None:
        """A job's copies: file name -> bytes (None when there are none)."""
        out = {FILES[kind]: data for kind in FILES if (data := getattr(self, kind)) is not None}
        return out or None

    @classmethod
    def read(cls, folder: Path) -> LayerUploads:
        """A job's copies, read from its folder."""
        got = {kind: (folder / name).read_bytes() if (folder / name).is_file() else None
               for kind, name in FILES.items()}
        return cls(**got)


def map_over(data: bytes, map_upload: bytes | None) -> Any:
    """The maps of option ``map``, drawn over the region colours of table `data` (as ``--lh``/``--rh``
    beside INPUT; tracts may be drawn with them, option ``tracts``).

    Raises
    ------
    BrainPainterError
        The main upload is no region table, or option ``map`` names no map upload (or a CIFTI file).
    """
    from brainpainter.errors import BrainPainterError
    from brainpainter.web.maps import bundle_header, is_bundle, read_bundle
    from brainpainter.web.tracts import is_tract_bundle

    if is_bundle(data) or is_tract_bundle(data):
        raise BrainPainterError("option map draws a map over a region table's colours; the upload is a map "
                                "or tractograms already. Upload a region table and give the map as option "
                                "map, or leave option map out.")
    if map_upload is None or not is_bundle(map_upload):
        raise BrainPainterError("option map names no map upload (it expired, or is a table); upload the map "
                                "again (POST /api/uploads) and give its upload_id.")
    if bundle_header(map_upload)[0].get("kind") == "cifti":  # as the CLI: CIFTI is INPUT, never --lh/--rh
        raise BrainPainterError("a CIFTI file is drawn alone, not over a region table (as brainpainter "
                                "render takes it: INPUT, not --lh/--rh); give a surface map pair or a volume "
                                "as option map, or upload the CIFTI file as the main upload.")
    return read_bundle(map_upload)


def contour_maps(contour_upload: bytes | None) -> Any:
    """The maps of option ``contour`` (a map bundle), whose iso-lines are drawn over the map (``--contour``).

    Raises
    ------
    BrainPainterError
        Option ``contour`` names no map upload.
    """
    from brainpainter.errors import BrainPainterError
    from brainpainter.web.maps import is_bundle, read_bundle

    if contour_upload is None or not is_bundle(contour_upload):
        raise BrainPainterError("option contour names no map upload (it expired, or is a table); upload the "
                                "map again (POST /api/uploads) and give its upload_id.")
    return read_bundle(contour_upload)


def layer_maps(options: Any, data: bytes, map_upload: bytes | None,
               contour_upload: bytes | None) -> dict[str, Any]:
    """The run's keywords of options ``map`` and ``contour`` (a
    :class:`~brainpainter.web.options.RenderOptions`): ``lh``, the maps over the table (as ``--lh``/``--rh``
    beside INPUT), ``contour``, the maps whose iso-lines are drawn (``--contour``), and the map's colour-bar
    label when none was given (its files' names: ``lh.thickness + rh.thickness``)."""
    from brainpainter.web.maps import base_of, is_bundle

    out: dict[str, Any] = {}
    if options.map is not None:
        out["lh"] = map_over(data, map_upload)
    if options.contour is not None:
        out["contour"] = contour_maps(contour_upload)
    drawn = map_upload if options.map is not None else data
    if options.map_label is None and drawn is not None and is_bundle(drawn):
        out["map_label"] = " + ".join(base_of(drawn)["files"])  # its colour bar: the files, as uploaded
    return out
