"""CIFTI-2 and fsLR maps (issue 34): reading, the fsLR -> fsaverage resampling, ``to_fsaverage``, refusals."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from nibabel.cifti2 import cifti2_axes as axes

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps.cifti import region_key
from brainpainter.maps.fslr import fslr_to_fsaverage
from brainpainter.maps.inputs import read_maps

N32 = 32492
N164 = 163842
#: ../shared/data beside the repository (as tests/conftest.py), or $BRAINPAINTER_SHARED_DATA.
SHARED = Path(os.environ.get("BRAINPAINTER_SHARED_DATA",
                             Path(__file__).resolve().parents[1].parent / "shared" / "data"))
FSLR = SHARED / "fslr"
FREESURFER = SHARED / "freesurfer"


def _cortex(n: int = N32, left: int = 6, right: int = 4) -> axes.BrainModelAxis:
    return (axes.BrainModelAxis.from_surface(np.arange(left), n, "CortexLeft")
            + axes.BrainModelAxis.from_surface(np.arange(10, 10 + right), n, "CortexRight"))


def _voxels(name: str, count: int) -> axes.BrainModelAxis:
    mask = np.zeros((4, 4, 4), bool)
    mask.flat[:count] = True
    return axes.BrainModelAxis.from_mask(mask, name=name, affine=np.eye(4))


def _write(path: Path, data: np.ndarray, rows: axes.Axis, cols: axes.Axis) -> Path:
    nib.Cifti2Image(np.asarray(data, np.float32), header=(rows, cols)).to_filename(str(path))
    return path


def test_dscalar_cortex_and_subcortical_structures(tmp_path):
    cols = _cortex() + _voxels("thalamus_left", 3) + _voxels("brain_stem", 2)
    data = np.arange(2 * len(cols), dtype=np.float32).reshape(2, -1)
    path = _write(tmp_path / "x.dscalar.nii", data, axes.ScalarAxis(["zstat", "tstat"]), cols)
    maps = read_maps(path)
    assert maps.space == "fsLR" and maps.images == ("zstat", "tstat")
    assert maps.values["lh"].shape == (2, N32) and maps.values["rh"].shape == (2, N32)
    np.testing.assert_array_equal(maps.values["lh"][:, :6], data[:, :6])
    np.testing.assert_array_equal(maps.values["rh"][:, 10:14], data[:, 6:10])
    assert np.isnan(maps.values["lh"][:, 6:]).all()  # absent from the file (medial wall): no value
    assert set(maps.regions or {}) == {"Left-Thalamus", "Brain-Stem"}
    np.testing.assert_allclose(maps.regions["Left-Thalamus"], data[:, 10:13].mean(axis=1))
    np.testing.assert_allclose(maps.regions["Brain-Stem"], data[:, 13:15].mean(axis=1))


def test_structure_names():
    assert region_key("CIFTI_STRUCTURE_HIPPOCAMPUS_LEFT") == "Left-Hippocampus"
    assert region_key("CIFTI_STRUCTURE_ACCUMBENS_RIGHT") == "Right-Accumbens-area"
    assert region_key("CIFTI_STRUCTURE_CEREBELLUM_LEFT") == "Left-Cerebellum-Cortex"
    assert region_key("CIFTI_STRUCTURE_DIENCEPHALON_VENTRAL_RIGHT") == "Right-VentralDC"
    assert region_key("CIFTI_STRUCTURE_BRAIN_STEM") == "Brain-Stem"
    assert region_key("CIFTI_STRUCTURE_OTHER") is None


def test_dlabel_categories_and_colours(tmp_path):
    cols = _cortex()
    table = {0: ("???", (0, 0, 0, 0)), 3: ("V1", (1, 0, 0, 1)), 7: ("MT", (0, 0, 1, 1))}
    data = np.array([[0, 3, 3, 7, 7, 0, 3, 7, 7, 0]], np.float32)
    path = _write(tmp_path / "x.dlabel.nii", data, axes.LabelAxis(["parc"], [table]), cols)
    maps = read_maps(path)
    assert maps.categories == ("V1", "MT")
    np.testing.assert_array_equal(maps.category_colors, [[1, 0, 0], [0, 0, 1]])
    np.testing.assert_array_equal(maps.values["lh"][0, :6], [np.nan, 0, 0, 1, 1, np.nan])
    assert not maps.regions
    on = maps.on_fsaverage("lh", 0)  # labels resampled by nearest vertex: only the file's labels
    assert set(np.unique(on[np.isfinite(on)])) <= {0.0, 1.0}


def test_pscalar_parcels_take_their_value(tmp_path):
    parcels = axes.ParcelsAxis.from_brain_models([
        ("a", axes.BrainModelAxis.from_surface(np.arange(5), N32, "CortexLeft")),
        ("b", axes.BrainModelAxis.from_surface(np.arange(100, 103), N32, "CortexRight"))])
    path = _write(tmp_path / "x.pscalar.nii", np.array([[2.0, -1.0]]), axes.ScalarAxis(["m"]), parcels)
    maps = read_maps(path)
    np.testing.assert_array_equal(maps.values["lh"][0, :5], 2.0)
    np.testing.assert_array_equal(maps.values["rh"][0, 100:103], -1.0)
    assert np.isfinite(maps.values["lh"]).sum() == 5


def test_dtseries_frames(tmp_path):
    data = np.arange(20 * 10, dtype=np.float32).reshape(20, 10)
    path = _write(tmp_path / "run.dtseries.nii", data, axes.SeriesAxis(0, 0.72, 20), _cortex())
    maps = read_maps(path, frames="0:20:5")
    assert maps.images == ("run_00", "run_05", "run_10", "run_15")
    np.testing.assert_array_equal(maps.values["lh"][:, 0], data[[0, 5, 10, 15], 0])
    assert read_maps(path, frames="3").images == ("run",)
    assert read_maps(path).n_images == 20
    for bad in ("20", "a:b", "5:1", "0:10:0", "-1"):
        with pytest.raises(BrainPainterError, match="--frames") as e:
            read_maps(path, frames=bad)
        assert "\n" not in str(e.value)


def test_refusals_are_one_line(tmp_path):
    conn = axes.BrainModelAxis.from_surface(np.arange(3), N32, "CortexLeft")
    dconn = _write(tmp_path / "x.dconn.nii", np.eye(3), conn, conn)
    odd = _write(tmp_path / "y.dscalar.nii", np.zeros((1, 3)), axes.ScalarAxis(["m"]),
                 axes.BrainModelAxis.from_surface(np.arange(3), 1000, "CortexLeft"))
    cifti1 = tmp_path / "old.dscalar.nii"
    img = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 1, 3), np.float32), np.eye(4))
    img.header.extensions.append(nib.nifti1.Nifti1Extension(32, b'<CIFTI Version="1.0"><Matrix/></CIFTI>'))
    img.to_filename(str(cifti1))
    for path, pattern in ((dconn, r"\(dconn/pconn\), not a map: draw a pconn with --connectome"),
                          (odd, r"1000 values.*32492 fsLR 32k"),
                          (cifti1, r"CIFTI-1.*-cifti-version-convert old\.dscalar\.nii 2 OUT")):
        with pytest.raises(BrainPainterError, match=pattern) as e:
            read_maps(path)
        assert "\n" not in str(e.value)


def test_cli_cifti1_exits_2_with_one_line(tmp_path):
    cifti1 = tmp_path / "old.dscalar.nii"
    img = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 1, 3), np.float32), np.eye(4))
    img.header.extensions.append(nib.nifti1.Nifti1Extension(32, b'<CIFTI Version="1"><Matrix/></CIFTI>'))
    img.to_filename(str(cifti1))
    out = subprocess.run([sys.executable, "-m", "brainpainter", "render", str(cifti1), "--out",
                          str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "cifti-version-convert" in out.stderr
    assert not (tmp_path / "o").exists()


def test_cli_space_contradicting_the_cifti_metadata_exits_2_with_one_line(tmp_path):
    cols = (axes.BrainModelAxis.from_surface(np.arange(5), N164, "CortexLeft")
            + axes.BrainModelAxis.from_surface(np.arange(5), N164, "CortexRight"))
    img = nib.Cifti2Image(np.ones((1, 10), np.float32), header=(axes.ScalarAxis(["m"]), cols))
    img.header.matrix.metadata = nib.cifti2.Cifti2MetaData({"Provenance": "x.164k_fs_LR.dscalar.nii"})
    path = tmp_path / "x.dscalar.nii"
    img.to_filename(str(path))
    assert read_maps(path).space == "fsLR" and read_maps(path, space="fsLR").space == "fsLR"
    out = subprocess.run([sys.executable, "-m", "brainpainter", "render", str(path), "--space", "fsaverage",
                          "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    line = out.stderr.strip()
    assert len(line.splitlines()) == 1 and "says fsLR in its metadata" in line and "--space fsaverage" in line
    assert not (tmp_path / "o").exists()


def test_a_parcel_file_that_would_grow_too_much_is_refused(tmp_path):
    parcels = axes.ParcelsAxis.from_brain_models([("a", axes.BrainModelAxis.from_surface(np.arange(3), N164,
                                                                                          "CortexLeft"))])
    path = _write(tmp_path / "x.ptseries.nii", np.zeros((200, 1)), axes.SeriesAxis(0, 1, 200), parcels)
    with pytest.raises(BrainPainterError, match="--frames"):
        read_maps(path)
    assert read_maps(path, frames="0:2").n_images == 2


def _gifti(path: Path, values: np.ndarray, meta: dict[str, str] | None = None) -> Path:
    img = nib.GiftiImage(darrays=[nib.gifti.GiftiDataArray(np.asarray(values, np.float32),
                                                           intent="NIFTI_INTENT_SHAPE")])
    for key, value in (meta or {}).items():
        img.meta[key] = value
    img.to_filename(str(path))
    return path


def test_fslr_gifti_space(tmp_path):
    assert read_maps(lh=_gifti(tmp_path / "a.shape.gii", np.zeros(N32))).space == "fsLR"
    plain = _gifti(tmp_path / "b.shape.gii", np.zeros(N164))
    guessed = read_maps(lh=plain)
    assert guessed.space == "fsaverage" and "--space fsLR" in guessed.notes[0]
    assert read_maps(lh=plain, space="fsLR").space == "fsLR"
    said = _gifti(tmp_path / "c.shape.gii", np.zeros(N164), {"Provenance": "x.164k_fs_LR.dscalar.nii"})
    assert read_maps(lh=said).space == "fsLR" and not read_maps(lh=said).notes
    assert read_maps(lh=said, space="fsLR").space == "fsLR"
    with pytest.raises(BrainPainterError, match=r"says fsLR in its metadata, but --space fsaverage") as e:
        read_maps(lh=said, space="fsaverage")  # the file's metadata decides: a contradiction is refused
    assert "\n" not in str(e.value)
    fsavg = _gifti(tmp_path / "f.shape.gii", np.zeros(N164), {"SubjectID": "fsaverage"})
    assert read_maps(lh=fsavg).space == "fsaverage" and not read_maps(lh=fsavg).notes
    with pytest.raises(BrainPainterError, match=r"says fsaverage in its metadata, but --space fsLR"):
        read_maps(lh=fsavg, space="fsLR")
    both = _gifti(tmp_path / "g.shape.gii", np.zeros(N164), {"Provenance": "resampled fs_LR to fsaverage"})
    assert read_maps(lh=both, space="fsaverage").space == "fsaverage"  # names both: --space decides
    bids = _gifti(tmp_path / "hemi-L_space-fsLR_den-164k_x.shape.gii", np.zeros(N164))
    assert read_maps(lh=bids).space == "fsLR"
    with pytest.raises(BrainPainterError, match="fsLR 32k, not fsaverage"):
        read_maps(lh=_gifti(tmp_path / "d.shape.gii", np.zeros(N32)), space="fsaverage")
    with pytest.raises(BrainPainterError, match=r"fsLR 59k.*wb_command -metric-resample"):
        read_maps(lh=_gifti(tmp_path / "e.shape.gii", np.zeros(59292)))


def test_resampling_keeps_constants_and_leaves_the_medial_wall_empty():
    ones = np.ones(N32, np.float32)
    for hemi in ("lh", "rh"):
        out = fslr_to_fsaverage(ones, hemi)[0]
        finite = np.isfinite(out)
        assert 0.8 < finite.mean() < 0.95  # the medial wall (HCP's atlasroi = 0) has no value
        np.testing.assert_allclose(out[finite], 1.0, rtol=1e-5)
    half = ones.copy()
    half[: N32 // 2] = np.nan
    assert np.isfinite(fslr_to_fsaverage(half, "lh")[0]).mean() < finite.mean() * 0.8


def test_resampling_interpolates_a_smooth_field_linearly():
    """A smooth field on the deformed sphere comes back as the same field on fsaverage's sphere."""
    sphere = FREESURFER / "subjects" / "fsaverage" / "surf" / "lh.sphere"
    deformed = FSLR / "resample_fsaverage" / "fs_LR-deformed_to-fsaverage.L.sphere.32k_fs_LR.surf.gii"
    if not sphere.is_file() or not deformed.is_file():
        pytest.skip("shared data not found")
    xyz = nib.load(str(deformed)).darrays[0].data
    target, _ = nib.freesurfer.read_geometry(str(sphere))
    field = (xyz / np.linalg.norm(xyz, axis=1, keepdims=True))[:, 2]
    out = fslr_to_fsaverage(field, "lh")[0]
    expected = (target / np.linalg.norm(target, axis=1, keepdims=True))[:, 2]
    ok = np.isfinite(out)
    error = np.abs(out[ok] - expected[ok])
    assert np.percentile(error, 99) < 0.002  # barycentric: exact but for the sphere's curvature
    assert error.max() < 0.05  # by the medial wall, a vertex takes its cortex neighbours' values (~2 degrees)


