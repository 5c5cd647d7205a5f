"""GIfTI files that point elsewhere (issue 33 item 1) and gzipped GIfTI (item 9).

A ``DataArray`` with ``Encoding="ExternalFileBinary"`` makes nibabel read
another file while it parses: on the command line only a file inside the
GIfTI's own folder may be read, on the web server none at all
(``external="refuse"``). Files are written with nibabel's GIfTI writer; the
external reference is set in its XML.
"""

from __future__ import annotations

import gzip
import os
import re
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.maps.inputs import is_map_input, read_maps

N5 = 10242
NILEARN_FS5 = Path(nib.__file__).parents[1] / "nilearn" / "datasets" / "data" / "fsaverage5"
SECRET = np.arange(N5, dtype=np.float32)  # what a file outside the folder holds


def gifti_xml(values: np.ndarray) -> bytes:
    """A one-array .func.gii as nibabel writes it (data inside, base64 + gzip)."""
    da = nib.gifti.GiftiDataArray(np.asarray(values, np.float32), datatype="NIFTI_TYPE_FLOAT32")
    return nib.gifti.GiftiImage(darrays=[da]).to_xml(enc="utf-8")


def external_xml(external_name: str, n: int = N5) -> bytes:
    """A .func.gii whose one data array is in the file `external_name` (as the XML says it)."""
    xml = gifti_xml(np.zeros(n)).decode()
    xml = xml.replace('Encoding="GZipBase64Binary"', 'Encoding="ExternalFileBinary"')
    xml = xml.replace('ExternalFileName=""', f'ExternalFileName="{external_name}"')
    return re.sub(r"<Data>.*?</Data>", "<Data></Data>", xml, flags=re.S).encode()


def external_gifti(path: Path, external_name: str, n: int = N5) -> Path:
    """:func:`external_xml` written to `path`."""
    path.write_bytes(external_xml(external_name, n))
    return path


@pytest.fixture
def site(tmp_path: Path) -> Path:
    """``secret.bin`` (the values of SECRET) beside an empty folder ``maps/``."""
    SECRET.tofile(tmp_path / "secret.bin")
    (tmp_path / "maps").mkdir()
    return tmp_path


@pytest.mark.parametrize("how", ["parent", "absolute", "symlink"])
def test_cli_reads_no_external_gifti_data_outside_its_folder(site, how):
    name = {"parent": "../secret.bin", "absolute": str(site / "secret.bin"), "symlink": "inner.bin"}[how]
    if how == "symlink":
        (site / "maps" / "inner.bin").symlink_to(site / "secret.bin")
    path = external_gifti(site / "maps" / "lh.x.func.gii", name)
    with pytest.raises(BrainPainterError, match="outside its own folder") as info:
        read_maps(lh=path)
    assert "\n" not in str(info.value)


def test_cli_reads_external_gifti_data_inside_its_folder(site):
    (SECRET * 2).tofile(site / "maps" / "lh.x.bin")
    maps = read_maps(lh=external_gifti(site / "maps" / "lh.x.func.gii", "lh.x.bin"))
    np.testing.assert_array_equal(maps.values["lh"][0], SECRET * 2)


def test_cli_missing_external_file_is_one_line(site):
    with pytest.raises(BrainPainterError, match=r"its data in 'gone.bin', which is not a file in its folder"):
        read_maps(lh=external_gifti(site / "maps" / "lh.x.func.gii", "gone.bin"))


@pytest.mark.parametrize("name", ["lh.x.bin", "../secret.bin", "/etc/passwd", "/nonexistent/x.bin"])
def test_refuse_reads_no_external_data_and_says_the_same_wherever_it_points(site, name):
    """The web server's policy: no external data, and no answer that tells whether the file exists."""
    SECRET.tofile(site / "maps" / "lh.x.bin")
    path = external_gifti(site / "maps" / "lh.x.func.gii", name)
    with pytest.raises(BrainPainterError) as info:
        read_maps(lh=path, external="refuse")
    assert str(info.value) == (
        f"map file 'lh.x.func.gii' keeps its data in another file ({name!r}, Encoding=ExternalFileBinary); "
        "this server reads only data inside the file. Save it with its data inside (e.g. "
        "Encoding=GZipBase64Binary) and upload it again.")


