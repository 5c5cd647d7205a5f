"""Several layers from one page (issue 35, item 6): a region table with a map over it (option ``map``) or
tracts, each layer with its own colour options (``regions_*``, ``map_*``, ``tracts_*``: the fields of
:class:`brainpainter.rendering.layers.LayerOptions`), through the real worker and preview processes with the
stand-in renderer (tests/test_web_maps.py's server)."""

from __future__ import annotations

import nibabel as nib
import numpy as np
import pytest
import test_web_maps
from test_web_maps import N5, morph, post, preview
from web_support import EXAMPLE, wait_for, zip_pngs

pytest.importorskip("fastapi")

from brainpainter.rendering.layers import LayerOptions
from brainpainter.rendering.options import option_names
from brainpainter.web.options import RenderOptions

#: The app of tests/test_web_maps.py (1 worker, the preview process, the stand-in renderer).
server = test_web_maps.server
#: Regions all red, the map all blue: a pixel of either colour is that layer's.
LAYERS = {"regions_gradient": "red,red", "map_gradient": "blue,blue", "map_label": "thickness (mm)"}


def upload_table(client) -> str:
    r = client.post("/api/uploads", params={"name": "dk.csv"}, content=EXAMPLE.read_bytes(),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return str(r.json()["upload_id"])


def upload_half_map(client, tmp_path) -> str:
    """lh: 1 on the first half of fsaverage5's vertices, NaN (no value: the regions show) on the rest."""
    lh = np.where(np.arange(N5) < N5 // 2, 1.0, np.nan)
    r = post(client, [("lh.thickness", morph(lh, tmp_path, "lh.thickness"))])
    assert r.status_code == 200, r.text
    return str(r.json()["upload_id"])


def upload_tracts(client, tmp_path, rows: int = 4) -> str:
    """AF_L.trk (20 streamlines, left) and its FA per row (0.4 to 0.7: the example table's 4 rows)."""
    from test_tracts import bundle, write

    write(tmp_path / "AF_L.trk", bundle(-30.0, n=20, z=30.0, length=60.0))
    fa = "AF_left\n" + "".join(f"{v:.2f}\n" for v in np.linspace(0.4, 0.7, rows))
    files = [("AF_L.trk", (tmp_path / "AF_L.trk").read_bytes()), ("fa.csv", fa.encode())]
    r = client.post("/api/tracts", params={"name": [n for n, _ in files], "size": [len(d) for _, d in files]},
                    content=b"".join(d for _, d in files),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return str(r.json()["upload_id"])


def shares(img: np.ndarray) -> tuple[float, float, float]:
    """Shares of opaque pixels that are red (regions), blue (the map) and a mix of both (purple)."""
    rgb = img[img[..., 3] > 0][:, :3].astype(int)
    r, g, b = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    red = (r > 200) & (b < 60) & (g < 60)
    blue = (b > 200) & (r < 60) & (g < 60)
    mixed = (r > 90) & (b > 90) & (g < 60)
    return float(red.mean()), float(blue.mean()), float(mixed.mean())


def test_every_layer_option_is_a_web_option_with_the_core_default_and_help():
    """The web API's layer options are LayerOptions' fields (no second definition)."""
    from dataclasses import fields

    for f in fields(LayerOptions):
        info = RenderOptions.model_fields[f.name]
        assert info.default == f.default and info.description == f.metadata["help"], f.name
    assert set(option_names(LayerOptions)) <= set(RenderOptions().run_kwargs())
    assert RenderOptions(map_alpha=0.5).layers_given() and not RenderOptions().layers_given()


def test_a_map_over_a_table_previews_checks_and_renders_two_layers(server, tmp_path):
    """Regions red, the map blue over half the left cortex: both show; at map_alpha 0.5 they mix; the check
    report and the job's manifest list both layers' scales, labelled."""
    table, lh = upload_table(server), upload_half_map(server, tmp_path)
    options = {**LAYERS, "map": lh}
    red, blue, _ = shares(preview(server, table, "lateral-left", **options))
    assert red > 0.1 and blue > 0.1, (red, blue)
    red, blue, mixed = shares(preview(server, table, "lateral-left", **options, map_alpha=0.5))
    assert mixed > 0.1 and blue < 0.02, (red, blue, mixed)

    c = server.post("/api/check", json={"upload_id": table, "options": options}).json()
    assert [(lay["kind"], lay["label"]) for lay in c["layers"]] == [("regions", "dk.csv"),
                                                                     ("map", "thickness (mm)")]
    assert c["layers"][1]["scale"]["ramp"][0] == "#0000ff" and c["layers"][0]["scale"]["ramp"][0] == "#ff0000"
    assert "--lh lh.thickness" in c["reproduce"]["command"]
    assert "--map-gradient blue,blue" in c["reproduce"]["command"]

    r = server.post("/api/jobs", json={"upload_id": table, "kind": "images", "options": {
        **options, "map_alpha": 1, "size": "64x48", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    pngs = zip_pngs(server.get(job["files"][-1]["url"]).content)
    assert len(pngs) == 4  # the table's 4 rows
    red, blue, _ = shares(next(iter(pngs.values())))
    assert red > 0.1 and blue > 0.1, (red, blue)
    manifest = server.get(f"{url}/files/manifest.json").json()
    layers = manifest["settings"]["layers"]
    assert [(lay["kind"], lay["label"]) for lay in layers] == [("regions", "dk.csv"),
                                                               ("map", "thickness (mm)")]
    assert "--lh lh.thickness" in manifest["reproduce"]["command"]


def test_a_table_alone_reports_its_layer_and_its_own_options(server):
    table = upload_table(server)
    c = server.post("/api/check", json={"upload_id": table, "options": {}}).json()
    assert [(lay["kind"], lay["label"]) for lay in c["layers"]] == [("regions", "dk.csv")]
    c = server.post("/api/check", json={"upload_id": table, "options": {"regions_cmap": "magma",
                                                                          "regions_label": "tau"}}).json()
    assert c["layers"][0]["label"] == "tau" and c["layers"][0]["scale"]["name"] == "magma"


@pytest.mark.parametrize("options, status, message", [
    ({"map": "0" * 32}, 404, "the map upload of option map was not found"),
    ({"map_cmap": "magma"}, 400, "--map-cmap colours the map, but this run draws none"),
    ({"map_alpha": 2}, 400, "--map-alpha must be a number from 0"),
    ({"regions_cmap": "nope"}, 400, "--regions-* options"),
    ({"tracts_label": "x" * 201}, 422, "tracts_label"),
])
def test_bad_layer_options_are_one_line(server, options, status, message):
    table = upload_table(server)
    r = server.post("/api/preview", json={"upload_id": table, "options": options})
    assert r.status_code == status, r.text
    err = r.json()["error"]
    assert message in err and "\n" not in err, err


def test_option_map_is_the_clients_own_map_and_not_a_table_or_a_map_under_a_map(server, tmp_path):
    """Another client's map upload is not found; a table as the map, a map as the main upload: one line."""
    table, lh = upload_table(server), upload_half_map(server, tmp_path)
    other = {"x-brainpainter-client": "another-client-0123456789abcdef0123"}
    mine = server.post("/api/uploads", params={"name": "t.csv"}, content=EXAMPLE.read_bytes(),
                       headers={"content-type": "application/octet-stream", **other}).json()["upload_id"]
    r = server.post("/api/preview", json={"upload_id": mine, "options": {"map": lh}}, headers=other)
    assert r.status_code == 404 and "option map was not found" in r.json()["error"]
    r = server.post("/api/preview", json={"upload_id": table, "options": {"map": table}})
    assert r.status_code == 404 and "option map was not found" in r.json()["error"]
    r = server.post("/api/preview", json={"upload_id": lh, "options": {"map": lh}})
    assert r.status_code == 400 and "the upload is a map or tractograms already" in r.json()["error"]


def test_a_job_keeps_its_own_copy_of_the_map(server, tmp_path):
    """The map upload is copied beside the job's input and charged to the disk budget with it."""
    table, lh = upload_table(server), upload_half_map(server, tmp_path)
    store = server.app.state.store
    r = server.post("/api/jobs", json={"upload_id": table, "kind": "images", "options": {
        **LAYERS, "map": lh, "size": "32x24", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    folder = store.job_dir(r.json()["id"])
    assert (folder / "map.bin").read_bytes() == store.get_upload(lh)[1]


def upload_mask(client, tmp_path) -> str:
    """A cluster mask over both hemispheres: 1 on the first half of fsaverage5's vertices, else 0."""
    mask = (np.arange(N5) < N5 // 2).astype(float)
    image = nib.MGHImage(mask.astype(np.float32).reshape(-1, 1, 1), np.eye(4))
    for h in ("lh", "rh"):
        nib.save(image, str(tmp_path / f"{h}.mask.mgh"))
    r = post(client, [(f"{h}.mask.mgh", (tmp_path / f"{h}.mask.mgh").read_bytes()) for h in ("lh", "rh")])
    assert r.status_code == 200, r.text
    return str(r.json()["upload_id"])


def test_a_contour_upload_goes_to_the_painter_the_job_and_the_command(server, tmp_path):
    """Option contour (a map upload): its iso-lines reach the preview's painter (Contours of the mask), a job
    keeps its copy, and the command draws it with --contour LH,RH and the levels."""
    from brainpainter.web.config import ServerConfig
    from brainpainter.web.pool import preview_request

    table, lh, mask = upload_table(server), upload_half_map(server, tmp_path), upload_mask(server, tmp_path)
    store = server.app.state.store
    options = {**LAYERS, "map": lh, "contour": mask, "contour_levels": "0.5"}
    req = preview_request(store.get_upload(table)[1], "dk.csv", RenderOptions(**options), 0, "lateral-left",
                          ServerConfig(), map_upload=store.get_upload(lh)[1],
                          contour_upload=store.get_upload(mask)[1])
    contours = req["contours"]
    assert contours.levels == (0.5,) and set(contours.values) == {"lh", "rh"}
    assert 0.3 < float(np.mean(contours.values["lh"] > 0.5)) < 0.7
    assert preview(server, table, "lateral-left", **options).shape == (120, 160, 4)
    c = server.post("/api/check", json={"upload_id": table, "options": options}).json()
    command = c["reproduce"]["command"]
    assert "--contour lh.mask.mgh,rh.mask.mgh" in command and "--contour-levels 0.5" in command, command
    r = server.post("/api/jobs", json={"upload_id": table, "kind": "images", "options": {
        **options, "size": "32x24", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    assert (store.job_dir(r.json()["id"]) / "contour.bin").read_bytes() == store.get_upload(mask)[1]
    r = server.post("/api/preview", json={"upload_id": table, "options": {"contour": table}})
    assert r.status_code == 404 and "option contour was not found" in r.json()["error"]


@pytest.mark.render
def test_the_preview_painter_draws_the_contour_lines(tmp_path):
    """The painter the preview process makes (PainterCache.get with the request's painter arguments, real
    Blender) draws the mask's edge as dark lines over the map; the same map without a contour has none."""
    pytest.importorskip("bpy")
    from brainpainter.rendering.views import get_view
    from brainpainter.web.maps import build_bundle
    from brainpainter.web.options import prepare
    from brainpainter.web.worker import PainterCache

    bundles = {}
    for name, values in (("map", np.full(N5, 2.0)), ("mask", (np.arange(N5) < N5 // 2).astype(float))):
        for h in ("lh", "rh"):
            nib.freesurfer.write_morph_data(str(tmp_path / f"{h}.{name}"), values.astype(np.float32))
        work = tmp_path / name
        work.mkdir()
        build_bundle(work, [(h, tmp_path / f"{h}.{name}") for h in ("lh", "rh")], 10)
        bundles[name] = (work / "bundle.bin").read_bytes()
    painters = PainterCache("blender")
    dark = []
    try:
        for contour in (None, bundles["mask"]):
            o = RenderOptions(size="320x240", gradient="white,white", vmin=0, vmax=1,
                              contour="0" * 32 if contour else None)
            prep = prepare(bundles["map"], "lh.map + rh.map", o, contour_upload=contour)
            painter = painters.get(prep.run.table.atlas, "pial", [], prep.run.settings, prep.coloring,
                                   **prep.painter_args())
            pixels = painter.paint_colors(prep.run.colors(0), get_view("lateral-left"))
            dark.append(int((pixels[..., :3].astype(int).max(-1) < 60).sum()))
    finally:
        painters.close()
    assert dark[0] < 20 and dark[1] > 200, dark


@pytest.mark.parametrize("kind, params", [("figure", {"format": "png", "dpi": 50}),
                                          ("movie", {"format": "gif", "frames_per_step": 1})])
def test_figure_and_movie_jobs_draw_a_map_over_the_table(server, tmp_path, kind, params):
    """A figure's and a movie's jobs take the layers as an images job does; their manifest's command too."""
    table, lh = upload_table(server), upload_half_map(server, tmp_path)
    r = server.post("/api/jobs", json={"upload_id": table, "kind": kind, kind: params, "options": {
        **LAYERS, "map": lh, "size": "64x48", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 180)
    assert job and job["status"] == "done", job
    manifest = server.get(f"{url}/files/manifest.json").json()
    command = manifest["reproduce"]["command"]
    assert command.startswith(f"brainpainter {kind} dk.csv") and "--lh lh.thickness" in command, command
    assert "--map-gradient blue,blue" in command


def test_a_job_is_charged_for_its_copy_of_the_map(tmp_path):
    """The job's copy of option map's upload counts against the disk budget with its input: a job that fits
    without it is refused with it (507), and nothing of it is kept."""
    from fastapi.testclient import TestClient

    from brainpainter.web.app import create_app
    from brainpainter.web.config import ServerConfig

    with TestClient(create_app(ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False))) as client:
        table = upload_table(client)
        noisy = np.random.default_rng(0).normal(2.0, 0.5, N5)  # 41 KB that do not compress away
        r = post(client, [("lh.thickness", morph(noisy, tmp_path, "lh.thickness"))])
        assert r.status_code == 200, r.text
        store = client.app.state.store
        sizes = [len(store.get_upload(u)[1]) for u in (table, r.json()["upload_id"])]
        assert sizes[1] > 5 * 4096, sizes
        store.budget.limit = store.budget.used(max_age_s=0) + 3 * 4096  # the table's copy fits, the map's not
        job = {"upload_id": table, "kind": "images", "options": {"map": r.json()["upload_id"]}}
        refused = client.post("/api/jobs", json=job)
        assert refused.status_code == 507 and "storage budget" in refused.json()["error"], refused.text
        assert not any((tmp_path / "data" / "jobs").iterdir())
        del job["options"]["map"]
        assert client.post("/api/jobs", json=job).status_code == 202


def test_tracts_with_a_table_get_their_own_scale_and_colour_bar(server, tmp_path):
    """Tracts given tracts_cmap/vmin/vmax are a layer of their own: the check report has two bars, the second
    the tracts' (magma over 0.3-0.7, labelled), and the command carries --tracts-cmap."""
    table, tracts = upload_table(server), upload_tracts(server, tmp_path)
    shared = server.post("/api/check", json={"upload_id": table, "options": {"tracts": tracts}}).json()
    assert [lay["kind"] for lay in shared["layers"]] == ["regions"]  # one scale over both: one bar
    options = {"tracts": tracts, "tracts_cmap": "magma", "tracts_vmin": 0.3, "tracts_vmax": 0.7,
               "tracts_label": "FA"}
    c = server.post("/api/check", json={"upload_id": table, "options": options}).json()
    assert [(lay["kind"], lay["label"]) for lay in c["layers"]] == [("regions", "dk.csv"), ("tracts", "FA")]
    bar = c["layers"][1]["scale"]
    assert (bar["name"], bar["vmin"], bar["vmax"]) == ("magma", 0.3, 0.7)
    assert "--tracts-cmap magma" in c["reproduce"]["command"]
    assert preview(server, table, "subcortical", **options).shape == (120, 160, 4)


def test_a_table_a_map_over_it_and_tracts_are_three_layers(server, tmp_path):
    """Regions, a map over them and tracts with their own colours: three bars, one job, one command."""
    table, lh = upload_table(server), upload_half_map(server, tmp_path)
    options = {**LAYERS, "map": lh, "tracts": upload_tracts(server, tmp_path), "tracts_cmap": "magma",
               "tracts_label": "FA"}
    c = server.post("/api/check", json={"upload_id": table, "options": options}).json()
    assert [(lay["kind"], lay["label"]) for lay in c["layers"]] == [
        ("regions", "dk.csv"), ("map", "thickness (mm)"), ("tracts", "FA")], c.get("error")
    command = c["reproduce"]["command"]
    assert "--lh lh.thickness" in command and "--tracts AF_L.trk" in command
    assert "--tracts-cmap magma" in command
    red, blue, _ = shares(preview(server, table, "lateral-left", **options))
    assert red > 0.1 and blue > 0.1, (red, blue)
    r = server.post("/api/jobs", json={"upload_id": table, "kind": "images", "options": {
        **options, "size": "64x48", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    layers = server.get(f"{url}/files/manifest.json").json()["settings"]["layers"]
    assert [lay["kind"] for lay in layers] == ["regions", "map", "tracts"]


def test_a_map_upload_takes_tracts_with_their_own_colours(server, tmp_path):
    """A map with tracts (option tracts, as render lh.thickness --tracts): two layers, two bars."""
    lh, tracts = upload_half_map(server, tmp_path), upload_tracts(server, tmp_path, rows=1)
    options = {"tracts": tracts, "tracts_cmap": "magma", "tracts_label": "FA", "map_label": "thickness"}
    c = server.post("/api/check", json={"upload_id": lh, "options": options}).json()
    assert [(lay["kind"], lay["label"]) for lay in c.get("layers", [])] == [("map", "thickness"),
                                                                             ("tracts", "FA")], c
    assert "--tracts AF_L.trk" in c["reproduce"]["command"]
    assert preview(server, lh, "subcortical", **options).shape == (120, 160, 4)
