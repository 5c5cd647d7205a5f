"""Slice and glass-brain panels of a volume beside the 3-D views (issue 45, items 3 and 4).

The volume: a sphere of radius 8 mm at MNI (40, -20, 50), value 5 over zeros, on the MNI152 2 mm
grid (FSL's 91 x 109 x 91), thresholded at 2.3. Its panels must show it where it is (right of the
midline: on the right in the neurological convention) in colours that read back on the bar.
"""

from __future__ import annotations

import io
import socket
from pathlib import Path
from typing import Any

import nibabel as nib
import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps import sections
from brainpainter.maps.sections import (
    Section,
    panel_grid,
    parse_panel,
    parse_projections,
    parse_slices,
    project,
)
from brainpainter.testing import StandInRenderer, stand_in

MNI_2MM = np.array([[-2.0, 0, 0, 90], [0, 2, 0, -126], [0, 0, 2, -72], [0, 0, 0, 1]])
SHAPE_2MM = (91, 109, 91)
CENTRE = np.array([40.0, -20.0, 50.0])
THRESHOLD = 2.3


def _sphere(affine: np.ndarray = MNI_2MM) -> np.ndarray:
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in SHAPE_2MM], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    return np.where(np.linalg.norm(xyz - CENTRE, axis=-1) <= 8.0, 5.0, 0.0).astype(np.float32)


def _save(data: np.ndarray, path: Path, affine: np.ndarray = MNI_2MM) -> Path:
    image = nib.Nifti1Image(data, affine)
    image.header.set_sform(affine, 4)
    image.header.set_qform(affine, 4)
    nib.save(image, path)
    return path