def test_hcp_refsulc_correlates_with_fsaverage_sulc():
    """The bar: HCP's real fsLR 164k group sulcal depth matches fsaverage's own sulc (|r| >= 0.85)."""
    path = FSLR / "MSMSulc.refsulc.164k_fs_LR.dscalar.nii"
    if not path.is_file():
        pytest.skip("shared data not found")
    on = brainpainter.to_fsaverage(path)
    assert set(on) == {"lh", "rh"} and on["lh"].shape == (N164,)
    for hemi in ("lh", "rh"):
        surf = FREESURFER / "subjects" / "fsaverage" / "surf"
        sulc = nib.freesurfer.read_morph_data(str(surf / f"{hemi}.sulc"))
        ok = np.isfinite(on[hemi])
        assert abs(np.corrcoef(on[hemi][ok], sulc[ok])[0, 1]) >= 0.85
        other = on["rh" if hemi == "lh" else "lh"]
        ok = np.isfinite(other)
        assert abs(np.corrcoef(other[ok], sulc[ok])[0, 1]) < 0.3  # the other hemisphere does not match


def test_to_fsaverage_of_arrays_and_fsaverage5():
    out = brainpainter.to_fsaverage({"lh": np.ones(N32), "rh": np.full(N32, 2.0)})
    assert out["lh"].shape == (N164,) and out["lh"].dtype == np.float32
    assert np.nanmax(out["rh"]) == pytest.approx(2.0) and np.isnan(out["lh"]).any()
    coarse = brainpainter.to_fsaverage({"lh": np.ones(10242)})
    assert set(coarse) == {"lh"} and np.isfinite(coarse["lh"]).all()


