"""What the routes of the web API share: their error, the work threads, who the client is, the disk budget,
receiving an upload's body, a request that does not fit the schema as one line."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any, TypeVar

import anyio
import anyio.to_thread
from starlette.concurrency import run_in_threadpool

if TYPE_CHECKING:
    from pathlib import Path

    from fastapi import Request
    from fastapi.exceptions import RequestValidationError

    from brainpainter.web.config import ServerConfig
    from brainpainter.web.store import Store
    from brainpainter.web.work_processes import WorkProcesses

T = TypeVar("T")
#: Most characters of one string, and entries of one list, a check report echoes (names of nodes, labels,
#: images): a report of an upload's own text stays bounded whatever the names (5000: the image names a
#: tract upload's report lists).
MAX_ECHO_CHARS = 200
MAX_ECHO_ITEMS = 5000


class Work:
    """Work that grows with the upload (reading it into a run, checking options), apart from the threads
    that answer status reads: at most `threads` run and `max_waiting` wait; more get 503 at once.

    :meth:`run` runs a call in one of `processes` (:class:`~brainpainter.web.work_processes.WorkProcesses`:
    killed past their time limit), or on a thread without them; :meth:`run_thread` on a thread (receiving
    an upload, whose readers bound their own work in processes of their own).
    """

    def __init__(self, threads: int, max_waiting: int, processes: WorkProcesses | None = None) -> None:
        self.limiter = anyio.CapacityLimiter(max(1, threads))
        self.max_waiting = max_waiting
        self.pending = 0
        self.processes = processes

    def _admit(self) -> None:
        if self.pending >= self.limiter.total_tokens + self.max_waiting:
            raise ApiError(503, f"the server is reading {self.pending} tables already; try again in a few "
                                "seconds.", {"retry-after": "5"})

    async def run(self, func: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        if self.processes is None:
            return await self.run_thread(func, *args, **kwargs)
        self._admit()
        self.pending += 1
        try:
            result: T = await asyncio.wrap_future(self.processes.submit(func, *args, **kwargs))
            return result
        finally:
            self.pending -= 1

    async def run_thread(self, func: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        self._admit()
        self.pending += 1
        try:
            return await anyio.to_thread.run_sync(partial(func, *args, **kwargs), limiter=self.limiter)
        finally:
            self.pending -= 1


class ApiError(Exception):
    """An answer other than 200: `status`, a one-line message and headers (``{"error": message}``)."""

    def __init__(self, status: int, message: str, headers: dict[str, str] | None = None) -> None:
        super().__init__(message)
        self.status, self.headers = status, headers or {}


def one_line(exc: BaseException) -> str:
    """The first line of an error's message (its type's name when it has none)."""
    text = str(exc)
    return text.splitlines()[0] if text else type(exc).__name__


def client_of(request: Request) -> str:
    """The client's address (the connection's, or the proxy's X-Forwarded-For where trusted): what the
    per-client limits count by."""
    return request.client.host if request.client else "-"


def owner_of(request: Request) -> str:
    """Who owns what the request makes, and may see it: the key of the client's token
    (:mod:`brainpainter.web.guard` puts it in the request's state)."""
    owner: str = request.state.owner
    return owner


async def disk_budget(store: Store, config: ServerConfig) -> None:
    """507 when the data folder uses its ``--max-disk-gb`` budget."""
    if config.max_disk_bytes <= 0:
        return
    used = await run_in_threadpool(store.disk_usage)
    if used >= config.max_disk_bytes:
        raise ApiError(507, f"this server's storage budget ({config.max_disk_gb:g} GB) is used up; try "
                            "again after older results expire.", {"retry-after": "600"})


def require_octet_stream(request: Request, what: str) -> None:
    """415 unless the body comes as ``application/octet-stream`` (`what`: "the table", "the files")."""
    from brainpainter.web.upload import content_type_allowed

    if not content_type_allowed(request.headers.get("content-type")):
        raise ApiError(415, f"send {what} as the request body with 'Content-Type: "
                            "application/octet-stream' (form and text/plain bodies are refused, so that "
                            "other web sites cannot upload into this server).")


async def receive_body(request: Request, root: Path) -> tuple[Path, int]:
    """The request body streamed into a new file of ``root/incoming``, and its size in bytes.

    The caller removes the file; if the body breaks off, it is removed here.
    """
    from brainpainter.web.upload import new_incoming

    fh, path = await run_in_threadpool(new_incoming, root)
    size = 0
    try:
        with fh:
            async for chunk in request.stream():
                size += len(chunk)
                fh.write(chunk)
    except BaseException:
        path.unlink(missing_ok=True)
        raise
    return path, size


async def keep_upload(request: Request, store: Store, config: ServerConfig, work: Work, shown: str,
                      read: Callable[..., tuple[bytes, Any]], *args: Any,
                      **kwargs: Any) -> tuple[str, int, Any]:
    """Receive the body, read it on a work thread and keep what was read as the client's upload.

    ``read(path, *args, **kwargs)`` returns ``(data, report)``: the bytes kept and what the answer
    reports. The body's file is removed whatever happens.

    Returns
    -------
    upload_id : str
    size : int
        The body's bytes.
    report : object
        What `read` reported.
    """
    path, size = await receive_body(request, store.root)
    try:
        data, report = await work.run_thread(read, path, *args, **kwargs)
    finally:
        path.unlink(missing_ok=True)
    upload_id = await run_in_threadpool(store.add_upload, client_of(request), shown, data,
                                        config.result_ttl_s, config.max_uploads_per_client,
                                        owner=owner_of(request))
    return upload_id, size, report


def validation_line(exc: RequestValidationError) -> str:
    """A request that does not fit the API's schema, as one line: the first problem, and how many more."""
    errors = exc.errors()
    if not errors:
        return "the request is not valid JSON of the expected form."
    e = errors[0]
    loc = ".".join(str(p) for p in e.get("loc", ()) if p not in ("body", "query"))
    given = e.get("input")
    shown = "" if isinstance(given, dict | list) or given is None else f"; {str(given)[:80]!r} was given"
    more = f" ({len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
    return f"option {loc or 'body'!r}: {e.get('msg', 'invalid')}{shown}.{more}"


def bounded(value: Any) -> Any:
    """`value` (a report: dicts, lists, strings, numbers) with each string cut to :data:`MAX_ECHO_CHARS`
    characters (ending with an ellipsis) and each list to :data:`MAX_ECHO_ITEMS` entries (then a last
    entry saying how many more there were)."""
    if isinstance(value, str):
        return value if len(value) <= MAX_ECHO_CHARS else value[:MAX_ECHO_CHARS - 1] + "\u2026"
    if isinstance(value, dict):
        return {bounded(k): bounded(v) for k, v in list(value.items())[:MAX_ECHO_ITEMS * 4]}
    if isinstance(value, list | tuple):
        kept = [bounded(v) for v in value[:MAX_ECHO_ITEMS]]
        return kept + ([f"\u2026 {len(value) - MAX_ECHO_ITEMS} more"] if len(value) > MAX_ECHO_ITEMS else [])
    return value
