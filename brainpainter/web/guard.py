"""The server's guard: security headers, body size limits, a rate limit, client tokens and the access log.

:class:`Guard` is pure ASGI middleware around the app (:mod:`brainpainter.web.app`);
every response carries a strict Content-Security-Policy and every request is
logged as one JSON line on the ``brainpainter.web.access`` logger.

Uploads and jobs belong to the client that made them. A client is known by a
token: the cookie :data:`TOKEN_COOKIE` (issued on the first request without
one: ``HttpOnly; SameSite=Strict``) or the header :data:`TOKEN_HEADER` (a
script's own random token). Routes see only its hash (``brainpainter.web.http.owner_of``),
and the database keeps only the hash (:func:`owner_key`), so reading it gives no token away.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
import secrets
import threading
import time
from typing import Any

import anyio
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import Message, Receive, Scope, Send

from brainpainter.web.config import ServerConfig

access_log = logging.getLogger("brainpainter.web.access")
log = logging.getLogger(__name__)

CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; "
       "media-src 'self'; connect-src 'self'; font-src 'self'; form-action 'none'; base-uri 'none'; "
       "frame-ancestors 'none'")
SECURITY_HEADERS = [
    (b"content-security-policy", CSP.encode()),
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
    (b"cross-origin-opener-policy", b"same-origin"),
    (b"cross-origin-resource-policy", b"same-origin"),
]
JSON_BODY_LIMIT = 64 * 1024
JSON_BODY_TIME_LIMIT_S = 30.0
#: Requests whose body is an upload (the upload size and time limits, and upload slots, apply).
UPLOAD_PATHS = ("/api/uploads", "/api/tracts", "/api/connectomes")
MAX_UPLOADS_IN_FLIGHT = 64  # uploads being received from all clients together
UPLOAD_SLOT_WAIT_S = 5.0  # an upload beyond a client's slots waits this long for one, then gets 429
STATE_CHANGING = ("POST", "PUT", "DELETE", "PATCH")
TOKEN_COOKIE = "bp_client"
TOKEN_HEADER = "x-brainpainter-client"
TOKEN_MAX_AGE_S = 30 * 24 * 3600
_TOKEN = re.compile(r"[0-9A-Za-z_-]{32,128}")


def client_token(headers: dict[bytes, bytes]) -> str | None:
    """The client's token from its :data:`TOKEN_HEADER` header or :data:`TOKEN_COOKIE` cookie (the header
    first), or None when it sent none of the right form (32 to 128 letters, digits, ``-`` or ``_``)."""
    from starlette.requests import cookie_parser

    given = headers.get(TOKEN_HEADER.encode(), b"").decode("latin-1").strip()
    if not given:
        given = cookie_parser(headers.get(b"cookie", b"").decode("latin-1")).get(TOKEN_COOKIE, "")
    return given if _TOKEN.fullmatch(given) else None


def owner_key(token: str) -> str:
    """What the server keeps of a token: 32 hex digits of its SHA-256."""
    return hashlib.sha256(token.encode()).hexdigest()[:32]


class _TooLarge(StarletteHTTPException):
    """A request body over its limit (raised while it is read: the app answers 413 with the message)."""

    def __init__(self, what: str, limit: int) -> None:
        hint = ("Split the table or remove unneeded columns." if what == "upload" else
                "Send the table as an upload (POST /api/uploads) and refer to it by its upload_id.")
        mb = f"{limit / 2**20:.3g} MB"
        super().__init__(413, f"the {what} is larger than this server's limit; at most {mb} is read, to keep "
                              f"memory bounded. {hint}")


class _TooSlow(StarletteHTTPException):
    """A request body not received within its deadline (408)."""

    def __init__(self, what: str, seconds: float) -> None:
        super().__init__(408, f"the {what} was not received within {seconds:g} s; send it again (on a slow "
                              "connection, a smaller file).")


class RateLimiter:
    """Token bucket per client: `per_minute` state-changing requests a minute, bursts up to a quarter."""

    def __init__(self, per_minute: int) -> None:
        self.rate = per_minute / 60.0
        self.burst = max(5.0, per_minute / 4)
        self._buckets: dict[str, tuple[float, float]] = {}
        self._lock = threading.Lock()

    def allow(self, client: str) -> float:
        """0 when allowed; else the seconds to wait."""
        now = time.monotonic()
        with self._lock:
            if len(self._buckets) > 10_000:  # keep memory bounded: forget full buckets
                self._buckets = {k: v for k, v in self._buckets.items()
                                 if (now - v[1]) * self.rate + v[0] < self.burst}
            tokens, last = self._buckets.get(client, (self.burst, now))
            tokens = min(self.burst, tokens + (now - last) * self.rate)
            if tokens < 1.0:
                self._buckets[client] = (tokens, now)
                return (1.0 - tokens) / self.rate
            self._buckets[client] = (tokens - 1.0, now)
            return 0.0


class Guard:
    """Pure ASGI middleware: security headers, body size limits, rate limit, access log."""

    def __init__(self, app: Any, config: ServerConfig) -> None:
        self.app = app
        self.config = config
        self.limiter = RateLimiter(config.rate_per_minute)
        self._uploading: dict[str, int] = {}  # client -> uploads being received (event loop only)
        self._slot_freed: anyio.Event | None = None  # made in the event loop

    async def _upload_slot(self, client: str) -> bool:
        """Take one of `client`'s upload slots, waiting up to :data:`UPLOAD_SLOT_WAIT_S` for one (a
        waiting request's body is not read: it costs a socket, not memory); False when none came."""
        end = time.monotonic() + UPLOAD_SLOT_WAIT_S
        while True:
            mine = self._uploading.get(client, 0)
            if mine < self.config.max_uploads_in_flight and sum(self._uploading.values()) < \
                    MAX_UPLOADS_IN_FLIGHT:
                self._uploading[client] = mine + 1
                return True
            left = end - time.monotonic()
            if left <= 0:
                return False
            if self._slot_freed is None or self._slot_freed.is_set():
                self._slot_freed = anyio.Event()
            with anyio.move_on_after(left):
                await self._slot_freed.wait()

    def _release_slot(self, client: str) -> None:
        left = self._uploading.pop(client, 1) - 1
        if left > 0:
            self._uploading[client] = left
        if self._slot_freed is not None:
            self._slot_freed.set()

    async def _refusal(self, method: str, path: str, client: str,
                       headers: dict[bytes, bytes]) -> tuple[int, str, dict[str, str]] | None:
        """``(status, message, headers)`` when the request is refused before it is read; else None (an
        upload then holds one of its client's upload slots)."""
        if method not in STATE_CHANGING:
            return None
        if headers.get(b"sec-fetch-site") == b"cross-site":
            return 403, ("requests from other web sites are refused; use this server's own page or a "
                         "script."), {}
        if path.startswith("/api/"):
            wait = self.limiter.allow(client)
            if wait:
                return (429, f"too many requests from {client}; at most {self.config.rate_per_minute} a "
                             f"minute. Retry in {wait:.0f} s.", {"retry-after": str(max(1, round(wait)))})
        if path in UPLOAD_PATHS and method == "POST" and not await self._upload_slot(client):
            mine = self._uploading.get(client, 0)
            busy = (f"{mine} upload(s) from {client} are still being received; wait for them to finish, then "
                    "upload again." if mine >= self.config.max_uploads_in_flight else
                    "the server is receiving as many uploads as it takes at once; upload again in a few "
                    "seconds.")
            return 429, busy, {"retry-after": "5"}
        return None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        t0 = time.perf_counter()
        rid = secrets.token_hex(6)
        client = (scope.get("client") or ("-", 0))[0]
        method, path = scope["method"], scope["path"]
        is_upload = path in UPLOAD_PATHS
        limit = self.config.max_upload_bytes if is_upload else JSON_BODY_LIMIT
        what = "upload" if is_upload else "request body"
        seconds = self.config.upload_time_limit_s if is_upload else JSON_BODY_TIME_LIMIT_S
        deadline = time.monotonic() + seconds
        body_done = method not in STATE_CHANGING
        state = {"status": 0, "bytes": 0, "started": False}
        cookie = _own(scope)

        async def send_wrapper(message: Message) -> None:
            if message["type"] == "http.response.start":
                state["status"], state["started"] = message["status"], True
                headers = [h for h in message.get("headers", []) if h[0].lower() != b"server"]
                headers += [*SECURITY_HEADERS, (b"x-request-id", rid.encode())]
                if cookie is not None:
                    headers.append((b"set-cookie", cookie))
                if path.startswith("/api/"):
                    headers.append((b"cache-control", b"no-store"))
                message = {**message, "headers": headers}
            elif message["type"] == "http.response.body":
                state["bytes"] += len(message.get("body", b""))
            await send(message)

        received = 0

        async def receive_wrapper() -> Message:
            nonlocal received, body_done
            if body_done:  # e.g. waiting for a disconnect while a file streams out: no deadline
                return await receive()
            try:
                with anyio.fail_after(max(0.0, deadline - time.monotonic())):
                    message = await receive()
            except TimeoutError:
                raise _TooSlow(what, seconds) from None
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    raise _TooLarge(what, limit)
                body_done = not message.get("more_body", False)
                if body_done:
                    release()  # the slot is for receiving; reading the table is bounded elsewhere
            return message

        counted = False

        def release() -> None:
            nonlocal counted
            if counted:
                counted = False
                self._release_slot(client)

        try:
            headers = dict(scope.get("headers", []))
            length = headers.get(b"content-length")
            if length is not None and length.isdigit() and int(length) > limit:
                raise _TooLarge(what, limit)
            refusal = await self._refusal(method, path, client, headers)
            if refusal is not None:
                await _send_json(send_wrapper, refusal[0], {"error": refusal[1]}, refusal[2])
                return
            counted = is_upload and method == "POST"  # _refusal took an upload slot
            await self.app(scope, receive_wrapper, send_wrapper)
        except (_TooLarge, _TooSlow) as exc:
            if not state["started"]:
                await _send_json(send_wrapper, exc.status_code, {"error": exc.detail})
        except Exception as exc:  # an error no handler answered: 500 here, with the headers, logged as 500
            if state["started"]:  # a body half sent: nothing more can be said to the client
                raise
            await _internal_error(send_wrapper, method, path, exc)
        finally:
            release()
            _log_access(rid, client, method, path, state, t0, received)


