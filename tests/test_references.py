"""Readers that could follow a reference to another file open only the files they were given
(issue 33 item 1): GIfTI external data, a NIfTI header of the ``.hdr``/``.img`` pair kind in a
``.nii``, member names of a ``.trx`` and of a tract upload's zip (``..``, absolute, symbolic links).

Every file a reader opens is recorded with a Python audit hook (the ``open`` event: ``open()``,
``os.open``, numpy's ``fromfile``/``memmap`` through them) while it runs.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
import sys
import tempfile
import zipfile
from collections.abc import Iterator
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from test_gifti import N5, external_gifti

from brainpainter.errors import BrainPainterError

_RECORDS: list[list[tuple[str, bool]]] = []


def _hook(event: str, args: tuple) -> None:
    if event == "open" and _RECORDS and isinstance(args[0], str | bytes | os.PathLike):
        mode, flags = args[1], args[2] if len(args) > 2 else 0
        writes = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
            mode is None and isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT))
        _RECORDS[-1].append((os.path.realpath(os.fsdecode(args[0])), bool(writes)))


sys.addaudithook(_hook)  # hooks cannot be removed: it records only inside opened()


@contextlib.contextmanager
def opened() -> Iterator[list[tuple[str, bool]]]:
    """The (real path, written) of every file opened inside the block."""
    _RECORDS.append([])
    try:
        yield _RECORDS[-1]
    finally:
        _RECORDS.pop()


def test_a_gifti_never_opens_external_data_it_may_not(tmp_path):
    from brainpainter.maps.inputs import read_maps

    np.arange(N5, dtype=np.float32).tofile(tmp_path / "secret.bin")
    (tmp_path / "maps").mkdir()
    np.arange(N5, dtype=np.float32).tofile(tmp_path / "maps" / "beside.bin")
    secret, beside = str(tmp_path / "secret.bin"), str(tmp_path / "maps" / "beside.bin")
    for name, external, message in (("../secret.bin", "folder", "outside its own folder"),
                                    (secret, "folder", "outside its own folder"),
                                    ("beside.bin", "refuse", "keeps its data in another file")):
        path = external_gifti(tmp_path / "maps" / "lh.x.func.gii", name)
        with opened() as files, pytest.raises(BrainPainterError, match=message):
            read_maps(lh=path, external=external)
        assert {f for f, _ in files if f.startswith(str(tmp_path))} == {str(path)}, files
    with opened() as files:  # allowed: beside it, on the command line
        read_maps(lh=external_gifti(tmp_path / "maps" / "lh.x.func.gii", "beside.bin"))
    assert beside in {f for f, _ in files} and secret not in {f for f, _ in files}


def test_a_gifti_given_as_a_volume_is_never_parsed(tmp_path):
    """``--volume x.func.gii`` (or ``atlas add --volume``): ``nib.load`` reads GIfTI too, and followed its
    external data before the volume reader found it was no volume (then an internal error, exit 1)."""
    from brainpainter.atlas.volumes import read_volume
    from brainpainter.maps.volume import load_volume

    np.arange(N5, dtype=np.float32).tofile(tmp_path / "secret.bin")
    path = external_gifti(tmp_path / "lh.x.func.gii", str(tmp_path / "secret.bin"))
    with opened() as files:
        with pytest.raises(BrainPainterError, match="looks like a GIfTI file, not a NIfTI or MGH"):
            load_volume(path)
        with pytest.raises(BrainPainterError, match="looks like a GIfTI file, not a volume"):
            read_volume(path)
    assert str(tmp_path / "secret.bin") not in {f for f, _ in files}


def test_a_nii_with_a_pair_header_reads_only_itself(tmp_path):
    """A ``.nii`` whose magic says ``ni1`` (header of a ``.hdr``/``.img`` pair): the ``.img`` beside it
    is never read, by the map reader (from bytes) or the volume reader (``nib.load``)."""
    from brainpainter.maps.inputs import read_maps
    from brainpainter.maps.volume import load_volume

    nib.save(nib.Nifti1Pair(np.zeros((40, 48, 40), np.float32), np.diag([4.0, 4.0, 4.0, 1.0])),
             str(tmp_path / "pair.hdr"))
    header = (tmp_path / "pair.hdr").read_bytes()
    assert header[344:347] == b"ni1"
    for stem in ("vol", "lh.map"):
        (tmp_path / f"{stem}.nii").write_bytes(header)
        np.full((40, 48, 40), 7.0, np.float32).tofile(tmp_path / f"{stem}.img")
    with opened() as files:
        with contextlib.suppress(BrainPainterError, OSError):  # its data: the header's bytes, too few
            np.asarray(load_volume(tmp_path / "vol.nii").dataobj)
        with contextlib.suppress(BrainPainterError):
            read_maps(lh=tmp_path / "lh.map.nii")
    names = {Path(f).name for f, _ in files if f.startswith(str(tmp_path))}
    assert names <= {"vol.nii", "lh.map.nii"}, names


# trx-python's writer (TrxFile.from_tractogram) leaves a temporary folder to the garbage collector
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_trx_members_named_out_of_the_archive_are_written_inside(tmp_path, monkeypatch):
    """A compressed .trx is extracted by trx-python: members ``../../x`` and ``/x`` stay inside."""
    pytest.importorskip("trx.trx_file_memmap")
    from trx.trx_file_memmap import TrxFile, save

    from brainpainter.tracts.read import read_bundles

    monkeypatch.setenv("TRX_TMPDIR", str(tmp_path / "t"))
    (tmp_path / "t").mkdir()
    lines = [np.array([[x, 0.0, 0.0], [x, 10.0, 0.0], [x, 20.0, 0.0]], np.float32) for x in range(5)]
    tg = nib.streamlines.Tractogram(lines, affine_to_rasmm=np.eye(4))
    trx = TrxFile.from_tractogram(tg, reference=nib.Nifti1Image(np.zeros((2, 2, 2), np.uint8), np.eye(4)))
    save(trx, str(tmp_path / "good.trx"), compression_standard=zipfile.ZIP_DEFLATED)
    trx.close()
    hostile = tmp_path / "in" / "AF_L.trx"
    hostile.parent.mkdir()
    with zipfile.ZipFile(tmp_path / "good.trx") as src, zipfile.ZipFile(hostile, "w", 8) as dst:  # deflated
        for info in src.infolist():
            dst.writestr(info, src.read(info))
        dst.writestr("../../escape.float32", np.ones(3, np.float32).tobytes())
        dst.writestr("/abs-escape.float32", np.ones(3, np.float32).tobytes())
    with opened() as files, contextlib.suppress(BrainPainterError):
        read_bundles([hostile], np.eye(4), 100, 8)
    written = [f for f, w in files if w]
    assert any(f.startswith(str(tmp_path / "t")) for f in written), "the .trx was not extracted"
    assert all(f.startswith((str(tmp_path / "t"), tempfile.gettempdir())) for f in written), written
    assert not [p for p in Path(tmp_path).parent.rglob("*escape*")]


def test_a_tract_zip_member_that_is_a_symbolic_link_is_only_a_file(tmp_path):
    """Zip members marked as symbolic links (``ln -s /etc/passwd AF_L.trk; zip -y``) become regular
    files holding the link's text, never links; ``..`` and absolute names are refused."""
    from brainpainter.web.tracts import unzip

    link = zipfile.ZipInfo("AF_L.trk")
    link.external_attr = (stat.S_IFLNK | 0o777) << 16
    for names, refused in ((["AF_L.trk"], False), (["../AF_L.trk"], True), (["/tmp/AF_L.trk"], True)):
        path = tmp_path / "b.zip"
        with zipfile.ZipFile(path, "w") as zf:
            for name in names:
                link.filename = name
                zf.writestr(link, "/etc/passwd")
        into = tmp_path / "into"
        into.mkdir(exist_ok=True)
        with opened() as files:
            if refused:
                with pytest.raises(BrainPainterError, match="a path outside the zip"):
                    unzip(path, into, 10)
                continue
            out, _ = unzip(path, into, 10)
        assert [p.name for p in out] == ["AF_L.trk"] and not out[0].is_symlink()
        assert out[0].read_bytes() == b"/etc/passwd"
        assert all(f.startswith(str(into)) for f, w in files if w), files
        assert json.dumps(sorted(os.listdir(into))) == '["AF_L.trk"]'


