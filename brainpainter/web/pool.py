"""Start, watch and restart the rendering processes of a server.

:class:`Pool` owns the job workers (``config.workers`` processes taking jobs
from the store) and the preview process (one warm painter answering one
request at a time over a pipe). A monitor thread, once a second:

- restarts a dead worker and re-queues the job it held (or fails it when its
  worker died ``max_attempts`` times while running it; restarts of the server
  do not count);
- stops a job past ``job_time_limit_s`` (the worker is killed and restarted;
  the job fails with a one-line message);
- restarts a dead preview process;
- every 30 s deletes expired results and uploads.

At start-up every job still marked ``running`` belongs to a previous server's
workers: it is queued again with a new attempt number, so those workers can no
longer change it. Workers die with their server: Linux's parent-death signal
(``PR_SET_PDEATHSIG``) reaches them within milliseconds of a ``kill -9``, and
they also check their parent after every image and movie frame.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import threading
import time
from dataclasses import replace
from typing import Any

from brainpainter.web.config import ServerConfig
from brainpainter.web.folder_lock import lock_data_dir, unlock_data_dir
from brainpainter.web.store import Store

log = logging.getLogger("brainpainter.web")

MONITOR_S = 1.0
EXPIRE_EVERY_S = 30.0
PREVIEW_TIMEOUT_S = 120.0
MAX_PREVIEW_WAITING = 8


class PreviewBusy(Exception):
    """More preview requests wait than the server takes; the client should retry."""


class PreviewUnavailable(Exception):
    """The preview process is not running (starting, or restarting after a failure)."""


class Pool:
    """The rendering processes of one server.

    Parameters
    ----------
    config : ServerConfig
    store : Store
    """

    def __init__(self, config: ServerConfig, store: Store) -> None:
        self.config = config
        self.store = store
        self._ctx = mp.get_context("spawn")
        self._boot = f"{os.getpid()}-{int(time.time())}"
        self._workers: dict[int, tuple[str, Any]] = {}  # slot -> (name, process)
        self._spawned = 0
        self._stop = threading.Event()
        self._monitor: threading.Thread | None = None
        self._preview_lock = threading.Lock()
        self._preview_proc: Any = None
        self._preview_conn: Any = None
        self._preview_ready = False
        self._waiting = 0
        self._waiting_lock = threading.Lock()
        self._last_expire = 0.0
        self.restarts = 0

    # -- life ------------------------------------------------------------------------------
    def start(self) -> None:
        c = self.config
        lock_data_dir(self.store.root)
        self.store.keep_open()
        again = self.store.requeue(max_attempts=c.max_attempts, ttl_s=c.result_ttl_s)
        if again:
            log.info("re-queued %d job(s) left running by a previous server", len(again))
        self.store.forget_workers()
        self.store.expire()
        for slot in range(c.workers):
            self._spawn_worker(slot)
        if c.preview:
            self._spawn_preview()
        self._monitor = threading.Thread(target=self._watch, name="brainpainter-pool", daemon=True)
        self._monitor.start()

    def stop(self) -> None:
        self._stop.set()
        if self._monitor is not None:
            self._monitor.join(timeout=5)
        procs = [p for _, p in self._workers.values()] + ([self._preview_proc] if self._preview_proc else [])
        for p in procs:
            p.terminate()
        for p in procs:
            p.join(timeout=10)
            if p.is_alive():
                p.kill()
                p.join(timeout=5)
        # jobs the stopped workers held go back to the queue now (a restart would do it too)
        try:
            self.store.requeue(max_attempts=self.config.max_attempts, ttl_s=self.config.result_ttl_s)
        finally:
            self.store.close()
            unlock_data_dir(self.store.root)

    def _spawn_worker(self, slot: int) -> None:
        from brainpainter.web.worker import job_worker_main

        c = self.config
        self._spawned += 1
        name = f"w{slot}-{self._boot}-{self._spawned}"
        proc = self._ctx.Process(
            target=job_worker_main, name=f"brainpainter-{name}", daemon=True,
            args=(str(self.store.root), name, c.renderer, c.lp_threads(), c.result_ttl_s, c.job_time_limit_s),
            kwargs={"memory": c.worker_memory_bytes})
        proc.start()
        self._workers[slot] = (name, proc)

    def _spawn_preview(self) -> None:
        from brainpainter.web.worker import preview_main

        c = self.config
        parent_conn, child_conn = self._ctx.Pipe()
        proc = self._ctx.Process(target=preview_main, name="brainpainter-preview", daemon=True,
                                 args=(child_conn, c.renderer, c.lp_threads(),
                                       (c.preview_max_width, c.preview_max_width * 3 // 4)),
                                 kwargs={"memory": c.worker_memory_bytes})
        proc.start()
        child_conn.close()
        self._preview_proc, self._preview_conn, self._preview_ready = proc, parent_conn, False

    # -- monitor ---------------------------------------------------------------------------
    def _watch(self) -> None:
        while not self._stop.wait(MONITOR_S):
            try:
                self.check()
            except Exception:  # the monitor must outlive any one failure
                log.exception("pool monitor")

    def check(self) -> None:
        """One round of the monitor (also callable from tests)."""
        c = self.config
        for slot, (name, proc) in list(self._workers.items()):
            if not proc.is_alive():
                proc.join(timeout=1)
                again = self.store.requeue(worker=name, max_attempts=c.max_attempts, ttl_s=c.result_ttl_s)
                log.warning("worker %s exited (code %s); re-queued %s", name, proc.exitcode, again)
                self.restarts += 1
                self._spawn_worker(slot)
        by_name = dict(self._workers.values())
        for job in self.store.overdue(c.job_time_limit_s + 30):
            proc = by_name.get(job["worker"] or "")
            msg = (f"the job ran longer than this server's limit of {c.job_time_limit_s:g} s; choose fewer "
                   "rows or views, or a smaller size.")
            if self.store.fail(job["id"], job["attempt"], msg, c.result_ttl_s) and proc is not None:
                proc.kill()  # a stuck renderer: the next round restarts the worker
        if c.preview:
            with self._preview_lock:
                if self._preview_proc is not None and not self._preview_proc.is_alive():
                    log.warning("preview process exited (code %s); restarting", self._preview_proc.exitcode)
                    self._spawn_preview()
                self._poll_ready(0)
        if time.time() - self._last_expire > EXPIRE_EVERY_S:
            self._last_expire = time.time()
            n = self.store.expire()
            if n:
                log.info("deleted %d expired job(s)/upload(s)", n)

    # -- state -----------------------------------------------------------------------------
    def alive_workers(self) -> int:
        return sum(p.is_alive() for _, p in self._workers.values())

    @property
    def preview_ready(self) -> bool:
        return self._preview_ready and self._preview_proc is not None and self._preview_proc.is_alive()

    def _poll_ready(self, timeout: float) -> bool:
        """Under the preview lock: read the process's "ready" message when it has come."""
        if not self._preview_ready and self._preview_conn is not None:
            try:
                if self._preview_conn.poll(timeout):
                    status, _, _ = self._preview_conn.recv()
                    self._preview_ready = status == "ready"
            except (EOFError, OSError):
                pass
        return self._preview_ready

    # -- preview ---------------------------------------------------------------------------
    def preview(self, request: dict[str, Any]) -> tuple[bytes, int]:
        """Render one preview: ``(png bytes, render milliseconds)``.

        Raises
        ------
        PreviewBusy
            Too many previews wait already.
        PreviewUnavailable
            No preview process (disabled, starting too long, or it failed and is restarting).
        brainpainter.errors.BrainPainterError
            The renderer's one-line error.
        """
        from brainpainter.errors import BrainPainterError

        if not self.config.preview:
            raise PreviewUnavailable("this server runs without the preview process (--no-preview)")
        with self._waiting_lock:
            if self._waiting >= MAX_PREVIEW_WAITING:
                raise PreviewBusy(f"{self._waiting} previews are waiting; try again in a moment")
            self._waiting += 1
        try:
            with self._preview_lock:
                if not self._poll_ready(PREVIEW_TIMEOUT_S):
                    raise PreviewUnavailable("the preview renderer is still starting; try again shortly")
                conn = self._preview_conn
                try:
                    conn.send(request)
                    if not conn.poll(PREVIEW_TIMEOUT_S):
                        raise TimeoutError
                    status, payload, ms = conn.recv()
                except (EOFError, OSError, TimeoutError, BrokenPipeError):
                    # the monitor thread starts a new one: processes are started only by long-lived
                    # threads (a process's death signal fires when the thread that started it ends)
                    self._preview_proc.kill()
                    self._preview_proc.join(timeout=5)
                    self._preview_ready = False
                    raise PreviewUnavailable("the preview renderer stopped and is restarting; try again "
                                             "in a few seconds") from None
        finally:
            with self._waiting_lock:
                self._waiting -= 1
        if status != "ok":
            raise BrainPainterError(payload)
        return payload, ms


