"""The ``brainpainter serve`` API through FastAPI's TestClient (in-process; loopback only).

Rendering goes through the real worker and preview processes with the stand-in
renderer (an installed entry point), so these tests need no Blender.
"""

from __future__ import annotations

import json
import logging
import re
from html.parser import HTMLParser

import numpy as np
import pytest
from bad_inputs import corpus
from web_support import EXAMPLE, png_pixels, standin_app, standin_site, wait_for, zip_pngs

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient

from brainpainter.web.app import create_app
from brainpainter.web.config import ServerConfig
from brainpainter.web.store import Store

SMALL = {"size": "64x48", "views": "lateral-left,subcortical"}


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return standin_site(tmp_path_factory.mktemp("site"))


@pytest.fixture(scope="module")
def server(tmp_path_factory, site):
    """A running app (1 worker, preview process) with the stand-in renderer."""
    with standin_app(site, tmp_path_factory.mktemp("data"), workers=1, max_jobs_per_client=50,
                     rate_per_minute=100_000, max_upload_mb=10) as client:
        yield client


def upload(client, data: bytes, name: str = "table.csv", **params) -> dict:
    r = client.post("/api/uploads", params={"name": name, **params}, content=data,
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return r.json()


def run_job(client, upload_id: str, options: dict, kind: str = "images", **extra) -> dict:
    r = client.post("/api/jobs", json={"upload_id": upload_id, "kind": kind, "options": options, **extra})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := client.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job, client.get(url).json()
    return job


# -- the page and the probes ----------------------------------------------------------------
class _Scripts(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.problems: list[str] = []
        self.scripts: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "script":
            if not a.get("src"):
                self.problems.append("inline <script>")
            self.scripts.append(a.get("src", ""))
        self.problems += [f"{tag} {k}=" for k in a if k.startswith("on") or k == "style"]
        for k in ("src", "href"):
            if a.get(k, "").startswith(("http:", "https:", "//")):
                self.problems.append(f"external {a[k]}")


def test_page_is_self_contained_under_a_strict_csp(server):
    r = server.get("/")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    csp = r.headers["content-security-policy"]
    assert "default-src 'none'" in csp and "script-src 'self'" in csp and "unsafe" not in csp
    assert r.headers["x-content-type-options"] == "nosniff" and r.headers["x-frame-options"] == "DENY"
    parser = _Scripts()
    parser.feed(r.text)
    assert parser.problems == [] and parser.scripts == ["/static/app.js"]
    js = server.get("/static/app.js").text
    assert "eval(" not in js and "new Function" not in js and "innerHTML" not in js
    assert "http" not in js.replace("http://www.w3.org/2000/svg", "")
    css = server.get("/static/style.css").text
    assert "@import" not in css and "url(http" not in css
    # the bundled example is the repository's example, byte for byte
    assert server.get("/static/brainpainter_dk.csv").content == EXAMPLE.read_bytes()


def test_probes_schema_and_meta(server):
    assert server.get("/healthz").json() == {"status": "ok"}
    ready = server.get("/readyz")
    assert ready.status_code == 200 and ready.json()["checks"] == {"database": True, "disk": True,
                                                                   "workers": True, "preview": True}
    schema = server.get("/openapi.json").json()
    assert {"/api/uploads", "/api/check", "/api/preview", "/api/jobs", "/api/jobs/{job_id}",
            "/api/jobs/{job_id}/files/{file_name}", "/healthz", "/readyz"} <= set(schema["paths"])
    props = schema["components"]["schemas"]["RenderOptions"]["properties"]
    assert props["glass_opacity"]["default"] == 0.12
    # no size: 1200x900, which an atlas of another shape (the mouse) reshapes, as on the CLI
    assert props["size"].get("default") is None and "1200x900" in props["size"]["description"]
    assert props["nan_color"]["default"] == "#8c8c8c" and props["lighting"]["default"] == "studio"
    meta = server.get("/api/meta").json()
    assert "dk" in meta["atlases"] and "viridis" in meta["cmaps"] and "subcortical" in meta["views"]
    # no views: the run's own (a table's three, a map's both hemispheres), as on the CLI
    assert meta["defaults"]["views"] is None
    assert "lateral-left,medial-left,subcortical" in props["views"]["description"]
    assert server.get("/docs").status_code == 404  # Swagger UI would load scripts from a CDN


# -- upload = check ----------------------------------------------------------------------
def test_upload_returns_the_check_report_of_the_cli(server, tmp_path):
    from brainpainter.table.region_table import inspect_table
    from brainpainter.table.report import check_report

    got = upload(server, EXAMPLE.read_bytes(), "brainpainter_dk.csv")
    want = check_report(inspect_table(EXAMPLE))
    report = got["report"]
    assert re.fullmatch(r"[0-9a-f]{32}", got["upload_id"])
    assert report["ok"] and report["atlas"] == want["atlas"] and report["n_images"] == 4
    assert got["images"] == ["stage-1", "stage-2", "stage-3", "stage-4"]
    assert report["names"] == [{**n, "source": "brainpainter_dk.csv"} for n in want["names"]]
    assert report["values"] == want["values"]


def test_pasted_tab_separated_text_and_options(server):
    text = "Image-name-unique\tLeft-insula\tRight-insula\nA\t1\t2\nB\t3\t0\n"
    got = upload(server, text.encode(), "pasted.tsv", atlas="dk")
    assert got["report"]["atlas"]["inferred"] is False and got["report"]["n_images"] == 2
    r = server.post("/api/check", json={"upload_id": got["upload_id"],
                                        "options": {"cmap": "viridis", "vmin": 0, "vmax": 3}})
    assert r.status_code == 200 and r.json()["values"]["scale"]["name"] == "viridis"


def _check_params(args: list[str]) -> tuple[list[str], dict]:
    from brainpainter.cli.render import check

    ctx = check.make_context("check", list(args), resilient_parsing=False)
    p = ctx.params
    params = {k: p[k] for k in ("atlas", "image_column", "value", "region_column") if p.get(k)}
    if p.get("strict"):
        params["strict"] = "true"
    return [str(i) for i in p["inputs"]], params


# File-system cases have no upload equivalent: the server never opens a path a user gives.
NOT_UPLOADS = {"missing-file", "device-file", "same-region-in-two-inputs", "named-and-numbered-inputs",
               "second-input-empty"}


@pytest.mark.parametrize("case", corpus.params([c for c in corpus.CASES if c.id not in NOT_UPLOADS]))
def test_bad_input_corpus_through_the_upload_path(server, case, tmp_path, monkeypatch, request):
    store: Store = server.app.state.store
    for k, v in case.env.items():
        monkeypatch.setenv(k, v)
    corpus.write(case, tmp_path, request.getfixturevalue("big_files") if corpus.is_big(case) else None)
    stand_in = case.command == "render" and case.args[-len(corpus.STAND_IN):] == corpus.STAND_IN
    inputs, params = _check_params(case.args[: -len(corpus.STAND_IN)] if stand_in else case.args)
    assert len(inputs) == 1
    data = (tmp_path / inputs[0]).read_bytes()
    before_uploads = sorted(p.name for p in (store.root / "uploads").iterdir())
    before_jobs = store.counts()
    r = server.post("/api/uploads", params={"name": inputs[0], **params}, content=data,
                    headers={"content-type": "application/octet-stream"})
    if case.command == "render" and r.status_code == 200:  # check accepts it; render (the job) must not
        uid = r.json()["upload_id"]
        before_uploads.append(f"{uid}.bin")
        r = server.post("/api/jobs", json={"upload_id": uid, "options": {"size": "64x48"}})
    assert 400 <= r.status_code < 500, (r.status_code, r.text[:300])
    body = r.json()
    assert set(body) == {"error"} and "\n" not in body["error"] and len(body["error"]) < 600
    assert case.message in body["error"], body["error"]
    assert "Traceback" not in r.text
    assert sorted(p.name for p in (store.root / "uploads").iterdir()) == sorted(before_uploads)
    assert store.counts() == before_jobs  # nothing stored


@pytest.mark.parametrize("options, message", [
    ({"views": "lateral-lft"}, "Did you mean 'lateral-left'?"),
    ({"size": "big"}, "--size must be WIDTHxHEIGHT"),
    ({"size": "9000x10"}, "width must be between 16 and 8192"),
    ({"glass_opacity": 2}, "glass opacity must be in [0, 1]"),
    ({"gradient": "white,notacolour"}, "notacolour"),
    ({"gradient": "white,red", "cmap": "viridis"}, "give either a gradient or a colour map, not both"),
    ({"cmap": "viridiss"}, "viridis"),
    ({"hide": ["cerebelum"]}, "Did you mean 'cerebellum'?"),
    ({"image_column": "subject"}, "--image-column 'subject' is not a column"),
    ({"lighting": "disco"}, "option 'options.lighting'"),
    ({"colour": "red"}, "option 'options.colour': Extra inputs are not permitted"),
])
def test_bad_options_give_the_cli_messages(server, options, message):
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    for path in ("/api/jobs", "/api/preview"):
        r = server.post(path, json={"upload_id": uid, "options": options})
        assert r.status_code in (400, 422), r.text
        assert set(r.json()) == {"error"} and message in r.json()["error"], r.json()
        assert "\n" not in r.json()["error"]


def test_unknown_ids_and_foreign_files_are_not_served(server):
    r = server.post("/api/preview", json={"upload_id": "../../jobs.sqlite3", "options": {}})
    assert r.status_code == 404 and "upload not found" in r.json()["error"]
    for path in ("/api/jobs/" + "0" * 32, "/api/jobs/xyz", "/api/jobs/..%2F..%2Fjobs.sqlite3"):
        assert server.get(path).status_code == 404
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    job = run_job(server, uid, {**SMALL, "views": "lateral-left"})
    base = job["url"] + "/files/"
    for name in ("input.bin", "..%2Finput.bin", "../input.bin", "%2E%2E%2Fjobs.sqlite3", "manifest.jsonx"):
        r = server.get(base + name)
        assert r.status_code == 404, (name, r.status_code)
    assert server.get(base + "manifest.json").json()["input"]["n_images"] == 4


# -- preview and jobs ------------------------------------------------------------------------
def test_preview_follows_the_options(server):
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]

    def preview(**options):
        r = server.post("/api/preview", json={"upload_id": uid, "row": "stage-4", "view": "lateral-left",
                                              "options": {"size": "800x600", **options}})
        assert r.status_code == 200 and r.headers["content-type"] == "image/png", r.text
        assert int(r.headers["x-render-ms"]) >= 0
        return png_pixels(r.content)

    warm = preview()
    assert warm.shape == (360, 480, 4)  # scaled to the preview width, same aspect
    reds = preview(gradient="white,red")
    blues = preview(gradient="white,blue")
    assert not np.array_equal(reds, blues)
    assert reds[..., 0].mean() > reds[..., 2].mean() and blues[..., 2].mean() > blues[..., 0].mean()
    r = server.post("/api/preview", json={"upload_id": uid, "row": 9, "options": {}})
    assert r.status_code == 400 and r.json()["error"] == "row must be 0..3; 9 was given."


def test_render_all_job_makes_every_png_and_a_zip(server):
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    job = run_job(server, uid, {**SMALL, "gradient": "white,red"})
    assert job["status"] == "done" and job["progress"] == job["total"] == 8 and job["attempt"] == 1
    names = [f["name"] for f in job["files"]]
    assert names[-1].endswith(".zip") and "manifest.json" in names
    manifest = server.get(job["files"][names.index("manifest.json")]["url"]).json()
    assert manifest["reproduce"]["command"] == ("brainpainter render table.csv -o brainpainter-out --views "
                                                "lateral-left,subcortical --gradient white,red --size 64x48")
    zipped = zip_pngs(server.get(job["files"][-1]["url"], params={"download": 1}).content)
    assert sorted(zipped) == sorted(n for n in names if n.endswith(".png"))
    assert sorted(zipped) == sorted(f"stage-{i}_{v}.png" for i in range(1, 5)
                                    for v in ("lateral-left", "subcortical"))
    for pixels in zipped.values():
        assert pixels.shape == (48, 64, 4) and (pixels[..., 3] == 255).all()
    # stage-4 is redder than stage-1 (larger values on a white..red gradient)
    green = {n: p[..., 1].mean() for n, p in zipped.items()}
    assert green["stage-4_lateral-left.png"] < green["stage-1_lateral-left.png"]
    r = server.get(job["files"][-1]["url"], params={"download": 1})
    assert r.headers["content-disposition"].startswith("attachment")
    events = [e["event"] for e in server.app.state.store.events(job["id"])]
    assert events == ["queued", "started", "done"]


@pytest.mark.parametrize("kind, params, suffix, magic", [
    ("figure", {"figure": {"format": "pdf"}}, ".pdf", b"%PDF"),
    ("movie", {"movie": {"format": "gif", "frames_per_step": 2}}, ".gif", b"GIF8"),
])
def test_figure_and_movie_jobs(server, kind, params, suffix, magic):
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    job = run_job(server, uid, {"size": "80x60", "views": "lateral-left"}, kind=kind, **params)
    assert job["status"] == "done", job
    f, manifest = job["files"]
    assert f["name"].endswith(suffix) and server.get(f["url"]).content.startswith(magic)
    # the download carries the command that makes it again (issue 38, item 4)
    made = server.get(manifest["url"]).json()
    assert made["file"] == f["name"] and made[kind] == job_params(params[kind], kind)
    more = " --frames-per-step 2" if kind == "movie" else ""
    assert made["reproduce"]["command"] == (f"brainpainter {kind} table.csv -o {f['name']} --views "
                                            f"lateral-left --size 80x60{more}")


def test_export_job_writes_a_row_as_an_interactive_page(server):
    """Issue 38, item 8: the page's "Interactive 3D (HTML)" is the CLI's export of the row shown."""
    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    job = run_job(server, uid, {"size": "80x60", "views": "lateral-left", "gradient": "white,red"},
                  kind="export", export={"row": 3})
    assert job["status"] == "done", job
    f, manifest = job["files"]
    assert f["name"] == "stage-4.html"
    page = server.get(f["url"], params={"download": 1})
    assert page.headers["content-disposition"].startswith("attachment")
    assert b"<title>stage-4</title>" in page.content and b"three" in page.content
    made = server.get(manifest["url"]).json()
    assert made["reproduce"]["command"] == ("brainpainter export table.csv -o stage-4.html --gradient "
                                            "white,red --format html --row stage-4")
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "export", "options": {},
                                       "export": {"row": 4}})
    assert r.status_code == 400 and r.json()["error"] == "row must be 0..3; 4 was given.", r.text


