"""``brainpainter serve`` as a real uvicorn process on 127.0.0.1 under floods and kills (issue 27).

Stalled uploads and idle sockets, forged ``X-Forwarded-For`` headers, and a
``kill -9`` of the server during a movie job. Sized down to run in about a
minute; ``benchmarks/bench_serve_attack.py`` runs the issue's full bars.
"""

from __future__ import annotations

import json
import os
import socket
import sqlite3
import sys
import time

import pytest
from web_support import CLIENT, STANDIN, Server, alive, env_with_site, rss_mb, standin_site, wait_for

httpx = pytest.importorskip("httpx")

HEADER = "Image-name-unique,Left-insula,Right-insula,Left-Hippocampus\n"
OCTET = {"content-type": "application/octet-stream"}


def _stalled_upload(port: int, sent: int, claimed: int) -> socket.socket:
    """A connection that sends the headers of a `claimed`-byte upload, `sent` bytes of it, then nothing."""
    s = socket.create_connection(("127.0.0.1", port), timeout=10)
    s.sendall((f"POST /api/uploads?name=t.csv HTTP/1.1\r\nHost: 127.0.0.1\r\n"
               f"Content-Type: application/octet-stream\r\nContent-Length: {claimed}\r\n\r\n").encode())
    s.setblocking(False)
    chunk = (HEADER + "a,1,1,1\n" * 10_000).encode()[:65536]
    left = sent
    end = time.monotonic() + 10
    while left > 0 and time.monotonic() < end:
        try:
            left -= s.send(chunk[:left])
        except BlockingIOError:  # the server stopped reading (flow control): the rest stays with us
            time.sleep(0.01)
    return s


def _answer(s: socket.socket, deadline: float) -> bytes:
    s.setblocking(True)
    s.settimeout(max(0.1, deadline - time.monotonic()))
    try:
        return s.recv(4096)
    except OSError:
        return b""


def test_stalled_uploads_and_idle_sockets_do_not_hold_the_server(tmp_path):
    server = Server(tmp_path / "data", dict(os.environ), tmp_path / "server.log",
                    ["--workers", "0", "--no-preview", "--rate", "100000"])
    server.start()
    sockets: list[socket.socket] = []
    idle: list[socket.socket] = []
    try:
        assert httpx.get(f"{server.url}/api/meta", timeout=30).status_code == 200  # imports done
        base = rss_mb(server.proc.pid)
        sockets = [_stalled_upload(server.port, 2 * 2**20, 10 * 2**20) for _ in range(30)]
        idle = [socket.create_connection(("127.0.0.1", server.port)) for _ in range(50)]
        opened = time.monotonic()
        time.sleep(1.0)
        grown = rss_mb(server.proc.pid) - base
        t0 = time.monotonic()
        assert httpx.get(f"{server.url}/api/meta", timeout=10).status_code == 200
        assert time.monotonic() - t0 < 2
        assert grown < 60, f"RSS grew {grown:.0f} MB"  # bodies go to disk, not memory
        # at most 4 uploads at once from one client: the others wait 5 s for a slot, then get 429
        time.sleep(max(0.0, opened + 6.5 - time.monotonic()))
        refused = sum(_answer(s, opened + 20).startswith(b"HTTP/1.1 429") for s in sockets)
        assert refused >= 30 - 4, refused
        # idle sockets are closed after the header timeout (10 s)
        for s in idle:
            s.settimeout(20)
        closed = sum(s.recv(10) == b"" for s in idle)
        assert closed == len(idle)
        # the stalled uploads end at their deadline (60 s by default: checked by the benchmark);
        # meanwhile a real upload from another connection is refused clearly, not hung
        r = httpx.post(f"{server.url}/api/uploads", content=b"x", headers=OCTET, timeout=10)
        assert r.status_code == 429 and "still being received" in r.json()["error"]
        # a client that leaves half-way is no internal error (no traceback in the log)
        sockets[0].close()
        time.sleep(1.0)
        assert "Traceback" not in server.log.read_text()
    finally:
        for s in sockets + idle:
            s.close()
        server.stop()


def test_forged_forwarded_headers_are_one_client(tmp_path):
    server = Server(tmp_path / "data", dict(os.environ), tmp_path / "server.log", [
        "--workers", "0", "--no-preview", "--max-jobs-per-client", "2", "--rate", "100000"])
    server.start()
    try:
        with httpx.Client(base_url=server.url, timeout=30) as client:
            table = (HEADER + "a,1,2,3\nb,2,3,1\n").encode()
            accepted = 0
            for k in range(10):
                forged = {"x-forwarded-for": f"203.0.113.{k + 1}"}
                r = client.post("/api/uploads", content=table, headers={**OCTET, **forged})
                assert r.status_code == 200, r.text
                r = client.post("/api/jobs", json={"upload_id": r.json()["upload_id"],
                                                   "options": {"size": "32x24"}}, headers=forged)
                accepted += r.status_code == 202
                assert r.status_code in (202, 429), r.text
        assert accepted == 2
        db = sqlite3.connect(f"file:{tmp_path / 'data' / 'jobs.sqlite3'}?mode=ro", uri=True)
        assert {c for (c,) in db.execute("SELECT DISTINCT client FROM jobs")} == {"127.0.0.1"}
        db.close()
    finally:
        server.stop()


