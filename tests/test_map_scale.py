"""A map's automatic colour scale (issue 33, item 11): diverging only for data substantially of both
signs (robust percentiles), sequential from 0 when 0 is near, and a line that says which and why."""

from __future__ import annotations

from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

from brainpainter.color.scale import ScaleOptions
from brainpainter.maps.inputs import read_maps
from brainpainter.maps.layers import map_scale

N5 = 10242


def _thickness() -> dict[str, np.ndarray]:
    """nilearn's fsaverage5 cortical thickness (its wheel's data), both hemispheres."""
    nilearn = pytest.importorskip("nilearn")
    folder = Path(nilearn.__file__).parent / "datasets" / "data" / "fsaverage5"
    return {hemi: np.asarray(nib.load(folder / f"thick_{side}.gii.gz").darrays[0].data, np.float64)
            for hemi, side in (("lh", "left"), ("rh", "right"))}


def _scale(lh: np.ndarray, rh: np.ndarray | None = None, **options: object):
    return map_scale(ScaleOptions(**options), read_maps({"lh": lh} if rh is None else {"lh": lh, "rh": rh}))


def test_real_thickness_is_sequential_over_its_robust_range_despite_a_stray_negative_vertex():
    """Issue 44 item 16: viridis 0-4.7 put 90 % of the cortex's vertices in a third of the bar (one green);
    the robust range (2nd-98th percentiles of the non-zero values, the low end at Tukey's fence: the medial
    wall's partial values) spreads them over two thirds."""
    thick = _thickness()
    assert min(float(v.min()) for v in thick.values()) < 0  # one vertex at -0.0028: once a -4.7..4.7 RdBu_r
    scale = _scale(thick["lh"], thick["rh"])
    assert (scale.name, scale.center) == ("viridis", None)
    assert (round(scale.vmin, 2), round(scale.vmax, 2)) == (1.08, 3.53)
    assert scale.describe().startswith("viridis 1.08-3.53 (values >= 0, over their 2nd-98th percentiles; ")
    cortex = np.concatenate(list(thick.values()))
    cortex = cortex[cortex > 0.5]  # not the medial wall
    where = np.clip((cortex - scale.vmin) / (scale.vmax - scale.vmin), 0, 1)
    low, high = np.percentile(where, [5, 95])
    assert high - low > 0.6  # 90 % of the cortex spans most of the bar (0 to 4.7: 0.35-0.68)
    assert np.histogram(where, bins=8, range=(0, 1))[0].max() < 0.3 * len(cortex)  # no colour holds it


def test_symmetric_and_two_signed_data_are_diverging_about_0():
    rng = np.random.default_rng(0)
    t = rng.normal(size=N5)
    scale = _scale(t)
    assert scale.name == "RdBu_r" and scale.center == 0 and scale.vmin == -scale.vmax
    assert scale.vmax == pytest.approx(np.abs(t).max())
    assert scale.describe() == f"RdBu_r {scale.vmin:.3g} to {scale.vmax:.3g} (values of both signs)"
    z = np.where(t > 0, 3 * t, t)  # a z-map whose negative side is a third of its positive one
    assert _scale(z).name == "RdBu_r"


@pytest.mark.parametrize("negatives", [
    np.array([-0.01]),                      # one stray negative vertex
    np.full(300, -0.02),                    # 3 % of the vertices, at 1 % of the top: noise about 0
])
def test_positive_data_with_a_few_small_negatives_is_sequential(negatives):
    rng = np.random.default_rng(1)
    v = rng.uniform(0.5, 3.0, N5)
    v[: len(negatives)] = negatives
    scale = _scale(v)
    assert (scale.name, scale.center) == ("viridis", None)
    assert scale.vmax == pytest.approx(v.max())
    # 3 % at -0.02 reach the 2nd percentile: the scale starts at 0 (their colour); one stray vertex does not
    assert scale.vmin == (0.0 if len(negatives) > 1 else pytest.approx(np.percentile(v[v != 0], 2)))
    assert scale.chosen.startswith("values >= 0")


def test_one_sign_far_from_0_starts_at_the_data_and_near_0_ends_at_0():
    rng = np.random.default_rng(2)
    myelin = rng.uniform(1.0, 1.8, N5)
    scale = _scale(myelin)
    assert scale.name == "viridis" and scale.vmin == pytest.approx(myelin.min())
    assert scale.chosen == "values >= 0, over their 2nd-98th percentiles"
    atrophy = -rng.uniform(0.0, 4.0, N5)  # z-scores of one sign: the scale ends at 0
    scale = _scale(atrophy)
    assert (scale.name, scale.vmax, scale.chosen) == ("viridis", 0.0, "values <= 0")
    assert scale.vmin == pytest.approx(atrophy.min())


