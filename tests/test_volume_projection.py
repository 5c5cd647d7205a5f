"""Volumes onto the surface (brainpainter.maps.volume): registration fusion, depth sampling,
subcortical means, refusals; and the bar against nilearn's vol_to_surf."""

from __future__ import annotations

import tomllib
import warnings
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps import sheet
from brainpainter.maps.inputs import read_maps
from brainpainter.maps.options import MapOptions, check_projection
from brainpainter.maps.regfusion import ASEG_FILE, REGFUSION_FILE, aseg_mni152, fsaverage_mni152
from brainpainter.maps.resolution import fsaverage_faces
from brainpainter.maps.volume import project_volume, subcortical_means, subcortical_table, volume_images

REPO = Path(__file__).resolve().parents[1]
# MNI152 2 mm grid (FSL's MNI152_T1_2mm: 91 x 109 x 91)
MNI_2MM = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
SHAPE_2MM = (91, 109, 91)


def world_grid(shape: tuple[int, ...], affine: np.ndarray) -> np.ndarray:
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), axis=-1)
    return ijk @ affine[:3, :3].T + affine[:3, 3]


def blob(centre: np.ndarray, sigma: float = 3.0) -> np.ndarray:
    xyz = world_grid(SHAPE_2MM, MNI_2MM)
    return np.exp(-((xyz - centre) ** 2).sum(-1) / (2 * sigma**2)).astype(np.float32)


def nearest_vertex(hemi: str, point: tuple[float, float, float]) -> int:
    return int(np.argmin(np.linalg.norm(fsaverage_mni152()[hemi] - np.asarray(point), axis=1)))


def save(tmp_path: Path, data: np.ndarray, affine: np.ndarray = MNI_2MM, name: str = "stat.nii.gz") -> Path:
    path = tmp_path / name
    nib.save(nib.Nifti1Image(data, affine), path)
    return path


# -- registration fusion --------------------------------------------------------------------------

# left precentral, left superior temporal, right cuneus-ish, right superior frontal (MNI152 mm)
POINTS = [("lh", (-38.0, -20.0, 56.0)), ("lh", (-58.0, -24.0, 6.0)), ("rh", (8.0, -84.0, 20.0)),
          ("rh", (22.0, 30.0, 50.0))]


@pytest.mark.parametrize(("hemi", "point"), POINTS)
def test_a_blob_peaks_on_the_vertex_at_its_mni_position(tmp_path, hemi, point):
    vertex = nearest_vertex(hemi, point)
    centre = fsaverage_mni152()[hemi][vertex]
    maps = project_volume(save(tmp_path, blob(centre)))
    assert set(maps) == {"lh", "rh"} and maps[hemi].shape == (163842,) and maps[hemi].dtype == np.float32
    peak = int(np.nanargmax(maps[hemi]))
    assert np.linalg.norm(fsaverage_mni152()[hemi][peak] - centre) < 1.5
    point = project_volume(save(tmp_path, blob(centre)), projection="point")[hemi]   # the position alone
    assert point[vertex] > 0.97 * np.nanmax(point)
    other = "rh" if hemi == "lh" else "lh"
    assert np.nanmax(maps[other]) < 0.05 * maps[hemi][peak]      # the other hemisphere stays dark


def test_public_name_and_nibabel_image_input():
    centre = fsaverage_mni152()["lh"][nearest_vertex("lh", POINTS[0][1])]
    maps = brainpainter.project_volume(nib.Nifti1Image(blob(centre), MNI_2MM))
    assert brainpainter.project_volume is project_volume
    assert np.linalg.norm(fsaverage_mni152()["lh"][int(np.nanargmax(maps["lh"]))] - centre) < 1.5


