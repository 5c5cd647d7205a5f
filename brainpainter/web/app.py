"""The ASGI application: one page and a JSON API.

API (all JSON unless said; errors are ``{"error": "one line"}`` with the CLI's messages)::

    GET  /                         the page (static HTML/CSS/JS from the package)
    GET  /openapi.json             the API schema
    GET  /healthz                  the process answers
    GET  /readyz                   database writable, a worker and the preview renderer warm (else 503)
    GET  /api/meta                 atlases, views, colour maps, option defaults, limits
    POST /api/uploads?name=&atlas=&image_column=&value=&region_column=&strict=
                                   body: the table file (CSV/TSV/XLSX bytes, or pasted text)
                                   -> {"upload_id", "name", "report", "images"} (`check --json`'s report)
                                   or a map (web/maps.py; report.kind "map"): name=lh.x.mgh[&name=rh.x.mgh
                                   &size=N1&size=N2: both files in the body], or a volume name=v.nii.gz
    POST /api/tracts?name=&size=   body: tractograms (.trk/.tck/.trx, one per bundle, or a .zip of them;
                                   one .csv/.tsv/.xlsx of bundle values may come with them), sizes in
                                   the query -> {"upload_id", "name", "report"} (web/tracts.py); the id is
                                   option "tracts" of a table's renders, or an upload_id itself (the tracts
                                   alone, coloured by their values table)
    POST /api/connectomes?name=&size=&role=  a matrix[, nodes, values, categories]: web/connectomes.py
    POST /api/check                {"upload_id", "options", "preview"?} -> the check report for those options
                                   (with ``preview`` {"row", "view"}: ``reproduce_preview``, its command)
    POST /api/preview              {"upload_id", "options", "row", "view"} -> image/png
    POST /api/jobs                 {"upload_id", "kind", "options", "figure"|"movie"|"export"} -> 202 {job}
    GET  /api/jobs/{id}            status, progress, files
    DELETE /api/jobs/{id}          cancel
    GET  /api/jobs/{id}/files/{name}   one of the job's own files (?download=1: as attachment)

Every response carries a strict Content-Security-Policy; every request is
logged as one JSON line on the ``brainpainter.web.access`` logger (both by
:class:`brainpainter.web.guard.Guard`).
"""

from __future__ import annotations

import logging
import sqlite3
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from importlib import resources
from typing import Annotated, Any, Literal

import anyio
import anyio.to_thread
from fastapi import FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response, StreamingResponse
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import ClientDisconnect

from brainpainter.errors import BrainPainterError
from brainpainter.web.config import ServerConfig, no_paths
from brainpainter.web.disk import FULL_BELOW, disk_free, disk_full
from brainpainter.web.guard import Guard
from brainpainter.web.http import (
    ApiError,
    Work,
    bounded,
    client_of,
    disk_budget,
    keep_upload,
    one_line,
    owner_of,
    require_octet_stream,
    validation_line,
)
from brainpainter.web.job_plan import job_plan
from brainpainter.web.layer_uploads import LayerUploads
from brainpainter.web.maps import file_name, is_bundle, is_map_upload
from brainpainter.web.options import (
    ExportParams,
    FigureParams,
    MovieParams,
    RenderOptions,
    TableOptions,
    map_check,
    table_layers,
    upload_name,
)
from brainpainter.web.pool import MAX_PREVIEW_WAITING, Pool, PreviewBusy, PreviewUnavailable, preview_request
from brainpainter.web.reproduce import PreviewShown, reproduce
from brainpainter.web.store import LimitError, Store, valid_id
from brainpainter.web.tract_routes import add_tracts_route, alone_check, layer_uploads
from brainpainter.web.tracts import is_tract_bundle, is_tract_upload
from brainpainter.web.upload import (
    check_table,
    read_and_check,
    read_map_upload,
)
from brainpainter.web.work_processes import WorkProcesses

log = logging.getLogger("brainpainter.web")

MAX_LISTED_IMAGES = 5000  # image names sent to the page for its row chooser


