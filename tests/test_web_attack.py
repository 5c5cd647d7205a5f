"""``brainpainter serve`` under attack and faults (issue 27), in process (TestClient; loopback only).

Each test is one case of the review: bounded work per request, bodies on disk
with deadlines and caps, requests from other sites refused, honest cancel,
disk budget and a full disk, a private data folder, and the smaller items.
The cases that need a real uvicorn (stalled sockets, forwarded headers, a
killed server) are in ``tests/test_web_faults.py``.
"""

from __future__ import annotations

import errno
import io
import os
import sqlite3
import stat
import sys
import threading
import time
from pathlib import Path

import pytest
from web_support import EXAMPLE, standin_app, standin_site, wait_for

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient

from brainpainter.errors import BrainPainterError
from brainpainter.web.app import create_app
from brainpainter.web.config import ServerConfig
from brainpainter.web.options import RenderOptions, prepare
from brainpainter.web.store import Store, valid_id

OCTET = {"content-type": "application/octet-stream"}
HEADER = "Image-name-unique,Left-insula,Right-insula,Left-Hippocampus\n"


def rows_table(n: int) -> bytes:
    return (HEADER + "".join(f"img{k},{k % 4},1,2\n" for k in range(n))).encode()


@pytest.fixture
def api(tmp_path):
    """An app without rendering processes (uploads, checks, limits)."""
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, rate_per_minute=100_000,
                          max_rows=30_000)
    with TestClient(create_app(config)) as client:
        yield client


def upload(client, data: bytes, **params):
    return client.post("/api/uploads", params={"name": "t.csv", **params}, content=data, headers=OCTET)


# -- 1. bounded work per request ----------------------------------------------------------------
def test_a_table_over_the_row_limit_is_refused_at_once_in_one_line(api):
    t0 = time.monotonic()
    r = upload(api, rows_table(200_000))
    took = time.monotonic() - t0
    assert r.status_code == 400, r.text
    msg = r.json()["error"]
    assert "200000 rows" in msg and "30000" in msg and "\n" not in msg
    assert took < 10, took


def test_the_image_name_clash_check_is_linear_in_the_rows():
    data = rows_table(20_000)
    t0 = time.monotonic()
    prep = prepare(data, "t.csv", RenderOptions(size="64x48"))
    assert len(prep.file_names) == 20_000
    assert time.monotonic() - t0 < 10  # names.count per name took 20 s here (loaded machine)
    clash = (HEADER + "a b,1,1,1\na_b,2,2,2\n").encode()
    with pytest.raises(BrainPainterError, match="become the same file name"):
        prepare(clash, "t.csv", RenderOptions())


def test_status_reads_answer_while_tables_are_read(api):
    uid = upload(api, rows_table(20_000)).json()["upload_id"]
    assert api.get("/api/meta").status_code == 200  # its first call's imports are not what is timed
    answers: list[int] = []

    def check() -> None:
        answers.append(api.post("/api/check", json={"upload_id": uid}).status_code)

    threads = [threading.Thread(target=check) for _ in range(10)]
    for t in threads:
        t.start()
    time.sleep(0.5)
    t0 = time.monotonic()
    assert api.get("/api/meta").status_code == 200
    meta_s = time.monotonic() - t0
    for t in threads:
        t.join(timeout=300)
    assert meta_s < 2, meta_s
    assert set(answers) <= {200, 503} and 200 in answers


def _xlsx(rows: int) -> bytes:
    openpyxl = pytest.importorskip("openpyxl")
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.append(["Image-name-unique", "Left-insula", "Right-insula"])
    for k in range(rows):
        ws.append([f"img{k}", k % 4, 1.0])
    buf = io.BytesIO()
    wb.save(buf)
    return buf.getvalue()


def test_a_spreadsheet_is_read_in_a_process_with_a_time_limit(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, parse_time_limit_s=0.05)
    with TestClient(create_app(config)) as client:
        r = client.post("/api/uploads", params={"name": "t.xlsx"}, content=_xlsx(50), headers=OCTET)
        assert r.status_code == 400 and "took longer than this server's limit of 0.05 s" in r.json()["error"]
    config = ServerConfig(data_dir=tmp_path / "data2", workers=0, preview=False, max_rows=20)
    with TestClient(create_app(config)) as client:
        r = client.post("/api/uploads", params={"name": "t.xlsx"}, content=_xlsx(5), headers=OCTET)
        assert r.status_code == 200, r.text
        assert r.json()["images"] == [f"img{k}" for k in range(5)]
        r = client.post("/api/uploads", params={"name": "t.xlsx"}, content=_xlsx(50), headers=OCTET)
        assert r.status_code == 400 and "50 rows" in r.json()["error"]