def test_4d_gives_one_row_per_volume(tmp_path):
    centres = [fsaverage_mni152()[h][nearest_vertex(h, p)] for h, p in POINTS[:2]]
    path = save(tmp_path, np.stack([blob(c) for c in centres], axis=-1))
    maps = project_volume(path)
    assert maps["lh"].shape == (2, 163842) and maps["rh"].shape == (2, 163842)
    for i, centre in enumerate(centres):
        peak = int(np.nanargmax(maps["lh"][i]))
        assert np.linalg.norm(fsaverage_mni152()["lh"][peak] - centre) < 1.5
    images = volume_images(path)
    assert [name for name, _ in images] == ["stat_0", "stat_1"]
    np.testing.assert_array_equal(images[1][1]["lh"], maps["lh"][1])
    plain = project_volume(save(tmp_path, np.stack([blob(c) for c in centres], axis=-1), name="s.nii"))
    np.testing.assert_array_equal(plain["rh"], maps["rh"])                   # read volume by volume
    one = volume_images(save(tmp_path, blob(centres[0]), name="one.nii"))      # uncompressed, 3-D
    assert [name for name, _ in one] == ["one"] and one[0][1]["lh"].shape == (163842,)


def test_nearest_keeps_labels_and_outside_is_nan(tmp_path):
    labels = np.zeros(SHAPE_2MM, np.int16)
    labels[:45] = 3                     # i < 45: x > 0, the right half
    labels[45:] = 7
    maps = project_volume(save(tmp_path, labels, name="labels.nii.gz"), method="nearest")
    values = np.concatenate([maps["lh"], maps["rh"]])
    assert set(np.unique(values[np.isfinite(values)])) <= {0.0, 3.0, 7.0}
    assert np.mean(maps["rh"] == 3) > 0.95 and np.mean(maps["lh"] == 7) > 0.95
    # a volume cut at z = 30 mm: vertices above it have no value (NaN), not the edge's value
    cut = np.ones((91, 109, 51), np.float32)
    maps = project_volume(save(tmp_path, cut, name="cut.nii.gz"))
    z = fsaverage_mni152()["lh"][:, 2]
    assert np.isnan(maps["lh"][z > 32]).all() and (maps["lh"][z < 28] == 1).all()


def test_nan_voxels_are_skipped_not_spread(tmp_path):
    data = np.full(SHAPE_2MM, 2.0, np.float32)
    data[np.indices(SHAPE_2MM).sum(axis=0) % 2 == 1] = np.nan          # a NaN checkerboard
    data[0, 0, 0] = np.inf
    maps = project_volume(save(tmp_path, data))
    values = np.concatenate([maps["lh"], maps["rh"]])
    finite = values[np.isfinite(values)]
    assert 0.3 < finite.size / values.size < 0.9                      # half the weight is finite
    np.testing.assert_allclose(finite, 2.0, rtol=1e-5)
    series = project_volume(save(tmp_path, np.stack([data, data], axis=-1), name="series.nii.gz"))
    both = np.isfinite(series["lh"][1]) & np.isfinite(maps["lh"])      # a series: the same values, and
    np.testing.assert_allclose(series["lh"][1][both], 2.0, rtol=1e-5)   # NaN alike but where the finite
    assert np.mean(np.isnan(series["lh"][1]) != np.isnan(maps["lh"])) < 1e-3   # weight is 0.5 exactly


# -- sampling around a vertex: --projection ribbon | line | point --------------------------------

def roughness(values: np.ndarray, faces: np.ndarray, keep: np.ndarray | None = None) -> float:
    """Mean absolute difference between the values of neighbouring vertices, over the mesh's edges
    (those between two `keep` vertices)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    if keep is not None:
        edges = edges[keep[edges].all(axis=1)]
    return float(np.nanmean(np.abs(values[edges[:, 0]] - values[edges[:, 1]])))


def test_fsaverage_faces_are_a_closed_consistently_wound_sphere():
    faces = fsaverage_faces()
    assert faces.shape == (327680, 3) and faces.min() == 0 and faces.max() == 163841
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    keys = directed[:, 0] * 163842 + directed[:, 1]
    assert len(np.unique(keys)) == len(keys)                          # no edge twice the same way
    assert np.isin(directed[:, 1] * 163842 + directed[:, 0], keys).all()   # each one both ways: closed
    assert 163842 - len(keys) // 2 + len(faces) == 2                  # Euler: a sphere
    for hemi in ("lh", "rh"):                                         # normals point out of the brain
        out = fsaverage_mni152()[hemi] - fsaverage_mni152()[hemi].mean(axis=0)
        assert np.mean(np.einsum("ij,ij->i", sheet.normals(hemi), out) > 0) > 0.75


def test_trilinear_matrix_samples_as_map_coordinates():
    from scipy.ndimage import map_coordinates

    from brainpainter.maps.trilinear import trilinear

    rng = np.random.default_rng(3)
    grid = rng.standard_normal((7, 9, 5)).astype(np.float32)
    ijk = rng.uniform(-0.5, [6.5, 8.5, 4.5], (500, 3)).T          # beyond the edges too
    expected = map_coordinates(grid, ijk, order=1, mode="nearest", prefilter=False)
    np.testing.assert_allclose(trilinear(grid.shape, ijk) @ grid.ravel(order="F"), expected, atol=1e-5)


@pytest.fixture(scope="module")
def noise(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """White noise on the 2 mm MNI152 grid: detail finer than the cortex's folds (uncompressed: fast)."""
    data = np.random.default_rng(0).standard_normal(SHAPE_2MM).astype(np.float32)
    return save(tmp_path_factory.mktemp("noise"), data, name="noise.nii")


