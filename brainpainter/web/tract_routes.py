"""The routes of tractogram and connectome uploads (``POST /api/tracts``, ``POST /api/connectomes``) and the
uploads a render's options name (tracts, a map over a table, a connectome:
:class:`~brainpainter.web.layer_uploads.LayerUploads`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

from fastapi import FastAPI, Query, Request

from brainpainter.web.config import ServerConfig
from brainpainter.web.connectomes import ROLES
from brainpainter.web.http import (
    ApiError,
    Work,
    disk_budget,
    keep_upload,
    require_octet_stream,
)
from brainpainter.web.layer_uploads import LayerUploads
from brainpainter.web.options import RenderOptions
from brainpainter.web.store import Store
from brainpainter.web.tracts import is_tract_bundle, is_tract_upload
from brainpainter.web.upload import read_tract_upload


def add_tracts_route(app: FastAPI, config: ServerConfig, store: Store) -> None:
    """Uploads of tractograms (web/tracts.py) and of connectomes (:func:`add_connectome_route`)."""
    work: Work = app.state.work
    add_connectome_route(app, config, store)

    @app.post("/api/tracts", tags=["api"], openapi_extra={"requestBody": {
        "required": True, "content": {"application/octet-stream": {"schema": {"type": "string",
                                                                              "format": "binary"}}}}})
    async def upload_tracts(request: Request,
                            name: Annotated[list[str] | None, Query(description=(
                                "File names, in the body's order: .trk, .tck, .trx (one bundle each, named "
                                "after it), a .zip of them, and at most one .csv/.tsv/.xlsx of bundle "
                                "values."))] = None,
                            sizes: Annotated[list[int] | None, Query(alias="size", description=(
                                "With several names: the bytes of each file, in the body's order."))] = None,
                            subject: Annotated[str | None, Query(max_length=200, description=(
                                "A zip of subject folders (sub_1/AF_L.trk, sub_2/AF_L.trk, ...): the folder "
                                "to draw (default: the first; the report lists them)."))] = None,
                            ) -> dict[str, Any]:
        """Upload tractograms and get their report (bundles, streamlines); nothing is kept when they cannot
        be drawn."""
        from brainpainter.web.tracts import member_name

        require_octet_stream(request, "the files")
        names, sizes = name or [], sizes or []
        if not names or len(names) > config.max_tract_files or len(sizes) > config.max_tract_files or any(
                len(n) > 200 for n in names):
            raise ApiError(422, f"give 1 to {config.max_tract_files} file names (name=AF_left.trk&name=..., "
                                "or one .zip), each at most 200 characters.")
        if not is_tract_upload(names):
            raise ApiError(422, f"{member_name(names[0])!r} is not a tractogram; upload .trk, .tck or .trx "
                                "files (one per bundle) or a .zip of them.")
        await disk_budget(store, config)
        shown = " + ".join(member_name(n) for n in names[:5]) + (" + ..." if len(names) > 5 else "")
        upload_id, size, report = await keep_upload(
            request, store, config, work, shown, read_tract_upload, names, sizes, store.root / "incoming",
            max_files=config.max_tract_files, max_streamlines=config.max_tract_streamlines,
            time_limit_s=config.parse_time_limit_s, subject=subject)
        return {"upload_id": upload_id, "name": shown, "size": size, "report": report}


def add_connectome_route(app: FastAPI, config: ServerConfig, store: Store) -> None:
    """Uploads of connectomes (web/connectomes.py)."""
    from brainpainter.web.connectomes import MAX_NODES
    from brainpainter.web.upload import read_connectome_upload

    work: Work = app.state.work

    @app.post("/api/connectomes", tags=["api"], openapi_extra={"requestBody": {
        "required": True, "content": {"application/octet-stream": {"schema": {"type": "string",
                                                                              "format": "binary"}}}}})
    async def upload_connectome(request: Request,
                                name: Annotated[list[str] | None, Query(description=(
                                    "File names, in the body's order: the matrix (CSV/TSV/text, .edge, .npy, "
                                    ".mat, .pconn.nii), then optionally a nodes file (name,x,y,z or .node), "
                                    "node values, node categories."))] = None,
                                sizes: Annotated[list[int] | None, Query(alias="size", description=(
                                    "With several names: each file's bytes, in the body's order."))] = None,
                                role: Annotated[list[str] | None, Query(description=(
                                    "The role of each file, one of matrix, nodes, node_values, "
                                    "node_categories (default: in that order)."))] = None,
                                ) -> dict[str, Any]:
        """Upload a connectome and get its report (nodes, edges); nothing is kept when it cannot be read."""
        from brainpainter.web.tracts import member_name

        require_octet_stream(request, "the files")
        names, sizes = name or [], sizes or []
        if not names or max(len(names), len(sizes)) > len(ROLES) or any(len(n) > 200 for n in names):
            raise ApiError(422, f"give 1 to {len(ROLES)} file names (name=matrix.csv&name=nodes.csv...), "
                                "each at most 200 characters.")
        await disk_budget(store, config)
        shown = " + ".join(member_name(n) for n in names)
        upload_id, size, report = await keep_upload(
            request, store, config, work, shown, read_connectome_upload, names, sizes, role or [],
            store.root / "incoming", max_nodes=MAX_NODES, time_limit_s=config.parse_time_limit_s)
        return {"upload_id": upload_id, "name": shown, "size": size, "report": report}


async def alone_check(work: Work, data: bytes, name: str, options: RenderOptions,
                      data_dir: Path) -> dict[str, Any] | None:
    """The check report of tracts or a connectome uploaded as the main upload (drawn alone: their report
    with the colour scales of `options`); None for another upload."""
    from brainpainter.web.connectomes import is_connectome_bundle
    from brainpainter.web.options import tract_check

    check: Any = (tract_check if is_tract_bundle(data) else connectome_check if is_connectome_bundle(data)
                  else None)
    return None if check is None else dict(await work.run(check, data, name, options, data_dir=data_dir))


def connectome_check(data: bytes, name: str, options: RenderOptions, *,
                     data_dir: Path | None = None) -> dict[str, Any]:
    """The report of a connectome upload drawn alone (:func:`report_of`) with the colour bars of its
    edges and nodes under `options` (a :class:`~brainpainter.web.options.RenderOptions`) and the number
    of edges drawn (``drawn``)."""
    from brainpainter.rendering.connectome_layers import connectome_summary
    from brainpainter.web.connectomes import report_of
    from brainpainter.web.options import layers_report, prepare, scale_report

    report = report_of(data)
    run = prepare(data, name, options, data_dir=data_dir).run
    report["scale"] = scale_report(run.scale)
    report["layers"] = layers_report(run)
    drawn = connectome_summary(run.connectome) if run.connectome is not None else {}
    report["drawn"] = {k: v for k, v in drawn.items() if k != "nodes"}  # n_edges, weight_range
    return report


def tracts_of(store: Store, options: RenderOptions, owner: str) -> bytes | None:
    """The tract upload of `owner` that option ``tracts`` names (None without it)."""
    if options.tracts is None:
        return None
    got = store.get_upload(options.tracts, owner)
    if got is None or not is_tract_bundle(got[1]):
        raise ApiError(404, "the tract upload of option tracts was not found (it expired, or the id is "
                            "wrong); upload the tractograms again.")
    return got[1]


def layer_uploads(store: Store, options: RenderOptions, owner: str) -> LayerUploads:
    """The uploads of `owner` that `options` name (``tracts``, ``map``, ``contour``, ``connectome``).

    Raises
    ------
    ApiError
        404 when one is not found (expired, a wrong id, another client's) or is not of its kind.
    """
    from brainpainter.web.maps import is_bundle

    maps: dict[str, bytes | None] = {}
    for name in ("map", "contour"):
        upload_id = getattr(options, name)
        got = None if upload_id is None else store.get_upload(upload_id, owner)
        if upload_id is not None and (got is None or not is_bundle(got[1])):
            raise ApiError(404, f"the map upload of option {name} was not found (it expired, the id is "
                                "wrong, or it is not a map); upload the map again.")
        maps[name] = None if got is None else got[1]
    from brainpainter.web.connectomes import is_connectome_bundle

    got = None if options.connectome is None else store.get_upload(options.connectome, owner)
    if options.connectome is not None and (got is None or not is_connectome_bundle(got[1])):
        raise ApiError(404, "the connectome upload of option connectome was not found (it expired, the id is "
                            "wrong, or it is no connectome); upload the connectome again.")
    return LayerUploads(tracts_of(store, options, owner), **maps, connectome=None if got is None else got[1])