# -- 2. bodies: on disk, with a deadline, a few at a time -----------------------------------------
def test_an_upload_body_that_stalls_gets_408_and_leaves_nothing(tmp_path):
    import anyio
    import httpx

    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, upload_time_limit_s=1.0)
    app = create_app(config)

    async def slow_body():
        yield b"Image-name-unique,Left-insula\n"
        await anyio.sleep(5)
        yield b"A,1\n"

    async def main() -> httpx.Response:
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://testserver") as client:
            return await client.post("/api/uploads", content=slow_body(), headers=OCTET)

    t0 = time.monotonic()
    r = anyio.run(main)
    assert r.status_code == 408 and "not received within 1 s" in r.json()["error"]
    assert time.monotonic() - t0 < 4
    assert not list((tmp_path / "data" / "incoming").glob("*"))  # the partial body is deleted


# -- 6. who the client is ---------------------------------------------------------------------------
def test_uploads_from_other_sites_are_refused(api):
    data = EXAMPLE.read_bytes()
    for headers in ({"content-type": "text/plain"}, {"content-type": "application/x-www-form-urlencoded"},
                    {"content-type": "multipart/form-data; boundary=x"}, {}):
        r = api.post("/api/uploads", content=data, headers=headers)
        assert r.status_code == 415 and "application/octet-stream" in r.json()["error"], headers
    r = api.post("/api/uploads", content=data, headers={**OCTET, "sec-fetch-site": "cross-site"})
    assert r.status_code == 403
    assert upload(api, data).status_code == 200


def test_one_clients_uploads_never_evict_anothers(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, max_uploads_per_client=3,
                          rate_per_minute=100_000)
    app = create_app(config)
    data = EXAMPLE.read_bytes()
    with TestClient(app, client=("10.0.0.1", 1000)) as alice, \
            TestClient(app, client=("10.0.0.2", 1000)) as bob:
        mine = upload(alice, data).json()["upload_id"]
        for _ in range(5):
            assert upload(bob, data).status_code == 200
        assert alice.post("/api/check", json={"upload_id": mine}).status_code == 200


# -- 4/5. results on disk ------------------------------------------------------------------------------
def test_uploads_and_jobs_belong_to_the_client_that_made_them(tmp_path):
    """Another client (another token; the same address) gets 404 for an upload's or a job's id."""
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, rate_per_minute=100_000)
    app = create_app(config)
    with TestClient(app) as alice, TestClient(app) as bob:
        r = upload(alice, EXAMPLE.read_bytes())
        cookie = r.headers["set-cookie"]
        assert "bp_client=" in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie, cookie
        uid = r.json()["upload_id"]
        job = alice.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}}).json()["id"]
        store = app.state.store
        claimed = store.claim("w")
        (store.job_dir(job) / "out" / "a.png").write_bytes(b"png")
        store.finish(job, claimed["attempt"], ["a.png"], 3600)
        other = alice.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}}).json()["id"]
        assert "set-cookie" not in alice.get(f"/api/jobs/{job}").headers  # issued once
        for r in (bob.get(f"/api/jobs/{job}"), bob.get(f"/api/jobs/{job}/files/a.png"),
                  bob.delete(f"/api/jobs/{other}"), bob.post("/api/check", json={"upload_id": uid}),
                  bob.post("/api/jobs", json={"upload_id": uid}),
                  bob.post("/api/preview", json={"upload_id": uid})):
            assert r.status_code == 404 and "another client" in r.json()["error"], r.text
        mine = upload(bob, EXAMPLE.read_bytes()).json()["upload_id"]
        r = bob.post("/api/check", json={"upload_id": mine, "options": {"tracts": uid}})
        assert r.status_code == 404, r.text  # nor another's upload as option tracts
        assert store.get(other)["status"] == "queued"
        assert alice.get(f"/api/jobs/{job}").json()["status"] == "done"
        assert alice.get(f"/api/jobs/{job}/files/a.png").content == b"png"
        assert alice.delete(f"/api/jobs/{other}").json()["status"] == "cancelled"
        assert alice.post("/api/check", json={"upload_id": uid}).status_code == 200
        token = alice.cookies["bp_client"]
    # a script may send its token as a header instead; the database holds no token
    with TestClient(app) as script:
        assert script.get(f"/api/jobs/{job}", headers={"x-brainpainter-client": token}).status_code == 200
        assert script.get(f"/api/jobs/{job}", headers={"x-brainpainter-client": "x" * 40}).status_code == 404
    for db in (tmp_path / "data").glob("jobs.sqlite3*"):
        assert token.encode() not in db.read_bytes()


