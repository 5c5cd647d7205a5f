"""A volume in one command (issue 21, item 3): ``render --volume STAT.nii.gz`` colours the cortex by
registration fusion and the subcortical structures by the volume's mean inside each."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from PIL import Image

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps.inputs import read_maps, read_volume
from brainpainter.maps.regfusion import aseg_mni152
from brainpainter.maps.volume import is_volume

# MNI152 2 mm grid (FSL's MNI152_T1_2mm: 91 x 109 x 91)
MNI_2MM = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
SHAPE_2MM = (91, 109, 91)
PRECENTRAL = (-38.0, -20.0, 56.0)  # left precentral gyrus, MNI152 mm


def _blob(centre: tuple[float, ...] | np.ndarray, sigma: float) -> np.ndarray:
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in SHAPE_2MM], indexing="ij"), axis=-1)
    xyz = ijk @ MNI_2MM[:3, :3].T + MNI_2MM[:3, 3]
    return np.exp(-((xyz - np.asarray(centre)) ** 2).sum(-1) / (2 * sigma**2)).astype(np.float32)


def _hippocampus() -> np.ndarray:
    points, structure, names = aseg_mni152()
    centre: np.ndarray = points[structure == names.index("Left-Hippocampus")].mean(axis=0)
    return centre


@pytest.fixture(scope="module")
def stat(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A t-map: +4 on the left precentral gyrus, -3 in the left hippocampus, 0 elsewhere."""
    data = 4.0 * _blob(PRECENTRAL, 6.0) - 3.0 * _blob(_hippocampus(), 5.0)
    path = tmp_path_factory.mktemp("vol") / "zstat1.nii.gz"
    nib.save(nib.Nifti1Image(data, MNI_2MM), path)
    return path


def test_a_volume_reads_as_maps_with_subcortical_means(stat, tmp_path):
    maps = read_maps(stat)  # a volume file given as INPUT is found to be one
    assert maps.images == ("zstat1",) and maps.values["lh"].shape == (1, 163842)
    assert maps.regions is not None and set(maps.regions) <= set(brainpainter.get_atlas("dk").keys)
    assert min(maps.regions, key=lambda k: float(maps.regions[k][0])) == "Left-Hippocampus"  # type: ignore[index]
    assert maps.region_values(0)["Left-Hippocampus"] < -0.3
    assert maps.finite().min() <= maps.regions["Left-Hippocampus"][0]  # the colour scale covers them
    series = tmp_path / "series.nii.gz"
    data = np.asarray(nib.load(stat).dataobj)
    nib.save(nib.Nifti1Image(np.stack([data, -data], -1), MNI_2MM), series)
    four_d = read_volume(series)
    assert four_d.images == ("series_0", "series_1") and four_d.values["rh"].shape == (2, 163842)
    halfway = four_d.region_values((0, 1, 0.5))["Left-Hippocampus"]  # a movie's in-between frame
    assert abs(halfway) < 1e-6


def test_a_vertex_map_in_nifti_is_not_taken_for_a_volume(tmp_path):
    surface = tmp_path / "lh.thickness.nii.gz"
    nib.save(nib.Nifti1Image(np.zeros((10242, 1, 1), np.float32), np.eye(4)), surface)
    volume = tmp_path / "stat.nii.gz"
    nib.save(nib.Nifti1Image(np.zeros((4, 4, 4), np.float32), MNI_2MM), volume)
    assert not is_volume(surface) and is_volume(volume) and is_volume(nib.load(volume))
    assert not is_volume(tmp_path / "missing.nii.gz") and not is_volume(tmp_path / "t.csv")
    assert read_maps(surface).regions is None


