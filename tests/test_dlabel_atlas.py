"""``atlas add NAME --dlabel FILE.dlabel.nii``: a CIFTI-2 label file becomes an atlas (issue 34, item 5)."""

from __future__ import annotations

import nibabel as nib
import numpy as np
import pytest
from nibabel.cifti2 import cifti2_axes as axes
from test_custom_atlases import run
from test_fslr import FREESURFER, FSLR, _dk_dlabel, _write

import brainpainter
from brainpainter.atlas import registry
from brainpainter.atlas.template import load_template
from brainpainter.testing import write_tiny_template

pytestmark = pytest.mark.usefixtures("fresh_registry")
#: Label table of the tiny dlabels: 0 unlabelled, 1 front, 2 back (each side's own name).
TABLE = {0: ("???", (0, 0, 0, 0)), 1: ("L_front", (0.8, 0.1, 0.05, 1)), 2: ("L_back", (0.1, 0.1, 0.55, 1)),
         3: ("R_front", (0.1, 0.6, 0.1, 1)), 4: ("R_back", (0.9, 0.8, 0.1, 1))}


@pytest.fixture
def tiny(tmp_path):
    """A tiny template whose 642-vertex icospheres are its source surfaces."""
    return write_tiny_template(tmp_path / "tiny")


def tiny_dlabel(path, tiny, table=TABLE, kind=axes.LabelAxis):
    """Front (y >= 0) and back labels per hemisphere of the tiny template; vertex 0 unlabelled."""
    keys, cols = [], None
    for first, hemi, structure in ((1, "lh", "CortexLeft"), (3, "rh", "CortexRight")):
        y = load_template(tiny).cortex("dk", hemi).vertices["pial"][:, 1]
        lab = np.where(y >= 0, first, first + 1)
        lab[0] = 0
        keys.append(lab)
        model = axes.BrainModelAxis.from_surface(np.arange(len(lab)), len(lab), structure)
        cols = model if cols is None else cols + model
    rows = axes.LabelAxis(["parts"], [table]) if kind is axes.LabelAxis else axes.ScalarAxis(["parts"])
    return _write(path, np.concatenate(keys)[None], rows, cols)


def test_dlabel_becomes_an_atlas_of_its_names_and_colours(tmp_path, tiny):
    path = tiny_dlabel(tmp_path / "parts.dlabel.nii", tiny)
    code, out, err = run("atlas", "add", "parts", "--dlabel", str(path), "--template", str(tiny))
    assert code == 0, err
    assert "2 left, 2 right cortical regions" in out
    atlas = registry.atlases.get("parts")
    assert [r.key for r in atlas.cortical()] == ["Left-L_front", "Left-L_back", "Right-R_front",
                                                 "Right-R_back"]
    assert atlas.region("Left-L_front").color == (204, 26, 13)  # the label table's colour, 0-1 -> 0-255
    assert atlas.region("Right-R_back").color == (230, 204, 26)
    cm = load_template(tiny).with_label_sets(atlas.label_dir).cortex("parts", "lh")
    centroid_y = cm.vertices["pial"][cm.faces].mean(axis=1)[:, 1]
    front = cm.face_label == cm.label_names.index("L_front")
    assert front.any() and (centroid_y[front] > -5).all()
    assert "unknown" in np.asarray(cm.label_names)[np.unique(cm.face_label)]  # unlabelled: no region


def test_dlabel_subcortical_voxels_are_a_note(tmp_path, tiny):
    path = tiny_dlabel(tmp_path / "parts.dlabel.nii", tiny)
    img = nib.load(str(path))
    rows, cols = img.header.get_axis(0), img.header.get_axis(1)
    mask = np.zeros((3, 3, 3), bool)
    mask.flat[:5] = True
    cols = cols + axes.BrainModelAxis.from_mask(mask, name="thalamus_left", affine=np.eye(4))
    data = np.concatenate([np.asarray(img.dataobj), np.ones((1, 5))], axis=1)
    path = _write(tmp_path / "deep.dlabel.nii", data, rows, cols)
    code, _, err = run("atlas", "add", "deep", "--dlabel", str(path), "--template", str(tiny))
    assert code == 0, err
    assert "note: the 5 subcortical voxels of deep.dlabel.nii are not used" in err


def _refused(tmp_path, tiny, path, pattern):
    code, _, err = run("atlas", "add", "bad", "--dlabel", str(path), "--template", str(tiny))
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert pattern in err, err
    assert not (registry.atlases_dir() / "bad").exists()


def test_dscalar_given_to_dlabel_is_one_line(tmp_path, tiny):
    scalar = tiny_dlabel(tmp_path / "parts.dscalar.nii", tiny, kind=axes.ScalarAxis)
    _refused(tmp_path, tiny, scalar, "'parts.dscalar.nii' is a CIFTI dscalar.nii file, which holds values")
    unlabelled = tiny_dlabel(tmp_path / "values.dlabel.nii", tiny, kind=axes.ScalarAxis)
    _refused(tmp_path, tiny, unlabelled, "'values.dlabel.nii' has no label table")