def job_params(given: dict, kind: str) -> dict:
    """A figure's or movie's parameters as the job keeps them (the API's defaults filled in)."""
    from brainpainter.web.options import FigureParams, MovieParams

    return (FigureParams if kind == "figure" else MovieParams)(**given).model_dump()


def test_movie_job_counts_frames_and_the_options_have_the_cli_defaults(server):
    """A movie job's progress is per frame (total = frames), not 0/1; figure and movie options default to
    the CLI's (frames per step 24, dpi 300), and the API documents them."""
    from brainpainter.media.layout import FigureOptions
    from brainpainter.media.movie import MovieOptions

    uid = upload(server, EXAMPLE.read_bytes())["upload_id"]
    job = run_job(server, uid, {"size": "64x48", "views": "lateral-left"}, kind="movie",
                  movie={"format": "gif", "frames_per_step": 3, "hold": 1, "easing": "smooth"})
    assert job["status"] == "done", job
    n_keys = 4  # the example table's rows
    assert job["total"] == (n_keys - 1) * 3 + 1 + n_keys * 1 and job["progress"] == job["total"], job
    schema = server.get("/openapi.json").json()["components"]["schemas"]
    movie, figure = schema["MovieParams"]["properties"], schema["FigureParams"]["properties"]
    assert movie["frames_per_step"]["default"] == MovieOptions().frames_per_step == 24
    assert movie["hold"]["default"] == 0 and movie["easing"]["default"] == "linear"
    assert figure["dpi"]["default"] == FigureOptions().dpi and "fig_width" in figure and "font_size" in figure
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "movie", "movie": {"frames_per_step": 0}})
    assert r.status_code in (400, 422) and "frames_per_step" in r.text


