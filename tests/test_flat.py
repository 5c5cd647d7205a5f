"""Flat maps (issue 34, item 4): views flat-left, flat-right and flat on HCP's Colin flat fsLR 32k sheets."""

from __future__ import annotations

import os
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
from click.testing import CliRunner
from nibabel.cifti2 import cifti2_axes as axes

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps.flat import N_FLAT, flat_sheet, flat_values, to_flat
from brainpainter.maps.fslr import cortex_roi
from brainpainter.maps.inputs import read_maps
from brainpainter.rendering import framing
from brainpainter.rendering.views import PRESETS, get_view, parse_views

SHARED = Path(os.environ.get("BRAINPAINTER_SHARED_DATA",
                             Path(__file__).resolve().parents[1].parent / "shared" / "data"))
FS5 = SHARED / "freesurfer" / "subjects" / "fsaverage5"


# -- the shipped sheets -----------------------------------------------------------------------------
def signed_area2(corners):
    """Twice the signed areas of 2-D triangles (positive: counter-clockwise), corners (n, 3, 2) -> (n,)."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]  # np.cross of 2-D vectors is deprecated (numpy 2)


def test_sheets_lie_side_by_side_facing_the_camera():
    lh, rh = flat_sheet("lh"), flat_sheet("rh")
    assert lh.vertices[lh.used, 0].max() < 0 < rh.vertices[rh.used, 0].min()  # left on the left
    for sheet in (lh, rh):
        assert sheet.vertices.shape == (N_FLAT, 3) and not sheet.vertices[:, 2].any()
        c = sheet.vertices[sheet.faces][..., :2].astype(float)
        area = signed_area2(c)
        assert (area >= 0).all()  # counter-clockwise from +z: none culled
        np.testing.assert_allclose(sheet.weights.sum(axis=1), 1.0, atol=1e-4)
        assert 25_000 < len(sheet.used) < N_FLAT  # the cuts are no triangles'


def test_fsaverage_values_reach_the_sheet_by_barycentric_weights():
    sheet = flat_sheet("lh")
    ramp = np.arange(163842, dtype=np.float32)
    np.testing.assert_allclose(to_flat(np.ones(163842), "lh"), 1.0, atol=1e-6)
    np.testing.assert_allclose(to_flat(ramp, "lh"), (sheet.weights * sheet.fsaverage).sum(axis=1), rtol=1e-4)
    np.testing.assert_array_equal(to_flat(ramp, "lh", categorical=True), sheet.nearest)
    holes = ramp.copy()
    holes[sheet.fsaverage[:, 0]] = np.nan  # one corner missing: the others' weighted mean
    assert np.isfinite(to_flat(holes, "lh")).mean() > 0.99


def _dscalar(path: Path, left: np.ndarray, right: np.ndarray) -> Path:
    """A 32k dscalar of both cortices without the medial wall (as HCP's 91k files), one map."""
    lh, rh = (np.flatnonzero(cortex_roi(hemi, "32k")) for hemi in ("lh", "rh"))
    cols = (axes.BrainModelAxis.from_surface(lh, N_FLAT, "CortexLeft")
            + axes.BrainModelAxis.from_surface(rh, N_FLAT, "CortexRight"))
    data = np.concatenate([left, right])[None].astype(np.float32)
    nib.Cifti2Image(data, header=(axes.ScalarAxis(["m"]), cols)).to_filename(str(path))
    return path


def test_an_fslr_32k_map_is_drawn_on_the_sheet_as_it_is(tmp_path):
    roi = cortex_roi("lh", "32k")
    rng = np.random.default_rng(0)
    left = rng.normal(size=int(roi.sum()))
    path = _dscalar(tmp_path / "x.dscalar.nii", left, rng.normal(size=int(cortex_roi("rh", "32k").sum())))
    on_sheet = flat_values(read_maps(path), "lh", 0)
    np.testing.assert_array_equal(on_sheet[roi], left.astype(np.float32))  # no resampling
    assert np.isnan(on_sheet[~roi]).all()


def test_regions_meet_half_way_between_vertices_of_two_labels():
    from brainpainter.rendering.flat_parts import split_at_borders

    square = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], np.float32)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    for labels in ([0, 0, 1, 1], [0, 1, 2, 2], [5, 5, 5, 5]):
        v, f, fl = split_at_borders(square, faces, np.array(labels))
        c = v[f][..., :2].astype(float)
        area = signed_area2(c) / 2
        assert (area > 0).all() and area.sum() == pytest.approx(4.0)  # the same square, all facing +z
        for label in set(labels):  # each label's area: its vertices' share, split at the midpoints
            corners = [i for i, x in enumerate(labels) if x == label]
            assert area[fl == label].sum() > 0 and all(np.isin(fl[(f == i).any(axis=1)], labels[i]).all()
                                                       for i in corners)
    v, f, fl = split_at_borders(square, faces, np.array([0, 0, 1, 1]))
    c = v[f][..., :2].astype(float)
    area = signed_area2(c) / 2
    assert area[fl == 0].sum() == pytest.approx(2.0)  # the border runs through the middle
    assert len(v) == 4 + 3  # three midpoints (edges 1-2, 0-2, 0-3), shared by both triangles


