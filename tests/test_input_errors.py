"""Errors that callers branch on are types (brainpainter.errors), not message text."""

from __future__ import annotations

import pytest

from brainpainter.errors import BrainPainterError, NoRegionColumnError
from brainpainter.table.region_table import read_table


def test_no_region_column_names_the_atlas_that_fits(tmp_path):
    """A table naming no region raises NoRegionColumnError; one naming another atlas's regions says which."""
    path = tmp_path / "in.csv"
    path.write_text("Image-name-unique,foo,bar\na,1,2\n")
    with pytest.raises(NoRegionColumnError, match="no column names a dk region"):
        read_table(path, "dk")
    destrieux = tmp_path / "destrieux.csv"
    destrieux.write_text("Image-name-unique,Left-G_and_S_frontomargin,Right-G_and_S_frontomargin\na,1,2\n")
    with pytest.raises(NoRegionColumnError, match="The names fit atlas 'destrieux': give --atlas destrieux"):
        read_table(destrieux, "dk")
    with pytest.raises(BrainPainterError) as other:
        read_table(path, "dk", image_column="nope")
    assert not isinstance(other.value, NoRegionColumnError)


def test_a_table_read_with_the_wrong_atlas_says_which_fits(tmp_path):
    """DK names read with --atlas destrieux: its subcortical columns match, its cortical ones do not; a
    note says the names fit dk (the cortex was drawn grey, the names listed with destrieux look-alikes)."""
    path = tmp_path / "dk.csv"
    path.write_text("Image-name-unique,Left-insula,Left-precuneus,Right-insula,Left-Hippocampus\na,1,2,3,4\n")
    table = read_table(path, "destrieux")
    assert len(table.unmatched) == 3
    assert "the names fit atlas 'dk' better (4 of its regions against 1 of 'destrieux'): give --atlas dk" \
        in table.notes
    assert not read_table(path, "dk").notes  # the right atlas: no note
    typo = tmp_path / "typo.csv"
    typo.write_text("Image-name-unique,Left-insula,Left-insular\na,1,2\n")
    assert not read_table(typo, "dk").notes  # an unmatched name that fits no atlas better: no note


def test_names_that_match_nothing_are_each_listed_with_their_closest_region(tmp_path):
    """Issue 44 item 15: every unmatched name with its closest match, not only the first (nor none)."""
    path = tmp_path / "in.csv"
    path.write_text("Image-name-unique,Left-insular,Left-precuneous,bar\na,1,2,3\n")
    listed = (r"the columns: 'Left-insular' \(did you mean 'Left-insula'\?\), 'Left-precuneous' \(did you "
              r"mean 'Left-precuneus'\?\), 'bar'")
    with pytest.raises(NoRegionColumnError, match=listed + r"\. Use names"):
        read_table(path)
    with pytest.raises(NoRegionColumnError, match=r"\(" + listed + r"\); use region names"):
        read_table(path, "dk")


@pytest.mark.parametrize("spelt", ["fslr", "FSLR", "fsLR"])
def test_space_fslr_is_case_insensitive(tmp_path, capsys, spelt):
    """Issue 44 item 15: ``--space fslr`` was "Invalid value for '--space'"; any case names fsLR."""
    from brainpainter.cli.main import main
    from brainpainter.maps.options import MapOptions

    assert MapOptions(space=spelt).space == "fsLR"
    with pytest.raises(SystemExit) as exit_:
        main(["render", "--lh", str(tmp_path / "none.gii"), "--space", spelt, "--out", str(tmp_path / "out")])
    said = capsys.readouterr().err
    assert exit_.value.code == 2 and "Invalid value" not in said and "does not exist" in said, said
    with pytest.raises(BrainPainterError, match="space must be one of"):
        MapOptions(space="fslrr")