def test_access_log_is_one_json_line_per_request(server, caplog):
    with caplog.at_level(logging.INFO, logger="brainpainter.web.access"):
        server.get("/healthz", headers={"x-test": "1"})
    lines = [json.loads(r.getMessage()) for r in caplog.records if r.name == "brainpainter.web.access"]
    assert lines and lines[-1]["path"] == "/healthz" and lines[-1]["status"] == 200
    assert {"t", "id", "client", "method", "ms", "bytes_in", "bytes_out"} <= set(lines[-1])


# -- limits (a server without workers: jobs stay queued) -----------------------------------------
@pytest.fixture
def limited(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, max_jobs_per_client=2,
                          max_queued=3, rate_per_minute=40, max_upload_mb=0.01, max_images=6,
                          max_pixels=100 * 100)
    with TestClient(create_app(config)) as client:
        yield client


def test_limits_answer_with_clear_4xx_and_503(limited):
    big = b"Image-name-unique,Left-insula\n" + b"A,1\n" * 4000
    r = limited.post("/api/uploads", content=big)
    assert r.status_code == 413 and "MB is read, to keep memory bounded" in r.json()["error"]
    assert list((limited.app.state.store.root / "uploads").iterdir()) == []
    small = b"Image-name-unique,Left-insula\nA,1\nB,2\n"
    uid = upload(limited, small)["upload_id"]
    r = limited.post("/api/jobs", json={"upload_id": uid, "options": {"size": "200x200"}})
    assert r.status_code == 400 and "at most 10000 pixels" in r.json()["error"]
    r = limited.post("/api/jobs", json={"upload_id": uid, "options": {"size": "50x50", "views": "all"}})
    assert r.status_code == 400 and "at most 6 per job" in r.json()["error"]
    ok = {"upload_id": uid, "options": {"size": "50x50"}}
    assert [limited.post("/api/jobs", json=ok).status_code for _ in range(3)] == [202, 202, 429]
    r = limited.post("/api/jobs", json=ok)
    assert r.status_code == 429 and "at most 2 at once" in r.json()["error"] and r.headers["retry-after"]
    codes = [limited.post("/api/check", json={"upload_id": uid}).status_code for _ in range(30)]
    assert codes.count(429) > 0
    r = limited.post("/api/check", json={"upload_id": uid})
    assert r.status_code == 429 and int(r.headers["retry-after"]) >= 1 and "a minute" in r.json()["error"]