def _dk_dlabel(path: Path) -> Path:
    """DK (fsaverage's lh/rh.aparc.annot) brought to fsLR 32k by nearest vertex on the deformed spheres."""
    from scipy.spatial import cKDTree

    fsaverage = FREESURFER / "subjects" / "fsaverage"
    surf, label = fsaverage / "surf", fsaverage / "label"
    table: dict[int, tuple[str, tuple[float, float, float, float]]] = {0: ("???", (0, 0, 0, 0))}
    keys, cols = [], None
    for hemi, side, structure in (("lh", "L", "CortexLeft"), ("rh", "R", "CortexRight")):
        deformed = f"fs_LR-deformed_to-fsaverage.{side}.sphere.32k_fs_LR.surf.gii"
        xyz = nib.load(str(FSLR / "resample_fsaverage" / deformed)).darrays[0].data
        sphere, _ = nib.freesurfer.read_geometry(str(surf / f"{hemi}.sphere"))
        _, nearest = cKDTree(sphere / 100.0).query(xyz / np.linalg.norm(xyz, axis=1, keepdims=True))
        lab, ctab, names = nib.freesurfer.read_annot(str(label / f"{hemi}.aparc.annot"))
        for i, name in enumerate(n.decode() for n in names):
            table[i + 1] = (name, (*(ctab[i, :3] / 255.0), 1.0))
        keys.append(np.where(lab[nearest] >= 0, lab[nearest] + 1, 0))
        model = axes.BrainModelAxis.from_surface(np.arange(N32), N32, structure)
        cols = model if cols is None else cols + model
    return _write(path, np.concatenate(keys)[None], axes.LabelAxis(["dk"], [table]), cols)


