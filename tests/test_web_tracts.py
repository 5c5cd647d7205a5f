"""Tracts on the ``brainpainter serve`` API (issue 24): tractogram uploads drawn with a table, or alone.

Bundles are written with nibabel in tmp_path (test_tracts.bundle: streamlines along y at a given x).
Jobs and most previews go through the real worker and preview processes with the stand-in renderer
(which paints each value-coloured bundle's colour in a stripe); one preview is drawn by Blender and
its pixels are checked where the bundles project.
"""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest
from test_tracts import bundle, write
from web_support import png_pixels, standin_app, standin_site, wait_for

pytest.importorskip("fastapi")

RED, BLUE = (255, 0, 0), (0, 0, 255)
#: Two subcortical regions at 0.5: purple on the red-blue gradient, apart from the bundles' red and blue.
TABLE = b"Image-name-unique,Left-Hippocampus,Right-Hippocampus\nsub1,0.5,0.5\n"
OPTS = {"tracts_space": "template", "gradient": "red,blue", "vmin": 0, "vmax": 1, "size": "160x120"}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A running app (1 worker, preview process) with the stand-in renderer and small tract caps."""
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     workers=1, max_jobs_per_client=50, rate_per_minute=100_000, max_tract_streamlines=500,
                     max_tract_files=6) as client:
        yield client


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, bytes]:
    """AF_L.trk (left, x=-30) and CST_R.tck (right, x=+30), 40 streamlines each, and a values table."""
    folder = tmp_path_factory.mktemp("bundles")
    write(folder / "AF_L.trk", bundle(-30.0, n=40, z=30.0, length=60.0))
    write(folder / "CST_R.tck", bundle(30.0, n=40, seed=1, z=30.0, length=60.0))
    write(folder / "many.trk", bundle(0.0, n=600, seed=2))
    out = {p.name: p.read_bytes() for p in folder.iterdir()}
    out["fa.csv"] = b"AF_left,CST_right\n0,1\n"
    return out


def post(client, files: list[tuple[str, bytes]], route: str = "/api/tracts"):
    q = {"name": [n for n, _ in files]}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    return client.post(route, params=q, content=b"".join(d for _, d in files),
                       headers={"content-type": "application/octet-stream"})


def zipped(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


def near(img: np.ndarray, rgb, tol: int = 12) -> np.ndarray:
    return np.abs(img[..., :3].astype(int) - np.array(rgb)).max(-1) <= tol


def stored(client) -> tuple[int, list[str]]:
    """Uploads in the store, and the work folders left in incoming/ (none after a refused upload)."""
    store = client.app.state.store
    with store.connect() as db:
        n = db.execute("SELECT count(*) FROM uploads").fetchone()[0]
    return n, sorted(p.name for p in (store.root / "incoming").glob("*") if not p.name.startswith("tracts-"))


# -- uploads and their report ----------------------------------------------------------------------
def test_tract_upload_reports_what_is_drawn(server, files):
    r = post(server, [("AF_L.trk", files["AF_L.trk"]), ("CST_R.tck", files["CST_R.tck"])])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["kind"] == "tracts"
    assert rep["summary"] == "tracts: AF_left, CST_right (80 streamlines of 80)"
    assert [b["name"] for b in rep["bundles"]] == ["AF_left", "CST_right"] and rep["values"] is None


def test_a_zip_with_a_folder_and_a_values_table(server, files):
    data = zipped({"bundles/AF_L.trk": files["AF_L.trk"], "bundles/CST_R.tck": files["CST_R.tck"],
                   "bundles/fa.csv": files["fa.csv"], "__MACOSX/._AF_L.trk": b"junk",
                   "README.md": np.random.default_rng(0).bytes(100_000)})  # > 64 KiB: an upload's limits
    r = post(server, [("bundles.zip", data)])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"] == ("tracts: AF_left, CST_right (80 streamlines of 80); values: fa.csv (one value "
                              "per bundle)")
    assert rep["values"]["bundles"] == ["AF_left", "CST_right"]
    assert rep["notes"] == ["ignored (not a tractogram or a table): README.md"]


# -- with a table, through the worker and preview processes (stand-in renderer) -------------------------
def test_a_table_with_tracts_previews_and_renders_them(server, files):
    t = post(server, [("AF_L.trk", files["AF_L.trk"]), ("CST_R.tck", files["CST_R.tck"]),
                      ("fa.csv", files["fa.csv"])]).json()["upload_id"]
    table = server.post("/api/uploads", params={"name": "t.csv"}, content=TABLE,
                        headers={"content-type": "application/octet-stream"}).json()["upload_id"]
    # the check report's colour bar is the scale over the regions and the bundles (0.5, and 0 and 1)
    free = {**OPTS, "gradient": None, "cmap": "viridis", "vmin": None, "vmax": None}
    c = server.post("/api/check", json={"upload_id": table, "options": {**free, "tracts": t}}).json()
    assert (c["values"]["scale"]["vmin"], c["values"]["scale"]["vmax"]) == (0, 1)
    c = server.post("/api/check", json={"upload_id": table, "options": free}).json()
    assert c["values"]["scale"]["vmin"] != 0  # the regions alone: 0.5
    # the cortex hidden: a cortex view draws its hemisphere's bundles alone (the stand-in: their stripes)
    opts = {**OPTS, "tracts": t, "views": "lateral-left", "cortex": "hidden"}
    for view, rgb in (("lateral-left", RED), ("lateral-right", BLUE)):  # AF_left = 0, CST_right = 1
        r = server.post("/api/preview", json={"upload_id": table, "view": view, "options": opts})
        assert r.status_code == 200, r.text
        assert near(png_pixels(r.content), rgb).mean() > 0.99
    # without the tracts: nothing of theirs
    r = server.post("/api/preview", json={"upload_id": table, "view": "lateral-left",
                                          "options": {**opts, "tracts": None}})
    assert near(png_pixels(r.content), RED).sum() == 0
    r = server.post("/api/jobs", json={"upload_id": table, "kind": "images", "options": opts})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    manifest = server.get(f"{url}/files/manifest.json").json()
    assert [b["name"] for b in manifest["tracts"]["bundles"]] == ["AF_left", "CST_right"]
    png = server.get(f"{url}/files/{manifest['files'][0]['file']}").content
    assert near(png_pixels(png), RED).mean() > 0.99
    assert (server.app.state.store.job_dir(job["id"]) / "tracts.bin").is_file()  # the job's own copy


def test_tracts_alone_with_their_values_and_a_figure(server, files):
    data = zipped({"AF_L.trk": files["AF_L.trk"], "CST_R.tck": files["CST_R.tck"], "fa.csv": files["fa.csv"]})
    uid = post(server, [("b.zip", data)]).json()["upload_id"]
    c = server.post("/api/check", json={"upload_id": uid, "options": OPTS}).json()
    assert c["kind"] == "tracts" and c["scale"]["vmin"] == 0 and c["scale"]["vmax"] == 1
    r = server.post("/api/preview", json={"upload_id": uid, "view": "lateral-right",
                                          "options": {**OPTS, "cortex": "hidden"}})
    assert r.status_code == 200, r.text
    assert near(png_pixels(r.content), BLUE).mean() > 0.99
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "figure", "figure": {"format": "png"},
                                       "options": {**OPTS, "views": "subcortical"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    assert server.get(job["files"][0]["url"]).content.startswith(b"\x89PNG")
    # tracts alone without a values table: one line says what to do
    bare = post(server, [("AF_L.trk", files["AF_L.trk"])]).json()["upload_id"]
    r = server.post("/api/preview", json={"upload_id": bare, "options": OPTS})
    assert r.status_code == 400 and "table of bundle values" in r.json()["error"]


def test_profiles_and_a_movie_of_two_rows(server, files):
    """An along-tract profile table (long: subject, bundle, node, value) in the upload: the report says
    so, and a movie goes through its two rows (key frames) with the tracts alone."""
    rows = ["subject,bundle,node,fa"] + [f"{s},{b},{k},{k / 9 if s == 'a' else 1 - k / 9:.3f}"
                                         for s in "ab" for b in ("AF_L", "CST_R") for k in range(10)]
    data = zipped({"AF_L.trk": files["AF_L.trk"], "CST_R.tck": files["CST_R.tck"],
                   "profiles.csv": "\n".join(rows).encode()})
    r = post(server, [("b.zip", data)])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"].endswith("values: profiles.csv (profiles of 10 nodes)")
    assert rep["values"]["images"] == ["a", "b"]
    uid = r.json()["upload_id"]
    r = server.post("/api/preview", json={"upload_id": uid, "row": "b", "view": "lateral-left",
                                          "options": {**OPTS, "cortex": "hidden"}})
    assert r.status_code == 200, r.text
    img = png_pixels(r.content)  # the stand-in: one stripe per node of AF_left, 1 (blue) to 0 (red)
    assert near(img[:, 0], BLUE).all() and near(img[:, -1], RED).all()
    assert not near(img[:, img.shape[1] // 2], RED, 40).any()  # in between: neither end's colour
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "movie",
                                       "movie": {"format": "gif", "frames_per_step": 2, "fps": 4},
                                       "options": {**OPTS, "views": "subcortical", "size": "80x60"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 180)
    assert job and job["status"] == "done", job
    assert server.get(job["files"][0]["url"]).content.startswith(b"GIF8")


# -- the painter cache ------------------------------------------------------------------------------
def test_two_tract_uploads_never_share_a_painter(server, files):
    from brainpainter.web.config import ServerConfig
    from brainpainter.web.options import RenderOptions
    from brainpainter.web.pool import preview_request
    from brainpainter.web.tracts import report_of
    from brainpainter.web.worker import painter_key

    store = server.app.state.store
    a = post(server, [("AF_L.trk", files["AF_L.trk"])]).json()["upload_id"]
    b = post(server, [("AF_L.trk", files["AF_L.trk"]), ("CST_R.tck", files["CST_R.tck"])]).json()["upload_id"]
    c = post(server, [("AF_L.trk", files["AF_L.trk"])]).json()["upload_id"]  # the same files as a
    data = TABLE

    def key(tracts_id: str | None, **opts) -> tuple:
        tracts = None if tracts_id is None else store.get_upload(tracts_id)[1]
        if tracts is not None:
            assert report_of(tracts)["kind"] == "tracts"
        o = RenderOptions(**{**OPTS, "tracts": tracts_id, **opts})
        req = preview_request(data, "t.csv", o, 0, "subcortical", ServerConfig(), tracts=tracts,
                              data_dir=store.root)
        return painter_key(req["atlas"], req["surface"], req["hidden"], req["settings"], req["coloring"],
                           req["contours"], req["layers"])

    ka, kb, kc = key(a), key(b), key(c)
    assert ka != kb and ka == kc  # content addressed: the same files may share, different ones never
    assert key(None) != ka
    assert key(a, max_streamlines=10) != ka and key(a, tract_radius=1.0) != ka
    assert key(a, tracts_affine="1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1") != ka


# -- errors: one line, 4xx, nothing stored ------------------------------------------------------------
@pytest.mark.parametrize("upload, status, message", [
    ([("AF_L.trk", b"not a tractogram at all\n" * 20)], 400, "could not be read by nibabel"),
    ([("notes.csv", b"a,b\n1,2\n")], 422, "is not a tractogram"),
    ([("b.zip", "traversal")], 400, "a path outside the zip"),
    ([("b.zip", b"PK\x03\x04 not really a zip")], 400, "is not a readable zip file"),
    ([("many.trk", "many")], 400, "hold 600 streamlines; this server reads at most 500"),
    ([("b.zip", "seven")], 400, "holds 7 files; this server reads at most 6"),
    ([("AF_L.trk", "AF"), ("AF_left.tck", "CST")], 400, "bundle 'AF_left' was given twice"),
])
def test_bad_tract_uploads_are_one_line_4xx_and_store_nothing(server, files, upload, status, message):
    def content(kind):
        if kind == "traversal":
            return zipped({"../../evil/AF_L.trk": files["AF_L.trk"]})
        if kind == "seven":
            return zipped({f"b{i}.trk": files["AF_L.trk"] for i in range(7)})
        return {"many": files["many.trk"], "AF": files["AF_L.trk"], "CST": files["CST_R.tck"]}.get(kind, kind)

    before = stored(server)
    r = post(server, [(n, content(k)) for n, k in upload])
    assert r.status_code == status, r.text
    err = r.json()["error"]
    assert message in err and "\n" not in err and "Traceback" not in err, err
    assert str(server.app.state.store.root) not in err and "DATA_DIR" not in err, err
    assert stored(server) == before


def test_a_tractogram_sent_as_a_table_and_bad_options(server, files):
    r = post(server, [("AF_L.trk", files["AF_L.trk"])], route="/api/uploads")
    assert r.status_code == 422 and "POST /api/tracts" in r.json()["error"]
    table = server.post("/api/uploads", params={"name": "t.csv"}, content=TABLE,
                        headers={"content-type": "application/octet-stream"}).json()["upload_id"]
    t = post(server, [("AF_L.trk", files["AF_L.trk"])]).json()["upload_id"]

    def err(**opts) -> tuple[int, str]:
        r = server.post("/api/preview", json={"upload_id": table, "options": {**OPTS, "tracts": t, **opts}})
        return r.status_code, r.json()["error"]

    code, msg = err(tracts_affine="1 0 0 0 0 1 0 0 0 0 1 0 5 5 5 5")
    assert code == 400 and msg.startswith("--tracts-affine holds") and "last row 0 0 0 1" in msg, msg
    assert err(tracts=table)[0] == 404  # a table is not a tract upload
    assert err(tracts="0" * 32)[0] == 404
    assert err(cortex="see-through")[0] == 422
    assert err(max_streamlines=10**9)[0] == 422
    code, msg = err(tract_radius=50)
    assert code == 400 and "--tract-radius must be 0.01 to 10" in msg


def test_a_table_cannot_pose_as_a_stored_tract_upload(server):
    from brainpainter.web.tracts import MAGIC

    r = server.post("/api/uploads", params={"name": "t.csv"}, content=MAGIC + b'{"files": []}\n',
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 400 and "is not a table" in r.json()["error"]


def test_zip_inflation_is_bounded(tmp_path, monkeypatch):
    from brainpainter.errors import BrainPainterError
    from brainpainter.web import tracts

    (tmp_path / "b.zip").write_bytes(zipped({"AF_L.trk": b"\0" * (1 << 21)}))
    (tmp_path / "out").mkdir()
    monkeypatch.setattr(tracts, "MAX_UNZIPPED", 1 << 20)
    with pytest.raises(BrainPainterError, match="inflates to more than 1 MB"):
        tracts.unzip(tmp_path / "b.zip", tmp_path / "out", 10)


def test_a_zip_of_subject_folders_draws_the_chosen_subject(server, files):
    """dipy's minimal_bundles.zip layout (sub_1/AF_L.trk, ... sub_10/...): the first subject in natural
    order by default, another chosen by ``subject``; the report lists them; an unknown one is one line."""
    subjects = {f"sub_{i}": files["many.trk"] if i == 2 else files["AF_L.trk"] for i in (10, 2, 1)}
    data = zipped({f"{s}/{n}": d for s, d in subjects.items() for n in ("AF_L.trk", "CST_R.trk")}
                  | {"sub_1/": b""})
    r = post(server, [("minimal_bundles.zip", data)])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["subjects"] == ["sub_1", "sub_2", "sub_10"] and rep["subject"] == "sub_1"
    assert rep["summary"] == "tracts: AF_left, CST_right (80 streamlines of 80); subject sub_1 of 3"
    r = server.post("/api/tracts", params={"name": "minimal_bundles.zip", "subject": "sub_10"}, content=data,
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200 and r.json()["report"]["subject"] == "sub_10", r.text
    before = stored(server)
    r = server.post("/api/tracts", params={"name": "minimal_bundles.zip", "subject": "sub_3"}, content=data,
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 400 and r.json()["error"] == (
        "subject 'sub_3' is not a folder of 'minimal_bundles.zip'; its subject folders are 'sub_1', 'sub_2', "
        "'sub_10'. Choose one of them (or leave subject out)."), r.text
    assert stored(server) == before


# -- drawn by Blender: the bundles' colours where they project ------------------------------------------
@pytest.mark.render
def test_blender_preview_draws_each_bundle_in_its_colour_on_its_side(tmp_path_factory, files):
    data = zipped({"AF_L.trk": files["AF_L.trk"], "CST_R.tck": files["CST_R.tck"], "fa.csv": files["fa.csv"]})
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     renderer="blender", workers=0, rate_per_minute=100_000) as client:
        uid = post(client, [("b.zip", data)]).json()["upload_id"]
        opts = {**OPTS, "size": "320x240", "shading": "flat", "quality": "fast", "glass_opacity": 0.0,
                "tract_radius": 1.0}
        r = client.post("/api/preview", json={"upload_id": uid, "view": "subcortical-dorsal",
                                              "options": opts})
        assert r.status_code == 200, r.text
    img = png_pixels(r.content)
    red, blue = near(img, RED), near(img, BLUE)
    assert red.sum() > 100 and blue.sum() > 100, (red.sum(), blue.sum())
    # seen from above, the image's right is the subject's right: AF_left (x=-30) left of CST_right (x=+30)
    assert np.nonzero(red)[1].mean() < img.shape[1] / 2 < np.nonzero(blue)[1].mean()
