"""Running the app on uvicorn: connection limits, timeouts, client identity and a quiet log.

:func:`run` is what ``brainpainter serve`` calls. Against slow or idle clients
(each one holds a socket, a file descriptor): a connection must send its
request headers within :data:`HEADER_TIMEOUT_S` (:class:`TimedH11Protocol`),
idle keep-alive connections close after :data:`KEEP_ALIVE_S`, and beyond
``max_connections`` open connections new requests get 503. Request bodies have
their own deadline (:class:`brainpainter.web.guard.Guard`). ``X-Forwarded-For``
is trusted only from the addresses given with ``--forwarded-allow-ips``: by
default the client is the address of the TCP connection, so no local process
can claim to be another client. Repeated log lines (the same message over and
over during a flood) are kept to a few a minute (:class:`RepeatFilter`).
"""

from __future__ import annotations

import asyncio
import logging
import os
import socket
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

from uvicorn.protocols.http.h11_impl import H11Protocol

HEADER_TIMEOUT_S = 10.0
KEEP_ALIVE_S = 5.0
GRACEFUL_SHUTDOWN_S = 5.0


class TimedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol that closes a connection whose request headers do not arrive in time
    (new connections, and keep-alive connections between requests)."""

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._header_timer: asyncio.TimerHandle | None = None
        self._arm(None)

    def _arm(self, cycle: Any) -> None:
        if self._header_timer is not None:
            self._header_timer.cancel()
        self._header_timer = self.loop.call_later(HEADER_TIMEOUT_S, self._headers_late, cycle)

    def _headers_late(self, cycle: Any) -> None:
        """No request began since the timer was armed: close the connection."""
        if self.cycle is cycle and not self.transport.is_closing():
            self.transport.close()

    def on_response_complete(self) -> None:
        cycle = self.cycle
        super().on_response_complete()
        if not self.transport.is_closing():
            self._arm(cycle)  # a pipelined request that began inside super() is not `cycle`

    def connection_lost(self, exc: Exception | None) -> None:
        if self._header_timer is not None:
            self._header_timer.cancel()
        super().connection_lost(exc)


class RepeatFilter(logging.Filter):
    """Let each distinct message (logger, level, text template) through at most `per_minute` times a
    minute; then one line says how many were dropped."""

    def __init__(self, per_minute: int = 5) -> None:
        super().__init__()
        self.per_minute = per_minute
        self._seen: dict[tuple[str, int, str], tuple[float, int, int]] = {}  # key -> (start, n, dropped)
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        key = (record.name, record.levelno, f"{record.msg}|{type(exc).__name__ if exc else ''}")
        now = time.monotonic()
        with self._lock:
            if len(self._seen) > 1000:
                self._seen.clear()
            start, n, dropped = self._seen.get(key, (now, 0, 0))
            if now - start >= 60.0:
                if dropped:
                    record.msg = f"{record.msg} [{dropped} more like this in the last minute not logged]"
                start, n, dropped = now, 0, 0
            if n >= self.per_minute:
                self._seen[key] = (start, n, dropped + 1)
                return False
            self._seen[key] = (start, n + 1, dropped)
        return True


def quiet_repeats(filter_: RepeatFilter | None = None) -> RepeatFilter:
    """Put a :class:`RepeatFilter` on the handlers of the server's loggers (uvicorn's, asyncio's and
    brainpainter.web's)."""
    filter_ = filter_ or RepeatFilter()
    for name in ("", "uvicorn", "uvicorn.error", "asyncio", "brainpainter.web"):
        for handler in logging.getLogger(name).handlers:
            if filter_ not in handler.filters:
                handler.addFilter(filter_)
    return filter_


def raise_open_files_limit() -> int:
    """Raise this process's soft limit on open files to its hard limit (at most 65536); returns it."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return 0
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    want = 65536 if hard == resource.RLIM_INFINITY else min(hard, 65536)
    if soft != resource.RLIM_INFINITY and soft < want:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))
            soft = want
        except (ValueError, OSError):
            pass
    return int(soft)


def run(app: Any, *, host: str, port: int, log_level: str, max_connections: int,
        forwarded_allow_ips: str | None, on_listening: Callable[[], None] | None = None) -> None:
    """Serve `app` with uvicorn until SIGINT/SIGTERM; `on_listening` is called once the socket listens."""
    import uvicorn

    class Server(uvicorn.Server):
        async def startup(self, sockets: list[socket.socket] | None = None) -> None:
            await super().startup(sockets)
            if self.started and on_listening is not None:
                on_listening()

    files = raise_open_files_limit()
    limit = max(1, min(max_connections, files // 2)) if files else max_connections
    config = uvicorn.Config(
        app, host=host, port=port, access_log=False, log_level=log_level, server_header=False,
        http=TimedH11Protocol, timeout_keep_alive=int(KEEP_ALIVE_S), limit_concurrency=limit,
        timeout_graceful_shutdown=int(GRACEFUL_SHUTDOWN_S),
        proxy_headers=forwarded_allow_ips is not None, forwarded_allow_ips=forwarded_allow_ips,
    )
    server = Server(config)
    config.load()  # configures uvicorn's loggers, so their handlers exist for the filter
    quiet_repeats()
    server.run()
    # Stopped (SIGINT/SIGTERM: connections closed, the app's lifespan ended, its processes stopped). Leave
    # now: Python would wait for every thread at exit, and a thread can be busy (an upload waiting for its
    # reading process) for as long as its limit.
    if server.started:
        logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        os._exit(0)