@pytest.mark.render
@pytest.mark.integration
def test_dk_dlabel_on_fslr_renders_as_dk(tmp_path):
    """The bar: a DK dlabel on fsLR 32k renders lateral-left with >= 90 % of brain pixels DK's colour."""
    from brainpainter.color.scale import make_scale
    from brainpainter.layers.vertex_map import VertexColors
    from brainpainter.maps.layers import vertex_colors
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    label = FREESURFER / "subjects" / "fsaverage" / "label"
    if not label.is_dir() or not (FSLR / "resample_fsaverage").is_dir():
        pytest.skip("shared data not found")
    dlabel = read_maps(_dk_dlabel(tmp_path / "dk.dlabel.nii"))
    annot = read_maps(label / "lh.aparc.annot")
    assert dlabel.space == "fsLR" and set(dlabel.categories or ()) <= set(annot.categories or ())
    view, scale = get_view("lateral-left"), make_scale(cmap="viridis", vmin=0, vmax=1)
    images = []
    with Painter("dk", settings=RenderSettings(width=600, height=450), coloring="vertices") as p:
        for maps in (annot, dlabel):
            colors = vertex_colors(maps, 0, p.scene.geometry.source_vertex, scale, "none")
            images.append(p.paint_colors(VertexColors({}, colors), view))
    brain = [(img[..., 3] > 0) & ~np.all(img[..., :3] == 255, axis=-1) for img in images]
    both = brain[0] & brain[1]
    assert both.sum() > 0.3 * 600 * 450
    diff = np.abs(images[0][..., :3].astype(int) - images[1][..., :3].astype(int)).max(-1)
    assert (diff[both] <= 10).mean() >= 0.90