def test_a_volume_and_surface_maps_together_are_refused(stat):
    with pytest.raises(BrainPainterError, match="not both"):
        read_maps(volume=stat, lh=np.zeros(10242))
    with pytest.raises(BrainPainterError, match="not both"):
        brainpainter.render(volume=stat, lh=np.zeros(10242))


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "brainpainter", *args], capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize("extra", [["--lh", "x.npy"], []])
def test_cli_refusals_are_one_line(stat, tmp_path, extra):
    flat = tmp_path / "flat.nii.gz"
    nib.save(nib.Nifti1Image(np.ones((91, 109, 1), np.float32), MNI_2MM), flat)
    np.save(tmp_path / "x.npy", np.zeros(10242))
    given = stat if extra else flat
    out = subprocess.run([sys.executable, "-m", "brainpainter", "render", "--volume", str(given),
                          *[str(tmp_path / a) if a.endswith(".npy") else a for a in extra],
                          "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.render
def test_render_volume_colours_cortex_and_subcortex(stat, tmp_path):
    out = _cli("render", "--volume", str(stat), "--views", "lateral-left,subcortical", "--size", "600x450",
               "--vmin", "-1", "--vmax", "1", "--threshold", "0.2", "-q", "--out", str(tmp_path / "o"))
    assert out.returncode == 0, out.stderr
    lateral = np.asarray(Image.open(tmp_path / "o" / "zstat1_lateral-left.png").convert("RGBA")).astype(int)
    sub = np.asarray(Image.open(tmp_path / "o" / "zstat1_subcortical.png").convert("RGBA")).astype(int)
    r, g, b = (lateral[..., i] for i in range(3))
    red = (r > 150) & (g < 90) & (b < 90)
    assert red.sum() > 300                                    # the precentral blob, in the scale's red
    ys, _ = np.nonzero(red)
    assert ys.mean() < 0.45 * lateral.shape[0]                # at the top of the brain (precentral)
    grey = (abs(r - g) < 8) & (abs(g - b) < 8) & (lateral[..., 3] > 0) & (r < 250)
    assert grey.sum() > 20 * red.sum()                        # below the threshold: the grey underlay
    r, g, b = (sub[..., i] for i in range(3))
    blue = (b > 120) & (r < 100) & (b - r > 60)
    assert blue.sum() > 300                                   # the hippocampus's negative mean, in blue
    assert not ((r > 150) & (g < 90) & (b < 90)).any()        # nothing positive below the cortex


# -- views given win over the defaults (issue 33, item 10) ---------------------------------------
TABLE_VIEWS = "lateral-left,medial-left,subcortical"  # a table's default, and README's example for a volume


def test_views_given_are_drawn_as_given_even_when_they_equal_a_default(stat):
    from brainpainter.rendering.run import prepare_run
    from brainpainter.web.options import RenderOptions

    given = prepare_run(None, volume=stat, views=TABLE_VIEWS)
    assert [v.name for v in given.views] == TABLE_VIEWS.split(",")
    default = prepare_run(None, volume=stat)  # not given: both hemispheres, and the subcortical means
    assert [v.name for v in default.views] == ["lateral-left", "medial-left", "lateral-right", "medial-right",
                                               "subcortical"]
    surface = prepare_run(None, lh=np.zeros(10242), views=["lateral-left", "medial-left", "subcortical"])
    assert [v.name for v in surface.views] == TABLE_VIEWS.split(",")
    # the web API: views left out are the run's own, views sent are the run's views
    assert RenderOptions().run_kwargs()["views"] is None
    assert RenderOptions(views=TABLE_VIEWS).run_kwargs()["views"] == TABLE_VIEWS


def test_cli_figure_of_a_volume_draws_the_views_given(stat, tmp_path):
    from click.testing import CliRunner

    from brainpainter.cli.main import cli
    from brainpainter.testing import StandInRenderer, stand_in

    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer:
        result = CliRunner().invoke(cli, [
            "figure", "--volume", str(stat), "--views", TABLE_VIEWS, "--size", "80x60",
            "--renderer", renderer, "--out", str(tmp_path / "fig.png"), "-q"])
    assert result.exit_code == 0, result.output
    assert "1 row(s) x 3 view(s)" in result.output
