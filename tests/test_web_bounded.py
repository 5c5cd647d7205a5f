"""``brainpainter serve``, round 5 (issue 46): no request holds a thread or the renderer for minutes, user
text is text, what is stored renders.

Each hostile upload and option of the review is posted to the app (stand-in renderer, real worker, preview
and request processes) and answered with a 4xx or a bounded result, never a 5xx.
"""

from __future__ import annotations

import io
import json
import logging
import shlex
import time

import numpy as np
import pytest
from test_web_cifti import cifti, left_cortex
from test_web_connectomes import MATRIX, NODES, OPTS, post, stored
from web_support import standin_app, standin_site, wait_for

pytest.importorskip("fastapi")
from nibabel.cifti2 import cifti2_axes as axes

from brainpainter.web.guard import SECURITY_HEADERS


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A running app (1 worker, preview process, 2 request processes) with the stand-in renderer."""
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     workers=1, max_jobs_per_client=50, rate_per_minute=100_000) as client:
        yield client


def finished(client, body: dict, timeout: float = 120) -> dict:
    r = client.post("/api/jobs", json=body)
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    done = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j, timeout)
    assert done, f"the job did not finish in {timeout} s"
    return {**done, "url": url}


def dlabel(tmp_path, n_labels: int, name_chars: int, colour=(1.0, 0.0, 0.0, 1.0)) -> bytes:
    """A left-cortex fsLR dlabel of `n_labels` labels, each named with `name_chars` characters."""
    rng = np.random.default_rng(0)
    table = {0: ("???", (0, 0, 0, 0))}
    for k in range(1, n_labels + 1):
        rgb = tuple(rng.random(3)) if k > 1 else colour[:3]
        table[k] = (f"{k:05d}" + "x" * max(0, name_chars - 5), (*rgb, 1.0))
    labels = (np.arange(32492) % n_labels + 1)[None]
    return cifti(tmp_path, "p.dlabel.nii", labels, axes.LabelAxis(["p"], [table]), left_cortex())


def upload(client, name: str, data: bytes) -> str:
    r = client.post("/api/uploads", params={"name": name}, content=data,
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return r.json()["upload_id"]


# -- 1: a figure of a label map of thousands of long names ----------------------------------------
def test_a_figure_of_8000_long_labels_is_laid_out_in_seconds(server, tmp_path):
    """Before: sizing the PNG laid out 8000 names of 900 characters on a server thread for more than 20
    minutes. The key is summarised (a count, no names) and the job is planned in seconds."""
    uid = upload(server, "p.dlabel.nii", dlabel(tmp_path, 8000, 900))
    t0 = time.perf_counter()
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "figure", "options": {"size": "160x120"},
                                       "figure": {"format": "png", "dpi": 100}})
    took = time.perf_counter() - t0
    assert r.status_code == 202, r.text
    assert took < 15, f"planning the figure took {took:.1f} s"
    c = server.post("/api/check", json={"upload_id": uid, "options": {}})
    assert c.status_code == 200 and len(c.content) < 300_000, len(c.content)  # item 7: the echo is bounded
    key = c.json()["layers"][0]["scale"]
    assert key["n_categories"] == 8000 and len(key["categories"]) == 256
    assert {len(k["name"]) for k in key["categories"]} == {200}


def test_request_work_past_its_time_limit_is_killed_and_the_process_replaced():
    """A call that runs past the limit fails with one line in about the limit; the next call runs."""
    from brainpainter.web.work_processes import WorkProcesses, WorkTooSlow

    procs = WorkProcesses(1, time_limit_s=2.0)
    procs.start()
    try:
        assert procs.submit(abs, -3).result(timeout=60) == 3  # warm
        first = procs.pids()
        t0 = time.perf_counter()
        with pytest.raises(WorkTooSlow, match="limit of 2 s"):
            procs.submit(time.sleep, 60).result(timeout=30)
        assert time.perf_counter() - t0 < 10
        assert procs.submit(abs, -4).result(timeout=60) == 4
        assert procs.pids() != first  # the slow one was killed, a new one took its place
        with pytest.raises(ValueError, match="invalid literal"):  # an error comes back as itself
            procs.submit(int, "x").result(timeout=30)
    finally:
        procs.stop()


# -- 2: a dense connectome, long node labels ------------------------------------------------------
def dense(n: int) -> bytes:
    rng = np.random.default_rng(1)
    w = rng.random((n, n)).astype(np.float32) + 0.01
    w = (w + w.T) / 2
    buf = io.BytesIO()
    np.save(buf, w)
    return buf.getvalue()


def test_a_dense_connectome_draws_the_strongest_5000_edges(server):
    """Before: 499,500 edges were drawn (42 s, 3.7 GB, MemoryError); now the strongest 5000, with a
    note, and top_edges is at most 5000."""
    uid = post(server, [("m.npy", dense(1000)), ("nodes.csv", nodes(1000))], ["matrix", "nodes"]).json()[
        "upload_id"]
    c = server.post("/api/check", json={"upload_id": uid, "options": OPTS})
    assert c.status_code == 200, c.text
    assert c.json()["drawn"]["n_edges"] == 5000 and c.json()["drawn"]["edges_left_out"] == 494_500
    t0 = time.perf_counter()
    p = server.post("/api/preview", json={"upload_id": uid, "view": "dorsal", "options": OPTS})
    assert p.status_code == 200, p.text
    assert time.perf_counter() - t0 < 60
    bad = server.post("/api/check", json={"upload_id": uid, "options": {**OPTS, "top_edges": 1_000_000}})
    assert bad.status_code == 422 and "top_edges" in bad.text


def nodes(n: int, name_chars: int = 0) -> bytes:
    rows = ["name,x,y,z"] + [f"n{i:04d}{'y' * name_chars},{-60 + i % 120},{-80 + i % 160},{i % 60}"
                              for i in range(n)]
    return "\n".join(rows).encode()


def test_long_node_labels_are_cut_and_the_echo_is_bounded(server):
    """Before: 50 labels of 100,000 characters held the preview 120 s (killed) and an images job 341 s; a
    check of 60 nodes with 100 KB names answered 5 MB."""
    m = np.full((60, 60), 0.5, np.float32)
    buf = io.BytesIO()
    np.save(buf, m)
    uid = post(server, [("m.npy", buf.getvalue()), ("nodes.csv", nodes(60, 100_000))],
               ["matrix", "nodes"]).json()["upload_id"]
    opts = {**OPTS, "node_labels": True}
    c = server.post("/api/check", json={"upload_id": uid, "options": opts})
    assert c.status_code == 200 and len(c.content) < 200_000, (c.status_code, len(c.content))
    t0 = time.perf_counter()
    assert server.post("/api/preview", json={"upload_id": uid, "view": "dorsal", "options": opts}
                       ).status_code == 200
    job = finished(server, {"upload_id": uid, "kind": "images", "options": {**opts, "views": "dorsal"}})
    assert job["status"] == "done", job
    assert time.perf_counter() - t0 < 90
    manifest = server.get(f"{job['url']}/files/manifest.json").json()
    assert {len(n["label"]) for n in manifest["connectome"]["nodes"]} == {60}  # cut, ending in an ellipsis


# -- 3: user text is text; every error has its headers ---------------------------------------------
@pytest.mark.parametrize("text", [r"$\undefinedmacro$", "$" + "{" * 98 + "$"])
def test_mathtext_in_titles_and_labels_is_drawn_as_text(server, tmp_path, text):
    uid = upload(server, "p.dlabel.nii", dlabel(tmp_path, 3, 5))
    job = finished(server, {"upload_id": uid, "kind": "figure",
                            "options": {"size": "160x120", "views": "lateral-left", "map_label": text},
                            "figure": {"format": "png", "dpi": 50, "title": text, "label": text}})
    assert job["status"] == "done", job
    table = upload(server, "t.csv", b"Image-name-unique,Left-Hippocampus\n" + text.encode() + b",1\nb,2\n")
    movie = finished(server, {"upload_id": table, "kind": "movie", "options": {"size": "96x72"},
                              "movie": {"format": "gif", "frames_per_step": 1, "title": text, "label": text}})
    assert movie["status"] == "done", movie


def test_a_label_colour_of_nan_is_refused_at_upload(server, tmp_path):
    r = server.post("/api/uploads", params={"name": "p.dlabel.nii"},
                    content=dlabel(tmp_path, 3, 5, colour=(float("nan"), 0.0, 0.0, 1.0)),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 400 and "number from 0 to 1" in r.json()["error"], r.text
    assert "\n" not in r.json()["error"]


def test_an_unexpected_error_is_500_with_the_headers_and_logged_as_500(server, monkeypatch, caplog):
    store = server.app.state.store

    def broken(*args, **kwargs):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(store, "get_upload", broken)
    with caplog.at_level(logging.INFO, logger="brainpainter.web.access"):
        r = server.post("/api/check", json={"upload_id": "0" * 32, "options": {}})
    assert r.status_code == 500 and r.json() == {"error": "internal error: ZeroDivisionError (logged on the "
                                                          "server)"}
    for name, value in SECURITY_HEADERS:
        assert r.headers[name.decode()] == value.decode()
    lines = [json.loads(rec.getMessage()) for rec in caplog.records if rec.name == "brainpainter.web.access"]
    assert [line["status"] for line in lines if line["path"] == "/api/check"] == [500]


# -- 4: figures and exports of a connectome uploaded alone -----------------------------------------
@pytest.mark.parametrize("kind", ["figure", "export"])
def test_a_connectome_alone_makes_figures_and_exports(server, kind):
    uid = post(server, [("m20.csv", MATRIX), ("nodes20.csv", NODES)], ["matrix", "nodes"]).json()[
        "upload_id"]
    job = finished(server, {"upload_id": uid, "kind": kind, "options": {**OPTS, "views": "dorsal"}})
    assert job["status"] == "done", job


# -- 5: what is stored renders --------------------------------------------------------------------
@pytest.mark.parametrize("role, body, message", [
    ("node_values", b"1\ninf\n3\n", "not a number"),
    ("node_values", b"1\nabc\n3\n", "not a number"),
    ("node_values", b"1\n2\n", "has 2 entries but the connectome has 3 nodes"),
    ("node_categories", b"a\nb\n", "has 2 entries but the connectome has 3 nodes"),
])
def test_bad_node_files_are_400_at_upload(server, role, body, message):
    before = stored(server)
    r = post(server, [("m.csv", MATRIX), ("v.txt", body)], ["matrix", role])
    assert r.status_code == 400 and message in r.json()["error"], r.text
    err = r.json()["error"]
    assert "\n" not in err and "incoming" not in err and "DATA_DIR" not in err, err
    assert stored(server) == before


def test_weights_beyond_float32_are_400_at_upload(server):
    buf = io.BytesIO()
    np.save(buf, np.array([[0, 1e308], [1e308, 0]]))
    r = post(server, [("m.npy", buf.getvalue())])
    assert r.status_code == 400 and "float32" in r.json()["error"], r.text
    assert "incoming" not in r.json()["error"]


def test_a_category_with_a_quote_round_trips(server):
    uid = post(server, [("m.csv", MATRIX), ("nodes.csv", NODES), ("c.txt", b'x"y\nmotor\nmotor\n')],
               ["matrix", "nodes", "node_categories"]).json()["upload_id"]
    job = finished(server, {"upload_id": uid, "kind": "images", "options": {**OPTS, "views": "dorsal"}})
    assert job["status"] == "done", job
    manifest = server.get(f"{job['url']}/files/manifest.json").json()
    assert [n["category"] for n in manifest["connectome"]["nodes"]] == ['x"y', "motor", "motor"]


# -- 6: control characters never reach the command to copy ----------------------------------------
def test_control_characters_are_escaped_in_the_command(server):
    uid = post(server, [("m.csv", MATRIX), ("nodes.csv", NODES)], ["matrix", "nodes"]).json()["upload_id"]
    label = "a\x1b[201~b\x03c\rd"
    c = server.post("/api/check", json={"upload_id": uid, "options": {**OPTS, "edges_label": label}})
    assert c.status_code == 200, c.text
    command = c.json()["reproduce"]["command"]
    assert not any(ord(ch) < 32 or 127 <= ord(ch) < 160 for ch in command), repr(command)
    assert "--edges-label $'a\\x1b[201~b\\x03c\\x0dd'" in command
    assert f"edges_label={label!r}" in c.json()["reproduce"]["python"]  # escaped; the same string when run
    assert not any(ord(ch) < 32 and ch != "\n" for ch in c.json()["reproduce"]["python"])
    words = shlex.split(command.replace("$'a\\x1b[201~b\\x03c\\x0dd'", "LABEL"))
    assert words[words.index("--edges-label") + 1] == "LABEL"  # one shell word


def test_no_server_path_in_a_message(tmp_path):
    """A file of the data folder is named by its name (before: ``DATA_DIR/incoming/connectome-.../m.npy``)."""
    from brainpainter.web.config import no_paths

    said = f"connectome matrix '{tmp_path}/incoming/connectome-ab12/matrix.npy' is damaged (in {tmp_path})"
    assert no_paths(said, tmp_path) == "connectome matrix 'matrix.npy' is damaged (in DATA_DIR)"


def test_sigterm_stops_a_server_busy_with_a_hostile_request_within_seconds(tmp_path):
    """Before: a figure request of a label map of 8000 long names survived SIGTERM (its thread kept the
    interpreter alive at exit) until SIGKILL."""
    import signal
    import threading

    import httpx
    from web_support import CLIENT, STANDIN, Server, alive, env_with_site

    site = standin_site(tmp_path / "site")
    server = Server(tmp_path / "data", env_with_site(site), tmp_path / "server.log",
                    ["--workers", "1", "--no-preview", "--renderer", STANDIN])
    server.start()
    labels = dlabel(tmp_path, 8000, 900)
    sent = threading.Event()

    def hostile() -> None:
        try:
            with httpx.Client(base_url=server.url, headers=CLIENT, timeout=600) as c:
                uid = c.post("/api/uploads", params={"name": "p.dlabel.nii"}, content=labels,
                             headers={"content-type": "application/octet-stream"}).json()["upload_id"]
                sent.set()
                figure = {"upload_id": uid, "kind": "figure", "options": {"size": "160x120"},
                          "figure": {"format": "png"}}
                for _ in range(20):
                    c.post("/api/jobs", json=figure)
        except httpx.HTTPError:
            pass  # the server stopped under it

    thread = threading.Thread(target=hostile, daemon=True)
    thread.start()
    try:
        assert sent.wait(120)
        time.sleep(1.0)
        t0 = time.monotonic()
        server.proc.send_signal(signal.SIGTERM)
        server.proc.wait(timeout=30)
        assert time.monotonic() - t0 < 15
        assert wait_for(lambda: not alive(server.proc.pid), 5)
    finally:
        server.stop()
