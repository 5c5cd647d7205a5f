"""What ``brainpainter serve`` keeps of an upload (issue 33, items 2, 3 and 5).

A stored upload is what its reader read (vertex arrays, kept streamlines), never the inflated bytes
that were sent; whatever is accepted reads back; a compressed .trx is unpacked with its sizes checked,
inside the reader's own folder, and removed; the disk budget counts each stored byte as it is written.
Files are tiny and written with the real writers (nibabel, trx-python, zipfile).
"""

from __future__ import annotations

import gzip
import io
import struct
import zipfile

import nibabel as nib
import numpy as np
import pytest
from test_tracts import bundle, write

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient

from brainpainter.errors import BrainPainterError
from brainpainter.web.app import create_app
from brainpainter.web.config import ServerConfig

N5 = 10242
PADDING = 24 << 20  # zeros after a valid file: deflated to ~24 KB, inflated to 24 MB
TEMPLATE = {"tracts_space": "template", "gradient": "red,blue", "vmin": 0, "vmax": 1}


@pytest.fixture
def api(tmp_path):
    """An app that reads uploads (in its reader processes) and renders nothing."""
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, rate_per_minute=100_000)
    with TestClient(create_app(config)) as client:
        yield client


def post(client, files: list[tuple[str, bytes]], route: str):
    q = {"name": [n for n, _ in files]}
    if len(files) > 1:
        q["size"] = [len(d) for _, d in files]
    return client.post(route, params=q, content=b"".join(d for _, d in files),
                       headers={"content-type": "application/octet-stream"})


def zipped(members: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


def stored_size(client, upload_id: str) -> int:
    return client.app.state.store.upload_path(upload_id).stat().st_size


# -- item 3: what is stored is what was read ----------------------------------------------------------
def test_a_padded_tractogram_is_stored_as_its_streamlines(api, tmp_path):
    """A zip of a valid AF_L.trk (200 streamlines) followed by 24 MB of zeros: stored as the streamlines
    read (one .tck of 200 x 32 points), not as the 24 MB the zip inflates to; they read back as sent."""
    from brainpainter.tracts.read import read_bundles
    from brainpainter.web.tracts import materialise

    trk = write(tmp_path / "AF_L.trk", bundle(-30.0, n=200)).read_bytes()
    body = zipped({"AF_L.trk": trk + b"\0" * PADDING})
    assert len(body) < 100_000
    r = post(api, [("af.zip", body)], "/api/tracts")
    assert r.status_code == 200, r.text
    uid = r.json()["upload_id"]
    assert r.json()["report"]["bundles"] == [{"name": "AF_left", "streamlines": 200, "drawn": 200}]
    assert stored_size(api, uid) < 120_000  # 200 x 32 points x 12 bytes + the header
    data = api.app.state.store.get_upload(uid)[1]
    files = materialise(data, tmp_path / "root")
    again = read_bundles([files.bundles / "AF_left.tck"], np.eye(4), 1000, 32)
    sent = read_bundles([tmp_path / "AF_L.trk"], np.eye(4), 1000, 32)
    assert again.names == sent.names and again.lines.shape == sent.lines.shape == (200, 32, 3)
    assert np.abs(again.lines - sent.lines).max() < 0.05  # resampled once more: the same points


def test_a_padded_values_table_is_refused_not_stored(api, tmp_path):
    """A values table is kept as sent (option tract_value chooses its column later), so one inflated
    from a zip past 16 MB (here a valid table plus 17 MB of blank lines) is refused in one line, before
    it is parsed (before: parsed until the reader's 20 s limit; a faster-parsing one was kept)."""
    trk = write(tmp_path / "AF_L.trk", bundle(-30.0, n=20)).read_bytes()
    body = zipped({"AF_L.trk": trk, "fa.csv": b"AF_left\n0.5\n" + b"\n" * (17 << 20)})
    assert len(body) < 100_000
    r = post(api, [("af.zip", body)], "/api/tracts")
    assert r.status_code == 400, r.text
    assert r.json()["error"] == ("the table 'fa.csv' has 17 MB; this server keeps at most 16 MB of bundle "
                                 "values per upload. Upload a smaller table.")
    assert not any((api.app.state.store.root / "uploads").iterdir())


def test_a_padded_mgz_is_stored_as_its_vertex_values(api, tmp_path):
    """An lh .mgz whose gzip stream is a valid fsaverage5 map followed by 24 MB of zeros: stored as the
    map's values (gzipped .npy), which read back equal."""
    from brainpainter.web.maps import read_bundle

    values = np.linspace(1.0, 4.0, N5, dtype=np.float32)
    mgh = nib.MGHImage(values.reshape(N5, 1, 1), np.eye(4)).to_bytes()
    body = gzip.compress(mgh + b"\0" * PADDING, compresslevel=9)
    assert len(body) < 100_000
    r = post(api, [("lh.thick.mgz", body)], "/api/uploads")
    assert r.status_code == 200, r.text
    uid = r.json()["upload_id"]
    assert stored_size(api, uid) < 60_000  # 10242 float32 (41 KB), gzipped, + the header
    maps = read_bundle(api.app.state.store.get_upload(uid)[1])
    assert maps.images == ("thick",) and maps.source == "lh=lh.thick.mgz"
    np.testing.assert_array_equal(maps.values["lh"], values[None])
    check = api.post("/api/check", json={"upload_id": uid, "options": {}})
    assert check.status_code == 200 and check.json()["values"]["range"] == [1.0, 4.0], check.text


def test_the_disk_budget_counts_each_stored_byte_when_it_is_written(tmp_path):
    """The usage walk is cached for 10 s; bytes stored since count at once, so a second upload that
    would pass the budget is refused (507) though the cached walk says there is room."""
    from brainpainter.web.store import LimitError, Store

    probe = Store(tmp_path / "data")
    budget = probe.disk_usage(max_age_s=0) + 100_000
    store = Store(tmp_path / "data", max_disk_bytes=budget)
    store.add_upload("a", "one", b"x" * 60_000, 60)
    with pytest.raises(LimitError, match="storage budget") as exc:
        store.add_upload("b", "two", b"x" * 60_000, 60)
    assert exc.value.status == 507
    with pytest.raises(LimitError):
        store.submit("a", "images", {}, {}, "t.csv", b"x" * 60_000, 1, max_per_client=5, max_queued=5)
    assert len(list((tmp_path / "data" / "uploads").iterdir())) == 1
    assert not any((tmp_path / "data" / "jobs").iterdir())


def test_an_upload_past_the_disk_budget_is_507_at_once(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False)
    with TestClient(create_app(config)) as client:
        used = client.app.state.store.disk_usage(max_age_s=0)
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False,
                          max_disk_gb=(used + 150_000) / 2**30)
    table = b"Image-name-unique,Left-Hippocampus\n" + b"".join(b"s%06d,0.5\n" % i for i in range(9000))
    with TestClient(create_app(config)) as client:
        first = post(client, [("t.csv", table)], "/api/uploads")
        assert first.status_code == 200, first.text
        second = post(client, [("t.csv", table)], "/api/uploads")
        assert second.status_code == 507 and "storage budget" in second.json()["error"], second.text
        assert second.headers["retry-after"] == "600"


