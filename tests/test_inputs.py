"""Reading the original BrainPainter CSV (first pass) and DataFrames/dicts."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from brainpainter.errors import BrainPainterError
from brainpainter.inputs import read_table


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