def test_a_movie_job_survives_a_killed_server_and_its_workers_die_with_it(tmp_path):
    site = standin_site(tmp_path / "site")
    server = Server(tmp_path / "data", env_with_site(site), tmp_path / "server.log", [
        "--workers", "1", "--no-preview", "--renderer", STANDIN, "--rate", "100000"])
    server.start()
    try:  # one client (its token) before and after the restart
        rows = "".join(f"s{k},{k % 3},{(k + 1) % 3},{(k + 2) % 3}\n" for k in range(4))
        with httpx.Client(base_url=server.url, headers=CLIENT, timeout=30) as client:
            r = client.post("/api/uploads", content=(HEADER + rows).encode(), headers=OCTET)
            uid = r.json()["upload_id"]
            r = client.post("/api/jobs", json={"upload_id": uid, "kind": "movie", "options": {
                "size": "64x48", "views": "lateral-left", "vmin": 0, "vmax": 2},
                "movie": {"format": "gif", "frames_per_step": 12}})
            assert r.status_code == 202, r.text
            url = f"/api/jobs/{r.json()['id']}"
            assert wait_for(lambda: client.get(url).json()["progress"] > 3, 120), client.get(url).json()
        db = sqlite3.connect(f"file:{tmp_path / 'data' / 'jobs.sqlite3'}?mode=ro", uri=True)
        old = [pid for (pid,) in db.execute("SELECT pid FROM workers")]
        db.close()
        server.kill()
        killed = time.monotonic()
        assert wait_for(lambda: not any(alive(p) for p in old), 15), old
        assert time.monotonic() - killed < 15
        server.start()
        with httpx.Client(base_url=server.url, headers=CLIENT, timeout=30) as client:
            job = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j, 180)
            assert job and job["status"] == "done", job
            assert [f["name"] for f in job["files"]] == ["movie.gif"]
            gif = client.get(job["files"][0]["url"]).content
            assert gif[:6] == b"GIF89a"
        db = sqlite3.connect(f"file:{tmp_path / 'data' / 'jobs.sqlite3'}?mode=ro", uri=True)
        (deaths,) = db.execute("SELECT deaths FROM jobs").fetchone()
        db.close()
        assert deaths == 0  # the server's death is not the job's fault
    finally:
        server.stop()


def test_serve_says_where_to_open_it_and_stops_without_leaking_a_semaphore(tmp_path):
    """Issue 33: a human line besides the JSON log; a movie job's worker (tqdm made a multiprocessing
    lock in it) left "1 leaked semaphore objects" in the resource tracker's warning at stop."""
    site = standin_site(tmp_path / "site")
    log = tmp_path / "server.log"
    server = Server(tmp_path / "data", env_with_site(site), log, [
        "--workers", "1", "--no-preview", "--renderer", STANDIN, "--rate", "100000"])
    server.start()
    try:
        with httpx.Client(base_url=server.url, timeout=30) as client:
            rows = "".join(f"s{k},{k % 3},{(k + 1) % 3},{(k + 2) % 3}\n" for k in range(2))
            r = client.post("/api/uploads", content=(HEADER + rows).encode(), headers=OCTET)
            uid = r.json()["upload_id"]
            r = client.post("/api/jobs", json={"upload_id": uid, "kind": "movie", "options": {
                "size": "32x24", "views": "lateral-left"}, "movie": {"format": "gif", "frames_per_step": 2}})
            url = f"/api/jobs/{r.json()['id']}"
            job = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j, 120)
            assert job and job["status"] == "done", job
    finally:
        server.stop()
    text = log.read_text()
    assert f"open {server.url}/ in a browser" in text, text[-2000:]
    assert "leaked" not in text and "resource_tracker" not in text, text[-2000:]


def test_the_curl_example_of_docs_serve_md_works_with_its_cookie_jar(tmp_path):
    """The API example (upload, then a job naming the upload) as written, then the job's status with the
    same jar; without the jar the job is another client's (404)."""
    import re
    import shutil
    import subprocess

    from web_support import REPO

    if shutil.which("curl") is None:
        pytest.skip("curl is not installed")
    api = (REPO / "docs" / "serve.md").read_text().split("## API", 1)[1].split("## Logs", 1)[0]
    script = re.search(r"```bash\n(.*?)```", api, re.S).group(1)
    assert "-b jar -c jar" in script
    server = Server(tmp_path / "data", dict(os.environ), tmp_path / "server.log",
                    ["--workers", "0", "--no-preview", "--rate", "100000"])
    server.start()
    try:
        script = script.replace("http://127.0.0.1:8000", server.url)
        script = script.replace("python -c", f"{sys.executable} -c")
        (tmp_path / "examples").mkdir()
        shutil.copy(REPO / "examples" / "brainpainter_dk.csv", tmp_path / "examples")
        r = subprocess.run(["bash", "-e", "-c", script], cwd=tmp_path, capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 0, r.stderr
        job = json.loads(r.stdout.strip().splitlines()[-1])
        assert job["status"] == "queued", job
        status = ["curl", "-s", "-o", "/dev/null", "-w", "%{http_code}", f"{server.url}{job['url']}"]
        mine = subprocess.run([*status[:2], "-b", "jar", *status[2:]], cwd=tmp_path, capture_output=True,
                              text=True, timeout=30)
        assert mine.stdout == "200"
        assert subprocess.run(status, capture_output=True, text=True, timeout=30).stdout == "404"
    finally:
        server.stop()
