"""Reading the original BrainPainter CSV (first pass) and DataFrames/dicts."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.table.region_table import read_table


def write(tmp_path, text, name="in.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_original_format(tmp_path):
    path = write(tmp_path, "Image-name-unique,Left-insula,Right-insula,Left-Hippocampus,Brain-Stem\n"
                           "a,0,1.5,3,\nb,1,2,0,2\n")
    table = read_table(path, "dk")
    assert table.images == ("a", "b")
    assert table.regions == ("Left-insula", "Right-insula", "Left-Hippocampus", "Brain-Stem")
    np.testing.assert_array_equal(table.values[1], [1, 2, 0, 2])
    assert np.isnan(table.values[0, 3])
    assert "Right-bankssts" in table.absent
    assert table.summary()["n_empty_cells"] == 1


def test_names_case_insensitive_and_freesurfer_spellings(tmp_path):
    path = write(tmp_path, "image-name-unique,left-INSULA,ctx-rh-insula,Left-Thalamus-Proper,lh_precuneus\n"
                           "x,1,2,3,0\n")
    table = read_table(path, "dk")
    assert table.regions == ("Left-insula", "Right-insula", "Left-Thalamus", "Left-precuneus")


def test_dataframe_and_dict_work_the_same(tmp_path):
    frame = pd.DataFrame({"Image-name-unique": ["a"], "Left-insula": [2.0]})
    assert read_table(frame, "dk").row(0) == {"Left-insula": 2.0}
    table = read_table({"Left-insula": [1, 2], "Right-insula": [0, 3]}, "dk")
    assert table.images == ("1", "2") and table.values.shape == (2, 2)


def test_unmatched_columns_are_reported_or_strict(tmp_path):
    path = write(tmp_path, "Image-name-unique,Left-insula,Left-insulaa\nx,1,2\n")
    assert read_table(path, "dk").unmatched == ["Left-insulaa"]
    with pytest.raises(BrainPainterError, match="did you mean 'Left-insula'"):
        read_table(path, "dk", strict=True)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "is empty"),
        ("Image-name-unique,Left-insula\n", "no rows"),
        ("Image-name-unique,Left-insula\na,high\n", "'high', which is not a number"),
        ("Image-name-unique,Left-insula\na,inf\n", "infinite"),
        ("Image-name-unique,Left-insula,ctx-lh-insula\na,1,2\n", "both name region 'Left-insula'"),
        ("Image-name-unique,Left-insula\na,1\na,2\n", "must be unique"),
        ("Image-name-unique,foo,bar\na,1,2\n", "no column names a dk region"),
    ],
)
def test_bad_tables(tmp_path, text, message):
    with pytest.raises(BrainPainterError, match=message):
        read_table(write(tmp_path, text), "dk")


def test_binary_and_missing_files(tmp_path):
    binary = tmp_path / "x.csv"
    binary.write_bytes(b"\x00\x01\x02garbage")
    with pytest.raises(BrainPainterError, match="binary"):
        read_table(binary, "dk")
    with pytest.raises(BrainPainterError, match="does not exist"):
        read_table(tmp_path / "nope.csv", "dk")


# -- name resolution: one alias table per atlas -------------------------------------------------------
@pytest.mark.parametrize(
    ("atlas", "name", "keys"),
    [
        ("dk", "Left-insula", ("Left-insula",)),
        ("dk", "RIGHT-INSULA", ("Right-insula",)),
        ("dk", "insula", ("Left-insula", "Right-insula")),  # BrainPainter 2019: both hemispheres
        ("dk", "Thalamus-Proper", ("Left-Thalamus", "Right-Thalamus")),
        ("dk", "lh_insula_thickness", ("Left-insula",)),  # FreeSurfer stats
        ("dk", "rh_insula_area", ("Right-insula",)),
        ("dk", "lh_insula_volume", ("Left-insula",)),
        ("dk", "ctx-lh-insula", ("Left-insula",)),  # look-up table
        ("dk", "Left-Hippocampus", ("Left-Hippocampus",)),
        ("dk", "Left-Thalamus-Proper", ("Left-Thalamus",)),  # FreeSurfer 6
        ("dk", "L_insula", ("Left-insula",)),  # ENIGMA
        ("dk", "R_bankssts", ("Right-bankssts",)),
        ("dk", "L_bankssts_thickavg", ("Left-bankssts",)),
        ("dk", "R_insula_surfavg", ("Right-insula",)),
        ("dk", "Lhippo", ("Left-Hippocampus",)),
        ("dk", "Rthal", ("Right-Thalamus",)),
        ("dk", "Laccumb", ("Left-Accumbens-area",)),
        ("dk", "Lamyg", ("Left-Amygdala",)),
        ("dk", "Lcaud", ("Left-Caudate",)),
        ("dk", "Lpal", ("Left-Pallidum",)),
        ("dk", "Lput", ("Left-Putamen",)),
        ("dk", "LLatVent", ("Left-Lateral-Ventricle",)),
        ("dk", "RLatVent", ("Right-Lateral-Ventricle",)),
        ("dk", "lh_insula", ("Left-insula",)),  # ggseg
        ("dk", "Brain-Stem", ("Brain-Stem",)),
        ("destrieux", "rh_G_and_S_frontomargin_area", ("Right-G_and_S_frontomargin",)),
        ("destrieux", "ctx_lh_G_and_S_frontomargin", ("Left-G_and_S_frontomargin",)),
        ("destrieux", "lh_G&S_frontomargin_thickness", ("Left-G_and_S_frontomargin",)),
        ("destrieux", "G_cuneus", ("Left-G_cuneus", "Right-G_cuneus")),
        ("dkt", "lh_insula_thickness", ("Left-insula",)),
        ("tourville", "Left-Accumbens-area", ("Left-Accumbens-area",)),
    ],
)
def test_alias_table(atlas, name, keys):
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.table.names import NameResolver

    r = NameResolver.for_atlas(get_atlas(atlas)).lookup(name)
    assert (r.status, r.keys) == ("region", keys)


@pytest.mark.parametrize("name", [
    "lh_MeanThickness_thickness", "rh_WhiteSurfArea_area", "eTIV", "BrainSegVolNotVent",
    "EstimatedTotalIntraCranialVol", "ICV", "LThickness", "Left-vessel", "CC_Anterior", "unknown",
    "Right-unknown", "ctx_lh_Medial_wall"])
def test_non_region_names_are_recognised(name):
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.table.names import NameResolver

    assert NameResolver.for_atlas(get_atlas("dk")).lookup(name).status == "ignored"


def test_atlas_inference():
    from brainpainter.atlas.registry import get_atlas

    dkt = get_atlas("dkt")
    full_dkt = {r.key: [1.0] for r in dkt.regions}
    assert read_table(full_dkt).atlas.name == "dkt"  # complete in DKT, a subset of DK
    assert read_table({"Left-insula": 1}).atlas.name == "dk"  # tie: dk first
    assert read_table({"Left-bankssts": 1}).atlas.name == "dk"
    assert read_table({"Left-G_cuneus": 1}).atlas.name == "destrieux"
    sub = read_table({"Left-Hippocampus": 1})
    assert sub.atlas.name == "dk" and "subcortical" in sub.atlas_guess.reason
    assert read_table({"Left-insula": 1}, "dkt").atlas_guess is None


# -- file formats ------------------------------------------------------------------------------------
def test_bom_semicolons_and_decimal_commas(tmp_path):
    path = tmp_path / "eu.csv"
    path.write_bytes("\ufeffImage-name-unique;Left-insula;Right-insula\nsujet-é;1,5;-2,25e-1\n".encode())
    table = read_table(path)
    assert table.images == ("sujet-é",)
    np.testing.assert_allclose(table.values, [[1.5, -0.225]])
    assert "UTF-8 with BOM" in table.formats[0] and "';'-separated" in table.formats[0]
    assert any("decimal commas" in n for n in table.notes)


def test_tsv_utf16_cp1252_whitespace_and_old_mac_line_ends(tmp_path):
    text = "Image-name-unique\tLeft-insula\nMüller\t2\n"
    for name, data in [("a.tsv", text.encode()), ("b.txt", text.encode("utf-16")),
                       ("c.csv", text.replace("\t", ",").encode("cp1252")),
                       ("d.txt", text.replace("\t", "   ").encode()),
                       ("e.csv", text.replace("\t", ",").replace("\n", "\r").encode())]:
        (tmp_path / name).write_bytes(data)
        table = read_table(tmp_path / name)
        assert table.images == ("Müller",) and table.values.tolist() == [[2.0]], name


def test_xlsx_with_empty_extra_sheets(tmp_path):
    from openpyxl import Workbook

    wb = Workbook()
    ws = wb.active
    ws.title = "data"
    ws.append(["Image-name-unique", "Left-insula", "Right-Hippocampus"])
    ws.append(["A", 1.5, 2])
    ws.append([7, None, 3])
    wb.create_sheet("Sheet2")
    wb.save(tmp_path / "t.xlsx")
    table = read_table(tmp_path / "t.xlsx")
    assert table.images == ("A", "7")
    np.testing.assert_array_equal(table.values, [[1.5, 2], [np.nan, 3]])
    assert table.formats == ("Excel workbook, sheet 'data'",)


def test_python_objects(tmp_path):
    frame = pd.DataFrame({"Left-insula": [1.0, 2.0]}, index=pd.Index(["s1", "s2"], name="subject"))
    assert read_table(frame).images == ("s1", "s2")
    nested = read_table({"s1": {"Left-insula": 1, "Rthal": 2}, "s2": {"Left-insula": 3}})
    assert nested.images == ("s1", "s2") and np.isnan(nested.values[1, 1])
    series = read_table(pd.Series({"L_insula": 0.3, "R_insula": -0.1}))
    assert series.regions == ("Left-insula", "Right-insula")
    assert read_table(b"Left-insula\n4\n").values.tolist() == [[4.0]]
    import io

    assert read_table(io.BytesIO(b"Left-insula\n5\n")).values.tolist() == [[5.0]]
    with pytest.raises(BrainPainterError, match="not supported"):
        read_table(3.5)


def test_long_table_with_image_column(tmp_path):
    path = write(tmp_path, "Image-name-unique,Structure,value\nA,L_insula,1\nA,R_insula,2\nB,L_insula,3\n")
    table = read_table(path)
    assert table.shapes[0].kind == "long" and table.images == ("A", "B")
    np.testing.assert_array_equal(table.values, [[1, 2], [3, np.nan]])
    explicit = read_table(path, region_column="Structure", value="value", image_column="Image-name-unique")
    np.testing.assert_array_equal(explicit.values, table.values)


def test_inspect_lists_every_bad_cell(tmp_path):
    from brainpainter.table.region_table import inspect_table

    path = write(tmp_path, "Image-name-unique,Left-insula,Right-insula\na,x,inf\nb,1,y\n")
    table = inspect_table(path)
    assert [(p.where, p.column, p.problem) for p in table.problems] == [
        ("line 2", "Left-insula", "not a number"), ("line 2", "Right-insula", "infinite"),
        ("line 3", "Right-insula", "not a number")]
    assert table.errors and np.isnan(table.values[0]).all()
