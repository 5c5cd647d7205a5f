"""What an input is, decided in one place (brainpainter.layers.readers, issue 43): by its ending, then
its first bytes; the built-in readers and layer kinds come through their entry-point groups."""

from __future__ import annotations

import numpy as np
import pytest

from brainpainter.atlas.registry import layer_kinds, readers
from brainpainter.errors import BrainPainterError
from brainpainter.layers.readers import identify, is_map_data
from brainpainter.maps.inputs import is_map_input


def test_the_built_in_readers_and_kinds_are_entry_points():
    assert {"table", "surface-map", "volume", "cifti", "tractogram", "matrix", "nodes"} <= set(
        readers.names())
    assert {"regions", "map", "tracts", "connectome", "contour", "outline", "blobs"} <= set(
        layer_kinds.names())
    assert {e.distribution for e in readers.entries()} == {"brainpainter"}


@pytest.mark.parametrize(("name", "reader"), [
    ("stages.csv", "table"), ("lh.thickness", "surface-map"), ("lh.thickness.csv", "table"),
    ("rh.sulc.fwhm10.mgh", "surface-map"), ("x.func.gii", "surface-map"), ("z.nii.gz", "volume"),
    ("sub.dscalar.nii", "cifti"), ("conn.pconn.nii", "matrix"), ("AF_L.trk", "tractogram"),
    ("nodes.node", "nodes"), ("weights.mat", "matrix"), ("notes", "table"),
])
def test_a_name_says_its_reader(name, reader):
    assert identify(name).name == reader


def test_the_main_input_is_a_map_exactly_where_it_was_by_its_name():
    """Every name the old test (maps.inputs.is_map_input) took for a map is one, and no other."""
    names = ["stages.csv", "lh.thickness", "lh.thickness.csv", "lh.aparc.thickness.table", "x.mgz", "x.npy",
             "z.nii", "c.pconn.nii", "d.dscalar.nii", "l.annot", "a.label", "t.xlsx", "rh.curv.asc", "data"]
    assert [is_map_data(n) for n in names] == [is_map_input(n) for n in names]


def test_a_name_no_reader_claims_is_read_by_its_first_bytes(tmp_path):
    """A FreeSurfer curv file named without its hemisphere is a map; text without an ending a table."""
    curv = tmp_path / "thickness_left"
    curv.write_bytes(b"\xff\xff\xff" + np.array([3, 0, 1], ">i4").tobytes() + np.zeros(3, ">f4").tobytes())
    text = tmp_path / "values"
    text.write_text("Image-name-unique,Left-insula\na,1\n")
    assert identify(curv).name == "surface-map" and is_map_data(curv)
    assert identify(text).name == "table" and not is_map_data(text)
    assert is_map_input(curv) is False  # the name alone took it for a table


def test_a_file_of_no_kind_asked_for_says_which_are_read():
    with pytest.raises(BrainPainterError, match=r"\.trk"):
        identify("weights.bin", ("tracts",))


def test_check_asks_the_same_readers_what_an_input_is(tmp_path):
    """``brainpainter check``'s map-or-connectome question (rendering.input_report.input_kind) goes
    through the readers: an ending, a FreeSurfer name, a .npy by its shape, else the first bytes."""
    from brainpainter.rendering.input_report import input_kind

    curv = b"\xff\xff\xff" + np.array([3, 0, 1], ">i4").tobytes() + np.zeros(3, ">f4").tobytes()
    files = {"w.mat": b"", "w.edge": b"1 0\n0 1\n", "lh.thickness": curv, "thick_left": curv,
             "t.csv": b"a,b\n1,2\n", "n.node": b"1 2 3 1 1 a\n", "notes": b"text\n"}
    for name, content in files.items():
        (tmp_path / name).write_bytes(content)
    np.save(tmp_path / "square.npy", np.eye(4))
    np.save(tmp_path / "vertices.npy", np.zeros(10242))
    kinds = {name: input_kind(tmp_path / name) for name in [*files, "square.npy", "vertices.npy"]}
    assert kinds == {"w.mat": "connectome", "w.edge": "connectome", "lh.thickness": "map",
                     "thick_left": "map", "t.csv": None, "n.node": None, "notes": None,
                     "square.npy": "connectome", "vertices.npy": "map"}


def test_an_install_without_the_readers_entry_points_says_to_reinstall(monkeypatch):
    """Metadata older than the code (no brainpainter.readers): one line saying what to do, never a map
    file silently read as a table."""
    from brainpainter.errors import PluginError

    monkeypatch.setattr(readers, "names", lambda: [])
    with pytest.raises(PluginError, match="reinstall"):
        is_map_data("lh.thickness.mgh")