def _minc2(path: Path, storage: str, secret: Path) -> Path:
    """A MINC-2 volume (HDF5, as nibabel reads it) whose image is inside, or in `secret` by external
    storage, a virtual dataset or an external link (`storage`)."""
    h5py = pytest.importorskip("h5py")
    shape = (10, 12, 14)
    np.full(shape, 7, np.float32).tofile(secret)
    if storage == "link":
        with h5py.File(secret.with_suffix(".h5"), "w") as other:
            other.create_dataset("image", data=np.full(shape, 7, np.float32))
            other["image"].attrs["dimorder"] = np.bytes_(b"zspace,yspace,xspace")
    with h5py.File(path, "w") as f:
        for n, size, axis in zip(("xspace", "yspace", "zspace"), shape[::-1], np.eye(3), strict=True):
            d = f.create_dataset(f"minc-2.0/dimensions/{n}", data=0)
            d.attrs.update(length=size, step=1.0, start=0.0, direction_cosines=axis)
        image = "minc-2.0/image/0/image"
        if storage == "inside":
            f.create_dataset(image, data=np.ones(shape, np.float32))
        elif storage == "external":
            f.create_dataset(image, shape=shape, dtype=np.float32, external=[(str(secret), 0, 6720)])
        elif storage == "virtual":
            layout = h5py.VirtualLayout(shape=shape, dtype=np.float32)
            layout[:] = h5py.VirtualSource(str(secret.with_suffix(".h5")), "image", shape=shape)
            f.create_virtual_dataset(image, layout)
        else:
            f[image] = h5py.ExternalLink(str(secret.with_suffix(".h5")), "image")
        if storage != "link":
            f[image].attrs["dimorder"] = np.bytes_(b"zspace,yspace,xspace")
        f.create_dataset("minc-2.0/image/0/image-min", data=0.0)
        f.create_dataset("minc-2.0/image/0/image-max", data=1.0)
    return path


