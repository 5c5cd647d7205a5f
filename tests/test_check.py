"""``brainpainter check``: the report of how a table was read, and render's one-line summary."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from brainpainter.cli.main import cli, main
from brainpainter.testing import stand_in

GOOD = ("Image-name-unique,Left-insula,lh_precuneus_thickness,eTIV,Age,Left-insulaa\n"
        "A,1,2,1500000,30,1\nB,2,,1,31,2\n")


def _check(tmp_path, text, *args, name="in.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return CliRunner().invoke(cli, ["check", str(path), *args])


def test_text_report_says_how_each_name_was_read(tmp_path):
    result = _check(tmp_path, GOOD)
    assert result.exit_code == 0, result.output
    out = result.output
    assert "wide (one row per image" in out and "images in 'Image-name-unique'" in out
    assert "atlas   dk (inferred:" in out
    assert "Left-insula" in out and "-> Left-precuneus  [FreeSurfer stats table]" in out
    assert "eTIV" in out and "summary measure, not a region" in out
    assert "unmatched (2)" in out and "closest: Left-insula" in out
    assert "regions without a value (93)" in out and "... and 69 more" in out
    assert "cells   1 empty" in out and "scale   white,yellow,orange,red: 0 .. 3" in out
    assert out.rstrip().splitlines()[-1].startswith("OK ")


def test_json_report(tmp_path):
    result = _check(tmp_path, GOOD, "--json", "--atlas", "dk")
    assert result.exit_code == 0
    report = json.loads(result.output)
    assert report["ok"]
    assert report["atlas"] == {"name": "dk", "inferred": False, "reason": "given with --atlas", "scores": {}}
    by_name = {n["name"]: n for n in report["names"]}
    assert by_name["lh_precuneus_thickness"]["regions"] == ["Left-precuneus"]
    assert by_name["Left-insulaa"]["status"] == "unmatched"
    assert by_name["Left-insulaa"]["closest"][0] == "Left-insula"
    assert by_name["eTIV"]["status"] == "ignored"
    assert report["unmatched"] == ["Age", "Left-insulaa"]
    assert report["cells"]["n_empty"] == 1 and report["values"]["range"] == [1.0, 2.0]
    assert report["inputs"][0]["shape"]["kind"] == "wide"


def test_unmatched_name_of_another_atlas_is_pointed_out(tmp_path):
    text = "Image-name-unique,Left-insula,Left-bankssts\nA,1,2\n"
    result = _check(tmp_path, text, "--atlas", "dkt", "--json")
    by_name = {n["name"]: n for n in json.loads(result.output)["names"]}
    assert by_name["Left-bankssts"]["region_of_atlas"] == ["dk"]


def test_scale_comparison_and_hints(tmp_path):
    text = "Structure,d\nL_insula,-0.4\nR_insula,0.9\n"
    report = json.loads(_check(tmp_path, text, "--json").output)
    assert report["values"]["n_below_vmin"] == 1
    assert any("diverging" in h for h in report["values"]["hints"])
    report = json.loads(_check(tmp_path, text, "--json", "--cmap", "RdBu_r", "--center", "0").output)
    assert report["values"]["scale"]["center"] == 0 and report["values"]["n_below_vmin"] == 0


def test_bad_cells_are_all_listed_and_exit_2(tmp_path, capsys):
    path = tmp_path / "in.csv"
    path.write_text("Image-name-unique,Left-insula,Right-insula\nA,high,inf\nB,1,low\n")
    with pytest.raises(SystemExit) as exc:
        main(["check", str(path)])
    assert exc.value.code == 2
    captured = capsys.readouterr()
    assert "'high' is not a number" in captured.out and "'inf' is infinite" in captured.out
    assert "'low' is not a number" in captured.out and "render would stop" in captured.out
    assert captured.err.strip().startswith("error: ") and len(captured.err.strip().splitlines()) == 1


def test_strict_turns_unmatched_into_an_error(tmp_path, capsys):
    path = tmp_path / "in.csv"
    path.write_text(GOOD)
    with pytest.raises(SystemExit) as exc:
        main(["check", str(path), "--strict"])
    assert exc.value.code == 2
    assert ("2 name(s) match no dk region: 'Age', 'Left-insulaa' (did you mean 'Left-insula'?)"
            in capsys.readouterr().err)


def test_several_inputs_are_merged(tmp_path):
    lh = tmp_path / "lh.tsv"
    rh = tmp_path / "rh.tsv"
    lh.write_text("lh.aparc.thickness\tlh_insula_thickness\teTIV\ns1\t2.5\t1\ns2\t2.6\t1\n")
    rh.write_text("rh.aparc.thickness\trh_insula_thickness\teTIV\ns1\t2.4\t1\ns3\t2.7\t1\n")
    result = CliRunner().invoke(cli, ["check", str(lh), str(rh), "--json"])
    report = json.loads(result.output)
    assert report["n_images"] == 3 and report["unmatched"] == []
    assert report["n_regions_with_value"] == 2 and len(report["inputs"]) == 2
    assert any("not in" in n for n in report["notes"])


def test_render_prints_the_summary_line_and_writes_it_to_the_manifest(tmp_path, tiny):
    with stand_in("blank"):
        path = tmp_path / "in.csv"
        path.write_text("Structure;d\nL_insula;0,5\nRhippo;1,25\nICV;3\n")
        out = tmp_path / "out"
        result = CliRunner().invoke(cli, ["render", str(path), "--out", str(out), "--renderer", "blank",
                                          "--template", str(tiny), "--views", "lateral-left", "--size",
                                          "32x32", "--quiet"])
        assert result.exit_code == 0, result.output
        first = result.output.splitlines()[0]
        assert first.startswith("input: long (ENIGMA names), atlas dk (inferred): 1 image(s), 2/")
        manifest = json.loads((out / "manifest.json").read_text())
        summary = manifest["input"]
        assert summary["atlas_inferred"]
        assert summary["ignored_columns"] == {"ICV": "summary measure, not a region (ENIGMA)"}
        assert summary["value_range"] == [0.5, 1.25] and summary["inputs"][0]["shape"]["value_column"] == "d"
        assert any("decimal commas" in n for n in summary["notes"])
        assert sorted(p.name for p in out.iterdir()) == ["d_lateral-left.png", "manifest.json"]


# -- issue 44 item 14: maps and connectomes are reported as what they are ------------------------------
def _run_check(path, *args):
    return CliRunner().invoke(cli, ["check", str(path), *args])


def test_check_reports_a_cifti_dscalar_as_a_map_and_how_it_is_drawn():
    """A valid dscalar got "contains NUL bytes: it is binary, not a text table; give a CSV"."""
    from pathlib import Path

    dscalar = Path(__file__).resolve().parents[2] / "shared" / "data" / "fslr" / \
        "MSMSulc.refsulc.164k_fs_LR.dscalar.nii"
    if not dscalar.is_file():
        pytest.skip("../shared/data/fslr is not here")
    result = _run_check(dscalar)
    assert result.exit_code == 0, result.output
    out = result.output
    assert f"input   {dscalar}: a CIFTI-2 dense scalar file" in out
    assert "mesh    lh: 163,842 vertices (fsLR 164k)" in out and "images  1: 100307_Sulc" in out
    assert "scale   RdBu_r -1.69 to 1.69 (values of both signs)" in out
    assert "draws   a map on the cortex, resampled onto fsaverage with HCP's fsLR weights" in out
    assert f"command brainpainter render {dscalar} --out DIR" in out and "NUL" not in out
    assert out.rstrip().splitlines()[-1] == "OK      map: render would draw it"
    report = json.loads(_run_check(dscalar, "--json").output)
    assert (report["kind"], report["space"], report["n_images"]) == ("map", "fsLR", 1)


@pytest.mark.parametrize("kind", ["curv", "gifti", "mgh"])
def test_check_reports_a_curv_gifti_or_mgh_map(tmp_path, kind):
    import nibabel as nib
    import numpy as np

    values = (np.arange(10242) % 300 / 100).astype(np.float32)
    if kind == "curv":
        path = tmp_path / "lh.thickness"
        nib.freesurfer.write_morph_data(str(path), values)
    elif kind == "gifti":
        path = tmp_path / "lh.thickness.func.gii"
        nib.save(nib.gifti.GiftiImage(darrays=[nib.gifti.GiftiDataArray(values)]), path)
    else:
        path = tmp_path / "lh.thickness.mgh"
        nib.save(nib.MGHImage(values.reshape(-1, 1, 1), np.eye(4)), path)
    result = _run_check(path)
    assert result.exit_code == 0, result.output
    fmt = {"curv": "a FreeSurfer curv file", "gifti": "a GIfTI file", "mgh": "an MGH image"}[kind]
    assert f"input   {path}: {fmt}" in result.output
    assert "mesh    lh: 10,242 vertices (fsaverage5)" in result.output
    assert "values  0 .. 2.99 (10,242 finite" in result.output and "scale   viridis 0-2.99" in result.output
    assert "draws   a map on the cortex, on fsaverage" in result.output


def test_check_reports_a_connectome_with_names_or_in_an_atlas_order(tmp_path):
    import numpy as np

    names = ["Left-insula", "Left-precuneus", "Right-insula"]
    rows = [",".join(["", *names])] + [f"{n},{','.join(str(w) for w in row)}" for n, row in
                                       zip(names, [[0, 0.5, -0.2], [0.5, 0, 0], [-0.2, 0, 0]], strict=True)]
    (tmp_path / "fc.csv").write_text("\n".join(rows) + "\n")
    result = _run_check(tmp_path / "fc.csv")
    assert result.exit_code == 0, result.output
    out = result.output
    assert f"input   {tmp_path / 'fc.csv'}: a connectivity matrix, 3 x 3" in out
    assert "nodes   names in the first row and column (e.g. 'Left-insula'); they fit atlas 'dk'" in out
    assert "edges   2 with a weight, -0.2 .. 0.5" in out
    assert f"command brainpainter render --connectome {tmp_path / 'fc.csv'} --atlas dk --out DIR" in out
    w = np.ones((68, 68))
    np.savetxt(tmp_path / "m68.txt", w)
    out = _run_check(tmp_path / "m68.txt").output
    assert "nodes   no names: the rows are placed in an atlas's node order; the atlases that take 68 rows: " \
        "dk" in out and out.rstrip().endswith("OK      connectome: render would draw it")