# -- item 5: what is accepted reads back ----------------------------------------------------------------
def test_a_volume_of_many_images_reads_back(tmp_path, monkeypatch):
    """A 4-D NIfTI of 100 volumes: image names and per-image subcortical means make a header of more than
    64 KiB (the old reader's limit); the stored bundle reads back with all of them. (The projection is
    replaced by a fast stand-in on fsaverage5: 100 real projections take 20 s.)"""
    from brainpainter.maps.inputs import VertexMaps
    from brainpainter.web import maps

    k = 100
    rng = np.random.default_rng(0)
    regions = {f"Left-Structure-{j}": rng.random(k) for j in range(30)}
    names = tuple(f"sub-{i:03d}_task-rest_space-MNI152NLin2009cAsym_desc-preproc_bold" for i in range(k))

    def projected(path):
        return VertexMaps({h: rng.random((k, N5), dtype=np.float32) for h in ("lh", "rh")}, names,
                          source="volume", regions=regions)

    monkeypatch.setattr("brainpainter.maps.inputs.read_volume", projected)
    img = nib.Nifti1Image(np.zeros((4, 4, 4, k), np.float32), np.diag([2.0, 2.0, 2.0, 1.0]))
    img.header.set_sform(img.affine, 1)
    nib.save(img, tmp_path / "bold.nii.gz")
    report, images = maps.build_bundle(tmp_path, [(None, tmp_path / "bold.nii.gz")], max_images=k)
    data = (tmp_path / "bundle.bin").read_bytes()
    assert data.index(b"\n", len(maps.MAGIC)) > 1 << 16  # the header is over the old limit
    back = maps.read_bundle(data)
    assert back.images == names == tuple(images) and report["n_images"] == k
    assert set(back.regions) == set(regions)
    assert all(np.array_equal(back.regions[key], v) for key, v in regions.items())
    assert back.values["lh"].shape == (k, N5)