def test_data_folder_and_uploads_are_private(api, tmp_path):
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    root = tmp_path / "data"
    assert stat.S_IMODE(root.stat().st_mode) == 0o700
    for sub in ("uploads", "jobs"):
        assert stat.S_IMODE((root / sub).stat().st_mode) == 0o700
    assert stat.S_IMODE((root / "uploads" / f"{uid}.bin").stat().st_mode) & 0o077 == 0
    assert stat.S_IMODE((root / "jobs.sqlite3").stat().st_mode) & 0o077 == 0


def test_a_disk_budget_refuses_new_work_with_507(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, max_disk_gb=1e-6)
    with TestClient(create_app(config)) as client:
        (tmp_path / "data" / "uploads" / "filler").write_bytes(b"x" * 4096)
        r = upload(client, EXAMPLE.read_bytes())
        assert r.status_code == 507 and "budget" in r.json()["error"]
        assert client.get("/api/meta").status_code == 200


def test_a_full_disk_fails_writes_in_one_line_and_reads_still_work(api, monkeypatch):
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    store = api.app.state.store

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(store, "add_upload", full)
    monkeypatch.setattr(store, "submit", full)
    r = upload(api, EXAMPLE.read_bytes())
    assert r.status_code == 507 and r.json()["error"].startswith("the server's disk is full")
    r = api.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}})
    assert r.status_code == 507
    assert api.post("/api/check", json={"upload_id": uid}).status_code == 200  # reads still work


class _FullDisk(sqlite3.Connection):
    """A connection on a full disk: every write fails as SQLite reports it ("disk I/O error")."""

    def execute(self, sql, *args):  # type: ignore[override]
        if sql.split()[0].upper() in ("INSERT", "UPDATE", "DELETE"):
            raise sqlite3.OperationalError("disk I/O error")
        return super().execute(sql, *args)


def _fill_disk(monkeypatch, free: int = 0) -> None:
    """What a full disk does to the server (measured on a 30 MB tmpfs): no free bytes, no database
    write, and no new SQLite shared-memory index (a connection that must create ``-shm`` fails)."""
    import shutil

    real = sqlite3.connect

    def connect(path, *args, **kwargs):
        if not Path(f"{path}-shm").exists():
            raise sqlite3.OperationalError("disk I/O error")
        return real(path, *args, factory=_FullDisk, **kwargs)

    monkeypatch.setattr(sqlite3, "connect", connect)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(1 << 30, 1 << 30, free))


def _full_disk_routes(api, fill) -> None:
    """A done and a queued job; `fill()` fills the disk; then reads answer and writes get 507."""
    store = api.app.state.store
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    done, queued = (api.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}}).json()["id"]
                    for _ in range(2))
    job = store.claim("w")
    assert job["id"] == done
    (store.job_dir(done) / "out" / "a.png").write_bytes(b"png")
    store.finish(done, job["attempt"], ["a.png"], 3600)
    fill()
    r = api.get(f"/api/jobs/{queued}")
    assert r.status_code == 200 and r.json()["status"] == "queued", r.text
    r = api.get(f"/api/jobs/{done}/files/a.png")
    assert r.status_code == 200 and r.content == b"png"
    assert api.post("/api/check", json={"upload_id": uid}).status_code == 200
    r = api.get("/readyz")
    assert r.status_code == 503 and r.json()["checks"]["disk"] is False, r.text
    for r in (api.delete(f"/api/jobs/{queued}"), upload(api, EXAMPLE.read_bytes()),
              api.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}})):
        assert r.status_code == 507, r.text
        assert r.json()["error"].startswith("the server's disk is full") and r.headers["retry-after"]
    assert store.get(queued)["status"] == "queued"  # nothing changed