# -- request bodies -------------------------------------------------------------------------
class CheckRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")
    upload_id: str
    options: RenderOptions = Field(default_factory=RenderOptions)
    preview: PreviewShown | None = Field(None, description="The preview shown: ``reproduce_preview``.")


class PreviewRequest(CheckRequest):
    row: int | str = Field(0, description="Row number (0-based) or image name.")
    view: str = Field("lateral-left", description="A view name or camera:AZ:EL[:ZOOM].")


class JobRequest(CheckRequest):
    kind: Literal["images", "figure", "movie", "export"] = "images"
    figure: FigureParams = Field(default_factory=FigureParams)
    movie: MovieParams = Field(default_factory=MovieParams)
    export: ExportParams = Field(default_factory=ExportParams)


# -- the app ------------------------------------------------------------------------------
def _static_dir() -> Any:
    return resources.files("brainpainter.web") / "static"


def create_app(config: ServerConfig | None = None) -> FastAPI:
    """The application for `config` (its pool starts and stops with the app's lifespan)."""
    config = config or ServerConfig()
    store = Store(config.data_dir, config.max_disk_bytes)
    pool = Pool(config, store)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        pool.start()
        processes.start()
        try:
            yield
        finally:
            processes.stop()
            pool.stop()

    app = FastAPI(title="brainpainter", version=_version(), lifespan=lifespan, docs_url=None, redoc_url=None,
                  description="Upload a table of values per brain region, or a per-vertex map or MNI152 "
                              "volume; check it, preview and render it.",
                  redirect_slashes=False)  # a redirect would build its Location from the Host header
    app.state.config, app.state.store, app.state.pool = config, store, pool
    processes = WorkProcesses(config.work_processes, config.work_time_limit_s, config.worker_memory_bytes)
    app.state.work = Work(config.work_threads, config.max_waiting_work, processes)
    app.add_middleware(Guard, config=config)

    _add_error_handlers(app, config)
    _add_page_and_probes(app, config, store, pool)
    _add_upload_route(app, config, store)
    add_tracts_route(app, config, store)
    _add_table_routes(app, config, store, pool)
    _add_job_routes(app, config, store)
    return app


def _add_error_handlers(app: FastAPI, config: ServerConfig) -> None:
    """Every error becomes ``{"error": "one line"}`` with its status (no server path in it)."""
    def line(exc: BaseException) -> str:
        return no_paths(one_line(exc), config.data_dir)  # a file of the data folder: its name only

    @app.exception_handler(BrainPainterError)
    async def _bp_error(request: Request, exc: BrainPainterError) -> JSONResponse:
        if disk_full(exc, config.data_dir):
            return _full(request, exc)
        return JSONResponse({"error": line(exc)}, status_code=400)

    @app.exception_handler(ApiError)
    async def _api_error(request: Request, exc: ApiError) -> JSONResponse:
        return JSONResponse({"error": line(exc)}, status_code=exc.status, headers=exc.headers)

    @app.exception_handler(LimitError)  # the disk budget, counted as an upload is stored
    async def _limit(request: Request, exc: LimitError) -> JSONResponse:
        return JSONResponse({"error": line(exc)}, status_code=exc.status,
                            headers={"retry-after": str(exc.retry_after)})

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse({"error": validation_line(exc)}, status_code=422)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        return JSONResponse({"error": str(exc.detail)}, status_code=exc.status_code,
                            headers=getattr(exc, "headers", None))

    @app.exception_handler(ClientDisconnect)
    async def _gone(request: Request, exc: ClientDisconnect) -> Response:
        log.info("client left during %s %s", request.method, request.url.path)
        return Response(status_code=400)  # nobody reads it

    @app.exception_handler(OSError)
    @app.exception_handler(sqlite3.OperationalError)
    async def _os_error(request: Request, exc: Exception) -> JSONResponse:
        if disk_full(exc, config.data_dir):
            return _full(request, exc)
        log.error("internal error on %s %s", request.method, request.url.path, exc_info=exc)
        return JSONResponse({"error": f"internal error: {type(exc).__name__} (logged on the server)"},
                            status_code=500)

    # any other error is answered by the guard (brainpainter.web.guard): 500 with the security headers, and
    # logged with its status (Starlette's handler of Exception runs outside every middleware)