# -- views, parts, camera ---------------------------------------------------------------------------
def test_flat_views_are_presets_that_draw_the_sheets_only():
    assert [v.name for v in parse_views("flat-left,flat-right,flat")] == ["flat-left", "flat-right", "flat"]
    flat = get_view("flat")
    assert flat.content == "flat" and flat.hemis == ("lh", "rh")
    assert framing.shows(flat, "flat", "lh") and framing.shows(get_view("flat-left"), "flat", "lh")
    assert not framing.shows(get_view("flat-left"), "flat", "rh")
    for kind, hemi in (("cortex", "lh"), ("subcortical", None), ("glass", "rh"), ("tract", None)):
        assert not framing.shows(flat, kind, hemi, "glass")
    assert not any(framing.shows(v, "flat", "lh") for v in PRESETS.values() if v.content != "flat")


@pytest.fixture(scope="module")
def dk_scene():
    from brainpainter.rendering.painter import load_scene
    from brainpainter.rendering.settings import RenderSettings

    return load_scene("dk", settings=RenderSettings(outline_width=2.0))[1]


def test_the_camera_frames_the_sheets_left_on_the_left(dk_scene):
    g = dk_scene.geometry
    parts = g.visible(get_view("flat"))
    assert [(p.name, p.kind) for p in parts] == [(n, "flat") for n in ("flat-lh", "flat-lh-rim", "flat-rh",
                                                                        "flat-rh-rim")]
    parts = [p for p in parts if not p.name.endswith("-rim")]
    assert all(p.outline is not None and len(p.outline) > 1000 for p in parts)  # --outline on the sheet
    pose = g.camera(get_view("flat"), 2.0)
    lh, rh = (framing.to_pixels(p.hull, pose, 800, 400) for p in parts)
    assert lh[:, 0].max() < 400 < rh[:, 0].min()
    both = np.vstack([lh, rh])
    assert both.min() >= 0 and both[:, 0].max() <= 800 and both[:, 1].max() <= 400
    outline = np.vstack([p.outline.reshape(-1, 3) for p in parts])
    m = framing.view_projection(pose, 2.0)
    depth = outline @ m[2, :3] + m[2, 3]
    assert -1 < depth.min() and depth.max() < 1  # the lifted borders are not clipped
    assert [p.name for p in g.visible(get_view("flat-right"))] == ["flat-rh", "flat-rh-rim"]


def test_a_map_scene_takes_the_sheets_palette_slots_only_when_a_flat_view_needs_them():
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.painter import load_scene

    g = load_scene("dk", coloring="vertices")[1].geometry
    n = g.n_slots
    assert "flat-lh" not in g.vertex_slots  # a run without flat views uploads no larger palette
    assert len(Palette({}, g, {"lh": np.zeros((g.vertex_slots["lh"][1], 3))}).rgb) == n
    grey = np.full((N_FLAT, 3), 0.5, np.float32)
    rgb = Palette({}, g, {"flat-lh": grey, "flat-rh": grey}).rgb
    assert rgb.shape == (n + 2 * N_FLAT, 3) and (rgb[n:] == 0.5).all()
    lh, lh_rim, rh, rh_rim = g.visible(get_view("flat"))
    assert (lh_rim.palette_index == rh_rim.palette_index[0]).all()  # the rims: one grey slot
    assert lh.palette_index[0] == n and rh.palette_index[-1] == n + 2 * N_FLAT - 1