def test_on_a_full_disk_reads_work_and_every_write_answers_507(api, monkeypatch):
    _full_disk_routes(api, lambda: _fill_disk(monkeypatch))


def test_on_a_real_full_disk_reads_work_and_every_write_answers_507(tmpfs):
    """The same on a 4 MB tmpfs filled to the last byte (root only)."""
    disk = tmpfs("size=4m")

    def fill() -> None:
        with open(disk / "filler", "wb", buffering=0) as fh, pytest.raises(OSError):
            while True:
                fh.write(b"x" * 4096)

    config = ServerConfig(data_dir=disk / "data", workers=0, preview=False, rate_per_minute=100_000)
    with TestClient(create_app(config)) as api:
        _full_disk_routes(api, fill)
        (disk / "filler").unlink()


def test_a_disk_io_error_with_space_left_is_not_called_a_full_disk(api, monkeypatch):
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    queued = api.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}}).json()["id"]
    _fill_disk(monkeypatch, free=10 << 30)
    r = api.delete(f"/api/jobs/{queued}")
    assert r.status_code == 500 and "OperationalError" in r.json()["error"]


def test_a_reading_process_that_fills_the_disk_reports_it_as_full():
    from brainpainter.web.upload import _failed

    assert _failed(OSError(errno.ENOSPC, "No space left on device"), "x")[0] == "full"
    assert _failed(OSError(errno.EDQUOT, "Disk quota exceeded"), "x")[0] == "full"
    full = BrainPainterError("cannot write 'a': the disk is full")
    full.errno = errno.ENOSPC  # type: ignore[attr-defined]  # as io.folders.os_error keeps it
    assert _failed(full, "x")[0] == "full"
    assert _failed(ValueError("bad"), "cannot read") == ("error", "cannot read")


def test_a_map_that_fills_the_disk_while_inflating_is_a_full_disk_not_a_bad_file(tmp_path):
    """Measured on a 30 MB tmpfs: a 64 KB .nii.gz of 64 MB answered 400 "not a readable gzip file"."""
    import gzip

    from brainpainter.web.maps import inflate

    class _Full(io.RawIOBase):
        def writable(self) -> bool:
            return True

        def write(self, b) -> int:
            raise OSError(errno.ENOSPC, "No space left on device")

    class FullDisk(type(tmp_path)):  # a file system with no space left
        def open(self, mode="r", *args, **kwargs):
            return _Full() if "w" in mode else super().open(mode, *args, **kwargs)

    (tmp_path / "v.nii.gz").write_bytes(gzip.compress(b"\0" * 100_000))
    with pytest.raises(OSError) as err:
        inflate(FullDisk(tmp_path / "v.nii.gz"))
    assert err.value.errno == errno.ENOSPC
    (tmp_path / "w.nii.gz").write_bytes(b"not gzip")
    with pytest.raises(BrainPainterError, match="not a readable gzip file"):
        inflate(tmp_path / "w.nii.gz")


def test_files_without_a_database_row_are_cleaned_up(tmp_path):
    store = Store(tmp_path / "data")
    stray_dir = store.root / "jobs" / ("a" * 32)
    (stray_dir / "out").mkdir(parents=True)
    stray_upload = store.root / "uploads" / f"{'b' * 32}.bin"
    stray_upload.write_bytes(b"x")
    uid = store.add_upload("c", "t.csv", b"data", 3600)
    old = time.time() - 7200
    for p in (stray_dir, stray_upload, store.upload_path(uid)):
        os.utime(p, (old, old))
    store.expire()
    assert not stray_dir.exists() and not stray_upload.exists()
    assert store.get_upload(uid) is not None  # a live upload stays, however old its file