def _own(scope: Scope) -> bytes | None:
    """Put the owner key of the request's client token in ``scope["state"]``; when the request has no
    token, make one: the ``Set-Cookie`` value that gives it to the client is returned."""
    token = client_token(dict(scope.get("headers", [])))
    cookie = None
    if token is None:
        token = secrets.token_hex(16)
        secure = "; Secure" if scope.get("scheme") == "https" else ""
        cookie = (f"{TOKEN_COOKIE}={token}; Path=/; Max-Age={TOKEN_MAX_AGE_S}; HttpOnly; "
                  f"SameSite=Strict{secure}").encode()
    scope.setdefault("state", {})["owner"] = owner_key(token)
    return cookie


def _log_access(rid: str, client: str, method: str, path: str, state: dict[str, Any], t0: float,
                received: int) -> None:
    """The request's one JSON line on the access log (its status as sent)."""
    access_log.info(json.dumps({
        "t": round(time.time(), 3), "id": rid, "client": client, "method": method, "path": path,
        "status": state["status"], "ms": round((time.perf_counter() - t0) * 1000, 1),
        "bytes_in": received, "bytes_out": state["bytes"]}))


async def _internal_error(send: Send, method: str, path: str, exc: Exception) -> None:
    """Log an error no route handled (with its traceback) and answer 500 with one line."""
    log.error("internal error on %s %s", method, path, exc_info=exc)
    await _send_json(send, 500, {"error": f"internal error: {type(exc).__name__} (logged on the server)"})


async def _send_json(send: Send, status: int, body: dict[str, Any],
                     headers: dict[str, str] | None = None) -> None:
    raw = json.dumps(body).encode()
    hdrs = [(b"content-type", b"application/json"), (b"content-length", str(len(raw)).encode())]
    hdrs += [(k.encode(), v.encode()) for k, v in (headers or {}).items()]
    await send({"type": "http.response.start", "status": status, "headers": hdrs})
    await send({"type": "http.response.body", "body": raw})
