"""CIFTI-2 uploads on the ``brainpainter serve`` API (issue 34, the web side): pscalar and dtseries render,
the upload is kept as its values only, hostile CIFTI (declared sizes the file does not hold, CIFTI-1, a
connectome) is one line with 400 and nothing kept, and the command line of a CIFTI upload names the file.
The app is tests/test_web_maps.py's (stand-in renderer)."""

from __future__ import annotations

import numpy as np
import pytest
import test_web_maps
from test_web_maps import colourful, post, preview

pytest.importorskip("fastapi")
import nibabel as nib
from nibabel.cifti2 import cifti2_axes as axes

from brainpainter.web.options import RenderOptions
from brainpainter.web.reproduce import reproduce

N32 = 32492
#: The app of tests/test_web_maps.py (1 worker, the preview process, the stand-in renderer).
server = test_web_maps.server


def cifti(tmp_path, name: str, data, rows, cols, marker: str = "") -> bytes:
    """A CIFTI-2 file written by nibabel; `marker` is kept in its header's metadata (never in a bundle)."""
    img = nib.Cifti2Image(np.asarray(data, np.float32), header=(rows, cols))
    if marker:
        img.header.matrix.metadata = nib.cifti2.Cifti2MetaData({"Provenance": marker})
    img.to_filename(str(tmp_path / name))
    return (tmp_path / name).read_bytes()


def left_cortex(n: int = N32) -> axes.BrainModelAxis:
    return axes.BrainModelAxis.from_surface(np.arange(n), n, "CortexLeft")


