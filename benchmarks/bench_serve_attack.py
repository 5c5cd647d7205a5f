"""The bars of issue 27 against a real ``brainpainter serve`` on 127.0.0.1 (not a test): prints numbers.

- rows: a 200,000-row table's upload (refused) and preview of a 20,000-row one answer within 10 s;
  ``/api/meta`` answers within 2 s while 10 such requests run;
- stalled: 200 uploads that send 5 MB of a 10 MB body and then nothing; the server's RSS
  (bar: < 300 MB) and whether it still answers; the uploads end at their deadline;
- forwarded: 10 jobs with 10 forged ``X-Forwarded-For`` values: accepted <= the per-client limit;
- kill: ``kill -9`` of the server during a movie job, restart: the job ends ``done`` and no worker
  of the old server is alive 15 s after the kill (``--renderer``: blender by default);
- sigterm: seconds from SIGTERM to exit while 8 previews are busy;
- files: the mode of the data folder and of an uploaded table.

    python benchmarks/bench_serve_attack.py                     # all, Blender renderer
    python benchmarks/bench_serve_attack.py --only rows,stalled

Record results in docs/benchmarks.md with the machine and its load (``uptime``).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import sqlite3
import stat
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import httpx
from serve_process import Serve

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "brainpainter_dk.csv"
HEADER = "Image-name-unique,Left-insula,Right-insula,Left-Hippocampus\n"
OCTET = {"content-type": "application/octet-stream"}
#: One client token for every connection of the benchmark (its uploads and jobs are its own: docs/serve.md).
CLIENT = {"x-brainpainter-client": "bench-serve-attack-0123456789abcdef"}


def rows_table(n: int) -> bytes:
    return (HEADER + "".join(f"img{k},{k % 4},1,2\n" for k in range(n))).encode()


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except OSError:
        return False


def bench_rows(tmp: Path, renderer: str) -> dict:
    server = Serve(tmp / "rows", "--workers", "0", "--renderer", renderer, "--rate", "100000")
    try:
        with httpx.Client(base_url=server.url, headers=CLIENT, timeout=120) as client:
            t0 = time.perf_counter()
            r = client.post("/api/uploads", content=rows_table(200_000), headers=OCTET)
            big = {"status": r.status_code, "s": round(time.perf_counter() - t0, 2), "answer": r.json()}
            uid = client.post("/api/uploads", content=rows_table(20_000), headers=OCTET).json()["upload_id"]
            t0 = time.perf_counter()
            r = client.post("/api/preview", json={"upload_id": uid, "row": 19_999})
            one = {"status": r.status_code, "s": round(time.perf_counter() - t0, 2)}
            codes: list[int] = []
            times: list[float] = []

            def preview() -> None:
                t = time.perf_counter()
                codes.append(httpx.post(f"{server.url}/api/preview", json={"upload_id": uid, "row": 5},
                                        headers=CLIENT, timeout=120).status_code)
                times.append(time.perf_counter() - t)

            threads = [threading.Thread(target=preview) for _ in range(10)]
            for t in threads:
                t.start()
            time.sleep(0.5)
            meta = []
            for _ in range(5):
                t0 = time.perf_counter()
                client.get("/api/meta").raise_for_status()
                meta.append(time.perf_counter() - t0)
                time.sleep(0.3)
            for t in threads:
                t.join()
    finally:
        server.close()
    return {"upload_200k_rows": big, "preview_20k_rows": one,
            "meta_s_while_10_previews": [round(x, 3) for x in meta],
            "ten_previews": {"codes": sorted(codes), "max_s": round(max(times), 2)}}


def _stall_all(port: int, n: int, sent: int, claimed: int, within_s: float = 20.0) -> list[socket.socket]:
    """`n` connections that send the headers of a `claimed`-byte upload, then up to `sent` bytes of it
    (round robin, for at most `within_s` seconds: the server reads only a few at once), then nothing."""
    socks, left = [], []
    for _ in range(n):
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        s.sendall((f"POST /api/uploads?name=t.csv HTTP/1.1\r\nHost: x\r\nContent-Type: "
                   f"application/octet-stream\r\nContent-Length: {claimed}\r\n\r\n").encode())
        s.setblocking(False)
        socks.append(s)
        left.append(sent)
    block, end = b"a,1,1,1\n" * 8192, time.monotonic() + within_s
    while any(left) and time.monotonic() < end:
        progressed = False
        for i, s in enumerate(socks):
            if left[i] <= 0:
                continue
            try:
                k = s.send(block[:left[i]])
                left[i] -= k
                progressed = progressed or k > 0
            except BlockingIOError:
                pass
            except OSError:  # answered and closed (429)
                left[i] = 0
        if not progressed:
            time.sleep(0.05)
    return socks


def bench_stalled(tmp: Path, n: int) -> dict:
    server = Serve(tmp / "stalled", "--workers", "0", "--no-preview", "--rate", "100000")
    try:
        httpx.get(f"{server.url}/api/meta", timeout=60).raise_for_status()  # its imports, before the flood
        base = _rss_mb(server.proc.pid)
        t0 = time.perf_counter()
        socks = _stall_all(server.port, n, 5 * 10**6, 10 * 10**6)
        stalled_s = time.perf_counter() - t0
        peak = max(_rss_mb(server.proc.pid), base)
        meta_s, ok = [], 200
        for _ in range(5):
            t = time.perf_counter()
            ok = max(ok, httpx.get(f"{server.url}/api/meta", timeout=30).status_code)
            meta_s.append(round(time.perf_counter() - t, 3))
            time.sleep(0.5)
        peak = max(peak, _rss_mb(server.proc.pid))
        incoming = sum(f.stat().st_size for f in (tmp / "stalled" / "incoming").glob("*"))
        ended = 0
        for s in socks:  # the deadline (60 s) ends them
            s.setblocking(True)
            s.settimeout(max(1.0, 90 - (time.perf_counter() - t0)))
            try:
                ended += s.recv(64).startswith(b"HTTP/1.1 4")
            except OSError:
                pass
            s.close()
        after = httpx.get(f"{server.url}/healthz", timeout=30).status_code
    finally:
        server.close()
    return {"stalled": n, "rss_base_mb": round(base), "rss_peak_mb": round(peak), "meta": ok,
            "meta_s": meta_s, "stall_s": round(stalled_s, 1), "bytes_on_disk": incoming,
            "answered_4xx": ended, "healthz_after": after}


def bench_forwarded(tmp: Path) -> dict:
    server = Serve(tmp / "xff", "--workers", "0", "--no-preview", "--max-jobs-per-client", "4")
    accepted = 0
    try:
        with httpx.Client(base_url=server.url, headers=CLIENT, timeout=60) as client:
            for k in range(10):
                h = {"x-forwarded-for": f"198.51.100.{k + 1}"}
                r = client.post("/api/uploads", content=EXAMPLE.read_bytes(), headers={**OCTET, **h})
                job = {"upload_id": r.json()["upload_id"], "options": {"size": "64x48"}}
                r = client.post("/api/jobs", json=job, headers=h)
                accepted += r.status_code == 202
    finally:
        server.close()
    return {"forged_clients": 10, "accepted": accepted, "limit": 4}


def bench_kill(tmp: Path, renderer: str) -> dict:
    data = tmp / "kill"
    server = Serve(data, "--workers", "1", "--no-preview", "--renderer", renderer)
    with httpx.Client(base_url=server.url, headers=CLIENT, timeout=60) as client:
        uid = client.post("/api/uploads", content=EXAMPLE.read_bytes(), headers=OCTET).json()["upload_id"]
        r = client.post("/api/jobs", json={"upload_id": uid, "kind": "movie", "options": {
            "size": "320x240", "views": "lateral-left"}, "movie": {"format": "mp4", "frames_per_step": 24}})
        url = r.json()["url"]
        for _ in range(3000):
            if client.get(url).json()["progress"] >= 3:
                break
            time.sleep(0.2)
    db = sqlite3.connect(f"file:{data / 'jobs.sqlite3'}?mode=ro", uri=True)
    old = [pid for (pid,) in db.execute("SELECT pid FROM workers")]
    db.close()
    server.proc.kill()
    server.proc.wait()
    killed = time.perf_counter()
    while any(_alive(p) for p in old) and time.perf_counter() - killed < 60:
        time.sleep(0.1)
    gone_s = time.perf_counter() - killed
    server.log.close()
    server.start()
    try:
        with httpx.Client(base_url=server.url, headers=CLIENT, timeout=60) as client:
            for _ in range(36000):
                job = client.get(url).json()
                if job["status"] in ("done", "failed", "cancelled"):
                    break
                time.sleep(0.5)
    finally:
        server.close()
    return {"old_workers_gone_s": round(gone_s, 2), "job_status": job["status"], "attempt": job["attempt"],
            "error": job["error"]}


def bench_sigterm(tmp: Path, renderer: str) -> dict:
    server = Serve(tmp / "term", "--workers", "0", "--renderer", renderer, "--rate", "100000")
    with httpx.Client(base_url=server.url, headers=CLIENT, timeout=60) as client:
        uid = client.post("/api/uploads", content=rows_table(20_000), headers=OCTET).json()["upload_id"]
    threads = [threading.Thread(target=lambda: _quiet_post(f"{server.url}/api/preview",
                                                           {"upload_id": uid, "row": 3})) for _ in range(8)]
    for t in threads:
        t.start()
    time.sleep(1.0)
    t0 = time.perf_counter()
    server.proc.send_signal(signal.SIGTERM)
    try:
        server.proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        server.proc.kill()
    stop_s = time.perf_counter() - t0
    for t in threads:
        t.join(timeout=5)
    server.log.close()
    return {"busy_previews": 8, "sigterm_to_exit_s": round(stop_s, 2)}


def _quiet_post(url: str, body: dict) -> None:
    try:
        httpx.post(url, json=body, headers=CLIENT, timeout=60)
    except httpx.HTTPError:
        pass


def bench_files(tmp: Path) -> dict:
    server = Serve(tmp / "files", "--workers", "0", "--no-preview")
    try:
        r = httpx.post(f"{server.url}/api/uploads", content=EXAMPLE.read_bytes(), headers=OCTET, timeout=60)
        uid = r.json()["upload_id"]
    finally:
        server.close()
    up = tmp / "files" / "uploads" / f"{uid}.bin"
    return {"data_dir_mode": oct(stat.S_IMODE((tmp / "files").stat().st_mode)),
            "upload_mode": oct(stat.S_IMODE(up.stat().st_mode))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", default="blender")
    ap.add_argument("--stalled", type=int, default=200)
    ap.add_argument("--only", default="rows,stalled,forwarded,kill,sigterm,files")
    args = ap.parse_args()
    chosen = set(args.only.split(","))
    results: dict = {"cpus": os.cpu_count(), "load_before": [round(x, 2) for x in os.getloadavg()]}
    with tempfile.TemporaryDirectory(prefix="bp-bench-attack-") as tmp_name:
        tmp = Path(tmp_name)
        steps = {"rows": lambda: bench_rows(tmp, args.renderer),
                 "stalled": lambda: bench_stalled(tmp, args.stalled),
                 "forwarded": lambda: bench_forwarded(tmp), "kill": lambda: bench_kill(tmp, args.renderer),
                 "sigterm": lambda: bench_sigterm(tmp, args.renderer), "files": lambda: bench_files(tmp)}
        for name, step in steps.items():
            if name in chosen:
                results[name] = step()
                print(json.dumps({name: results[name]}), flush=True)
    results["load_after"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