def test_a_template_of_your_own_surfaces_refuses_flat_views_in_one_line(tmp_path):
    from brainpainter.cli.main import main

    with CliRunner().isolation() as (out, err, _):
        with pytest.raises(SystemExit) as exit_:
            main(["render", "--lh", str(FS5 / "surf" / "lh.sulc"), "--lh-surface",
                  str(FS5 / "surf" / "lh.pial"), "--views", "flat", "--out", str(tmp_path / "out")])
        text = out.getvalue().decode() + (err.getvalue().decode() if err else "")
    assert exit_.value.code == 2, text
    lines = [line for line in text.splitlines() if line.strip()]
    assert len(lines) == 1 and "flat" in lines[0] and "3-D views" in lines[0], text
    assert "Traceback" not in text and not (tmp_path / "out").exists()


# -- pictures (Blender) -----------------------------------------------------------------------------
def _table(path: Path, hemis: tuple[str, ...] = ("Left", "Right")) -> Path:
    from brainpainter.atlas.registry import get_atlas

    # the cortical regions (lower-case names: Left-insula, not Left-Hippocampus), values 0, 1, 2, ...
    names = [k for k in get_atlas("dk").keys if k.split("-")[0] in hemis and k.split("-", 1)[1].islower()]
    values = ",".join(str(i) for i in range(len(names)))
    path.write_text("image," + ",".join(names) + "\nrow," + values + "\n")
    return path


def _coloured(rgb: np.ndarray) -> np.ndarray:
    c = rgb[..., :3].astype(int)
    return (c.max(axis=-1) - c.min(axis=-1)) > 40  # a hue: not the white background, greys or black lines