@pytest.mark.parametrize("storage", ["external", "virtual", "link"])
def test_a_minc2_volume_that_takes_data_from_another_file_is_refused(tmp_path, storage):
    """MINC-2 is HDF5, whose datasets can be bytes of any file (``--volume x.mnc`` read /etc/passwd)."""
    from brainpainter.atlas.volumes import read_volume
    from brainpainter.maps.volume import load_volume

    secret = tmp_path / "secret.bin"
    path = _minc2(tmp_path / "v.mnc", storage, secret)
    with opened() as files:
        with pytest.raises(BrainPainterError, match="takes data from another file"):
            np.asarray(load_volume(path).dataobj)
        with pytest.raises(BrainPainterError, match="takes data from another file"):
            read_volume(path)
    assert not [f for f, _ in files if f.startswith(str(secret.with_suffix("")))], files


def test_a_minc2_volume_with_its_data_inside_reads(tmp_path):
    from brainpainter.maps.volume import load_volume

    path = _minc2(tmp_path / "v.mnc", "inside", tmp_path / "secret.bin")
    assert float(np.asarray(load_volume(path).dataobj).max()) == 1.0


def _gltf(folder: Path, uri: str) -> Path:
    """A one-triangle glTF whose buffer is the file `uri`; the triangle's bytes are also in
    ``secret.bin`` beside `folder` and ``ok.bin`` inside it."""
    blob = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes() + np.uint16([0, 1, 2]).tobytes()
    (folder.parent / "secret.bin").write_bytes(blob + b"\0\0")
    (folder / "ok.bin").write_bytes(blob + b"\0\0")
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"uri": uri, "byteLength": 44}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                           {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "max": [1, 1, 0], "min": [0, 0, 0]},
                         {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    path = folder / "lh.region.gltf"
    path.write_text(json.dumps(doc))
    return path


def test_a_gltf_mesh_reads_buffers_only_from_its_folder(tmp_path):
    """``atlas add --meshes DIR``: a glTF buffer named ``../secret.bin`` or by an absolute path is refused
    whatever trimesh's release (trimesh 4, which the pins allow, read it)."""
    from brainpainter.atlas.meshfiles import read_mesh

    (tmp_path / "meshes").mkdir()
    secret = str(tmp_path / "secret.bin")
    for uri in ("../secret.bin", secret):
        path = _gltf(tmp_path / "meshes", uri)
        with opened() as files, pytest.raises(BrainPainterError, match="outside its own folder"):
            read_mesh(path)
        assert secret not in {f for f, _ in files}
    vertices, faces = read_mesh(_gltf(tmp_path / "meshes", "ok.bin"))
    assert vertices.shape == (3, 3) and faces.tolist() == [[0, 1, 2]]