# -- 7. smaller -------------------------------------------------------------------------------------
def test_smaller_items(api):
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    for value in ("-Infinity", "Infinity", "NaN"):
        r = api.post("/api/check", content=f'{{"upload_id": "{uid}", "options": {{"vmax": {value}}}}}',
                     headers={"content-type": "application/json"})
        assert r.status_code == 422 and "vmax" in r.json()["error"], value
    r = api.post("/api/check", json={"upload_id": uid, "options": {"vmax": -1}})
    assert r.status_code == 400 and r.json()["error"].startswith("vmax=-1 is not above the smallest value")
    r = api.post("/api/preview", json={"upload_id": uid, "row": "²"})
    assert r.status_code == 400 and "not an image of the table" in r.json()["error"]
    assert not valid_id("a" * 32 + "\n") and valid_id("a" * 32)
    r = api.get("/api/meta/", headers={"host": "evil.example"}, follow_redirects=False)
    assert r.status_code == 404 and "evil" not in r.headers.get("location", "")
    r = api.post("/api/check", content=b"{" + b" " * 70_000 + b"}",
                 headers={"content-type": "application/json"})
    assert r.status_code == 413 and "column" not in r.json()["error"]


def test_a_damaged_database_says_what_to_do(tmp_path):
    (tmp_path / "jobs.sqlite3").write_bytes(b"this is not a database" * 100)
    with pytest.raises(BrainPainterError, match=r"cannot be used .* move the file away"):
        Store(tmp_path)