def test_pscalar_and_dtseries_uploads_render_and_keep_only_their_values(server, tmp_path):
    """A pscalar's parcels take their values; a dtseries' frames are its images; neither is kept as sent."""
    parcels = axes.ParcelsAxis.from_brain_models([
        ("a", axes.BrainModelAxis.from_surface(np.arange(N32 // 2), N32, "CortexLeft")),
        ("b", axes.BrainModelAxis.from_surface(np.arange(N32 // 2, N32), N32, "CortexLeft"))])
    data = cifti(tmp_path, "p.pscalar.nii", [[2.0, -1.0]], axes.ScalarAxis(["m"]), parcels, "secret-origin")
    r = post(server, [("p.pscalar.nii", data)])
    assert r.status_code == 200, r.text
    assert r.json()["report"]["values"]["range"] == [-1.0, 2.0]
    uid = r.json()["upload_id"]
    assert colourful(preview(server, uid, "lateral-left")) > 0.5
    stored = server.app.state.store.get_upload(uid)[1]
    assert b"secret-origin" not in stored and data not in stored  # its values, not the file

    series = np.tile(np.linspace(0, 1, N32), (3, 1)) * np.arange(1, 4)[:, None]
    r = post(server, [("run.dtseries.nii", cifti(tmp_path, "run.dtseries.nii", series,
                                                 axes.SeriesAxis(0, 0.72, 3), left_cortex()))])
    assert r.status_code == 200, r.text
    assert r.json()["images"] == ["run_0", "run_1", "run_2"]
    assert colourful(preview(server, r.json()["upload_id"], "lateral-left")) > 0.3


def _patched(raw: bytes, frames: int) -> bytes:
    """A one-frame dtseries whose header and axes say it holds `frames` frames (the file holds one)."""
    i, j = raw.index(b"<CIFTI"), raw.index(b"</CIFTI>")
    xml = raw[i:j].replace(b'NumberOfSeriesPoints="1"', f'NumberOfSeriesPoints="{frames}"'.encode())
    grown = len(xml) - (j - i)
    assert raw[j + 8:j + 8 + grown] == bytes(grown)  # eaten from the extension's NUL padding
    raw = raw[:i] + xml + raw[j:j + 8] + raw[j + 8 + grown:]
    dims = np.frombuffer(raw[16:80], np.int64).copy()  # NIfTI-2: dim[0..7] at byte 16
    dims[5] = frames
    return raw[:16] + dims.tobytes() + raw[80:]


def test_hostile_cifti_is_one_line_400_and_nothing_is_kept(server, tmp_path):
    """Sizes the file does not hold (a million frames, 130 GB; two billion vertices), CIFTI-1, a dconn: 400,
    one line, with no upload kept and no file left behind."""
    one = cifti(tmp_path, "one.dtseries.nii", np.ones((1, N32)), axes.SeriesAxis(0, 1, 1), left_cortex())
    old = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 1, 3), np.float32), np.eye(4))
    old.header.extensions.append(nib.nifti1.Nifti1Extension(32, b'<CIFTI Version="1.0"><Matrix/></CIFTI>'))
    conn = axes.BrainModelAxis.from_surface(np.arange(3), N32, "CortexLeft")
    files = {
        "long.dtseries.nii": (_patched(one, 10**6), "says it holds 129968000000 bytes"),
        "wide.dscalar.nii": (cifti(tmp_path, "w.dscalar.nii", np.zeros((1, 3)), axes.ScalarAxis(["m"]),
                                   axes.BrainModelAxis.from_surface(np.arange(3), 2 * 10**9, "CortexLeft")),
                             "fits no known mesh"),
        "old.dscalar.nii": (old.to_bytes(), "CIFTI-1"),
        "x.dconn.nii": (cifti(tmp_path, "x.dconn.nii", np.eye(3), conn, conn), "connectome"),
    }
    store = server.app.state.store
    root = store.root
    before = sorted(p.name for p in (root / "uploads").iterdir())
    for name, (data, message) in files.items():
        r = post(server, [(name, data)])
        assert r.status_code == 400, (name, r.text)
        err = r.json()["error"]
        assert message in err and "\n" not in err and str(root) not in err, (name, err)
    assert sorted(p.name for p in (root / "uploads").iterdir()) == before
    assert not [p for p in (root / "incoming").glob("maps-*")]


def test_the_command_line_of_a_cifti_upload_names_the_file(tmp_path):
    """``brainpainter render FILE.dscalar.nii``: a CIFTI file is INPUT (on main the command had no input)."""
    from brainpainter.web.maps import build_bundle

    cifti(tmp_path, "z.dscalar.nii", np.ones((1, N32)), axes.ScalarAxis(["z"]), left_cortex())
    work = tmp_path / "work"
    work.mkdir()
    build_bundle(work, [(None, tmp_path / "z.dscalar.nii")], 10)
    got = reproduce((work / "bundle.bin").read_bytes(), "z.dscalar.nii", RenderOptions(threshold=0.5))
    assert got["command"].startswith("brainpainter render z.dscalar.nii -o ")
    assert "--threshold 0.5" in got["command"]
    assert got["python"].splitlines()[-1].startswith("brainpainter.render('z.dscalar.nii', out=")


def test_a_dlabel_upload_reports_its_key_as_its_colour_bar(server, tmp_path):
    """A label map's layer in the check report carries its categories (the page's key): names, colours."""
    table = {0: ("???", (0, 0, 0, 0)), 1: ("red", (1, 0, 0, 1)), 2: ("blue", (0, 0, 1, 1))}
    labels = (np.arange(N32) % 2 + 1)[None]
    r = post(server, [("p.dlabel.nii", cifti(tmp_path, "p.dlabel.nii", labels, axes.LabelAxis(["p"], [table]),
                                             left_cortex()))])
    assert r.status_code == 200, r.text
    c = server.post("/api/check", json={"upload_id": r.json()["upload_id"], "options": {}}).json()
    assert [(lay["kind"], lay["label"]) for lay in c["layers"]] == [("map", "p.dlabel.nii")]
    assert c["layers"][0]["scale"]["categories"] == [{"name": "red", "color": "#ff0000"},
                                                     {"name": "blue", "color": "#0000ff"}]
