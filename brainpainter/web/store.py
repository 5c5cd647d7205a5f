"""Uploads and jobs in SQLite (stdlib ``sqlite3``, WAL) with their files under the data folder.

Layout of the data folder::

    jobs.sqlite3            uploads, jobs, job events, workers
    uploads/<id>.bin        an uploaded table, as sent
    jobs/<id>/input.bin     the job's table (a copy: the job does not depend on the upload)
    jobs/<id>/tracts.bin    the tract upload its options name, if any (a copy too)
    incoming/tracts-<sha>/  a tract upload's files, written for the painters (deleted unused after an hour)
    jobs/<id>/out/          what the job made

Ids are 32 random hex digits (:func:`secrets.token_hex`); they are the only
names that become paths, and only after :func:`valid_id` has checked them.
Every upload and job has an ``owner`` (the key of the token of the client that
made it: :mod:`brainpainter.web.guard`); asked with another owner, the store
answers as if the id did not exist. ``client`` (an address) is what the
per-client limits count by.

A job's life: ``queued`` -> ``running`` (claimed by one worker with a new
``attempt`` number) -> ``done`` | ``failed`` | ``cancelled``; later
``expired`` (files deleted). Every change a worker makes names the attempt it
claimed, so a worker that was given up on (dead, or its server restarted)
can no longer change the job: a job is finished at most once, and a job that
was running when the server stopped is queued again (``attempt`` + 1).
"""

from __future__ import annotations

import json
import os
import re
import secrets
import shutil
import sqlite3
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from brainpainter.io.output import atomic_write_bytes
from brainpainter.web.disk import DiskBudget

_ID = re.compile(r"[0-9a-f]{32}")
ACTIVE = ("queued", "running")
ORPHAN_GRACE_S = 3600.0  # a file without a database row is deleted when older than this
FORGET_AFTER_S = 30 * 24 * 3600.0  # an expired job's row is kept this long (its id then answers 404)

SCHEMA = """
CREATE TABLE IF NOT EXISTS uploads (
    id TEXT PRIMARY KEY, client TEXT NOT NULL, name TEXT NOT NULL, size INTEGER NOT NULL,
    created REAL NOT NULL, expires REAL NOT NULL, owner TEXT NOT NULL DEFAULT ''
);
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY, client TEXT NOT NULL, kind TEXT NOT NULL, status TEXT NOT NULL,
    options TEXT NOT NULL, params TEXT NOT NULL, input_name TEXT NOT NULL,
    created REAL NOT NULL, started REAL, finished REAL, expires REAL,
    progress INTEGER NOT NULL DEFAULT 0, total INTEGER NOT NULL DEFAULT 0,
    attempt INTEGER NOT NULL DEFAULT 0, worker TEXT, heartbeat REAL,
    error TEXT, files TEXT NOT NULL DEFAULT '[]', completions INTEGER NOT NULL DEFAULT 0,
    deaths INTEGER NOT NULL DEFAULT 0, owner TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS jobs_status ON jobs (status, created);
CREATE INDEX IF NOT EXISTS jobs_client ON jobs (client, status);
CREATE TABLE IF NOT EXISTS events (
    job_id TEXT NOT NULL, attempt INTEGER NOT NULL, event TEXT NOT NULL, worker TEXT, detail TEXT,
    t REAL NOT NULL
);
CREATE INDEX IF NOT EXISTS events_job ON events (job_id);
CREATE TABLE IF NOT EXISTS workers (
    name TEXT PRIMARY KEY, pid INTEGER, state TEXT NOT NULL, heartbeat REAL NOT NULL
);
"""


class LimitError(Exception):
    """A submission refused by a limit; `status` is the HTTP status (429 or 503)."""

    def __init__(self, message: str, status: int, retry_after: int = 10) -> None:
        super().__init__(message)
        self.status = status
        self.retry_after = retry_after


def new_id() -> str:
    """An unguessable id: 128 random bits as 32 hex digits."""
    return secrets.token_hex(16)


def valid_id(text: str) -> bool:
    """True when `text` is an id this store could have made (so it is safe as a path part)."""
    return isinstance(text, str) and _ID.fullmatch(text) is not None