def test_entity_declarations_are_refused(tmp_path):
    entity = '<!DOCTYPE GIFTI [<!ENTITY a "aaaaaaaaaa">]>'
    xml = re.sub(r"<!DOCTYPE[^>]*>", entity, gifti_xml(np.zeros(N5)).decode())
    path = tmp_path / "lh.x.func.gii"
    path.write_text(xml)
    with pytest.raises(BrainPainterError, match="declares the XML entity 'a'"):
        read_maps(lh=path)


def test_a_gzipped_array_larger_than_it_says_is_refused_before_it_inflates(tmp_path):
    """A 90 KB GIfTI whose one array (Dim0 10242, float32: 40968 bytes) inflates to 64 MB."""
    import base64
    import tracemalloc
    import zlib

    xml = gifti_xml(np.zeros(N5)).decode()
    bomb = base64.b64encode(zlib.compress(bytes(64 << 20), 9)).decode()
    path = tmp_path / "lh.x.func.gii"
    path.write_text(re.sub(r"<Data>.*?</Data>", f"<Data>{bomb}</Data>", xml, flags=re.S))
    assert path.stat().st_size < 100_000
    tracemalloc.start()
    try:
        with pytest.raises(BrainPainterError, match="inflates to more than the 40968 bytes its Dim"):
            read_maps(lh=path, external="refuse")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 8 << 20, peak


def test_label_maps_and_surfaces_read_no_external_data_outside_their_folder(site):
    """The other GIfTI readers (atlas add --annot, --white/--pial surfaces) share the policy."""
    from brainpainter.atlas.labelset import read_label_map
    from brainpainter.maps.depth import read_surface

    path = external_gifti(site / "maps" / "lh.x.label.gii", "../secret.bin")
    with pytest.raises(BrainPainterError, match="outside its own folder"):
        read_label_map(path, "lh")
    with pytest.raises(BrainPainterError, match="outside its own folder"):
        read_surface(external_gifti(site / "maps" / "lh.white.surf.gii", "../secret.bin"), "white")


# -- gzipped GIfTI (item 9) ---------------------------------------------------------------------------------
@pytest.mark.parametrize("ending", [".gii.gz", ".func.gii.gz", ".shape.gii.gz"])
def test_gzipped_gifti_is_read(tmp_path, ending):
    values = np.linspace(1.5, 4.0, N5, dtype=np.float32)
    for hemi, v in (("lh", values), ("rh", values[::-1])):
        (tmp_path / f"{hemi}.thick{ending}").write_bytes(gzip.compress(gifti_xml(v)))
    assert is_map_input(f"lh.thick{ending}")
    maps = read_maps(tmp_path / f"lh.thick{ending}")
    assert maps.images == ("thick",)
    np.testing.assert_array_equal(maps.values["lh"][0], values)
    np.testing.assert_array_equal(maps.values["rh"][0], values[::-1])


def test_gzipped_label_gifti_is_read(tmp_path):
    table = nib.gifti.GiftiLabelTable()
    for key, name in ((0, "unknown"), (1, "net1"), (2, "net2")):
        label = nib.gifti.GiftiLabel(key=key, red=key / 2, green=0.5, blue=0.0, alpha=1.0)
        label.label = name
        table.labels.append(label)
    da = nib.gifti.GiftiDataArray((np.arange(N5) % 3).astype(np.int32), intent="NIFTI_INTENT_LABEL",
                                  datatype="NIFTI_TYPE_INT32")
    xml = nib.gifti.GiftiImage(darrays=[da], labeltable=table).to_xml()
    (tmp_path / "lh.nets.label.gii.gz").write_bytes(gzip.compress(xml))
    maps = read_maps(lh=tmp_path / "lh.nets.label.gii.gz")
    assert maps.categories == ("unknown", "net1", "net2")
    assert np.isnan(maps.values["lh"][0][0]) and maps.values["lh"][0][1] == 1