def test_cifti1_dlabel_is_one_line(tmp_path, tiny):
    cifti1 = tmp_path / "old.dlabel.nii"
    img = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 1, 3), np.float32), np.eye(4))
    img.header.extensions.append(nib.nifti1.Nifti1Extension(32, b'<CIFTI Version="1.0"><Matrix/></CIFTI>'))
    img.to_filename(str(cifti1))
    _refused(tmp_path, tiny, cifti1, "CIFTI-1, which nibabel (and brainpainter) cannot read")


def test_several_label_maps_or_one_hemisphere_is_one_line(tmp_path, tiny):
    path = tiny_dlabel(tmp_path / "parts.dlabel.nii", tiny)
    img = nib.load(str(path))
    twice = _write(tmp_path / "two.dlabel.nii", np.repeat(np.asarray(img.dataobj), 2, axis=0),
                   axes.LabelAxis(["a", "b"], [TABLE, TABLE]), img.header.get_axis(1))
    _refused(tmp_path, tiny, twice, "holds 2 label maps (a, b); an atlas is one")
    left = axes.BrainModelAxis.from_surface(np.arange(642), 642, "CortexLeft")
    lh_only = _write(tmp_path / "lh.dlabel.nii", np.ones((1, 642)), axes.LabelAxis(["a"], [TABLE]), left)
    _refused(tmp_path, tiny, lh_only, "has no CORTEX_RIGHT labels")


@pytest.mark.parametrize(("renamed", "message"), [
    ({2: ("L_front", (0.1, 0.1, 0.55, 1))}, "label keys 1 and 2 are both named 'L_front' but in different"),
    ({2: ("l_FRONT", (0.1, 0.1, 0.55, 1))}, "the region names 'L_front' and 'l_FRONT' differ only in case"),
])
def test_dlabel_whose_names_collide_is_one_line(tmp_path, tiny, renamed, message):
    path = tiny_dlabel(tmp_path / "parts.dlabel.nii", tiny, table={**TABLE, **renamed})
    _refused(tmp_path, tiny, path, message)


def test_space_of_the_other_kind_is_refused(tmp_path, tiny):
    path = tiny_dlabel(tmp_path / "parts.dlabel.nii", tiny)
    code, _, err = run("atlas", "add", "x", "--dlabel", str(path), "--space", "MNI152NLin6Asym")
    assert code == 2 and "--space MNI152NLin6Asym is for --volume" in err


@pytest.mark.render
@pytest.mark.integration
def test_dk_dlabel_on_fslr_atlas_renders_a_table_as_dk(tmp_path):
    """The bar: DK on fsLR 32k added with --dlabel; a table of DK regions lateral-left, >= 90 % as on dk."""
    if not (FREESURFER / "subjects" / "fsaverage" / "label").is_dir() or not FSLR.is_dir():
        pytest.skip("shared data not found")
    code, out, err = run("atlas", "add", "dkfslr", "--dlabel", str(_dk_dlabel(tmp_path / "dk.dlabel.nii")))
    assert code == 0, err
    assert "34 left, 34 right cortical regions" in out
    dk, ours = registry.atlases.get("dk"), registry.atlases.get("dkfslr")
    assert [(r.key, r.color) for r in ours.cortical()] == [(r.key, r.color) for r in dk.cortical()]
    regions = ("precentral", "superiortemporal", "lateraloccipital", "supramarginal", "rostralmiddlefrontal")
    table = {"Image-name-unique": ["a"], **{f"Left-{r}": [i + 1.0] for i, r in enumerate(regions)}}
    images = [brainpainter.render(table, atlas, views="lateral-left", width=400, height=300, vmin=0, vmax=5,
                                  cmap="viridis", progress=False).images[("a", "lateral-left")]
              for atlas in ("dk", "dkfslr")]
    colour = [img[..., :3].astype(int) for img in images]
    vivid = [(c.max(-1) - c.min(-1)) > 40 for c in colour]  # the table's viridis colours, not grey cortex
    assert vivid[0].sum() > 0.05 * 400 * 300
    agree = vivid[0] & (np.abs(colour[0] - colour[1]).max(-1) <= 10)
    assert agree.sum() >= 0.90 * vivid[0].sum()


def test_a_164k_dlabel_is_fsaverage_unless_space_says_fslr(tmp_path):
    """Every 8th vertex labelled: as it is on fsaverage (a note), resampled from fsLR 164k (--space fsLR)."""
    from brainpainter.maps.dlabel import dlabel_label_maps

    n, given = 163842, np.arange(0, 163842, 8)
    cols = (axes.BrainModelAxis.from_surface(given, n, "CortexLeft")
            + axes.BrainModelAxis.from_surface(given, n, "CortexRight"))
    path = _write(tmp_path / "sparse.dlabel.nii", np.repeat([[1, 3]], len(given), axis=1),
                  axes.LabelAxis(["sparse"], [TABLE]), cols)
    for space in (None, "fsLR"):
        maps, notes = dlabel_label_maps(path, load_template("fsaverage"), space)
        for hemi, name in (("lh", "L_front"), ("rh", "R_front")):
            labelled = np.flatnonzero(np.asarray(maps[hemi].names)[maps[hemi].labels] == name)
            assert np.array_equal(labelled, given) == (space is None)
            assert 0.05 < len(labelled) / n < 0.2
        assert ("does not say which" in " ".join(notes)) == (space is None)