def test_ribbon_and_line_average_what_a_point_sees_alone(noise, tmp_path):
    faces = fsaverage_faces()
    rough = {name: roughness(project_volume(noise, projection=projection, radius=radius)["lh"], faces)
             for name, projection, radius in (("point", "point", 3.0), ("ribbon", None, 3.0),
                                              ("line", "line", 3.0), ("narrow", "ribbon", 1.0))}
    assert rough["ribbon"] < 0.5 * rough["point"] and rough["line"] < 0.8 * rough["point"], rough
    assert rough["ribbon"] < rough["narrow"] < rough["point"], rough  # the radius sets how far
    constant = save(tmp_path, np.full(SHAPE_2MM, 3.0, np.float32), name="constant.nii")
    for projection in ("ribbon", "line"):                             # a constant stays that constant
        values = project_volume(constant, projection=projection)["rh"]
        np.testing.assert_allclose(values[np.isfinite(values)], 3.0, rtol=1e-5)
    # the defaults: the ribbon for values, the point alone for labels (never mixed)
    assert check_projection(None, "linear", 3.0) == "ribbon"
    assert check_projection(None, "nearest", 3.0) == "point"


def test_projection_reaches_read_maps_and_the_cli_options(noise):
    wide = read_maps(noise, projection="line", radius=2.0)              # a volume given as INPUT
    np.testing.assert_array_equal(wide.values["rh"][0],
                                  project_volume(noise, projection="line", radius=2.0)["rh"])
    from brainpainter.cli.options import MAP_OPTION_NAMES
    assert {"projection", "projection_radius"} <= set(MAP_OPTION_NAMES)


# -- refusals -------------------------------------------------------------------------------------

