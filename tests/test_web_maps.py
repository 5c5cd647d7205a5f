"""Maps on the ``brainpainter serve`` API (issue 21): hemisphere pairs and MNI152 volumes as uploads.

Rendering goes through the real worker and preview processes with the stand-in
renderer (as tests/test_web_api.py), which paints each cortex vertex's colour in
a stripe: pixels show where the map has colour.
"""

from __future__ import annotations

import gzip
import io

import nibabel as nib
import numpy as np
import pytest
from web_support import png_pixels, standin_app, standin_site, wait_for, zip_pngs

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient

from brainpainter.web.app import create_app
from brainpainter.web.config import ServerConfig
from brainpainter.web.maps import file_name, is_bundle

N5 = 10242
SMALL = {"size": "64x48", "views": "lateral-left,lateral-right"}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A running app (1 worker, preview process) with the stand-in renderer."""
    with standin_app(standin_site(tmp_path_factory.mktemp("site")), tmp_path_factory.mktemp("data"),
                     workers=1, max_jobs_per_client=50, rate_per_minute=100_000, max_upload_mb=10,
                     max_map_images=20) as client:
        yield client


def morph(values, tmp_path, name: str) -> bytes:
    path = tmp_path / name
    nib.freesurfer.write_morph_data(str(path), np.asarray(values, np.float32))
    return path.read_bytes()


def post(client, files: list[tuple[str, bytes]], **params):
    q = {"name": [n for n, _ in files], **params}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    return client.post("/api/uploads", params=q, content=b"".join(d for _, d in files),
                       headers={"content-type": "application/octet-stream"})


def mni_volume(n_volumes: int = 0, voxel: float = 4.0) -> bytes:
    """A NIfTI in MNI152 space (nibabel's writer): 5 in a 20 mm ball at (-50, -20, 10), left lateral
    cortex, 0 elsewhere; `n_volumes` > 0: a 4-D series of it."""
    origin = np.array([-90.0, -126.0, -72.0])
    shape = tuple(int(s) for s in np.ceil(np.array([182, 218, 182]) / voxel))
    affine = np.diag([voxel, voxel, voxel, 1.0])
    affine[:3, 3] = origin
    xyz = np.indices(shape).reshape(3, -1).T * voxel + origin
    vol = np.zeros(shape, np.float32)
    vol.reshape(-1)[np.linalg.norm(xyz - [-50, -20, 10], axis=1) < 20] = 5.0
    data = vol if not n_volumes else np.repeat(vol[..., None], n_volumes, axis=3)
    img = nib.Nifti1Image(data, affine)
    img.header.set_sform(affine, 1)
    return gzip.compress(img.to_bytes(), compresslevel=1)


def preview(client, uid: str, view: str, **options) -> np.ndarray:
    r = client.post("/api/preview", json={"upload_id": uid, "row": 0, "view": view,
                                          "options": {"size": "160x120", **options}})
    assert r.status_code == 200 and r.headers["content-type"] == "image/png", r.text
    return png_pixels(r.content)


def colourful(img: np.ndarray) -> float:
    """Share of opaque pixels with a saturated colour (the underlay is grey)."""
    rgb = img[..., :3].astype(int)
    sat = rgb.max(-1) - rgb.min(-1)
    return float((sat[img[..., 3] > 0] > 40).mean())


# -- names -------------------------------------------------------------------------------------
def test_client_file_names_are_only_labels():
    assert file_name("../../x/lh.thickness") == "lh.thickness"
    assert file_name("C:\\data\\my map.func.gii") == "my_map.func.gii"
    assert file_name(".hidden.nii.gz") == "hidden.nii.gz"
    assert "/" not in file_name("a/../../b") and file_name("...") == "image"


# -- a pair of hemisphere files --------------------------------------------------------------------
def test_map_pair_upload_preview_and_render_job(server, tmp_path):
    """lh +2, rh -2 (a signed map: RdBu_r about 0): the left cortex red, the right blue."""
    files = [("lh.thickness", morph(np.full(N5, 2.0), tmp_path, "lh.thickness")),
             ("rh.thickness", morph(np.full(N5, -2.0), tmp_path, "rh.thickness"))]
    r = post(server, files)
    assert r.status_code == 200, r.text
    j = r.json()
    assert j["name"] == "lh.thickness + rh.thickness" and j["images"] == ["thickness"]
    assert j["report"]["kind"] == "map"
    assert j["report"]["summary"] == "map: lh.thickness + rh.thickness, fsaverage5, 1 image"
    stored = server.app.state.store.get_upload(j["upload_id"])
    assert stored is not None and is_bundle(stored[1])
    uid = j["upload_id"]

    left, right = preview(server, uid, "lateral-left"), preview(server, uid, "lateral-right")
    assert (left[..., 3] == 255).mean() > 0.9  # the brain is drawn
    for img, hot, cold in ((left, 0, 2), (right, 2, 0)):
        coloured = img[..., :3].astype(int)
        assert colourful(img) > 0.5
        assert coloured[..., hot].mean() > coloured[..., cold].mean() + 40
    # above the threshold only: everything shows the (grey) underlay
    assert colourful(preview(server, uid, "lateral-left", threshold=3)) < 0.02
    # the check report carries the colour bar of the options
    c = server.post("/api/check", json={"upload_id": uid, "options": {"threshold": 1}}).json()
    assert c["kind"] == "map" and c["values"]["scale"]["name"] == "RdBu_r"
    assert c["values"]["scale"]["threshold"] == 1 and len(c["values"]["scale"]["ramp"]) == 32
    assert c["values"]["range"] == [-2.0, 2.0]

    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "images", "options": SMALL})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    zipped = zip_pngs(server.get(job["files"][-1]["url"]).content)
    assert sorted(zipped) == ["thickness_lateral-left.png", "thickness_lateral-right.png"]
    left = zipped["thickness_lateral-left.png"].astype(int)
    assert left.shape == (48, 64, 4) and left[..., 0].mean() > left[..., 2].mean() + 40
    manifest = server.get(f"{url}/files/manifest.json").json()
    assert manifest["input"]["kind"] == "vertex map"


def test_a_flat_view_previews_the_map_on_the_flat_maps(server, tmp_path):
    """The preview of a flat view (not among the options' views) colours the sheets' vertices."""
    files = [("lh.thickness", morph(np.full(N5, 2.0), tmp_path, "lh.thickness")),
             ("rh.thickness", morph(np.full(N5, -2.0), tmp_path, "rh.thickness"))]
    uid = post(server, files).json()["upload_id"]
    assert colourful(preview(server, uid, "flat", views="lateral-left")) > 0.5
    assert colourful(preview(server, uid, "flat-left")) > 0.5


def test_one_hemisphere_and_a_figure_job(server, tmp_path):
    v = np.linspace(0, 1, N5)
    gii = nib.gifti.GiftiImage(darrays=[nib.gifti.GiftiDataArray(a.astype(np.float32)) for a in (v, 1 - v)])
    r = post(server, [("sub-01_hemi-L_effect.func.gii", gii.to_bytes())])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["hemis"] == ["lh"] and rep["n_images"] == 2 and "2 images" in rep["summary"]
    uid = r.json()["upload_id"]
    right = preview(server, uid, "lateral-right")
    assert colourful(right) < 0.02  # no rh map: the underlay only
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": "figure", "figure": {"format": "png"},
                                       "options": {"size": "80x60", "views": "lateral-left"}})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    assert server.get(job["files"][0]["url"]).content.startswith(b"\x89PNG")


def test_gzipped_gifti_pair_uploads_and_previews(server):
    """nilearn ships fsaverage5 maps as .gii.gz (issue 33 item 9): read as a map, not as a table."""
    from test_gifti import gifti_xml

    files = [(f"{h}.thick.func.gii.gz", gzip.compress(gifti_xml(np.full(N5, v)))) for h, v in (("lh", 2.0),
                                                                                                ("rh", -2.0))]
    r = post(server, files)
    assert r.status_code == 200, r.text
    summary = r.json()["report"]["summary"]
    assert summary == "map: lh.thick.func.gii.gz + rh.thick.func.gii.gz, fsaverage5, 1 image", summary
    assert r.json()["images"] == ["thick"]
    assert colourful(preview(server, r.json()["upload_id"], "lateral-left")) > 0.5


def test_a_gifti_that_names_another_file_reads_nothing_and_tells_nothing(server, tmp_path):
    """``Encoding="ExternalFileBinary"`` made the reader draw any file of the server, and its error told
    whether a path exists (issue 33 item 1): no data outside the upload is read, the answer is the same."""
    from test_gifti import external_xml

    secret = tmp_path / "secret.bin"
    np.arange(N5, dtype=np.float32).tofile(secret)
    answers = []
    for name in (str(secret), str(tmp_path / "missing.bin"), "../../../secret.bin", "lh.x.bin"):
        r = post(server, [("lh.x.func.gii", external_xml(name))])
        assert r.status_code == 400, r.text
        answers.append(r.json()["error"].replace(repr(name[:80]), "NAME"))  # long names are cut
    assert len(set(answers)) == 1, "\n".join(answers)
    assert answers[0].startswith("map file 'lh.x.func.gii' keeps its data in another file (NAME, "), answers


# -- a volume ----------------------------------------------------------------------------------
def _figure_job(server, uid: str, figure: dict, views: str = "lateral-left") -> dict:
    body = {"upload_id": uid, "kind": "figure", "options": {"size": "64x48", "views": views},
            "figure": {"format": "png", **figure}}
    r = server.post("/api/jobs", json=body)
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job, "the job did not finish"
    return job


def test_a_volume_uploads_figure_holds_its_slice_and_glass_brain_panels(server, tmp_path):
    """Issue 45: the page's figure job shows the volume upload's slices and projections (the bundle keeps
    the NIfTI), on the map's colour bar."""
    uid = post(server, [("zstat1.nii.gz", mni_volume())]).json()["upload_id"]
    plain = _figure_job(server, uid, {"dpi": 100})
    job = _figure_job(server, uid, {"dpi": 100, "slices": ["z=10"], "projections": "z"})
    assert plain["status"] == job["status"] == "done", job
    images = [png_pixels(server.get(j["files"][0]["url"]).content) for j in (plain, job)]
    assert images[1].shape[1] > images[0].shape[1]             # two panels beside the view
    rgb = images[1][..., :3].astype(int)
    grey = (rgb.max(-1) - rgb.min(-1) < 6) & (rgb[..., 0] > 60) & (rgb[..., 0] < 240)  # the template's greys
    assert grey.sum() > 2000
    ball = (rgb.max(-1) - rgb.min(-1) > 60)[: int(0.8 * rgb.shape[0])]    # coloured pixels above the bar:
    assert ball[:, images[0].shape[1]:].sum() > 50                 # in the panels, right of the view's width
    failed = _figure_job(server, post(server, [("lh.thickness", morph(np.ones(N5), tmp_path, "lh.x"))]
                                      ).json()["upload_id"], {"slices": ["z=10"]})
    assert failed["status"] == "failed" and "show a volume in MNI152" in failed["error"], failed


def test_volume_upload_is_projected_onto_the_cortex(server):
    r = post(server, [("zstat1.nii.gz", mni_volume())])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"].startswith("volume: zstat1.nii.gz (MNI152, 46x55x46) projected onto fsaverage")
    assert rep["hemis"] == ["lh", "rh"] and r.json()["images"] == ["zstat1"]
    uid = r.json()["upload_id"]
    # the blob lies in the left lateral cortex: colour there (threshold 1: the zeros show the underlay)
    left = colourful(preview(server, uid, "lateral-left", threshold=1))
    right = colourful(preview(server, uid, "lateral-right", threshold=1))
    assert left > 0.01 and right < 0.005, (left, right)
    # the subcortical structures take the volume's mean inside each (0 here: the scale's first colour),
    # as with --volume on the command line; without it they would be the neutral grey
    assert colourful(preview(server, uid, "subcortical")) > 0.02


# -- errors and limits ----------------------------------------------------------------------------
@pytest.mark.parametrize("files, message", [
    ([("lh.x.npy", "npy1000")], "1000"),
    ([("x.npy", "npy10242")], "cannot tell the hemisphere of 'x.npy'"),
    ([("lh.a.npy", "npy10242"), ("lh.b.npy", "npy10242")], "are the lh hemisphere"),
    ([("lh.thickness", "junk")], "map file 'lh.thickness'"),
    ([("vol.nii.gz", "junk")], "not a readable gzip file"),
    ([("a.csv", "junk"), ("b.csv", "junk")], "'a.csv' is not a map file"),
    ([("lh.a.npy", "npy10242"), ("rh.a.npy", "npy10242"), ("lh.b.npy", "npy10242")], "or two"),
])
def test_bad_map_uploads_are_one_line_4xx(server, files, message):
    def content(kind: str) -> bytes:
        if kind == "junk":
            return b"not a map at all\n" * 10
        buf = io.BytesIO()
        np.save(buf, np.zeros(int(kind[3:]), np.float32))
        return buf.getvalue()

    r = post(server, [(n, content(k)) for n, k in files])
    assert 400 <= r.status_code < 500, r.text
    err = r.json()["error"]
    root = str(server.app.state.store.root)
    assert message in err and "\n" not in err and root not in err and "maps-" not in err, err


def test_a_4d_volume_over_the_image_limit_is_refused(server):
    r = post(server, [("bold.nii.gz", mni_volume(n_volumes=500, voxel=8.0))])
    assert r.status_code == 400, r.text
    err = r.json()["error"]
    assert "holds 500 volumes" in err and "at most 20 images" in err, err


def test_a_table_cannot_pose_as_a_stored_map(server):
    from brainpainter.web.maps import MAGIC

    r = server.post("/api/uploads", params={"name": "t.csv"}, content=MAGIC + b'{"files": []}\n',
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 400 and "is not a table" in r.json()["error"]


def test_sizes_must_add_up(server):
    r = server.post("/api/uploads", params={"name": ["lh.a.npy", "rh.a.npy"], "size": [3, 4]},
                    content=b"12345", headers={"content-type": "application/octet-stream"})
    assert r.status_code == 400 and "sizes given are [3, 4]" in r.json()["error"]


def test_label_map_and_hemi_given(server, tmp_path):
    """An .annot is a label map (categories in their own colours); hemi= names a file's hemisphere."""
    labels = (np.arange(N5) % 3).astype(np.int32)
    ctab = np.array([[255, 0, 0, 0, 1], [0, 200, 0, 0, 2], [0, 0, 255, 0, 3]], np.int32)
    nib.freesurfer.write_annot(str(tmp_path / "parc.annot"), labels, ctab, [b"red", b"green", b"blue"],
                               fill_ctab=True)
    r = post(server, [("parc.annot", (tmp_path / "parc.annot").read_bytes())], hemi=["rh"])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"] == "label map: parc.annot, fsaverage5, 3 labels" and rep["hemis"] == ["rh"]
    assert rep["categories"] == ["red", "green", "blue"]
    right = preview(server, r.json()["upload_id"], "lateral-right")
    assert colourful(right) > 0.5


def test_inflating_is_bounded(tmp_path, monkeypatch):
    from brainpainter.errors import BrainPainterError
    from brainpainter.web import maps

    bomb = tmp_path / "lh.x.mgz"
    bomb.write_bytes(gzip.compress(b"\0" * (1 << 22)))
    monkeypatch.setattr(maps, "MAX_INFLATED", 1 << 20)
    with pytest.raises(BrainPainterError, match="inflates to more than 1 MB"):
        maps.inflate(bomb)
    small = tmp_path / "rh.x.mgz"
    small.write_bytes(gzip.compress(b"abc"))
    assert maps.inflate(small).read_bytes() == b"abc" and not small.exists()


def test_a_map_is_read_in_a_process_with_a_time_limit(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, parse_time_limit_s=0.05)
    with TestClient(create_app(config)) as client:
        r = post(client, [("zstat1.nii.gz", mni_volume())])
        assert r.status_code == 400, r.text
        assert "took longer than this server's limit of 0.05 s" in r.json()["error"]
        assert not any((tmp_path / "data" / "incoming").glob("maps-*"))  # the work folder is gone


def test_a_region_table_takes_the_outline_option(server):
    """``outline`` reaches region renders too (the renderer draws the borders: not the stand-in's job)."""
    from web_support import EXAMPLE

    r = server.post("/api/uploads", params={"name": "t.csv"}, content=EXAMPLE.read_bytes(),
                    headers={"content-type": "application/octet-stream"})
    uid = r.json()["upload_id"]
    assert preview(server, uid, "lateral-left", outline="dk").shape == (120, 160, 4)
    r = server.post("/api/preview", json={"upload_id": uid, "options": {"outline": "destrieux"}})
    assert r.status_code == 400 and "outlines its own atlas" in r.json()["error"]


def _cifti(tmp_path, name: str, n: int, rows, data, voxels: bool = False) -> bytes:
    """A CIFTI-2 file of the whole left cortex of an `n`-vertex mesh (and 4 thalamus voxels)."""
    from nibabel.cifti2 import cifti2_axes as axes

    cols = axes.BrainModelAxis.from_surface(np.arange(n), n, "CortexLeft")
    if voxels:
        mask = np.zeros((4, 4, 4), bool)
        mask.flat[:4] = True
        cols = cols + axes.BrainModelAxis.from_mask(mask, name="thalamus_left", affine=np.eye(4))
    nib.Cifti2Image(np.asarray(data, np.float32), header=(rows, cols)).to_filename(str(tmp_path / name))
    return (tmp_path / name).read_bytes()


def test_cifti_uploads_dscalar_and_dlabel(server, tmp_path):
    """A CIFTI-2 dscalar (fsLR 32k, with a thalamus) and a dlabel upload, read as the CLI reads them."""
    from nibabel.cifti2 import cifti2_axes as axes

    n = 32492
    data = np.concatenate([np.linspace(-1, 1, n), np.full(4, 3.0)])[None]
    dscalar = _cifti(tmp_path, "z.dscalar.nii", n, axes.ScalarAxis(["z"]), data, True)
    r = post(server, [("z.dscalar.nii", dscalar)])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"] == "CIFTI map: z.dscalar.nii, fsLR 32k, 1 image" and rep["hemis"] == ["lh"]
    uid = r.json()["upload_id"]
    assert colourful(preview(server, uid, "lateral-left")) > 0.5
    assert colourful(preview(server, uid, "subcortical")) > 0.02  # the thalamus takes its voxels' mean
    table = {0: ("???", (0, 0, 0, 0)), 1: ("red", (1, 0, 0, 1)), 2: ("blue", (0, 0, 1, 1))}
    labels = (np.arange(n) % 2 + 1)[None]
    dlabel = _cifti(tmp_path, "p.dlabel.nii", n, axes.LabelAxis(["p"], [table]), labels)
    r = post(server, [("p.dlabel.nii", dlabel)])
    assert r.status_code == 200, r.text
    rep = r.json()["report"]
    assert rep["summary"] == "CIFTI label map: p.dlabel.nii, fsLR 32k, 2 labels"
    assert rep["categories"] == ["red", "blue"]
    assert colourful(preview(server, r.json()["upload_id"], "lateral-left")) > 0.5


def test_a_cifti_upload_keeps_its_fslr_164k_mesh(tmp_path):
    """A 163842-vertex CIFTI named fs_LR is stored and read back as fsLR, not as fsaverage."""
    from nibabel.cifti2 import cifti2_axes as axes

    from brainpainter.web.maps import build_bundle, read_bundle

    name = "s.164k_fs_LR.dscalar.nii"
    _cifti(tmp_path, name, 163842, axes.ScalarAxis(["s"]), np.ones((1, 163842)))
    work = tmp_path / "work"
    work.mkdir()
    report, images = build_bundle(work, [(None, tmp_path / name)], 10)
    assert report["surfaces"] == {"lh": "fsLR 164k"} and images == ["s"]
    maps = read_bundle((work / "bundle.bin").read_bytes())
    assert maps.space == "fsLR" and not maps.notes


# -- a volume drawn as blobs, and cut open (issue 45, item 5) ------------------------------------
BLOBS = {"volume_surface": True, "threshold": 2.3}


def png_frames(data: bytes) -> list[np.ndarray]:
    """The frames of a GIF, RGB."""
    from PIL import Image, ImageSequence

    with Image.open(io.BytesIO(data)) as gif:
        return [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(gif)]


def _job(server, uid: str, kind: str, options: dict, **more) -> dict:
    r = server.post("/api/jobs", json={"upload_id": uid, "kind": kind, "options": options, **more})
    assert r.status_code == 202, r.text
    url = r.json()["url"]
    job = wait_for(lambda: (j := server.get(url).json())["status"] in ("done", "failed") and j, 120)
    assert job and job["status"] == "done", job
    return job


def test_a_volume_upload_drawn_as_blobs_previews_renders_and_says_its_command(server):
    uid = post(server, [("zstat1.nii.gz", mni_volume())]).json()["upload_id"]
    check = server.post("/api/check", json={"upload_id": uid, "options": {
        **BLOBS, "clip": ["x<0"], "min_cluster_mm3": 10, "views": "dorsal,cutaway-left"}})
    assert check.status_code == 200, check.text
    report = check.json()
    (layer,) = report["layers"]
    assert layer["kind"] == "blobs" and layer["label"] == "zstat1.nii.gz"          # the blobs' own bar
    assert (layer["scale"]["vmin"], layer["scale"]["vmax"]) == (2.3, 5.0)
    command = report["reproduce"]["command"]
    assert "--volume-surface zstat1.nii.gz" in command and "--volume " not in command, command
    assert "--clip 'x<0'" in command and "--min-cluster-mm3 10.0" in command and "--threshold 2.3" in command
    assert "volume_surface='zstat1.nii.gz'" in report["reproduce"]["python"]
    # the preview: the blob (left lateral, value 5: the bar's top) drawn, not the cortex's projection
    blobs, projected = (preview(server, uid, "lateral-left", **o) for o in (BLOBS, {"threshold": 2.3}))
    assert not np.array_equal(blobs, projected)
    images = _job(server, uid, "images", {**BLOBS, "size": "64x48", "views": "dorsal,cutaway-left",
                                          "clip": ["z>60"]})
    names = {f["name"] for f in images["files"]}
    assert {"zstat1_dorsal.png", "zstat1_cutaway-left.png"} <= names, names
    figure = _job(server, uid, "figure", {**BLOBS, "size": "64x48", "views": "dorsal"},
                  figure={"format": "png", "dpi": 100, "slices": ["z=10"], "projections": "z"})
    png = png_pixels(server.get(figure["files"][0]["url"]).content)
    rgb = png[..., :3].astype(int)
    assert ((rgb.max(-1) - rgb.min(-1)) > 60).sum() > 100      # the blob in its panels, on the blobs' bar
    movie = _job(server, uid, "movie", {**BLOBS, "size": "64x48", "views": "cutaway-left"},
                 movie={"format": "gif", "frames_per_step": 3, "clip_sweep": "x"})
    gif = [f for f in movie["files"] if f["name"] == "movie.gif"]
    frames = png_frames(server.get(gif[0]["url"]).content)
    assert len(frames) == 4 and not np.array_equal(frames[0], frames[-1])   # the cut sweeps through
    export = _job(server, uid, "export", BLOBS, export={"row": 0})
    page = server.get(next(f["url"] for f in export["files"] if f["name"] == "zstat1.html")).text
    import base64
    import re

    (glb,) = (gzip.decompress(base64.b64decode(m)) for m in re.findall(r"H4sI[A-Za-z0-9+/=]+", page))
    assert glb[:4] == b"glTF" and b'"blobs"' in glb                # the blobs' mesh in the 3D page


@pytest.mark.parametrize("options, message", [
    ({**BLOBS, "clip": ["w<3"]}, "--clip 'w<3'"),
    ({**BLOBS, "threshold": 6}, "--threshold"),
    ({**BLOBS, "min_cluster_mm3": 1e8}, "--min-cluster-mm3"),
    ({"min_cluster_mm3": 10}, "--min-cluster-mm3"),
])
def test_bad_blob_and_clip_options_are_one_line_400(server, options, message):
    uid = post(server, [("zstat1.nii.gz", mni_volume())]).json()["upload_id"]
    r = server.post("/api/preview", json={"upload_id": uid, "row": 0, "view": "dorsal", "options": options})
    assert r.status_code == 400, r.text
    line = r.json()["error"]
    assert message in line and "\n" not in line, line