def test_a_tract_upload_with_a_values_table_of_3000_rows_reads_back(api, tmp_path):
    trk = write(tmp_path / "AF_L.trk", bundle(-30.0, n=20)).read_bytes()
    rows = b"".join(b"sub-%04d_ses-baseline_acq-multiband,%.3f\n" % (i, (i % 100) / 100) for i in range(3000))
    table = b"subject,AF_left\n" + rows
    r = post(api, [("AF_L.trk", trk), ("fa.csv", table)], "/api/tracts")
    assert r.status_code == 200, r.text
    uid = r.json()["upload_id"]
    assert len(r.json()["report"]["values"]["images"]) == 3000
    check = api.post("/api/check", json={"upload_id": uid, "options": TEMPLATE})
    assert check.status_code == 200, check.text
    assert check.json()["values"]["images"][-1] == "sub-2999_ses-baseline_acq-multiband"


def test_any_header_size_reads_back_and_damage_is_one_line(tmp_path):
    from brainpainter.web.bundle import bundle_header, write_bundle

    (tmp_path / "a.bin").write_bytes(b"abc")
    write_bundle(tmp_path / "b", b"M/1\n", {"report": {"images": ["x" * 100] * 2000}}, "role",
                 [("values", tmp_path / "a.bin")])
    data = (tmp_path / "b").read_bytes()
    header, start = bundle_header(data, b"M/1\n", "role", ("values",), "damaged")
    assert len(header["report"]["images"]) == 2000 and data[start:] == b"abc"
    for bad in (data[:-1], data[:200], b"M/0\n" + data[4:], data + b"x"):
        with pytest.raises(BrainPainterError, match=r"^damaged$"):
            bundle_header(bad, b"M/1\n", "role", ("values",), "damaged")


# -- item 2: a compressed .trx is unpacked with its sizes checked, where its reader says ---------------------
def _trx(path, *, extra: dict[str, bytes] | None = None, method: int = zipfile.ZIP_DEFLATED):
    """A valid .trx (trx-python's writer, 20 streamlines in group AF_L) re-zipped with `method`, plus
    `extra` members."""
    pytest.importorskip("trx.trx_file_memmap")
    from trx.trx_file_memmap import TrxFile, save

    ref = nib.Nifti1Image(np.zeros((2, 2, 2), np.uint8), np.eye(4))
    trx = TrxFile.from_tractogram(nib.streamlines.Tractogram(bundle(-25.0), affine_to_rasmm=np.eye(4)),
                                  reference=ref)
    trx.groups = {"AF_L": np.arange(20, dtype=np.uint32)}
    written = path.with_name(f"written-{path.name}")
    save(trx, str(written))
    trx.close()
    with zipfile.ZipFile(written) as zf:
        members = {i.filename: zf.read(i) for i in zf.infolist() if not i.is_dir()}
    path.write_bytes(zipped({**members, **(extra or {})}, method))
    return path


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_trx_bomb_is_refused_before_anything_is_unpacked(tmp_path):
    from brainpainter.tracts.read import read_bundles

    bomb = _trx(tmp_path / "b.trx", extra={"dpv/pad.float32": b"\0" * (8 << 20)})
    assert bomb.stat().st_size < 100_000
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    with pytest.raises(BrainPainterError, match="unpacks to 8 MB or more; this server unpacks at most 1 MB"):
        read_bundles([bomb], np.eye(4), 100, 8, scratch=scratch, max_inflated=1 << 20)
    assert not any(scratch.iterdir())


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_compressed_trx_is_unpacked_in_the_scratch_folder_and_removed(tmp_path, monkeypatch):
    import trx.trx_file_memmap as tmm

    from brainpainter.tracts.read import read_bundles

    path = _trx(tmp_path / "b.trx")
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    seen = []
    real = tmm.load_from_directory
    monkeypatch.setattr(tmm, "load_from_directory", lambda d: seen.append(d) or real(d))
    t = read_bundles([path], np.eye(4), 100, 8, scratch=scratch, max_inflated=1 << 20)
    assert t.names == ("AF_left",) and len(t.lines) == 20
    assert len(seen) == 1 and seen[0].startswith(str(scratch))
    assert not any(scratch.iterdir())
    stored = _trx(tmp_path / "s.trx", method=zipfile.ZIP_STORED)  # memory-mapped where it is
    assert read_bundles([stored], np.eye(4), 100, 8, scratch=scratch, max_inflated=1).names == ("AF_left",)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_the_cli_unpacks_a_trx_only_into_the_free_space(tmp_path, monkeypatch):
    """Without a cap (the command line), a compressed .trx that needs more than the free space of the
    temporary folder is refused before anything is written."""
    import collections

    from brainpainter.tracts import read

    path = _trx(tmp_path / "b.trx", extra={"dpv/pad.float32": b"\0" * (4 << 20)})
    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(read.shutil, "disk_usage", lambda p: usage(10 << 20, 8 << 20, 2 << 20))
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    read.tempfile.tempdir = None  # TMPDIR is read again
    try:
        with pytest.raises(BrainPainterError, match="unpacks to 4 MB or more; the free space is 2 MB"):
            read.read_bundles([path], np.eye(4), 100, 8)
    finally:
        read.tempfile.tempdir = None
    assert not any((tmp_path / "tmp").iterdir())


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_the_cli_unpacks_a_trx_where_trx_tmpdir_says(tmp_path, monkeypatch):
    import trx.trx_file_memmap as tmm

    from brainpainter.tracts.read import read_bundles

    path = _trx(tmp_path / "b.trx")
    (tmp_path / "big-disk").mkdir()
    monkeypatch.setenv("TRX_TMPDIR", str(tmp_path / "big-disk"))
    seen = []
    real = tmm.load_from_directory
    monkeypatch.setattr(tmm, "load_from_directory", lambda d: seen.append(d) or real(d))
    assert read_bundles([path], np.eye(4), 100, 8).names == ("AF_left",)
    assert seen[0].startswith(str(tmp_path / "big-disk" / "trx-"))
    assert not any((tmp_path / "big-disk").iterdir())


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_the_server_unpacks_a_trx_in_the_readers_folder(tmp_path, monkeypatch):
    """The tract reader unpacks a compressed .trx inside its own work folder (the folder the server
    removes however the reader ends), not in the temporary folder, and removes it when done."""
    import trx.trx_file_memmap as tmm

    from brainpainter.web.tracts import build_tract_bundle

    work = tmp_path / "work"
    (work / "in").mkdir(parents=True)
    path = _trx(work / "in" / "b.trx")
    seen = []
    real = tmm.load_from_directory
    monkeypatch.setattr(tmm, "load_from_directory", lambda d: seen.append(d) or real(d))
    report = build_tract_bundle(work, [path], 10, 1000)
    assert report["bundles"] == [{"name": "AF_left", "streamlines": 20, "drawn": 20}]
    assert len(seen) == 1 and seen[0].startswith(str(work) + "/trx-")
    assert sorted(p.name for p in work.iterdir()) == ["bundle.bin", "given", "in", "kept"]