def _add_page_and_probes(app: FastAPI, config: ServerConfig, store: Store, pool: Pool) -> None:
    """``/``, ``/static``, ``/healthz``, ``/readyz`` and ``/api/meta``."""
    @app.get("/", include_in_schema=False)
    async def index() -> Response:
        html = (_static_dir() / "index.html").read_bytes()
        return Response(html, media_type="text/html; charset=utf-8")

    app.mount("/static", StaticFiles(directory=str(_static_dir())), name="static")

    @app.get("/healthz", tags=["probes"])
    async def healthz() -> dict[str, str]:
        """The server process answers."""
        return {"status": "ok"}

    @app.get("/readyz", tags=["probes"])
    async def readyz() -> JSONResponse:
        """Ready to take work: database writable, disk not full, a job worker warm, the preview renderer
        warm."""
        try:
            db_ok = await run_in_threadpool(store.ping)
        except Exception:
            db_ok = False
        workers = await run_in_threadpool(store.workers)
        disk_ok = await run_in_threadpool(disk_free, store.root) >= FULL_BELOW
        ready_workers = [w for w in workers if w["state"] in ("ready", "busy")]
        checks = {"database": db_ok, "disk": disk_ok,
                  "workers": len(ready_workers) >= min(1, config.workers) and pool.alive_workers() >= min(
                      1, config.workers),
                  "preview": pool.preview_ready or not config.preview}
        ok = all(checks.values())
        return JSONResponse({"status": "ready" if ok else "starting", "checks": checks,
                             "jobs": await run_in_threadpool(store.counts)}, status_code=200 if ok else 503)

    @app.get("/api/meta", tags=["api"])
    async def meta() -> dict[str, Any]:
        """What the page needs to draw its form: choices, defaults and limits."""
        return await run_in_threadpool(_meta, config)


def _add_upload_route(app: FastAPI, config: ServerConfig, store: Store) -> None:
    """Uploads of a table or a map."""
    work: Work = app.state.work

    @app.post("/api/uploads", tags=["api"], openapi_extra={"requestBody": {
        "required": True, "content": {"application/octet-stream": {"schema": {"type": "string",
                                                                              "format": "binary"}}}}})
    async def upload(request: Request,
                     name: Annotated[list[str] | None, Query(description=(
                         "File name (its ending says the format; default table.csv). A map pair: two "
                         "names (lh, rh)."))] = None,
                     sizes: Annotated[list[int] | None, Query(alias="size", description=(
                         "With two names: the bytes of each file, in the body's order."))] = None,
                     hemi: Annotated[list[str] | None, Query(description=(
                         "lh or rh per map file (default: from its name)."))] = None,
                     atlas: str | None = Query(None, max_length=100),
                     image_column: str | None = Query(None, max_length=200),
                     value: str | None = Query(None, max_length=200),
                     region_column: str | None = Query(None, max_length=200),
                     strict: bool = False) -> dict[str, Any]:
        """Upload a table or a map (the raw file(s) as the body) and get the ``check`` report; nothing
        is kept when it would not render."""
        require_octet_stream(request, "the table")
        names, sizes, hemi = name or ["table.csv"], sizes or [], hemi or []
        if is_tract_upload(names):
            raise ApiError(422, f"{file_name(names[0])!r} is a tractogram; upload tractograms with POST "
                                "/api/tracts (the page's 'Tracts' field) and give their upload_id as option "
                                "tracts.")
        if len(names) > 2 or any(len(n) > 200 for n in names) or len(hemi) > 2 or len(sizes) > 2:
            raise ApiError(422, "give one name (a table, a map or a volume) or two (an lh and an rh map), "
                                "each at most 200 characters.")
        await disk_budget(store, config)
        is_map = len(names) > 1 or is_map_upload(names)
        shown = " + ".join(file_name(n) for n in names) if is_map else upload_name(names[0])
        opts = {"atlas": atlas or None, "image_column": image_column or None, "value": value or None,
                "region_column": region_column or None, "strict": strict}
        # read into memory only on a work thread: at most a few bodies are in memory at once
        if is_map:
            upload_id, size, (report, images) = await keep_upload(
                request, store, config, work, shown, read_map_upload, names, sizes, hemi,
                store.root / "incoming", max_images=config.max_map_images,
                time_limit_s=config.parse_time_limit_s)
        else:
            upload_id, size, (report, images) = await keep_upload(
                request, store, config, work, shown, read_and_check, shown, opts, max_rows=config.max_rows,
                time_limit_s=config.parse_time_limit_s)
        return {"upload_id": upload_id, "name": shown, "size": size, "report": report,
                "images": images[:MAX_LISTED_IMAGES]}