@pytest.fixture(scope="module")
def sphere(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _save(_sphere(), tmp_path_factory.mktemp("vol") / "sphere.nii.gz")


def _figure(sphere: Path, tmp_path: Path, **extra: Any) -> Any:
    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer:
        return brainpainter.figure(None, volume=sphere, threshold=THRESHOLD, views="dorsal", width=80,
                                   height=60, renderer=renderer, out=tmp_path / "fig.png", progress=False,
                                   **extra)


def _bar_rgb(scale: Any) -> np.ndarray:
    """Every colour of the bar, 0-255, shape (512, 3)."""
    return np.asarray(scale(np.linspace(scale.vmin, scale.vmax, 512))) * 255.0


def _bar_error(pixels: np.ndarray, scale: Any) -> float:
    """Median distance (RGB units) of `pixels` (n, 3) to the nearest colour of the bar."""
    bar = _bar_rgb(scale)
    distance = np.linalg.norm(pixels[:, None, :3].astype(float) - bar[None], axis=-1)
    return float(np.median(distance.min(axis=1)))


def _coloured(rgba: np.ndarray) -> np.ndarray:
    """Pixels that are not grey (the template, the outline, the background): the volume's colours."""
    rgb = rgba[..., :3].astype(int)
    return (rgb.max(axis=-1) - rgb.min(axis=-1) > 40) & (rgba[..., 3] > 0)


def _centre(mask: np.ndarray) -> tuple[float, float]:
    rows, cols = np.nonzero(mask)
    return float(rows.mean()), float(cols.mean())


def _expected(axis: str, convention: str = "neurological") -> tuple[float, float]:
    """The pixel (row, column) of the sphere's centre on an `axis` panel."""
    columns, rows = panel_grid(axis, convention)  # type: ignore[arg-type]
    c, r = sections.IN_PLANE[axis]
    return (float(np.argmin(abs(rows - CENTRE[r]))), float(np.argmin(abs(columns - CENTRE[c]))))


# -- where the sphere is, in the bar's colours ------------------------------------------------
@pytest.mark.parametrize("convention", ["neurological", "radiological"])
def test_slice_at_z50_shows_the_sphere_right_of_the_midline_in_the_bars_colours(sphere, tmp_path, convention):
    result = _figure(sphere, tmp_path, slices=["z=50", "x=40"], convention=convention)
    panel = result.images[("sphere", "z=50")]
    blob = _coloured(panel)
    assert 150 * 4 < blob.sum() < 250 * 4 * 1.2      # a disc of radius ~8 mm at 0.5 mm pixels (pi 64 mm2)
    row, col = _centre(blob)
    exp_row, exp_col = _expected("z", convention)
    assert abs(row - exp_row) < 3 and abs(col - exp_col) < 3      # within 1.5 mm of (40, -20)
    midline = float(np.argmin(abs(panel_grid("z", convention)[0])))
    assert (col > midline) == (convention == "neurological")     # right hemisphere: right (neurological)
    assert _bar_error(panel[blob], result.scale) < 10
    inside = panel[blob][:, :3].astype(float)                     # the sphere's inside is 5: the bar's top
    assert np.median(np.linalg.norm(inside - np.asarray(result.scale(5.0)) * 255, axis=-1)) < 10
    sagittal = result.images[("sphere", "x=40")]
    row, col = _centre(_coloured(sagittal))
    assert abs(row - _expected("x")[0]) < 3 and abs(col - _expected("x")[1]) < 3


def _panel_crop(png: np.ndarray, result, name: str):
    """The pixels of panel `name` in the written figure `png`, and the panel's axes box."""
    h, w = png.shape[:2]
    box = result.image_axes[("sphere", name)].get_position()
    return png[round((1 - box.y1) * h):round((1 - box.y0) * h), round(box.x0 * w):round(box.x1 * w)], box


def test_slice_in_the_written_figure_reads_back_on_its_bar(sphere, tmp_path):
    result = _figure(sphere, tmp_path, slices=["z=50"], projections="z", dpi=200)
    png = np.asarray(Image.open(result.path).convert("RGBA"))
    for name in ("z=50", "glass-z"):
        crop, box = _panel_crop(png, result, name)
        blob = _coloured(crop)
        assert blob.sum() > 30, name
        assert _bar_error(crop[blob], result.scale) < 10, name
        _, col = _centre(blob)
        assert col > 0.6 * crop.shape[1], name                   # x = 40: the right side of the panel
    bar = result.colorbar_ax.get_position()                      # one bar, the map's, under every panel
    assert len(result.colorbar_axes) == 1 and bar.y1 < box.y0


def test_blobs_alone_draw_their_panels_on_the_blobs_bar(sphere, tmp_path):
    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer:
        result = brainpainter.figure(None, volume_surface=sphere, threshold=THRESHOLD, views="dorsal",
                                     slices="z=50", projections="z", width=80, height=60, renderer=renderer,
                                     out=tmp_path / "fig.png", progress=False)
    assert (result.scale.vmin, result.scale.vmax) == (THRESHOLD, 5.0)   # the blobs' own: threshold to peak
    (name,) = {image for image, _ in result.images}
    for panel_name in ("z=50", "glass-z"):
        panel = result.images[(name, panel_name)]
        blob = _coloured(panel)
        assert blob.sum() > 100 and _centre(blob)[1] > panel.shape[1] / 2, panel_name   # right of midline
        assert _bar_error(panel[blob], result.scale) < 10, panel_name
        inside = panel[blob][:, :3].astype(float)                  # 5, the peak: the bar's top
        assert np.median(np.linalg.norm(inside - np.asarray(result.scale(5.0)) * 255, axis=-1)) < 10
    assert len(result.colorbar_axes) == 1


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_glass_projection_shows_the_sphere_where_it_is(sphere, tmp_path, axis):
    result = _figure(sphere, tmp_path, projections=axis)
    panel = result.images[("sphere", f"glass-{axis}")]
    blob = _coloured(panel)
    row, col = _centre(blob)
    exp_row, exp_col = _expected(axis)
    assert abs(row - exp_row) < 3 and abs(col - exp_col) < 3
    assert _bar_error(panel[blob], result.scale) < 10
    outline = (panel[..., :3].astype(int).max(-1) < 120) & ~blob  # the brain's outline, dark grey
    assert outline.sum() > 500


def test_projection_takes_the_value_of_largest_magnitude_of_either_sign():
    data = np.zeros(SHAPE_2MM, np.float32)
    i, j = 25, 50                                                # one ray along z: +5, then -6
    data[i, j, 30], data[i, j, 60] = 5.0, -6.0
    data[i + 5, j, 40] = 3.0                                     # another ray: +3 only
    glass = project(data, MNI_2MM, "z", "neurological")
    columns, rows = panel_grid("z")
    at = (MNI_2MM @ [i, j, 0, 1])[:3]
    assert glass[np.argmin(abs(rows - at[1])), np.argmin(abs(columns - at[0]))] == -6.0
    at = (MNI_2MM @ [i + 5, j, 0, 1])[:3]
    assert glass[np.argmin(abs(rows - at[1])), np.argmin(abs(columns - at[0]))] == 3.0


# -- options and names -------------------------------------------------------------------------
def test_slices_and_projections_are_parsed_to_panels():
    given = parse_slices(["z=-20,0,20,40", "x=40"])
    assert [s.name for s in given] == ["z=-20", "z=0", "z=20", "z=40", "x=40"]
    assert [s.name for s in parse_slices("z=-40:60:20")] == ["z=-40", "z=-20", "z=0", "z=20", "z=40", "z=60"]
    assert [s.name for s in parse_projections("xyz")] == ["glass-x", "glass-y", "glass-z"]
    assert parse_projections("sagittal,axial") == (Section("x"), Section("z"))
    assert parse_panel("z=50") == Section("z", 50.0) and parse_panel("glass-y") == Section("y")
    assert parse_panel("lateral-left") is None
    for bad in ("q=3", "z=", "z=1:0:5", "z=nan"):
        with pytest.raises(BrainPainterError, match="--slices"):
            parse_slices(bad)
    with pytest.raises(BrainPainterError, match="projections"):
        parse_projections("xw")


def test_the_template_is_read_from_nilearns_wheel_without_the_network(monkeypatch):
    def no_network(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("the template must not be downloaded")

    monkeypatch.setattr(socket, "socket", no_network)
    sections.template.cache_clear()
    data, affine = sections.template()
    assert data.shape == (197, 233, 189) and affine[0, 0] == 1.0 and data.max() > 0


def test_plot_draws_a_panel_into_axes_with_the_maps_bar(sphere):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3, 3))
    result = brainpainter.plot(None, view="z=50", ax=ax, volume=sphere, threshold=THRESHOLD, label="z")
    blob = _coloured(result.image)
    assert result.colorbar_ax is not None and _bar_error(result.image[blob], result.scale) < 10
    assert _centre(blob)[1] > result.image.shape[1] / 2
    assert {t.get_text() for t in ax.texts} == {"L", "R", "z=50"}
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)