class Store:
    """The server's persistent state (one object per process; connections are per thread/call).

    Parameters
    ----------
    data_dir : path
        Created if needed.
    max_disk_bytes : int
        Disk the data folder may use (0: no budget); an upload or a job's input that would write past
        it is refused (:class:`LimitError`, 507) before a byte is written.
    """

    def __init__(self, data_dir: str | Path, max_disk_bytes: int = 0) -> None:
        from brainpainter.errors import BrainPainterError

        self.root = Path(data_dir)
        self.max_disk_bytes = max_disk_bytes
        for folder in (self.root, self.root / "uploads", self.root / "jobs"):
            folder.mkdir(mode=0o700, parents=True, exist_ok=True)
            _private(folder)  # uploaded tables are readable by this user only
        self.path = self.root / "jobs.sqlite3"
        self.budget = DiskBudget(self.root, max_disk_bytes)
        self._keeper: sqlite3.Connection | None = None
        try:
            with self.connect() as db:
                db.execute("PRAGMA journal_mode=WAL")
                db.executescript(SCHEMA)
                columns = {r["name"] for r in db.execute("PRAGMA table_info(jobs)")}
                if "deaths" not in columns:  # a database of an earlier version
                    db.execute("ALTER TABLE jobs ADD COLUMN deaths INTEGER NOT NULL DEFAULT 0")
                for table in ("jobs", "uploads"):  # before owners: the old rows belong to nobody
                    if "owner" not in {r["name"] for r in db.execute(f"PRAGMA table_info({table})")}:
                        db.execute(f"ALTER TABLE {table} ADD COLUMN owner TEXT NOT NULL DEFAULT ''")
                db.execute("SELECT count(*) FROM jobs").fetchone()
        except sqlite3.DatabaseError as exc:
            raise BrainPainterError(
                f"the job database DATA_DIR/jobs.sqlite3 cannot be used ({exc}); stop the server, move "
                "the file away (its jobs are lost) or restore it from a backup, and start again."
            ) from None
        for name in ("jobs.sqlite3", "jobs.sqlite3-wal", "jobs.sqlite3-shm"):
            if (self.root / name).exists():
                _private(self.root / name)

    # -- plumbing ------------------------------------------------------------------------
    @contextmanager
    def connect(self) -> Iterator[sqlite3.Connection]:
        db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
        try:  # closed also when a damaged file fails the first statement (else a leaked connection)
            db.row_factory = sqlite3.Row
            db.execute("PRAGMA busy_timeout=30000")
            db.execute("PRAGMA synchronous=NORMAL")
            yield db
        finally:
            db.close()

    @contextmanager
    def transaction(self) -> Iterator[sqlite3.Connection]:
        """``BEGIN IMMEDIATE`` ... ``COMMIT`` (rolled back on error): one writer at a time."""
        with self.connect() as db:
            db.execute("BEGIN IMMEDIATE")
            try:
                yield db
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT")

    def keep_open(self) -> None:
        """Hold one connection for the server's life, so that SQLite keeps its ``-wal`` and ``-shm`` files.

        With no connection open, the last one to close removes them and the next must create them
        again, which fails on a full disk ("disk I/O error"): status reads would fail with writes.
        """
        if self._keeper is None:
            self._keeper = sqlite3.connect(self.path, timeout=30.0, isolation_level=None,
                                           check_same_thread=False)
            self._keeper.execute("SELECT count(*) FROM jobs").fetchone()  # maps the shared-memory index

    def close(self) -> None:
        """Let go of the connection :meth:`keep_open` holds."""
        if self._keeper is not None:
            self._keeper.close()
            self._keeper = None

    def job_dir(self, job_id: str) -> Path:
        if not valid_id(job_id):
            raise ValueError("not a job id")
        return self.root / "jobs" / job_id

    def upload_path(self, upload_id: str) -> Path:
        if not valid_id(upload_id):
            raise ValueError("not an upload id")
        return self.root / "uploads" / f"{upload_id}.bin"

    def ping(self) -> bool:
        """The database answers and is writable."""
        with self.transaction() as db:
            db.execute("SELECT count(*) FROM jobs").fetchone()
        return True

    def disk_usage(self, max_age_s: float | None = None) -> int:
        """Bytes used by the data folder (:meth:`brainpainter.web.disk.DiskBudget.used`)."""
        return self.budget.used(max_age_s)

    def charge(self, nbytes: int) -> None:
        """Count `nbytes` about to be written against the disk budget, or refuse them (:class:`LimitError`,
        507; :meth:`brainpainter.web.disk.DiskBudget.charge`)."""
        refused = self.budget.charge(nbytes)
        if refused:
            raise LimitError(refused, 507, retry_after=600)

    # -- uploads -------------------------------------------------------------------------
    def add_upload(self, client: str, name: str, data: bytes, ttl_s: float, keep: int = 20, *,
                   owner: str = "") -> str:
        """Store an upload of `owner`; the client's uploads beyond its newest `keep` are deleted (disk stays
        bounded; jobs keep their own copy of their table). Its bytes count against the disk budget as they
        are written (:meth:`charge`)."""
        self.charge(len(data))
        upload_id = new_id()
        atomic_write_bytes(self.upload_path(upload_id), data)
        _private(self.upload_path(upload_id))
        now = time.time()
        with self.transaction() as db:
            db.execute("INSERT INTO uploads (id, client, name, size, created, expires, owner) "
                       "VALUES (?, ?, ?, ?, ?, ?, ?)", (upload_id, client, name, len(data), now, now + ttl_s,
                                                        owner))
            old = [r["id"] for r in db.execute(
                "SELECT id FROM uploads WHERE client = ? ORDER BY created DESC, rowid DESC LIMIT -1 OFFSET ?",
                (client, keep)).fetchall()]
            db.executemany("DELETE FROM uploads WHERE id = ?", [(i,) for i in old])
        for i in old:
            self.upload_path(i).unlink(missing_ok=True)
        return upload_id

    def get_upload(self, upload_id: str, owner: str | None = None) -> tuple[str, bytes] | None:
        """``(name, bytes)`` of a live upload (of `owner`, when given), or None."""
        row = self._row("SELECT name, expires, owner FROM uploads WHERE id = ?", upload_id)
        if row is None or row["expires"] < time.time() or (owner is not None and row["owner"] != owner):
            return None
        try:
            return row["name"], self.upload_path(upload_id).read_bytes()
        except OSError:
            return None

    # -- jobs: the server's side -----------------------------------------------------------
    def submit(self, client: str, kind: str, options: dict[str, Any], params: dict[str, Any],
               input_name: str, data: bytes, total: int, *, max_per_client: int, max_queued: int,
               extra: dict[str, bytes] | None = None, owner: str = "") -> str:
        """Queue a job of `owner`, or raise :class:`LimitError` (nothing stored then); `extra`: more input
        files (name -> bytes, e.g. the tract upload the options name) kept beside ``input.bin``."""
        inputs = {"input.bin": data, **(extra or {})}
        self.charge(sum(len(c) for c in inputs.values()))
        job_id = new_id()
        folder = self.job_dir(job_id)
        (folder / "out").mkdir(mode=0o700, parents=True)
        _private(folder)
        for name, content in inputs.items():
            atomic_write_bytes(folder / name, content)
            _private(folder / name)
        try:
            with self.transaction() as db:
                mine = db.execute("SELECT count(*) FROM jobs WHERE client = ? AND status IN (?, ?)",
                                  (client, *ACTIVE)).fetchone()[0]
                if mine >= max_per_client:
                    raise LimitError(f"you have {mine} job(s) queued or running; at most {max_per_client} "
                                     "at once. Wait for one to finish, then submit again.", 429)
                queued = db.execute("SELECT count(*) FROM jobs WHERE status = 'queued'").fetchone()[0]
                if queued >= max_queued:
                    raise LimitError(f"the server has {queued} jobs waiting, its limit; try again in a "
                                     "minute.", 503, retry_after=30)
                db.execute(
                    "INSERT INTO jobs (id, client, kind, status, options, params, input_name, created, total,"
                    " owner) VALUES (?, ?, ?, 'queued', ?, ?, ?, ?, ?, ?)",
                    (job_id, client, kind, json.dumps(options), json.dumps(params), input_name, time.time(),
                     total, owner))
                self._event(db, job_id, 0, "queued", None)
        except BaseException:
            shutil.rmtree(folder, ignore_errors=True)
            raise
        return job_id

    def get(self, job_id: str, owner: str | None = None) -> dict[str, Any] | None:
        """The job `job_id` (status, progress, files...; of `owner`, when given), or None."""
        row = self._row("SELECT * FROM jobs WHERE id = ?", job_id)
        return None if row is None or (owner is not None and row["owner"] != owner) else _job(row)

    def _row(self, sql: str, row_id: str) -> sqlite3.Row | None:
        """The row that `sql` (``... WHERE id = ?``) selects, or None (also for a malformed id)."""
        if not valid_id(row_id):
            return None
        with self.connect() as db:
            row: sqlite3.Row | None = db.execute(sql, (row_id,)).fetchone()
        return row

    def cancel(self, job_id: str) -> bool:
        """Cancel a queued or running job (its worker stops at the next image)."""
        with self.transaction() as db:
            row = db.execute("SELECT attempt FROM jobs WHERE id = ? AND status IN (?, ?)",
                             (job_id, *ACTIVE)).fetchone()
            if row is None:
                return False
            db.execute("UPDATE jobs SET status = 'cancelled', finished = ?, attempt = attempt + 1 "
                       "WHERE id = ?", (time.time(), job_id))
            self._event(db, job_id, row["attempt"], "cancelled", None)
        return True

    def events(self, job_id: str) -> list[dict[str, Any]]:
        with self.connect() as db:
            rows = db.execute("SELECT * FROM events WHERE job_id = ? ORDER BY rowid", (job_id,)).fetchall()
        return [dict(r) for r in rows]

    def counts(self) -> dict[str, int]:
        with self.connect() as db:
            rows = db.execute("SELECT status, count(*) AS n FROM jobs GROUP BY status").fetchall()
        return {r["status"]: r["n"] for r in rows}

    # -- jobs: the workers' side ------------------------------------------------------------
    def claim(self, worker: str) -> dict[str, Any] | None:
        """Take the oldest queued job for `worker` (with a new attempt number), or None."""
        with self.transaction() as db:
            row = db.execute("SELECT id FROM jobs WHERE status = 'queued' ORDER BY created, rowid "
                             "LIMIT 1").fetchone()
            if row is None:
                return None
            now = time.time()
            db.execute("UPDATE jobs SET status = 'running', attempt = attempt + 1, worker = ?, heartbeat = ?,"
                       " started = ? WHERE id = ?", (worker, now, now, row["id"]))
            job = _job(db.execute("SELECT * FROM jobs WHERE id = ?", (row["id"],)).fetchone())
            self._event(db, job["id"], job["attempt"], "started", worker)
        return job

    def progress(self, job_id: str, attempt: int, done: int, total: int | None = None) -> bool:
        """Record progress (and the total of steps when it is known only now, e.g. a movie's frames);
        False when the job is no longer this attempt's (cancelled, given up)."""
        with self.transaction() as db:
            cur = db.execute("UPDATE jobs SET progress = ?, total = coalesce(?, total), heartbeat = ? "
                             "WHERE id = ? AND attempt = ? AND status = 'running'",
                             (done, total, time.time(), job_id, attempt))
        return cur.rowcount == 1

    def finish(self, job_id: str, attempt: int, files: list[str], ttl_s: float) -> bool:
        """Mark the job done with its output files; False (nothing changed) when the attempt is stale."""
        now = time.time()
        with self.transaction() as db:
            cur = db.execute(
                "UPDATE jobs SET status = 'done', finished = ?, expires = ?, files = ?, progress = total, "
                "completions = completions + 1 WHERE id = ? AND attempt = ? AND status = 'running'",
                (now, now + ttl_s, json.dumps(files), job_id, attempt))
            if cur.rowcount == 1:
                self._event(db, job_id, attempt, "done", None)
        return cur.rowcount == 1

    def fail(self, job_id: str, attempt: int | None, error: str, ttl_s: float) -> bool:
        now = time.time()
        with self.transaction() as db:
            sql = ("UPDATE jobs SET status = 'failed', finished = ?, expires = ?, error = ?, "
                   "attempt = attempt + 1 WHERE id = ? AND status = 'running'")
            args: tuple[Any, ...] = (now, now + ttl_s, error[:500], job_id)
            if attempt is not None:
                sql += " AND attempt = ?"
                args += (attempt,)
            cur = db.execute(sql, args)
            if cur.rowcount == 1:
                self._event(db, job_id, attempt or 0, "failed", error[:500])
        return cur.rowcount == 1

    def requeue(self, *, worker: str | None = None, max_attempts: int, ttl_s: float) -> list[str]:
        """Queue again the running jobs of `worker` (all running jobs when None), with a new attempt.

        With `worker` given, that worker died while holding the job: the job's ``deaths`` count
        goes up, and a job whose worker died `max_attempts` times fails instead (a job that kills
        its worker every time must not loop forever). Without it (the server stopped or restarted)
        the job did nothing wrong and only its attempt number changes, so that the old workers can
        no longer change it.
        """
        now = time.time()
        died = 1 if worker is not None else 0
        with self.transaction() as db:
            sql = "SELECT id, attempt, deaths FROM jobs WHERE status = 'running'"
            args: tuple[str, ...] = ()
            if worker is not None:
                sql, args = sql + " AND worker = ?", (worker,)
            rows = db.execute(sql, args).fetchall()
            for r in rows:
                deaths = r["deaths"] + died
                if deaths >= max_attempts:
                    msg = (f"the job stopped its worker {deaths} times; it is not tried again. Try a "
                           "smaller size or fewer views, or report it.")
                    db.execute("UPDATE jobs SET status = 'failed', error = ?, finished = ?, expires = ?, "
                               "attempt = attempt + 1, deaths = ? WHERE id = ?",
                               (msg, now, now + ttl_s, deaths, r["id"]))
                    self._event(db, r["id"], r["attempt"], "failed", msg)
                else:
                    db.execute("UPDATE jobs SET status = 'queued', worker = NULL, attempt = attempt + 1, "
                               "deaths = ? WHERE id = ?", (deaths, r["id"]))
                    self._event(db, r["id"], r["attempt"], "requeued", worker)
        return [r["id"] for r in rows]

    def overdue(self, limit_s: float) -> list[dict[str, Any]]:
        """Running jobs that started more than `limit_s` seconds ago."""
        with self.connect() as db:
            rows = db.execute("SELECT * FROM jobs WHERE status = 'running' AND started < ?",
                              (time.time() - limit_s,)).fetchall()
        return [_job(r) for r in rows]

    # -- workers -------------------------------------------------------------------------
    def worker_state(self, name: str, pid: int, state: str) -> None:
        with self.transaction() as db:
            db.execute("INSERT OR REPLACE INTO workers VALUES (?, ?, ?, ?)", (name, pid, state, time.time()))

    def workers(self) -> list[dict[str, Any]]:
        with self.connect() as db:
            return [dict(r) for r in db.execute("SELECT * FROM workers ORDER BY name").fetchall()]

    def forget_workers(self) -> None:
        with self.transaction() as db:
            db.execute("DELETE FROM workers")

    # -- expiry --------------------------------------------------------------------------
    def expire(self, now: float | None = None) -> int:
        """Delete the files of finished jobs and uploads past their time; returns how many went."""
        now = time.time() if now is None else now
        with self.transaction() as db:
            jobs = [r["id"] for r in db.execute(
                "SELECT id FROM jobs WHERE status IN ('done', 'failed', 'cancelled') AND "
                "coalesce(expires, finished) < ?", (now,)).fetchall()]
            db.execute("UPDATE jobs SET status = 'expired', files = '[]' WHERE status IN "
                       "('done', 'failed', 'cancelled') AND coalesce(expires, finished) < ?", (now,))
            uploads = [r["id"] for r in db.execute("SELECT id FROM uploads WHERE expires < ?",
                                                   (now,)).fetchall()]
            db.execute("DELETE FROM uploads WHERE expires < ?", (now,))
            # rows of long-expired jobs go too (their files went when they expired)
            gone = now - FORGET_AFTER_S
            db.execute("DELETE FROM events WHERE job_id IN (SELECT id FROM jobs WHERE status = 'expired' AND "
                       "coalesce(expires, finished) < ?)", (gone,))
            db.execute("DELETE FROM jobs WHERE status = 'expired' AND coalesce(expires, finished) < ?",
                       (gone,))
        for job_id in jobs:
            shutil.rmtree(self.job_dir(job_id), ignore_errors=True)
        for upload_id in uploads:
            self.upload_path(upload_id).unlink(missing_ok=True)
        return len(jobs) + len(uploads) + self._orphans(now)

    def _orphans(self, now: float, grace_s: float = ORPHAN_GRACE_S) -> int:
        """Delete files and folders older than `grace_s` that no database row owns (a crash between
        writing a file and its row, a body half received, a cancelled job's outputs)."""
        with self.connect() as db:
            uploads = {r[0] for r in db.execute("SELECT id FROM uploads")}
            live_jobs = {r[0] for r in db.execute("SELECT id FROM jobs WHERE status != 'expired'")}
        gone = 0
        paths = [p for sub in ("uploads", "jobs", "incoming") for p in (self.root / sub).glob("*")]
        for path in paths:
            try:
                if now - path.lstat().st_mtime < grace_s:
                    continue
            except OSError:
                continue
            stem = path.name[:-4] if path.name.endswith(".bin") else path.name
            owner = uploads if path.parent.name == "uploads" else live_jobs
            if path.parent.name != "incoming" and stem in owner:
                continue
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
            gone += 1
        return gone

    @staticmethod
    def _event(db: sqlite3.Connection, job_id: str, attempt: int, event: str, detail: str | None) -> None:
        db.execute("INSERT INTO events (job_id, attempt, event, detail, t) VALUES (?, ?, ?, ?, ?)",
                   (job_id, attempt, event, detail, time.time()))


def _private(path: Path) -> None:
    """Readable and writable by this user only (0700 folders, 0600 files); a no-op where not allowed."""
    try:
        os.chmod(path, 0o700 if path.is_dir() else 0o600)
    except OSError:
        pass


def _job(row: sqlite3.Row) -> dict[str, Any]:
    job = dict(row)
    for key in ("options", "params", "files"):
        job[key] = json.loads(job[key])
    return job