@pytest.mark.skipif(not (NILEARN_FS5 / "thick_left.gii.gz").is_file(), reason="nilearn's fsaverage5 data")
def test_nilearns_fsaverage5_thickness_is_read():
    """nilearn's own ``thick_left.gii.gz`` (and its right partner, found beside it)."""
    maps = read_maps(NILEARN_FS5 / "thick_left.gii.gz")
    assert maps.images == ("thick",) and sorted(maps.values) == ["lh", "rh"]
    for hemi, side in (("lh", "left"), ("rh", "right")):
        raw = gzip.decompress((NILEARN_FS5 / f"thick_{side}.gii.gz").read_bytes())
        expected = nib.gifti.GiftiImage.from_bytes(raw).darrays[0].data
        np.testing.assert_array_equal(maps.values[hemi][0], expected)
        assert maps.values[hemi].shape == (1, N5)


def test_a_file_whose_bytes_are_another_format_says_what_was_found(tmp_path):
    """nilearn's gzipped GIfTI under a FreeSurfer name was parsed as a curv file ("18023 values")."""
    (tmp_path / "lh.thickness").write_bytes(gzip.compress(gifti_xml(np.zeros(N5))))
    with pytest.raises(BrainPainterError) as info:
        read_maps(lh=tmp_path / "lh.thickness")
    assert str(info.value) == (
        "map file 'lh.thickness' looks like gzip-compressed data (a GIfTI file inside), not a FreeSurfer "
        "curv file; gunzip it first (a gzipped GIfTI is read when named .gii.gz).")
    cases = {"lh.x.mgh": (gifti_xml(np.zeros(N5)), "looks like a GIfTI file, not an MGH image"),
             "lh.x.npy": (b"\xff\xff\xff" + bytes(40), "a FreeSurfer curv file, not a NumPy .npy file"),
             "lh.x.func.gii": (np.zeros(4).tobytes(), "does not start with XML, not a GIfTI file"),
             "lh.y.func.gii": (b"\x93NUMPY" + bytes(40), "looks like a NumPy .npy array, not a GIfTI file"),
             "lh.x.txt": (b"\x89PNG\r\n\x1a\n" + bytes(40), "looks like a PNG image, not a text file")}
    for name, (content, message) in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(BrainPainterError, match=re.escape(message)):
            read_maps(lh=tmp_path / name)


def test_a_gzip_bomb_named_gii_gz_is_refused_bounded(tmp_path, monkeypatch):
    import brainpainter.io.files as files

    monkeypatch.setattr(files, "MAX_DATA_FILE", 1 << 20)
    (tmp_path / "lh.x.gii.gz").write_bytes(gzip.compress(b"<" + bytes(8 << 20)))
    with pytest.raises(BrainPainterError, match="inflates to more than 1 MB"):
        read_maps(lh=tmp_path / "lh.x.gii.gz")
    assert os.listdir(tmp_path) == ["lh.x.gii.gz"]


def test_gzipped_gifti_surfaces_read_as_meshes(tmp_path):
    """A region mesh (``atlas add --meshes``) and a white/pial surface may be ``.surf.gii.gz`` too."""
    from brainpainter.atlas.meshfiles import mesh_files, mesh_stem, read_mesh
    from brainpainter.maps.depth import read_surface

    xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    tri = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], np.int32)
    img = nib.gifti.GiftiImage(darrays=[nib.gifti.GiftiDataArray(xyz, intent="NIFTI_INTENT_POINTSET"),
                                        nib.gifti.GiftiDataArray(tri, intent="NIFTI_INTENT_TRIANGLE")])
    path = tmp_path / "lh.region.surf.gii.gz"
    path.write_bytes(gzip.compress(img.to_xml()))
    assert mesh_files(tmp_path) == [path] and mesh_stem(path) == "lh.region"
    vertices, faces = read_mesh(path)
    np.testing.assert_array_equal(vertices, xyz)
    np.testing.assert_array_equal(faces, tri)
    np.testing.assert_array_equal(read_surface(path, "white"), xyz)
