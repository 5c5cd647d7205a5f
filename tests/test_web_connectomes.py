"""Connectomes on the ``brainpainter serve`` API (issue 36): a matrix upload (with a nodes file, node values
and categories) drawn alone or with a region table in one job; hostile matrices refused in one line.

Jobs and previews go through the real worker and preview processes with the stand-in renderer.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from test_connectome_read import mat_with, write_pconn
from web_support import standin_app, standin_site, wait_for

pytest.importorskip("fastapi")

MATRIX = b",Left-precentral,Right-precentral,Left-insula\nLeft-precentral,0,0.8,\n" \
         b"Right-precentral,0.8,0,-0.4\nLeft-insula,,-0.4,0\n"
NODES = b"name,x,y,z,strength\nLeft-precentral,-38,-10,50,1\nRight-precentral,38,-10,50,3\n" \
        b"Left-insula,-36,2,2,2\n"
TABLE = b"Image-name-unique,Left-Hippocampus,Right-Hippocampus\nsub1,0.5,0.5\n"
OPTS = {"size": "160x120", "atlas": "dk"}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A running app (1 worker, preview process) with the stand-in renderer."""
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     workers=1, max_jobs_per_client=50, rate_per_minute=100_000) as client:
        yield client


def post(client, files: list[tuple[str, bytes]], roles: list[str] | None = None):
    q: dict[str, list] = {"name": [n for n, _ in files]}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    if roles:
        q["role"] = roles
    return client.post("/api/connectomes", params=q, content=b"".join(d for _, d in files),
                       headers={"content-type": "application/octet-stream"})


def stored(client) -> tuple[int, list[str]]:
    """Uploads in the store, and the work folders left in incoming/ (none after a refused upload)."""
    store = client.app.state.store
    with store.connect() as db:
        n = db.execute("SELECT count(*) FROM uploads").fetchone()[0]
    return n, sorted(p.name for p in (store.root / "incoming").glob("*")
                     if not p.name.startswith(("tracts-", "connectome-")))


def job(client, body: dict) -> tuple[str, dict]:
    r = client.post("/api/jobs", json=body)
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    done = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert done and done["status"] == "done", done
    return url, done


def test_a_connectome_upload_is_kept_as_what_was_read(server):
    r = post(server, [("m.csv", MATRIX), ("nodes.csv", NODES), ("net.txt", b"motor\nmotor\nsalience\n")],
             ["matrix", "nodes", "node_categories"])
    assert r.status_code == 200, r.text
    assert r.json()["report"] == {"kind": "connectome", "summary": "3 nodes, 4 weights", "nodes": 3,
                                  "named": True, "edges": 4, "files": {
        "matrix": "m.csv", "nodes": "nodes.csv", "node_categories": "net.txt"}}
    data = server.app.state.store.get_upload(r.json()["upload_id"])[1]
    assert MATRIX not in data and b"\x93NUMPY" in data  # the matrix as a float32 .npy, not the upload


def test_a_connectome_alone_with_its_bars_the_command_and_a_job(server):
    uid = post(server, [("m.csv", MATRIX), ("nodes.csv", NODES)], ["matrix", "nodes"]).json()["upload_id"]
    opts = {**OPTS, "edge_threshold": "0.5", "edges_cmap": "viridis"}
    c = server.post("/api/check", json={"upload_id": uid, "options": opts})
    assert c.status_code == 200, c.text
    rep = c.json()
    assert [layer["kind"] for layer in rep["layers"]][:1] == ["edges"]
    assert rep["drawn"]["n_edges"] == 1  # |weight| >= 0.5: the precentral pair alone
    command = rep["reproduce"]["command"]
    assert "--connectome m.csv --nodes nodes.csv" in command and "--edge-threshold 0.5" in command
    assert "brainpainter render -o" in command  # no table: the connectome alone
    r = server.post("/api/preview", json={"upload_id": uid, "view": "dorsal", "options": opts})
    assert r.status_code == 200, r.text
    url, _ = job(server, {"upload_id": uid, "kind": "images", "options": opts})
    manifest = server.get(f"{url}/files/manifest.json").json()
    assert manifest["connectome"]["n_edges"] == 1
    assert [n["name"] for n in manifest["connectome"]["nodes"]] == ["Left-precentral", "Right-precentral",
                                                                   "Left-insula"]


def test_a_table_with_a_connectome_in_one_job(server):
    uid = post(server, [("m.csv", MATRIX), ("v.txt", b"1\n2\n3\n")], ["matrix", "node_values"]).json()[
        "upload_id"]
    table = server.post("/api/uploads", params={"name": "t.csv"}, content=TABLE,
                        headers={"content-type": "application/octet-stream"}).json()["upload_id"]
    opts = {**OPTS, "connectome": uid, "top_edges": 1}
    c = server.post("/api/check", json={"upload_id": table, "options": opts}).json()
    assert [(layer["kind"], layer["label"]) for layer in c["layers"]][1:] == [("edges", "m.csv"),
                                                                               ("nodes", "v.txt")]
    assert c["layers"][0]["kind"] == "regions"
    assert "brainpainter render t.csv" in c["reproduce"]["command"]
    assert "--connectome m.csv --node-values v.txt" in c["reproduce"]["command"]
    assert "--top-edges 1" in c["reproduce"]["command"]
    url, _ = job(server, {"upload_id": table, "kind": "images", "options": opts})
    manifest = server.get(f"{url}/files/manifest.json").json()
    assert manifest["connectome"]["n_edges"] == 1
    assert [n["value"] for n in manifest["connectome"]["nodes"]] == [1, 2, 3]