def test_a_tract_reader_killed_for_time_leaves_no_folder(tmp_path):
    config = ServerConfig(data_dir=tmp_path / "data", workers=0, preview=False, parse_time_limit_s=0.05)
    trk = write(tmp_path / "AF_L.trk", bundle(-30.0, n=20)).read_bytes()
    with TestClient(create_app(config)) as client:
        r = post(client, [("AF_L.trk", trk)], "/api/tracts")
        assert r.status_code == 400 and "took longer than this server's limit of 0.05 s" in r.json()["error"]
        assert not any((tmp_path / "data" / "incoming").iterdir())


def declared(data: bytes, name: str, size: int) -> bytes:
    """Zip `data` with member `name` said to inflate to `size` bytes (its local and central headers)."""
    out, pos = bytearray(data), 0
    while (pos := out.find(b"PK\x01\x02", pos + 1)) >= 0:
        n = struct.unpack_from("<H", out, pos + 28)[0]
        if out[pos + 46:pos + 46 + n] == name.encode():
            struct.pack_into("<I", out, pos + 24, size)
            struct.pack_into("<I", out, struct.unpack_from("<I", out, pos + 42)[0] + 22, size)
    return bytes(out)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_trx_bomb_upload_is_one_line_and_leaves_nothing(api, tmp_path):
    """A .trx whose pad member says it inflates to 3 GB (the observed bomb deflated 9,000 MiB of zeros):
    refused on the declared sizes against the server's cap (1 GiB) before anything is written."""
    path = _trx(tmp_path / "b.trx", extra={"dpv/pad.float32": b"\0" * (1 << 20)})
    r = post(api, [("b.trx", declared(path.read_bytes(), "dpv/pad.float32", 3 << 30))], "/api/tracts")
    assert r.status_code == 400, r.text
    err = r.json()["error"]
    assert "unpacks to 3,072 MB or more; this server unpacks at most 1,024 MB" in err and "\n" not in err, err
    store = api.app.state.store
    assert not any((store.root / "incoming").iterdir()) and not any((store.root / "uploads").iterdir())