def test_queue_limit_gives_503(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "d", workers=0, preview=False, max_queued=2,
                          max_jobs_per_client=10, rate_per_minute=10_000)
    with TestClient(create_app(config)) as client:
        uid = upload(client, b"Image-name-unique,Left-insula\nA,1\n")["upload_id"]
        ok = {"upload_id": uid, "options": {"size": "50x50"}}
        codes = [client.post("/api/jobs", json=ok).status_code for _ in range(3)]
        assert codes == [202, 202, 503]
        r = client.post("/api/jobs", json=ok)
        assert "jobs waiting" in r.json()["error"] and r.headers["retry-after"] == "30"
        r = client.post("/api/preview", json=ok)
        assert r.status_code == 503 and "without the preview process" in r.json()["error"]


def test_json_bodies_are_bounded(limited):
    r = limited.post("/api/check", content=b'{"upload_id": "' + b"a" * 100_000 + b'"}',
                     headers={"content-type": "application/json"})
    assert r.status_code == 413 and "request body" in r.json()["error"]


def test_cancel_frees_the_clients_slot(limited):
    uid = upload(limited, b"Image-name-unique,Left-insula\nA,1\n")["upload_id"]
    ok = {"upload_id": uid, "options": {"size": "50x50"}}
    first, second = (limited.post("/api/jobs", json=ok).json() for _ in range(2))
    assert limited.post("/api/jobs", json=ok).status_code == 429
    r = limited.delete(first["url"])
    assert r.status_code == 200 and r.json()["status"] == "cancelled"
    assert limited.post("/api/jobs", json=ok).status_code == 202
    assert limited.get(second["url"]).json()["status"] == "queued"


def test_check_with_the_preview_shown_gives_its_command(server):
    """Issue 44 item 18: /api/check with the preview's row and view answers its command beside the run's."""
    got = upload(server, b"Image-name-unique,Left-insula,Right-insula\nA,1,2\nB,3,0\n", "t.csv")
    r = server.post("/api/check", json={"upload_id": got["upload_id"], "options": SMALL,
                                        "preview": {"row": "B", "view": "dorsal"}})
    assert r.status_code == 200, r.text
    report = r.json()
    assert report["reproduce"]["command"].endswith("--views lateral-left,subcortical --size 64x48")
    assert report["reproduce_preview"]["command"] == ("brainpainter render t.csv -o brainpainter-out --size "
                                                      "64x48 --rows B --views dorsal")
    assert "rows='B'" in report["reproduce_preview"]["python"]
    plain = server.post("/api/check", json={"upload_id": got["upload_id"], "options": SMALL}).json()
    assert "reproduce_preview" not in plain