def test_a_connectome_option_names_only_a_connectome_upload(server):
    table = server.post("/api/uploads", params={"name": "t.csv"}, content=TABLE,
                        headers={"content-type": "application/octet-stream"}).json()["upload_id"]
    r = server.post("/api/check", json={"upload_id": table, "options": {**OPTS, "connectome": table}})
    assert r.status_code == 404 and "connectome upload" in r.json()["error"]


def huge_npy() -> bytes:
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                               "shape": (100_000, 100_000)})
    return buf.getvalue() + b"\0" * 64


@pytest.mark.parametrize("kind, message", [
    ("npy", "100000 x 100000"),
    ("mat", "90000 x 90000"),
    ("mat-compressed", "90000 x 90000"),
    ("pconn", "3 x 1000000000"),
    ("big", "has 1001 nodes; this server draws at most 1000"),
    ("square", "square"),
    ("count", "has 2 nodes but connectome matrix"),
    ("roles", "role node_values was given twice"),
])
def test_hostile_connectomes_are_one_line_400_and_store_nothing(server, tmp_path, kind, message):
    dims = np.array([3, 3], "<i4").tobytes()
    huge = np.array([90_000, 90_000], "<i4").tobytes()
    if kind == "npy":
        files = [("m.npy", huge_npy())]
    elif kind.startswith("mat"):
        files = [("m.mat", mat_with(tmp_path, kind.endswith("compressed"), dims, huge).read_bytes())]
    elif kind == "pconn":
        raw = bytearray(write_pconn(tmp_path / "m.pconn.nii").read_bytes())
        raw[56:72] = np.array([3, 10**9], "<i8").tobytes()
        files = [("m.pconn.nii", bytes(raw))]
    elif kind == "big":
        np.save(tmp_path / "b.npy", np.zeros((1001, 1001), np.float32))
        files = [("b.npy", (tmp_path / "b.npy").read_bytes())]
    elif kind == "square":
        files = [("m.csv", b"1,2,3,4\n5,6,7,8\n9,1,2,3\n")]
    elif kind == "count":
        files = [("m.csv", MATRIX), ("n.csv", b"name,x,y,z\na,1,2,3\nb,4,5,6\n")]
    else:
        files = [("m.csv", MATRIX), ("a.txt", b"1\n2\n3\n"), ("b.txt", b"1\n2\n3\n")]
    before = stored(server)
    r = post(server, files, ["matrix", "node_values", "node_values"] if kind == "roles" else None)
    assert r.status_code == 400, r.text
    err = r.json()["error"]
    assert message in err and "\n" not in err and "Traceback" not in err, err
    assert str(server.app.state.store.root) not in err, err
    assert stored(server) == before


def test_a_mat_matrix_is_read_too(server, tmp_path):
    scipy.io.savemat(tmp_path / "m.mat", {"W": np.array([[0, 0.5], [0.5, 0]])}, do_compression=True)
    r = post(server, [("m.mat", (tmp_path / "m.mat").read_bytes())])
    assert r.status_code == 200 and r.json()["report"]["edges"] == 2, r.text


def test_node_labels_are_options_of_the_api_and_its_command(server):
    uid = post(server, [("m.csv", MATRIX), ("nodes.csv", NODES)], ["matrix", "nodes"]).json()["upload_id"]
    opts = {**OPTS, "node_labels_top": 1}
    rep = server.post("/api/check", json={"upload_id": uid, "options": opts}).json()
    assert rep["drawn"]["labelled"] == ["Right-precentral"]  # the strongest: |0.8| + |-0.4|
    assert "--node-labels-top 1" in rep["reproduce"]["command"]
    bad = server.post("/api/check", json={"upload_id": uid, "options": {**OPTS, "node_labels_top": 0}})
    assert bad.status_code in (400, 422) and "node_labels_top" in bad.text


def test_node_labels_per_category_is_an_option_of_the_api_and_its_command(server):
    files = [("m.csv", MATRIX), ("nodes.csv", NODES), ("cats.txt", b"Vis\nVis\nDefault\n")]
    uid = post(server, files, ["matrix", "nodes", "node_categories"]).json()["upload_id"]
    opts = {**OPTS, "node_labels_top": 1}
    top = server.post("/api/check", json={"upload_id": uid, "options": opts}).json()
    each = server.post("/api/check", json={"upload_id": uid, "options": {
        **opts, "node_labels_per_category": True}})
    assert each.status_code == 200, each.text
    assert top["drawn"]["labelled"] == ["Right-precentral"]                       # the strongest of all
    assert each.json()["drawn"]["labelled"] == ["Right-precentral", "Left-insula"]  # each network's
    assert "--node-labels-per-category" in each.json()["reproduce"]["command"]