def preview_settings(settings: Any, max_width: int) -> Any:
    """`settings` scaled down to at most `max_width` pixels wide (same aspect), path tracing off."""
    w, h = settings.width, settings.height
    if w > max_width:
        w, h = max_width, max(16, round(h * max_width / w))
    return replace(settings, width=w, height=h, quality="default" if settings.quality == "high" else
                   settings.quality)


def preview_request(data: bytes, name: str, options: Any, row: int | str, view: str, config: ServerConfig,
                    tracts: bytes | None = None, data_dir: Any = None,
                    map_upload: bytes | None = None, contour_upload: bytes | None = None,
                    connectome_upload: bytes | None = None) -> dict[str, Any]:
    """The preview process's request for `row` (index or image name) of an upload from `view`.

    `options` is a :class:`brainpainter.web.options.RenderOptions`; a map's colours are per vertex
    (``coloring`` ``"vertices"``); `tracts` is the tract upload option ``tracts`` names (its spec, nodes
    and radius go with the request: the preview painter's scene); `map_upload` and `contour_upload` the
    maps options ``map`` (drawn over the table's regions) and ``contour`` name, `connectome_upload` the
    connectome option ``connectome`` names. Raises the CLI's one-line
    errors.
    """
    import re

    from brainpainter.errors import BrainPainterError
    from brainpainter.rendering.views import parse_views
    from brainpainter.web.options import prepare

    views = parse_views(view)
    if views[0].content == "flat":  # a map's run colours the flat maps' vertices when it draws a flat view
        options = options.model_copy(update={"views": views[0].name})
    prep = prepare(data, name, options, max_pixels=config.max_pixels, tracts=tracts,
                   data_dir=data_dir, map_upload=map_upload, contour_upload=contour_upload,
                   connectome_upload=connectome_upload)
    table = prep.run.table
    if isinstance(row, int) or re.fullmatch(r"[0-9]{1,9}", row):
        i = int(row)
        if not 0 <= i < len(table.images):
            raise BrainPainterError(f"row must be 0..{len(table.images) - 1}; {row} was given.")
    elif row in table.images:
        i = table.images.index(row)
    else:
        raise BrainPainterError(f"row {str(row)[:100]!r} is not an image of the table; it has "
                                f"{list(table.images[:5])}{'...' if len(table.images) > 5 else ''}.")
    colors = prep.run.colors(i)  # every layer's, as render colours them
    return {"atlas": table.atlas.name, "surface": options.surface, "hidden": prep.hidden,
            "settings": preview_settings(prep.run.settings, config.preview_max_width),
            "colors": colors, "view": views[0], "coloring": prep.coloring, **prep.painter_args()}