def _add_table_routes(app: FastAPI, config: ServerConfig, store: Store, pool: Pool) -> None:
    """Checks and previews of an upload."""
    work: Work = app.state.work
    previews = anyio.CapacityLimiter(MAX_PREVIEW_WAITING)

    @app.post("/api/check", tags=["api"])
    async def check(body: CheckRequest, request: Request) -> dict[str, Any]:
        """The ``check`` report of an upload with these options (the colour scale included)."""
        name, data = await run_in_threadpool(_upload, store, body.upload_id, owner_of(request))
        o = body.options
        layers = LayerUploads() if is_tract_bundle(data) else await run_in_threadpool(layer_uploads, store, o,
                                                                                     owner_of(request))
        report: dict[str, Any] = bounded(await _check_report(data, name, o, layers))  # echo bounded
        # the command line and the Python call that make these images again
        more = {k: v for k, v in layers.kwargs().items() if k != "tracts"}
        report["reproduce"] = await work.run(reproduce, data, name, o, layers.tracts, **more)
        if body.preview is not None:  # the image and view the preview shows, alone
            report["reproduce_preview"] = await work.run(reproduce, data, name, o, layers.tracts, **more,
                                                         preview=(body.preview.row, body.preview.view))
        return report

    async def _check_report(data: bytes, name: str, o: RenderOptions, layers: LayerUploads) -> dict[str, Any]:
        if (alone := await alone_check(work, data, name, o, store.root)) is not None:  # tracts, connectome
            return alone
        if is_bundle(data):
            return await work.run(map_check, data, name, o, data_dir=store.root, **layers.kwargs())
        opts = {**o.model_dump(include=set(TableOptions.model_fields)),
                "scale": {"gradient": o.gradient, "cmap": o.cmap, "vmin": o.vmin, "vmax": o.vmax,
                          "center": o.center}}
        # read on a work thread: the upload was read within the time limit already (as preview and
        # job submission read it)
        report: dict[str, Any] = (await work.run(check_table, data, name, opts, config.max_rows))[0]
        if layers.files() or o.layers_given():
            # the scales as drawn: each layer's, the regions' over the bundles' values too where they share it
            drawn = await work.run(table_layers, data, name, o, data_dir=store.root, **layers.kwargs())
            report["values"]["scale"], report["layers"] = drawn["scale"], drawn["layers"]
        else:
            report["layers"] = [{"kind": "regions", "label": name, "opacity": 1.0,
                                 "scale": report["values"]["scale"]}]
        return report

    # -- preview -------------------------------------------------------------------------------
    @app.post("/api/preview", tags=["api"], responses={200: {"content": {"image/png": {}}}})
    async def preview(body: PreviewRequest, request: Request) -> Response:
        """One row from one view, small, rendered by the warm preview painter."""
        name, data = await run_in_threadpool(_upload, store, body.upload_id, owner_of(request))
        layers = await run_in_threadpool(layer_uploads, store, body.options, owner_of(request))
        req = await work.run(preview_request, data, name, body.options, body.row, body.view, config,
                             data_dir=store.root, **layers.kwargs())
        if previews.borrowed_tokens >= previews.total_tokens:  # never queue without bound
            raise ApiError(503, f"{MAX_PREVIEW_WAITING} previews are waiting; try again in a moment",
                           {"retry-after": "2"})
        try:
            png, ms = await anyio.to_thread.run_sync(pool.preview, req, limiter=previews)
        except PreviewBusy as exc:
            raise ApiError(503, str(exc), {"retry-after": "2"}) from None
        except PreviewUnavailable as exc:
            raise ApiError(503, str(exc), {"retry-after": "5"}) from None
        return Response(png, media_type="image/png", headers={"x-render-ms": str(ms)})


