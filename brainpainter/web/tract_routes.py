"""The route of tractogram uploads (``POST /api/tracts``) and the uploads a render's options name (tracts, a
map over a table: :class:`~brainpainter.web.layer_uploads.LayerUploads`)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import FastAPI, Query, Request
from starlette.concurrency import run_in_threadpool

from brainpainter.web.config import ServerConfig
from brainpainter.web.http import (
    ApiError,
    Work,
    client_of,
    disk_budget,
    owner_of,
    receive_body,
    require_octet_stream,
)
from brainpainter.web.layer_uploads import LayerUploads
from brainpainter.web.options import RenderOptions
from brainpainter.web.store import Store
from brainpainter.web.tracts import is_tract_bundle, is_tract_upload
from brainpainter.web.upload import read_tract_upload


def add_tracts_route(app: FastAPI, config: ServerConfig, store: Store) -> None:
    """Uploads of tractograms (web/tracts.py)."""
    work: Work = app.state.work

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
        path, size = await receive_body(request, store.root)
        try:
            data, report = await work.run(
                read_tract_upload, path, names, sizes, store.root / "incoming",
                max_files=config.max_tract_files, max_streamlines=config.max_tract_streamlines,
                time_limit_s=config.parse_time_limit_s, subject=subject)
        finally:
            path.unlink(missing_ok=True)
        upload_id = await run_in_threadpool(store.add_upload, client_of(request), shown, data,
                                            config.result_ttl_s, config.max_uploads_per_client,
                                            owner=owner_of(request))
        return {"upload_id": upload_id, "name": shown, "size": size, "report": report}


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
    """The uploads of `owner` that `options` name (``tracts``, ``map``, ``contour``).

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
    return LayerUploads(tracts_of(store, options, owner), **maps)