def test_serve_refuses_non_finite_limits_and_warns_on_every_interface(tmp_path, monkeypatch):
    import subprocess

    from click.testing import CliRunner

    from brainpainter.cli.main import cli

    proc = subprocess.run([sys.executable, "-m", "brainpainter", "serve", "--port", "1", "--data-dir",
                           str(tmp_path / "d"), "--max-upload-mb", "nan"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and "--max-upload-mb must be a positive number" in proc.stderr
    import brainpainter.web.server as server

    seen = {}
    monkeypatch.setattr(server, "run", lambda app, **kw: seen.update(kw))
    for key in ("MPLCONFIGDIR", "XDG_CACHE_HOME"):  # serve sets them for its own process
        monkeypatch.setenv(key, os.environ.get(key, ""))
    import logging

    web_log = logging.getLogger("brainpainter.web")  # serve sets up its log; later tests read it (caplog)
    monkeypatch.setattr(web_log, "propagate", web_log.propagate)
    monkeypatch.setattr(web_log, "handlers", list(web_log.handlers))
    monkeypatch.setattr(web_log, "level", web_log.level)
    mask = os.umask(0o022)
    try:
        r = CliRunner().invoke(cli, ["serve", "--data-dir", str(tmp_path / "e"), "--host", "0.0.0.0",
                                     "--workers", "0", "--no-preview"])
    finally:
        os.umask(mask)
        from brainpainter.web.folder_lock import unlock_data_dir
        unlock_data_dir(tmp_path / "e")
    assert r.exit_code == 0, r.output
    assert "http://127.0.0.1:8000/" in r.output and "no authentication" in r.output
    assert seen["forwarded_allow_ips"] is None  # X-Forwarded-For is not trusted unless asked
    assert stat.S_IMODE((tmp_path / "e").stat().st_mode) == 0o700
    assert os.environ["MPLCONFIGDIR"].startswith(str(tmp_path / "e"))


# -- 4. cancel is honest: the worker stops within a frame --------------------------------------------
@pytest.fixture(scope="module")
def rendering(tmp_path_factory):
    """An app with one job worker and the stand-in renderer."""
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     workers=1, preview=False, rate_per_minute=100_000, max_jobs_per_client=50) as client:
        yield client


def test_a_figure_over_the_pixel_limit_is_refused_before_it_is_queued(api):
    """Issue 33: dpi 600 x 40 in on the 4-row example made a 24000x23720 PNG (5.6 GB, 239 s)."""
    uid = upload(api, EXAMPLE.read_bytes()).json()["upload_id"]
    r = api.post("/api/jobs", json={"upload_id": uid, "kind": "figure",
                                    "figure": {"format": "png", "dpi": 600, "fig_width": 40}})
    assert r.status_code == 400, r.text
    msg = r.json()["error"]
    assert msg.startswith("the figure would be 24000x") and "at most 40000000 pixels" in msg
    assert "\n" not in msg
    assert api.app.state.store.counts() == {}  # nothing queued
    # the CLI's default figure of the same table (2160 px wide), and any PDF, are taken
    for figure in ({"format": "png"}, {"format": "pdf", "dpi": 600, "fig_width": 40}):
        r = api.post("/api/jobs", json={"upload_id": uid, "kind": "figure", "figure": figure})
        assert r.status_code == 202, r.text
    assert api.get("/api/meta").json()["limits"]["max_figure_pixels"] == 40_000_000


def test_rendering_processes_run_under_the_memory_limit(rendering):
    workers = rendering.app.state.store.workers()
    assert workers
    limits = Path(f"/proc/{workers[0]['pid']}/limits").read_text()
    line = next(x for x in limits.splitlines() if x.startswith("Max data size"))
    assert line.split()[3] == str(4 * 1024**3), line


def _long_movie(client) -> str:
    rows = "".join(f"s{k},{k % 3},{(k + 1) % 3},{(k + 2) % 3}\n" for k in range(12))
    uid = upload(client, (HEADER + rows).encode()).json()["upload_id"]
    r = client.post("/api/jobs", json={"upload_id": uid, "kind": "movie", "options": {
        "size": "64x48", "views": "lateral-left", "vmin": 0, "vmax": 2},
        "movie": {"format": "gif", "frames_per_step": 120, "fps": 24}})
    assert r.status_code == 202, r.text
    return r.json()["id"]


def test_cancel_stops_a_running_movie_within_a_frame(rendering):
    client = rendering
    job_id = _long_movie(client)
    url = f"/api/jobs/{job_id}"
    assert wait_for(lambda: (j := client.get(url).json())["status"] == "running" and j["progress"] > 2, 120)
    job = client.get(url).json()
    assert job["total"] > 100  # progress counts frames
    assert client.delete(url).json()["status"] == "cancelled"
    store = rendering.app.state.store
    # the worker is free again within seconds (it stopped at the next frame) and the outputs are gone
    assert wait_for(lambda: store.workers()[0]["state"] == "ready", 30), store.workers()
    assert wait_for(lambda: not (store.job_dir(job_id) / "out").exists(), 10)
    done_at = client.get(url).json()["progress"]
    time.sleep(1.0)
    assert client.get(url).json()["progress"] == done_at
    # and the next job runs at once
    uid = upload(client, EXAMPLE.read_bytes()).json()["upload_id"]
    r = client.post("/api/jobs", json={"upload_id": uid,
                                       "options": {"size": "32x24", "views": "lateral-left"}})
    nxt = f"/api/jobs/{r.json()['id']}"
    assert wait_for(lambda: client.get(nxt).json()["status"] == "done", 60)
    files = client.get(nxt).json()["files"]
    assert files[-1]["name"].endswith(".zip")
    assert not (store.job_dir(r.json()["id"]) / "out" / files[-1]["name"]).exists()  # never stored
    z = client.get(files[-1]["url"]).content
    import zipfile
    with zipfile.ZipFile(io.BytesIO(z)) as zf:
        assert sorted(zf.namelist()) == sorted(f["name"] for f in files[:-1])


# -- 3. restarts do not count against a job --------------------------------------------------------
def test_only_worker_deaths_the_job_caused_count(tmp_path):
    store = Store(tmp_path / "data")
    job_id = store.submit("c", "images", {}, {}, "t.csv", b"x", 1, max_per_client=5, max_queued=5)
    for _ in range(5):  # five server restarts while the job runs
        assert store.claim("w")["id"] == job_id
        store.requeue(max_attempts=3, ttl_s=60)
    assert store.get(job_id)["status"] == "queued"
    for k in range(3):  # its worker dies with it three times
        store.claim(f"w{k}")
        store.requeue(worker=f"w{k}", max_attempts=3, ttl_s=60)
    job = store.get(job_id)
    assert job["status"] == "failed" and "stopped its worker 3 times" in job["error"]


def test_repeated_log_lines_are_kept_to_a_few_a_minute():
    import logging

    from brainpainter.web.server import RepeatFilter

    f = RepeatFilter(per_minute=3)

    def record(msg: str) -> logging.LogRecord:
        return logging.LogRecord("uvicorn.error", logging.ERROR, __file__, 1, msg, None, None)

    passed = [f.filter(record("accept failed: EMFILE")) for _ in range(1000)]
    assert passed.count(True) == 3
    assert f.filter(record("another message"))