def _add_job_routes(app: FastAPI, config: ServerConfig, store: Store) -> None:
    """Jobs: submit, status, cancel, files."""
    work: Work = app.state.work

    @app.post("/api/jobs", tags=["api"], status_code=202)
    async def submit(body: JobRequest, request: Request) -> dict[str, Any]:
        """Queue a job: ``images`` (every row from every view, as PNGs plus a zip), ``figure`` (PDF/PNG),
        ``export`` (one row as an interactive 3D page, HTML)
        or ``movie`` (MP4/GIF)."""
        name, data = await run_in_threadpool(_upload, store, body.upload_id, owner_of(request))
        await disk_budget(store, config)
        layers = await run_in_threadpool(layer_uploads, store, body.options, owner_of(request))
        # the run, its limits and a PNG figure's layout, in a request process (killed past its time limit)
        total, _ = await work.run(job_plan, data, name, body.options, body.kind, body.figure, body.movie,
                                  body.export, max_images=config.max_images, max_pixels=config.max_pixels,
                                  max_figure_pixels=config.max_figure_pixels, data_dir=store.root,
                                  **layers.kwargs())
        params = body.figure.model_dump() if body.kind == "figure" else (
            body.movie.model_dump() if body.kind == "movie" else
            body.export.model_dump() if body.kind == "export" else {})
        if body.kind == "figure" and body.figure.format == "png":
            params["max_pixels"] = config.max_figure_pixels  # the worker checks the composed figure too
        try:
            job_id = await run_in_threadpool(
                store.submit, client_of(request), body.kind, body.options.model_dump(), params, name, data,
                total, max_per_client=config.max_jobs_per_client, max_queued=config.max_queued,
                extra=layers.files(), owner=owner_of(request))
        except LimitError as exc:
            raise ApiError(exc.status, str(exc), {"retry-after": str(exc.retry_after)}) from None
        return _public(await run_in_threadpool(store.get, job_id))

    @app.get("/api/jobs/{job_id}", tags=["api"])
    async def job_status(job_id: str, request: Request) -> dict[str, Any]:
        """Status, progress and files of a job."""
        return _public(await run_in_threadpool(_job, store, job_id, owner_of(request)))

    @app.delete("/api/jobs/{job_id}", tags=["api"])
    async def cancel(job_id: str, request: Request) -> dict[str, Any]:
        """Cancel a queued or running job."""
        await run_in_threadpool(_job, store, job_id, owner_of(request))
        await run_in_threadpool(store.cancel, job_id)
        return _public(await run_in_threadpool(_job, store, job_id, owner_of(request)))

    @app.get("/api/jobs/{job_id}/files/{file_name}", tags=["api"], response_model=None)
    async def job_file(job_id: str, file_name: str, request: Request, download: bool = False) -> Response:
        """One file the job made (only names listed in its ``files``)."""
        from brainpainter.web.job_zip import zip_name, zip_stream

        job = await run_in_threadpool(_job, store, job_id, owner_of(request))
        if file_name not in job["files"]:
            raise ApiError(404, f"job {job_id} has no file {file_name[:100]!r}; its files are listed in "
                                f"GET /api/jobs/{job_id}.")
        listed = job["files"][job["files"].index(file_name)]
        out = store.job_dir(job_id) / "out"
        path = out / listed
        disposition = "attachment" if download else "inline"
        if listed == zip_name(job_id) and not path.is_file():  # made while it is sent, never stored
            members = [f for f in job["files"] if f != listed]
            if not all((out / f).is_file() for f in members):
                raise ApiError(410, "the job's files have expired or were removed; render again.")
            return StreamingResponse(zip_stream(out, members), media_type="application/zip",
                                     headers={"content-disposition": f'{disposition}; filename="{listed}"'})
        if not path.is_file():
            raise ApiError(410, "the job's files have expired or were removed; render again.")
        return FileResponse(path, filename=file_name if download else None,
                            content_disposition_type=disposition)


