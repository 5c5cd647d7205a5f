"""The tables researchers have resolve with zero unmatched names, and render.

Each table is written here from its format description and the atlas region
lists: the original BrainPainter templates for DK, Destrieux and Tourville
(DKT) in the current format (``Image-name-unique`` + ``Left-``/``Right-``, with
FreeSurfer 6 ``Thalamus-Proper`` and ``unknown`` as in the originals) and the
2019 legacy format (bare names for both hemispheres); ENIGMA cortical-thickness
and subcortical-volume tables (summary statistics, long, and per-subject, wide);
``aparcstats2table`` (lh and rh files together, three parcellations, three
measures, also ``--transpose``) and ``asegstats2table`` (FreeSurfer 6 and 7).
Rendering uses a stand-in renderer like tests/test_render_core.py.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from brainpainter.atlas.registry import get_atlas
from brainpainter.rendering.run import render
from brainpainter.table.region_table import read_table
from brainpainter.testing import StandInRenderer, stand_in, write_tiny_template

PARC = {"dk": "aparc", "destrieux": "aparc.a2009s", "dkt": "aparc.DKTatlas"}
ENIGMA_SUBCORTICAL = ["LLatVent", "RLatVent", "Lthal", "Rthal", "Lcaud", "Rcaud", "Lput", "Rput", "Lpal",
                      "Rpal", "Lhippo", "Rhippo", "Lamyg", "Ramyg", "Laccumb", "Raccumb"]
ENIGMA_KEYS = {f"{side}-{name}" for side in ("Left", "Right") for name in (
    "Lateral-Ventricle", "Thalamus", "Caudate", "Putamen", "Pallidum", "Hippocampus", "Amygdala",
    "Accumbens-area")}
ASEG_FS7 = (
    "Left-Lateral-Ventricle Left-Inf-Lat-Vent Left-Cerebellum-White-Matter Left-Cerebellum-Cortex "
    "Left-Thalamus Left-Caudate Left-Putamen Left-Pallidum 3rd-Ventricle 4th-Ventricle Brain-Stem "
    "Left-Hippocampus Left-Amygdala CSF Left-Accumbens-area Left-VentralDC Left-vessel Left-choroid-plexus "
    "Right-Lateral-Ventricle Right-Inf-Lat-Vent Right-Cerebellum-White-Matter Right-Cerebellum-Cortex "
    "Right-Thalamus Right-Caudate Right-Putamen Right-Pallidum Right-Hippocampus Right-Amygdala "
    "Right-Accumbens-area Right-VentralDC Right-vessel Right-choroid-plexus 5th-Ventricle WM-hypointensities "
    "Left-WM-hypointensities Right-WM-hypointensities non-WM-hypointensities Left-non-WM-hypointensities "
    "Right-non-WM-hypointensities Optic-Chiasm CC_Posterior CC_Mid_Posterior CC_Central CC_Mid_Anterior "
    "CC_Anterior BrainSegVol BrainSegVolNotVent lhCortexVol rhCortexVol CortexVol lhCerebralWhiteMatterVol "
    "rhCerebralWhiteMatterVol CerebralWhiteMatterVol SubCortGrayVol TotalGrayVol SupraTentorialVol "
    "SupraTentorialVolNotVent MaskVol BrainSegVol-to-eTIV MaskVol-to-eTIV lhSurfaceHoles rhSurfaceHoles "
    "SurfaceHoles EstimatedTotalIntraCranialVol"
).split()
ASEG_FS6 = [c.replace("Thalamus", "Thalamus-Proper") for c in ASEG_FS7] + [
    "BrainSegVolNotVentSurf", "SupraTentorialVolNotVentVox"]


def _rows(n_images: int, n_values: int, seed: int = 0) -> np.ndarray:
    return np.round(np.random.default_rng(seed).uniform(0, 3, (n_images, n_values)), 3)


def _csv(header: list[str], names: list[str], values: np.ndarray, sep: str = ",") -> str:
    lines = [sep.join(header)]
    lines += [sep.join([n, *(f"{v:g}" for v in row)]) for n, row in zip(names, values, strict=True)]
    return "\n".join(lines) + "\n"


def brainpainter_current(atlas: str) -> str:
    """The original template: Right- then Left- cortex (with 'unknown'), FreeSurfer 6 subcortical names."""
    a = get_atlas(atlas)
    cols = [r.key for h in ("rh", "lh") for r in a.cortical(h)]
    cols[len(cols) // 2: len(cols) // 2] = ["Right-unknown"]
    cols.append("Left-unknown")
    cols += [r.key.replace("Thalamus", "Thalamus-Proper") for r in a.subcortical()]
    return _csv(["Image-name-unique", *cols], ["Image_0", "Image_1"], _rows(2, len(cols)))


def brainpainter_legacy(atlas: str) -> str:
    """The 2019 format: bare names that apply to both hemispheres."""
    a = get_atlas(atlas)
    cols = [r.name for r in a.cortical("lh")] + ["Unknown" if atlas == "destrieux" else "unknown"]
    cols += list(dict.fromkeys(r.name.replace("Thalamus", "Thalamus-Proper") for r in a.subcortical()))
    return _csv(["Image-name-unique", *cols], ["Image_1", "Image_2"], _rows(2, len(cols)))


def aparcstats2table(atlas: str, hemi: str, measure: str, subjects=("subj01", "subj02", "subj03")) -> str:
    a = get_atlas(atlas)
    cols = [f"{hemi}_{r.name}_{measure}" for r in a.cortical(hemi)]
    cols.append({"thickness": f"{hemi}_MeanThickness_thickness", "area": f"{hemi}_WhiteSurfArea_area",
                 "volume": "eTIV"}[measure])
    cols += ["BrainSegVolNotVent", "eTIV"] if measure != "volume" else ["BrainSegVolNotVent"]
    values = _rows(len(subjects), len(cols), seed=1 if hemi == "lh" else 2)
    return _csv([f"{hemi}.{PARC[atlas]}.{measure}", *cols], list(subjects), values, sep="\t")


def asegstats2table(columns: list[str]) -> str:
    values = _rows(2, len(columns)) * 1000
    return _csv(["Measure:volume", *columns], ["subj01", "subj02"], values, sep="\t")


def enigma_cortical_long(suffix: str = "", d: str = "d.icv") -> str:
    dk = get_atlas("dk")
    lines = [f"CorticalThickness,Structure,{d},se.icv,low.ci.icv,up.ci.icv,n.controls,n.patients,pobs,fdr.p"]
    rng = np.random.default_rng(3)
    for side, hemi in (("L", "lh"), ("R", "rh")):
        for r in dk.cortical(hemi):
            e = rng.uniform(-0.4, 0.3)
            lines.append(f"ALLEPI_vs_CTL,{side}_{r.name}{suffix},{e:.3f},0.05,{e - 0.1:.3f},{e + 0.1:.3f},"
                         "1584,1927,2.1E-05,3.3E-05")
    return "\n".join(lines) + "\n"


def enigma_subcortical_long() -> str:
    lines = ["SubcorticalVolume,Structure,d.icv,se.icv,low.ci.icv,up.ci.icv,n.controls,n.patients,pobs,fdr.p"]
    for i, code in enumerate(ENIGMA_SUBCORTICAL):
        lines.append(f"allepi_subvol,{code},{-0.3 + 0.04 * i:.3f},0.07,-0.4,0.1,1707,2136,8.33E-01,8.33E-01")
    return "\n".join(lines) + "\n"


def enigma_cortical_wide() -> str:
    dk = get_atlas("dk")
    cols = [f"{s}_{r.name}_thickavg" for s, h in (("L", "lh"), ("R", "rh")) for r in dk.cortical(h)]
    cols += ["LThickness", "RThickness", "LSurfArea", "RSurfArea", "ICV"]
    return _csv(["SubjID", *cols], ["sub-01", "sub-02"], _rows(2, len(cols)))


def enigma_subcortical_wide() -> str:
    cols = [*ENIGMA_SUBCORTICAL, "ICV"]
    return _csv(["SubjID", *cols], ["sub-01", "sub-02"], _rows(2, len(cols)) * 1000)


def _write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _all_keys(atlas: str) -> set[str]:
    return set(get_atlas(atlas).keys)


def _assert_clean(table, atlas: str, expected: set[str]) -> None:
    assert table.atlas.name == atlas
    assert table.unmatched == [], table.unmatched
    assert not table.errors, table.errors
    assert expected <= set(table.regions), sorted(expected - set(table.regions))


# -- BrainPainter templates ------------------------------------------------------------
@pytest.mark.parametrize("atlas", ["dk", "destrieux", "dkt"])
def test_brainpainter_current_templates(tmp_path, atlas):
    path = _write(tmp_path, f"{atlas}_template.csv", brainpainter_current(atlas))
    table = read_table(path)  # atlas inferred
    keys = _all_keys(atlas) - {"Brain-Stem", "3rd-Ventricle", "4th-Ventricle"}
    _assert_clean(table, atlas, keys)
    assert table.atlas_guess is not None
    assert set(table.ignored) == {"Right-unknown", "Left-unknown"}
    assert table.images == ("Image_0", "Image_1")
    assert table.shapes[0].kind == "wide" and table.shapes[0].image_column == "Image-name-unique"


@pytest.mark.parametrize("atlas", ["dk", "destrieux", "dkt"])
def test_brainpainter_2019_templates_paint_both_hemispheres(tmp_path, atlas):
    path = _write(tmp_path, f"{atlas}_legacy.csv", brainpainter_legacy(atlas))
    table = read_table(path, "tourville" if atlas == "dkt" else atlas)
    _assert_clean(table, atlas, _all_keys(atlas))
    row = table.row(0)
    for r in get_atlas(atlas).cortical("lh"):
        assert row[r.key] == row["Right-" + r.name]
    assert table.naming.get("BrainPainter 2019 (bare name, both hemispheres)", 0) > 30
    inferred = read_table(path)
    assert inferred.atlas.name == atlas


# -- FreeSurfer ---------------------------------------------------------------------------
@pytest.mark.parametrize("atlas", ["dk", "destrieux", "dkt"])
@pytest.mark.parametrize("measure", ["thickness", "area", "volume"])
def test_aparcstats2table_lh_and_rh_together(tmp_path, atlas, measure):
    lh = _write(tmp_path, "lh.tsv", aparcstats2table(atlas, "lh", measure))
    rh = _write(tmp_path, "rh.tsv", aparcstats2table(atlas, "rh", measure))
    table = read_table([lh, rh])
    cortical = {r.key for r in get_atlas(atlas).cortical()}
    _assert_clean(table, atlas, cortical)
    assert table.images == ("subj01", "subj02", "subj03")
    assert all(s.flavour == "FreeSurfer aparcstats2table" for s in table.shapes)
    assert "BrainSegVolNotVent" in table.ignored and not np.isnan(table.values).any()
    if measure == "thickness":
        assert {"lh_MeanThickness_thickness", "rh_MeanThickness_thickness", "eTIV"} <= set(table.ignored)


def test_aparcstats2table_transposed(tmp_path):
    text = aparcstats2table("destrieux", "lh", "thickness")
    rows = [line.split("\t") for line in text.strip().splitlines()]
    transposed = "\n".join("\t".join(col) for col in zip(*rows, strict=True)) + "\n"
    table = read_table(_write(tmp_path, "lh_t.tsv", transposed))
    _assert_clean(table, "destrieux", {r.key for r in get_atlas("destrieux").cortical("lh")})
    assert table.shapes[0].kind == "transposed"
    assert table.images == ("subj01", "subj02", "subj03")


@pytest.mark.parametrize("columns", [ASEG_FS7, ASEG_FS6], ids=["freesurfer7", "freesurfer6"])
def test_asegstats2table(tmp_path, columns):
    table = read_table(_write(tmp_path, "aseg.tsv", asegstats2table(columns)))
    subcortical = {r.key for r in get_atlas("dk").subcortical()}
    _assert_clean(table, "dk", subcortical)  # subcortical names only: every atlas fits, dk is used
    assert "EstimatedTotalIntraCranialVol" in table.ignored and "Left-vessel" in table.ignored
    assert table.shapes[0].flavour == "FreeSurfer asegstats2table"
    assert "subcortical" in table.atlas_guess.reason


def test_aparc_and_aseg_tables_merge(tmp_path):
    files = [_write(tmp_path, "lh.tsv", aparcstats2table("dk", "lh", "volume", ("subj01", "subj02"))),
             _write(tmp_path, "rh.tsv", aparcstats2table("dk", "rh", "volume", ("subj01", "subj02"))),
             _write(tmp_path, "aseg.tsv", asegstats2table(ASEG_FS7))]
    table = read_table(files)
    _assert_clean(table, "dk", _all_keys("dk"))


# -- ENIGMA ---------------------------------------------------------------------------------
@pytest.mark.parametrize(("suffix", "d"), [("", "d.icv"), ("_thickavg", "d_icv"), ("", "d")])
def test_enigma_cortical_summary_statistics(tmp_path, suffix, d):
    path = _write(tmp_path, "CortThick.csv", enigma_cortical_long(suffix, d))
    table = read_table(path, value=d)
    _assert_clean(table, "dk", {r.key for r in get_atlas("dk").cortical()})
    assert table.images == (d,) and table.shapes[0].kind == "long"
    assert table.shapes[0].region_column == "Structure"
    assert table.naming == {"ENIGMA": 68}
    assert table.values.min() < 0


def test_enigma_subcortical_summary_statistics(tmp_path):
    table = read_table(_write(tmp_path, "SubVol.csv", enigma_subcortical_long()), value="d.icv")
    _assert_clean(table, "dk", ENIGMA_KEYS)
    assert table.row(0)["Left-Accumbens-area"] == pytest.approx(-0.3 + 0.04 * 14)


def test_enigma_cortical_and_subcortical_merge_into_one_image(tmp_path):
    files = [_write(tmp_path, "CortThick.csv", enigma_cortical_long()),
             _write(tmp_path, "SubVol.csv", enigma_subcortical_long())]
    table = read_table(files, value="d.icv")
    _assert_clean(table, "dk", ENIGMA_KEYS | {r.key for r in get_atlas("dk").cortical()})
    assert table.images == ("d.icv",)


@pytest.mark.parametrize("maker", [enigma_cortical_wide, enigma_subcortical_wide])
def test_enigma_per_subject_tables(tmp_path, maker):
    table = read_table(_write(tmp_path, "enigma.csv", maker()))
    assert table.unmatched == [] and table.images == ("sub-01", "sub-02")
    assert "ICV" in table.ignored and table.shapes[0].image_column == "SubjID"


def test_ggseg_long_table(tmp_path):
    dk = get_atlas("dk")
    text = "label,p\n" + "".join(f"{h}_{r.name},{i / 100}\n" for i, (h, r) in enumerate(
        (h, r) for h in ("lh", "rh") for r in dk.cortical(h)))
    table = read_table(_write(tmp_path, "ggseg.csv", text))
    _assert_clean(table, "dk", {r.key for r in dk.cortical()})
    assert table.naming == {"ggseg": 68} and table.images == ("p",)


# -- rendering ------------------------------------------------------------------------------
#: Stand-in renderer: pixel (0, k) has the colour of the atlas's k-th region key.
KeyStrip = StandInRenderer.with_(layout="keys")


@pytest.fixture
def strip():
    with stand_in("keystrip", KeyStrip) as registered:
        yield registered


@pytest.fixture
def tiny(tmp_path):
    names = ("insula", "precuneus", "superiorfrontal", "unknown")
    return write_tiny_template(tmp_path / "tiny", {"dk": names, "dkt": names,
                                                   "destrieux": ("G_cuneus", "S_central", "Unknown")})


TABLES = {
    "dk-current": lambda tmp: [_write(tmp, "t.csv", brainpainter_current("dk"))],
    "destrieux-current": lambda tmp: [_write(tmp, "t.csv", brainpainter_current("destrieux"))],
    "tourville-current": lambda tmp: [_write(tmp, "t.csv", brainpainter_current("dkt"))],
    "dk-2019": lambda tmp: [_write(tmp, "t.csv", brainpainter_legacy("dk"))],
    "destrieux-2019": lambda tmp: [_write(tmp, "t.csv", brainpainter_legacy("destrieux"))],
    "tourville-2019": lambda tmp: [_write(tmp, "t.csv", brainpainter_legacy("dkt"))],
    "aparcstats2table": lambda tmp: [_write(tmp, "lh.tsv", aparcstats2table("destrieux", "lh", "thickness")),
                                     _write(tmp, "rh.tsv", aparcstats2table("destrieux", "rh", "thickness"))],
    "asegstats2table": lambda tmp: [_write(tmp, "aseg.tsv", asegstats2table(ASEG_FS6))],
    "enigma-cortical": lambda tmp: [_write(tmp, "ct.csv", enigma_cortical_long())],
    "enigma-subcortical": lambda tmp: [_write(tmp, "sv.csv", enigma_subcortical_long())],
}


@pytest.mark.parametrize("name", list(TABLES))
def test_every_format_renders(tmp_path, strip, tiny, name):
    inputs = TABLES[name](tmp_path)
    value = "d.icv" if name.startswith("enigma") else None
    out = tmp_path / "out"
    result = render(inputs if len(inputs) > 1 else inputs[0], out=out, template=str(tiny), renderer=strip,
                    width=200, height=16, views="lateral-left", value=value, progress=False)
    manifest = json.loads((out / "manifest.json").read_text())
    summary = manifest["input"]
    assert summary["unmatched_columns"] == [] and summary["atlas_inferred"] is True
    assert len(result.files) == summary["n_images"] >= 1
    # the painted colours follow the values: the first value of the first image, through the scale
    table = read_table(inputs if len(inputs) > 1 else inputs[0], value=value)
    keys = table.atlas.keys
    first = next(k for k in keys if k in table.regions)
    from PIL import Image

    from brainpainter.color.scale import make_scale

    scale = make_scale(data=table.values)
    expected = np.round(scale(np.array([table.row(0)[first]]))[0] * 255).astype(int)
    pixel = np.asarray(Image.open(result.files[0]))[0, keys.index(first), :3]
    assert np.abs(pixel.astype(int) - expected).max() <= 1