@pytest.mark.render
def test_dscalar_renders_cortex_and_subcortical_structure(tmp_path):
    """A 32k dscalar: the cortex and the thalamus (its voxels' mean) drawn in the map's colours."""
    cols = axes.BrainModelAxis.from_surface(np.arange(N32), N32, "CortexLeft") + _voxels("thalamus_left", 4)
    data = np.concatenate([np.full(N32, 1.0), np.full(4, -1.0)])[None]
    path = _write(tmp_path / "x.dscalar.nii", data, axes.ScalarAxis(["m"]), cols)
    result = brainpainter.render(path, views="lateral-left,subcortical", width=320, height=240, cmap="RdBu_r",
                                 vmin=-1, vmax=1)
    cortex, deep = result.images[("m", "lateral-left")], result.images[("m", "subcortical")]
    c, d = cortex[..., :3].astype(int), deep[..., :3].astype(int)
    red = (c[..., 0] > 60) & (c[..., 1] < 30) & (c[..., 0] > 2 * c[..., 2])  # RdBu_r's dark red
    blue = (d[..., 2] > 60) & (d[..., 2] > d[..., 0] + 40)  # RdBu_r's dark blue
    assert red.mean() > 0.2  # the left cortex: +1
    assert blue.sum() > 100  # the left thalamus: -1