def one_line(exc: pytest.ExceptionInfo[BrainPainterError]) -> str:
    message = str(exc.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(("data", "affine", "words"), [
    (np.ones((91, 109), np.float32), MNI_2MM, "2-D image"),
    (np.ones((91, 109, 1), np.float32), MNI_2MM, "2-D image"),
    (np.ones((10242, 1, 1), np.float32), MNI_2MM, "one value per vertex"),
    (np.ones(SHAPE_2MM, np.float32), np.diag([0.01, 0.01, 0.01, 1]), "voxels of"),
    (np.ones(SHAPE_2MM, np.float32), np.diag([50.0, 50, 50, 1]), "voxels of"),
    (np.ones(SHAPE_2MM, np.float32), MNI_2MM + np.array([[0, 0, 0, 400.0]] + [[0] * 4] * 3), "not an MNI152"),
    (np.zeros(SHAPE_2MM, np.float32), MNI_2MM, "every voxel"),
    (np.full(SHAPE_2MM, np.nan, np.float32), MNI_2MM, "every voxel"),
    (np.ones((*SHAPE_2MM, 2, 3), np.float32), MNI_2MM, "axes"),
])
def test_refusals_are_one_line(tmp_path, data, affine, words):
    with pytest.raises(BrainPainterError) as exc:
        project_volume(save(tmp_path, data, affine))
    assert words in one_line(exc)


def test_a_freesurfer_subject_volume_without_surfaces_is_refused(tmp_path):
    aseg = nib.MGHImage(np.ones((256, 256, 256), np.float32),
                        np.array([[-1.0, 0, 0, 128], [0, 0, 1, -128], [0, -1, 0, 128], [0, 0, 0, 1]]))
    nib.save(aseg, tmp_path / "orig.mgz")
    for call in (project_volume, subcortical_means):
        with pytest.raises(BrainPainterError) as exc:
            call(tmp_path / "orig.mgz")
        assert "FreeSurfer conformed volume" in one_line(exc)


def test_refusals_of_arguments(tmp_path):
    path = save(tmp_path, blob(np.zeros(3)))
    img = nib.Nifti1Image(blob(np.zeros(3)), MNI_2MM)
    img.set_sform(None, code=0)
    img.set_qform(None, code=0)
    (tmp_path / "x.nii.gz").write_text("not a volume")
    cases = [
        (lambda: project_volume(tmp_path / "missing.nii.gz"), "does not exist"),
        (lambda: project_volume(tmp_path / "x.nii.gz"), "cannot read"),
        (lambda: project_volume(np.ones(SHAPE_2MM)), "file path or a nibabel image"),
        (lambda: project_volume(path, method="cubic"), "method must be one of"),
        (lambda: subcortical_means(path, method="cubic"), "method must be one of"),
        (lambda: project_volume(path, white={"lh": np.zeros((3, 3))}), "both white and pial"),
        (lambda: project_volume(img), "no spatial transform"),
        (lambda: project_volume(path, projection="ball"), "projection must be one of"),  # type: ignore[arg-type]
        (lambda: project_volume(path, method="nearest", projection="ribbon"), "mix the labels"),
        (lambda: project_volume(path, radius=0.1), "radius must be 0.5 to 10 mm"),
        (lambda: project_volume(path, projection="line", radius=float("nan")), "radius must be"),
        (lambda: read_maps(volume=path, projection="cubes"), "projection must be one of"),
        (lambda: MapOptions(lh="lh.thickness", projection="line"), "sample a volume"),
        (lambda: MapOptions(volume=path, projection_radius=40.0), "radius must be"),
    ]
    for call, words in cases:
        with pytest.raises(BrainPainterError) as exc:
            call()
        assert words in one_line(exc), str(exc.value)


# -- depth sampling in subject space --------------------------------------------------------------

def ramp_volume(tmp_path: Path) -> Path:
    """A 1 mm subject-space volume whose value is its z coordinate (mm)."""
    affine = np.eye(4)
    affine[:3, 3] = [-20.0, -20.0, -20.0]
    z = world_grid((41, 41, 41), affine)[..., 2].astype(np.float32)
    return save(tmp_path, z, affine, "subject.nii.gz")


def tiny_surfaces() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    white = rng.uniform(-10, 10, (20, 3))
    return white, white + np.array([0.0, 0.0, 3.0])       # pial 3 mm above white


@pytest.mark.parametrize(("depth", "expected"), [("mean", 1.5), ("max", 3.0)])
def test_depth_sampling_between_white_and_pial(tmp_path, depth, expected):
    white, pial = tiny_surfaces()
    maps = project_volume(ramp_volume(tmp_path), white={"left": white}, pial={"lh": (pial, None)},
                          depth=depth)
    assert set(maps) == {"lh"} and maps["lh"].shape == (20,)
    np.testing.assert_allclose(maps["lh"], white[:, 2] + expected, atol=1e-4)


def test_depth_nearest_takes_the_commonest_label(tmp_path):
    white, pial = tiny_surfaces()
    affine = np.eye(4)
    affine[:3, 3] = -20.0
    labels = np.where(world_grid((41, 41, 41), affine)[..., 2] < 100, 5, 0).astype(np.int16)
    labels[0, 0, 0] = 9
    maps = project_volume(save(tmp_path, labels, affine), white={"lh": white}, pial={"lh": pial},
                          depth="nearest", n_depths=5)
    assert (maps["lh"] == 5).all()


def test_freesurfer_surface_files_are_moved_by_their_cras(tmp_path):
    white, pial = tiny_surfaces()
    cras = np.array([1.0, -2.0, 4.0])
    faces = np.array([[0, 1, 2]])
    info = {"head": np.array([2, 0, 20], np.int32), "valid": "1  # volume info valid",
            "filename": "orig.mgz", "volume": np.array([256, 256, 256]), "voxelsize": np.ones(3),
            "xras": np.array([-1.0, 0, 0]), "yras": np.array([0, 0, -1.0]), "zras": np.array([0, 1.0, 0]),
            "cras": cras}
    for name, xyz in (("lh.white", white), ("lh.pial", pial)):
        nib.freesurfer.write_geometry(tmp_path / name, xyz - cras, faces, volume_info=info)
    maps = project_volume(ramp_volume(tmp_path), white={"lh": tmp_path / "lh.white"},
                          pial={"lh": str(tmp_path / "lh.pial")})
    np.testing.assert_allclose(maps["lh"], white[:, 2] + 1.5, atol=1e-3)


def test_gifti_surfaces_and_combining_nan_depths(tmp_path):
    from brainpainter.maps.depth import combine

    white, pial = tiny_surfaces()
    for name, xyz in (("white.surf.gii", white), ("pial.surf.gii", pial)):
        array = nib.gifti.GiftiDataArray(xyz.astype(np.float32), intent="NIFTI_INTENT_POINTSET")
        nib.save(nib.gifti.GiftiImage(darrays=[array]), tmp_path / name)
    maps = project_volume(ramp_volume(tmp_path), white={"rh": tmp_path / "white.surf.gii"},
                          pial={"right": tmp_path / "pial.surf.gii"})
    assert set(maps) == {"rh"}
    np.testing.assert_allclose(maps["rh"], white[:, 2] + 1.5, atol=1e-3)
    samples = np.array([[1.0, np.nan, 4.0], [3.0, np.nan, 4.0], [np.nan, np.nan, 7.0]], np.float32)
    np.testing.assert_allclose(combine(samples, "mean"), [2.0, np.nan, 5.0])
    np.testing.assert_allclose(combine(samples, "max"), [3.0, np.nan, 7.0])
    np.testing.assert_allclose(combine(samples, "nearest"), [1.0, np.nan, 4.0])


def test_depth_refusals(tmp_path):
    white, pial = tiny_surfaces()
    volume = ramp_volume(tmp_path)
    cases = [
        ({"lh": white}, {"lh": pial[:5]}, "same vertices"),
        ({"lh": white}, {"rh": pial}, "same hemispheres"),
        ({"lh": white + 500}, {"lh": pial + 500}, "not those of this volume"),
        ({"lh": tmp_path / "lh.nothing"}, {"lh": pial}, "does not exist"),
        ({"xh": white}, {"xh": pial}, "hemisphere must be one of"),
    ]
    for w, p, words in cases:
        with pytest.raises(BrainPainterError) as exc:
            project_volume(volume, white=w, pial=p)
        assert words in one_line(exc), str(exc.value)
    with pytest.raises(BrainPainterError) as exc:
        project_volume(volume, white={"lh": white}, pial={"lh": pial}, depth="median")  # type: ignore[arg-type]
    assert "depth must be one of" in one_line(exc)


# -- subcortical means ----------------------------------------------------------------------------

def test_subcortical_means_keyed_as_region_tables(tmp_path):
    points, structure, names = aseg_mni152()
    left = points[structure == names.index("Left-Hippocampus")].mean(axis=0)
    means = subcortical_means(save(tmp_path, blob(left, sigma=4.0) + 1.0))
    assert set(means) <= set(brainpainter.get_atlas("dk").keys) and "Left-Hippocampus" in means
    assert max(means, key=lambda k: float(means[k])) == "Left-Hippocampus"
    assert float(means["Left-Hippocampus"]) > 1.05 and float(means["Right-Hippocampus"]) < 1.001
    series = subcortical_means(save(tmp_path, np.stack([np.full(SHAPE_2MM, 2.0, np.float32)] * 3, -1),
                                    name="series.nii.gz"))
    np.testing.assert_allclose(series["Brain-Stem"], [2.0, 2.0, 2.0])


def test_subcortical_table_reads_as_a_region_table(tmp_path):
    data = np.stack([np.full(SHAPE_2MM, v, np.float32) for v in (1.0, 2.0)], -1)
    data[:45] = np.nan                                 # x > 0 mm: no value
    table = subcortical_table(save(tmp_path, data, name="series.nii.gz"))
    assert list(table) == ["series_0", "series_1"] and table["series_1"]["Left-Putamen"] == 2.0
    assert "Right-Putamen" not in table["series_0"]                # no value: left out
    read = brainpainter.read_table(table, "dk")
    assert list(read.images) == ["series_0", "series_1"]
    assert "Left-Putamen" in read.regions


# -- shipped data ---------------------------------------------------------------------------------

def test_shipped_data_is_package_data_with_licences():
    globs = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert "data/*" in globs["brainpainter"]
    data = REPO / "brainpainter" / "data"
    for name in (REGFUSION_FILE, ASEG_FILE):
        assert (data / name).is_file()
        assert (data / name.replace(".npz", ".LICENSE.txt")).is_file()
    assert "Wu J" in (data / REGFUSION_FILE.replace(".npz", ".LICENSE.txt")).read_text()
    xyz = fsaverage_mni152()
    assert xyz["lh"].shape == xyz["rh"].shape == (163842, 3)
    assert (xyz["lh"][:, 0] < 5).mean() > 0.99 and (xyz["rh"][:, 0] > -5).mean() > 0.99


@pytest.mark.integration
def test_shipped_positions_follow_fsaverage5_moved_to_mni152(fsaverage5):
    """RF positions lie near fsaverage's midthickness carried to MNI152 by FreeSurfer's affine."""
    with np.load(REPO / "brainpainter" / "data" / ASEG_FILE) as z:
        mni305_to_mni152 = z["mni305_to_mni152"]
    for hemi in ("lh", "rh"):
        white = nib.freesurfer.read_geometry(fsaverage5 / "surf" / f"{hemi}.white")[0]
        pial = nib.freesurfer.read_geometry(fsaverage5 / "surf" / f"{hemi}.pial")[0]
        mid = (white + pial) / 2 @ mni305_to_mni152[:3, :3].T + mni305_to_mni152[:3, 3]
        distance = np.linalg.norm(fsaverage_mni152()[hemi][:10242] - mid, axis=1)
        assert np.median(distance) < 2.5 and np.percentile(distance, 99) < 8, (hemi, np.median(distance))


# -- the bar: registration fusion against nilearn.surface.vol_to_surf -----------------------------

@pytest.mark.integration
def test_grey_matter_map_lands_on_cortex_better_than_vol_to_surf(fsaverage5):
    """The ICBM152 grey-matter probability map: over the cortex, more grey matter than nilearn's
    vol_to_surf reads, and no rougher (neighbouring vertices differ no more: no spots)."""
    nilearn = pytest.importorskip("nilearn")
    from nilearn import datasets, surface

    gm = datasets.load_mni152_gm_template()              # ICBM152 2009, in nilearn's wheel
    ours = project_volume(gm)
    meshes = datasets.load_fsaverage("fsaverage5")       # nilearn's own fsaverage5 (MNI305) meshes
    for hemi, part in (("lh", "left"), ("rh", "right")):
        cortex = nib.freesurfer.read_label(fsaverage5 / "label" / f"{hemi}.cortex.label")
        keep = np.zeros(10242, bool)
        keep[cortex] = True
        faces = nib.freesurfer.read_geometry(fsaverage5 / "surf" / f"{hemi}.white")[1]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")              # nilearn's deprecation notices
            theirs = surface.vol_to_surf(gm, meshes["pial"].parts[part])
        rf, nl = float(np.mean(ours[hemi][:10242][cortex])), float(np.mean(theirs[cortex]))
        assert rf > nl + 0.02, (hemi, rf, nl, nilearn.__version__)
        rough, rough_nl = roughness(ours[hemi][:10242], faces, keep), roughness(theirs, faces, keep)
        assert rough < 0.8 * rough_nl, (hemi, rough, rough_nl, nilearn.__version__)