# -- helpers ------------------------------------------------------------------------------------
def _version() -> str:
    from brainpainter import __version__
    return __version__


def _upload(store: Store, upload_id: str, owner: str) -> tuple[str, bytes]:
    got = store.get_upload(upload_id, owner) if valid_id(upload_id) else None
    if got is None:  # another client's upload too: its id tells nothing
        raise ApiError(404, "upload not found (it expired, the id is wrong, or another client made it: send "
                            "this client's cookie or X-BrainPainter-Client header); upload the table again.")
    return got


def _full(request: Request, exc: BaseException) -> JSONResponse:
    log.warning("disk full during %s %s: %s", request.method, request.url.path, one_line(exc))
    return JSONResponse({"error": "the server's disk is full; nothing was changed. Try again later (the "
                                  "operator must free space)."}, status_code=507,
                        headers={"retry-after": "600"})


def _job(store: Store, job_id: str, owner: str) -> dict[str, Any]:
    job = store.get(job_id, owner) if valid_id(job_id) else None
    if job is None:
        raise ApiError(404, "job not found (it expired, the id is wrong, or another client made it: send "
                            "this client's cookie or X-BrainPainter-Client header).")
    return job


def _public(job: dict[str, Any] | None) -> dict[str, Any]:
    assert job is not None
    base = f"/api/jobs/{job['id']}"
    return {
        "id": job["id"], "kind": job["kind"], "status": job["status"], "progress": job["progress"],
        "total": job["total"], "error": job["error"], "input": job["input_name"], "created": job["created"],
        "finished": job["finished"], "expires": job["expires"], "attempt": job["attempt"],
        "files": [{"name": f, "url": f"{base}/files/{f}"} for f in job["files"]], "url": base,
    }


def _meta(config: ServerConfig) -> dict[str, Any]:
    import matplotlib

    from brainpainter.atlas import registry
    from brainpainter.atlas.model import SPACES
    from brainpainter.rendering.painter import HIDE_GROUPS
    from brainpainter.rendering.settings import CORTEX_MODES
    from brainpainter.rendering.views import PRESETS
    from brainpainter.web.tracts import MAX_WEB_STREAMLINES

    return {
        "version": _version(),
        "atlases": registry.atlases.names(),
        "views": list(PRESETS),
        "cmaps": sorted(n for n in matplotlib.colormaps if not n.endswith("_r")),
        "hide_groups": list(HIDE_GROUPS),
        "defaults": RenderOptions().model_dump(),
        "limits": {"max_upload_mb": config.max_upload_mb, "max_images": config.max_images,
                   "max_pixels": config.max_pixels, "max_figure_pixels": config.max_figure_pixels,
                   "max_jobs_per_client": config.max_jobs_per_client,
                   "result_ttl_s": config.result_ttl_s, "job_time_limit_s": config.job_time_limit_s,
                   "max_map_images": config.max_map_images, "max_tract_files": config.max_tract_files,
                   "max_tract_streamlines": config.max_tract_streamlines,
                   "max_streamlines": MAX_WEB_STREAMLINES},
        "tract_spaces": list(SPACES), "cortex_modes": list(CORTEX_MODES),
        "renderer": config.renderer,
    }