# -- bad input: one line, exit 2, nothing written ---------------------------------------------
@pytest.fixture(scope="module")
def elsewhere(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sphere's volume moved 300 mm away: not in MNI152."""
    shifted = MNI_2MM.copy()
    shifted[:3, 3] += 300.0
    return _save(_sphere(), tmp_path_factory.mktemp("vol") / "elsewhere.nii.gz", shifted)


@pytest.mark.parametrize("case, expected", [
    ("not-mni", "not an MNI152 volume"),
    ("threshold", "above the largest |value|"),
    ("outside", "slice z=200 lies outside sphere"),
    ("no-volume", "show a volume in MNI152"),
    ("bad-spec", "--slices 'w=3'"),
])
def test_bad_panel_input_is_one_line_exit_2_nothing_written(sphere, elsewhere, tmp_path, case, expected):
    from brainpainter.cli.main import main

    args = {"not-mni": ["--volume", str(elsewhere), "--slices", "z=50"],
            "threshold": ["--volume", str(sphere), "--slices", "z=50", "--threshold", "6"],
            "outside": ["--volume", str(sphere), "--slices", "z=0,200", "--threshold", "2.3"],
            "no-volume": ["--lh", str(tmp_path / "lh.npy"), "--projections", "z"],
            "bad-spec": ["--volume", str(sphere), "--slices", "w=3"]}[case]
    np.save(tmp_path / "lh.npy", np.zeros(10242))
    runner = CliRunner()
    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer, \
            runner.isolation() as (out, err, _), pytest.raises(SystemExit) as exit_:
        main(["figure", *args, "--views", "dorsal", "--size", "80x60", "--renderer", renderer, "-q",
              "--out", str(tmp_path / "fig.png")])
    assert exit_.value.code == 2
    lines = err.getvalue().decode().strip().splitlines()
    assert len(lines) == 1 and expected in lines[0] and not out.getvalue(), lines
    assert not (tmp_path / "fig.png").exists()


def test_cli_says_views_panels_and_the_convention(sphere, tmp_path):
    from brainpainter.cli.main import cli

    with stand_in("solid", StandInRenderer.with_(layout="solid")) as renderer:
        result = CliRunner().invoke(cli, [
            "figure", "--volume", str(sphere), "--threshold", "2.3", "--views", "dorsal", "--size", "80x60",
            "--slices", "z=-20,50", "--slices", "x=40", "--projections", "xz", "--convention", "radiological",
            "--renderer", renderer, "-q", "--out", str(tmp_path / "fig.png")])
    assert result.exit_code == 0, result.output
    assert "(1 row(s) x 1 view(s) + 5 panel(s)," in result.output
    assert "radiological convention (left on the right, labelled L/R)" in result.output


def test_panels_with_jobs_are_the_serial_ones(sphere, tmp_path):
    kw: dict[str, Any] = {"volume": sphere, "threshold": THRESHOLD, "views": "dorsal,lateral-right",
                          "width": 60, "height": 45, "slices": ["z=50"], "projections": "x",
                          "progress": False}
    with stand_in() as renderer:
        serial = brainpainter.figure(None, renderer=renderer, **kw)
        jobs = brainpainter.figure(None, renderer=renderer, jobs=2, **kw)
    assert list(jobs.images) == list(serial.images)
    assert [name for _, name in serial.images] == ["dorsal", "lateral-right", "z=50", "glass-x"]
    assert all(np.array_equal(jobs.images[k], v) for k, v in serial.images.items())


def test_slice_outline_draws_the_label_volumes_borders(sphere, tmp_path):
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in SHAPE_2MM], indexing="ij"), axis=-1)
    x = (ijk @ MNI_2MM[:3, :3].T + MNI_2MM[:3, 3])[..., 0]
    labels = _save(np.where(x < 0, 1, 2).astype(np.int16), tmp_path / "halves.nii.gz")  # border at x = -1
    result = _figure(sphere, tmp_path, slices=["z=20"], slice_outline=labels)
    panel = result.images[("sphere", "z=20")]
    black = (panel[..., :3].max(axis=-1) == 0) & (panel[..., 3] == 255)
    columns, _ = panel_grid("z")
    cols = np.nonzero(black.sum(axis=0) > 100)[0]                # a line from the front to the back
    assert len(cols) >= 1 and all(abs(columns[c] + 1) <= 1 for c in cols)
    plain = _figure(sphere, tmp_path / "plain", slices=["z=20"])
    assert not ((plain.images[("sphere", "z=20")][..., :3].max(axis=-1) == 0).sum(axis=0) > 100).any()


@pytest.mark.render
def test_the_issues_figure_with_blender_views_three_slices_and_a_projection(sphere, tmp_path):
    result = brainpainter.figure(None, volume=sphere, threshold=THRESHOLD, views="lateral-right,dorsal",
                                 width=400, height=300, slices=["z=-20,10,50"], projections="z",
                                 out=tmp_path / "fig.png", progress=False, dpi=150)
    names = [name for _, name in result.images]
    assert names == ["lateral-right", "dorsal", "z=-20", "z=10", "z=50", "glass-z"]
    for view in ("lateral-right", "dorsal"):                      # the renders: a brain, not empty
        assert (result.images[("sphere", view)][..., 3] > 0).mean() > 0.2
    png = np.asarray(Image.open(result.path).convert("RGBA"))
    for name in ("z=50", "glass-z"):
        crop, _box = _panel_crop(png, result, name)
        blob = _coloured(crop)
        assert blob.sum() > 20 and _bar_error(crop[blob], result.scale) < 10, name
        assert _centre(blob)[1] > 0.6 * crop.shape[1], name
    assert not _coloured(result.images[("sphere", "z=-20")]).any()  # the sphere is not at z = -20
