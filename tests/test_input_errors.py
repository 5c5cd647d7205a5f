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


def test_random_bytes_named_lh_thickness_are_not_a_curv_file(tmp_path, capsys):
    """Issue 44 item 15: 5,000 random bytes named lh.thickness were read as 2,497 values (nibabel's old curv
    format takes any bytes) and refused as 'fits no known mesh'; the old format's size is now checked."""
    import numpy as np

    from brainpainter.cli.main import main
    from brainpainter.maps.files import read_file

    path = tmp_path / "lh.thickness"
    path.write_bytes(np.random.default_rng(0).bytes(5000))
    with pytest.raises(SystemExit) as exit_:
        main(["render", "--lh", str(path), "--out", str(tmp_path / "out")])
    said = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(said) == 1, said
    assert "cannot read map file 'lh.thickness': it is not a FreeSurfer curv file (5,000 bytes" in said[0]
    assert "MGH, GIfTI" in said[0] and not (tmp_path / "out").exists()
    values = np.arange(10242) % 300 / 100  # a real old-format curv file: 3-byte counts, then int16 / 100
    old = tmp_path / "lh.old"
    old.write_bytes((10242).to_bytes(3, "big") + (20480).to_bytes(3, "big")
                    + np.round(values * 100).astype(">i2").tobytes())
    np.testing.assert_allclose(read_file(old, "lh").values[0], values, atol=1e-6)


def test_an_mgz_with_trailing_zeros_is_read_without_inflating_them(tmp_path):
    """Issue 44 item 15: an .mgz of 10,242 values and 1 GiB of zeros after them peaked at 2.1 GB (all
    inflated, then copied); its header says how many bytes it uses, and only those are inflated."""
    import gzip
    import tracemalloc

    import nibabel as nib
    import numpy as np

    from brainpainter.maps.files import read_file

    values = (np.arange(10242) % 300 / 100).astype(np.float32)
    path = tmp_path / "lh.zeros.mgz"
    with gzip.open(path, "wb", compresslevel=1) as f:
        f.write(nib.MGHImage(values.reshape(-1, 1, 1), np.eye(4)).to_bytes())
        for _ in range(16):
            f.write(bytes(16 << 20))  # 256 MiB of zeros
    tracemalloc.start()
    try:
        read = read_file(path, "lh")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(read.values[0], values)
    assert peak < 8 << 20, peak  # a few times the 41 kB of data, not the 256 MiB of zeros