def test_export_takes_the_map_options_of_a_cifti_series(tmp_path):
    data = np.arange(3 * 10, dtype=np.float32).reshape(3, 10)
    path = _write(tmp_path / "run.dtseries.nii", data, axes.SeriesAxis(0, 1, 3), _cortex())
    out = brainpainter.export(path, tmp_path / "x.glb", frames="1", space="fsLR")
    assert out.stat().st_size > 1000


def test_truncated_cifti_is_one_line_and_allocates_nothing_it_says(tmp_path):
    cols = axes.BrainModelAxis.from_surface(np.arange(N32), N32, "CortexLeft")
    path = _write(tmp_path / "x.dscalar.nii", np.ones((4, N32)), axes.ScalarAxis(list("abcd")), cols)
    raw = path.read_bytes()
    for cut, pattern in ((len(raw) // 2, "says it holds 519872 bytes"),
                         (len(raw) - 8, "cannot read the data")):
        short = tmp_path / f"cut{cut}.dscalar.nii"
        short.write_bytes(raw[:cut])
        with pytest.raises(BrainPainterError, match=pattern) as e:
            read_maps(short)
        assert "\n" not in str(e.value)


def test_a_cifti_path_that_is_no_regular_file_is_refused(tmp_path):
    fifo = tmp_path / "pipe.dscalar.nii"
    os.mkfifo(fifo)
    with pytest.raises(BrainPainterError, match="not a regular file"):
        read_maps(fifo)


def test_hcp_refsulc_at_32k_correlates_with_fsaverage_sulc(tmp_path):
    """HCP's sulcal depth taken to fsLR 32k (nearest 164k vertex), as a 91k-style dscalar, |r| >= 0.85."""
    from scipy.spatial import cKDTree

    deformed = FSLR / "resample_fsaverage"
    if not deformed.is_dir():
        pytest.skip("shared data not found")
    cols, rows = None, []
    for side, structure in (("L", "CortexLeft"), ("R", "CortexRight")):
        sphere = [nib.load(str(deformed / f"fs_LR-deformed_to-fsaverage.{side}.sphere.{r}_fs_LR.surf.gii"))
                  .darrays[0].data for r in ("32k", "164k")]
        _, nearest = cKDTree(sphere[1]).query(sphere[0])
        sulc = nib.load(str(FSLR / f"{side}.refsulc.164k_fs_LR.shape.gii")).darrays[0].data[nearest]
        roi = nib.load(str(FSLR / f"{side}.atlasroi.32k_fs_LR.shape.gii")).darrays[0].data
        cortex = np.flatnonzero(roi > 0)
        rows.append(sulc[cortex])  # 29696 + 29716 = 59412 grayordinates of cortex, as HCP's 91k files
        model = axes.BrainModelAxis.from_surface(cortex, N32, structure)
        cols = model if cols is None else cols + model
    path = _write(tmp_path / "sulc.32k_fs_LR.dscalar.nii", np.concatenate(rows)[None],
                  axes.ScalarAxis(["sulc"]), cols)
    on = brainpainter.to_fsaverage(path)
    for hemi in ("lh", "rh"):
        fs = nib.freesurfer.read_morph_data(str(FREESURFER / "subjects" / "fsaverage" / "surf"
                                                / f"{hemi}.sulc"))
        ok = np.isfinite(on[hemi])
        assert abs(np.corrcoef(on[hemi][ok], fs[ok])[0, 1]) >= 0.85