def test_an_outlier_does_not_stretch_the_scale():
    rng = np.random.default_rng(3)
    v = rng.uniform(0.0, 4.0, N5)
    v[7] = 1000.0  # a broken vertex
    scale = _scale(v)
    assert scale.vmax < 4.0 + 1e-9 and scale.vmin == 0.0
    assert scale.vmax == pytest.approx(np.percentile(v, 98))  # robust: the top 2 % take the end colour
    assert scale.chosen == "values >= 0; 205 value(s) outside the scale take its end colours"


def test_given_limits_and_gradients_keep_their_meaning():
    v = np.linspace(-0.01, 3.0, N5)
    given = _scale(v, vmin=1.0, vmax=2.0)
    assert (given.name, given.vmin, given.vmax, given.chosen) == ("viridis", 1.0, 2.0, "")
    centred = _scale(np.linspace(0.0, 3.0, N5), center=1.0)  # a centre asks for a diverging scale
    assert centred.name == "RdBu_r" and centred.center == 1.0 and centred.chosen == ""
    gradient = _scale(np.linspace(0.0, 3.0, N5), gradient="white,red")  # BrainPainter's 0..N-1
    assert (gradient.vmin, gradient.vmax) == (0.0, 1.0)
    assert _scale(np.linspace(0.0, 3.0, N5), cmap="magma").describe() == "magma 0-3 (values >= 0)"


def test_cli_says_which_scale_was_chosen_and_why(tmp_path):
    from click.testing import CliRunner

    from brainpainter.cli.main import cli
    from brainpainter.testing import StandInRenderer, stand_in

    paths = []
    for hemi, values in _thickness().items():
        paths.append(tmp_path / f"{hemi}.thickness.func.gii")
        array = nib.gifti.GiftiDataArray(values.astype(np.float32))
        nib.save(nib.gifti.GiftiImage(darrays=[array]), paths[-1])
    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer:
        result = CliRunner().invoke(cli, [
            "figure", "--lh", str(paths[0]), "--rh", str(paths[1]), "--views", "lateral-left",
            "--size", "80x60", "--renderer", renderer, "--out", str(tmp_path / "fig.png"), "-q"])
        assert result.exit_code == 0, result.output
        assert "scale: viridis 1.08-3.53 (values >= 0, over their 2nd-98th percentiles" in result.output
        rendered = CliRunner().invoke(cli, [
            "render", "--lh", str(paths[0]), "--views", "lateral-left", "--size", "80x60",
            "--renderer", renderer, "--out", str(tmp_path / "images"), "-q"])
        assert rendered.exit_code == 0, rendered.output
        assert "scale: viridis 1.06-3.54 (values >= 0" in rendered.output  # the left hemisphere alone
        given = CliRunner().invoke(cli, [
            "figure", "--lh", str(paths[0]), "--views", "lateral-left", "--vmin", "1", "--vmax", "4",
            "--size", "80x60", "--renderer", renderer, "--out", str(tmp_path / "given.png"), "-q"])
        assert given.exit_code == 0, given.output
        assert "scale:" not in given.output  # limits given: nothing was chosen


def test_a_thresholded_map_is_scaled_over_the_values_it_draws():
    """Two small blobs of z up to +-4 in a map of noise, --threshold 2.3: the scale reaches the blobs
    (it was -2.24..2.24 over all values, the blobs its outliers in the end colours, and the colour
    bar greyed out from end to end), and the bar's colours start at the threshold."""
    rng = np.random.default_rng(0)
    z = rng.normal(0.0, 0.5, N5)
    z[:40], z[40:80] = np.linspace(2.3, 4.0, 40), -np.linspace(2.3, 4.0, 40)
    z = np.clip(z, -4.0, 4.0)
    scale = map_scale(ScaleOptions(), read_maps({"lh": z}), threshold=2.3)
    assert (scale.name, scale.center) == ("RdBu_r", 0.0) and scale.vmax == pytest.approx(4.0)
    unthresholded = map_scale(ScaleOptions(), read_maps({"lh": z}))
    assert unthresholded.vmax < 2.3  # over all values: the whole scale under the threshold
    given = map_scale(ScaleOptions(vmin=-3, vmax=3), read_maps({"lh": z}), threshold=2.3)
    assert (given.vmin, given.vmax) == (-3, 3)  # limits given are kept