def test_dk_table_on_flat_both_hemispheres_left_on_the_left(tmp_path):
    result = brainpainter.render(_table(tmp_path / "t.csv"), "dk", views="flat", cmap="turbo",
                                 progress=False)
    img = result.images[("row", "flat")]
    h, w = img.shape[:2]
    assert w / h == pytest.approx(2.0, abs=0.01)  # a run of flat views alone is framed wide
    coloured = _coloured(img)
    assert coloured.mean() >= 0.25  # the brain covers a quarter of the image
    assert coloured[:, : w // 2].mean() > 0.2 and coloured[:, w // 2:].mean() > 0.2  # both hemispheres
    _, counts = np.unique(img[coloured][:, :3], axis=0, return_counts=True)
    assert (counts >= 200).sum() >= 20  # the regions' colours (flat, unlit: exact; 68 at the default size)

    left_only = brainpainter.render(_table(tmp_path / "l.csv", ("Left",)), "dk", views="flat", cmap="turbo",
                                    progress=False).images[("row", "flat")]
    lc = _coloured(left_only)
    assert lc[:, : w // 2].mean() > 0.2 and not lc[:, w // 2:].any()  # values in the left half only


def test_maps_on_flat_show_their_colours_where_they_have_values(tmp_path):
    """An fsaverage5 map (left +1, right none) and an fsLR 32k CIFTI (left +1, right -1)."""
    lh = tmp_path / "lh.mgh"
    nib.MGHImage(np.ones((10242, 1, 1), np.float32), np.eye(4)).to_filename(str(lh))
    (img,) = brainpainter.render(lh=lh, views="flat", cmap="RdBu_r", vmin=-1, vmax=1, width=600, height=300,
                                 progress=False).images.values()
    c = img[..., :3].astype(int)
    w = img.shape[1]
    red = (c[..., 0] > 60) & (c[..., 1] < 30) & (c[..., 0] > 2 * c[..., 2])  # RdBu_r's dark red
    assert red[:, : w // 2].mean() > 0.2 and not red[:, w // 2:].any()
    assert _coloured(img)[:, w // 2:].sum() == 0  # the right sheet: the underlay's greys

    path = _dscalar(tmp_path / "x.dscalar.nii", np.ones(int(cortex_roi("lh", "32k").sum())),
                    -np.ones(int(cortex_roi("rh", "32k").sum())))
    img = brainpainter.render(path, views="flat", cmap="RdBu_r", vmin=-1, vmax=1, width=600, height=300,
                              progress=False).images[("m", "flat")]
    c = img[..., :3].astype(int)
    red = (c[..., 0] > 60) & (c[..., 1] < 30) & (c[..., 0] > 2 * c[..., 2])
    blue = (c[..., 2] > 60) & (c[..., 2] > c[..., 0] + 40)  # RdBu_r's dark blue
    assert red[:, : w // 2].mean() > 0.2 and not red[:, w // 2:].any()
    assert blue[:, w // 2:].mean() > 0.2 and not blue[:, : w // 2].any()


def test_outline_on_flat_is_drawn_at_a_constant_pixel_width(tmp_path):
    table = _table(tmp_path / "t.csv")
    counts = []
    for width in (400, 800):
        img = brainpainter.render(table, "dk", views="flat", cmap="Greens", vmin=-1000, vmax=1000,
                                  outline="dk", outline_width=2, outline_color="black", width=width,
                                  height=width // 2, progress=False).images[("row", "flat")]
        counts.append(int((img[..., :3].astype(int).max(axis=-1) < 40).sum()))
    assert counts[0] > 1000
    assert 1.3 <= counts[1] / counts[0] <= 3.0  # lines of constant pixel width: about 2x, not 4x


def test_flat_views_mix_with_3d_views_and_refuse_cycles(tmp_path):
    result = brainpainter.render(_table(tmp_path / "t.csv"), "dk", views="lateral-left,flat-left",
                                 width=320, height=240, progress=False)
    for view in ("lateral-left", "flat-left"):
        assert _coloured(result.images[("row", view)]).mean() > 0.2
    with pytest.raises(BrainPainterError, match=r"flat map.*gpu path"):
        brainpainter.render(_table(tmp_path / "t.csv"), "dk", views="flat", quality="high", width=64,
                            height=32, progress=False)


def test_the_rim_is_a_band_just_outside_the_boundary_facing_the_camera():
    from brainpainter.rendering.flat_parts import rim

    square = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], np.float32)
    v, f = rim(square, np.array([[0, 1, 2], [0, 2, 3]]), 0.1)
    c = v[f][..., :2].astype(float)
    area = signed_area2(c) / 2
    assert len(f) == 8 and (area > 0).all()  # two triangles per boundary edge, none culled
    assert area.sum() == pytest.approx(2.2 ** 2 - 2 ** 2)  # a band 0.1 wide all round (mitred corners)
    np.testing.assert_allclose(np.abs(v[4:, :2] - 1), 1.1, rtol=1e-6)  # the outer ring outside the square


def _ramp_map(tmp_path: Path) -> Path:
    """An fsaverage5 left map from 0 (posterior) to 1 (anterior)."""
    y = nib.freesurfer.read_geometry(str(FS5 / "surf" / "lh.white"))[0][:, 1]
    path = tmp_path / "lh.mgh"
    ramp = ((y - y.min()) / np.ptp(y)).astype(np.float32).reshape(-1, 1, 1)
    nib.MGHImage(ramp, np.eye(4)).to_filename(str(path))
    return path


def test_hide_and_cluster_borders_reach_a_maps_flat_sheet(tmp_path):
    lh = _ramp_map(tmp_path)

    def flat_left(**kw):
        (img,) = brainpainter.render(lh=lh, views="flat-left", cmap="RdBu_r", vmin=0, vmax=1, threshold=0.5,
                                     width=400, height=300, progress=False, **kw).images.values()
        return img[..., :3].astype(int)

    plain, borders = flat_left(), flat_left(outline_threshold=True)
    dark = (borders.max(axis=-1) < 40).sum()
    assert (plain.max(axis=-1) < 40).sum() < 5 and dark > 40  # the cluster's edge, as on the 3-D cortex
    hidden = flat_left(hide=["Left-superiorfrontal", "Left-precentral"])
    white = (hidden.min(axis=-1) > 250).sum() - (plain.min(axis=-1) > 250).sum()
    assert white > 0.03 * hidden.shape[0] * hidden.shape[1]  # the hidden regions' triangles are not drawn


def test_a_sheet_in_the_backgrounds_colour_keeps_its_grey_rim(tmp_path):
    lh = tmp_path / "lh.mgh"
    nib.MGHImage(np.zeros((10242, 1, 1), np.float32), np.eye(4)).to_filename(str(lh))
    (img,) = brainpainter.render(lh=lh, views="flat-left", cmap="Greys", vmin=0, vmax=1, width=400,
                                 height=300, progress=False).images.values()
    c = img[..., :3].astype(int)
    assert (c.min(axis=-1) > 250).mean() > 0.9  # the map's white on white ...
    rim = (np.abs(c - 204).max(axis=-1) < 30)  # ... inside NEUTRAL_GREY's rim
    rows, cols = np.nonzero(rim)
    assert rim.sum() > 300 and np.ptp(cols) > 0.6 * c.shape[1] and np.ptp(rows) > 0.4 * c.shape[0]
