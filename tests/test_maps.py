"""Per-vertex maps (issue 21): inputs, the fsaverage family, layers, and rendered pictures.

Unit tests write tiny inputs with nibabel's own writers; tests marked
``render`` draw maps on the default template and check pixels (the bars of
docs/maps.md); ``integration`` tests read ../shared/data.
"""

from __future__ import annotations

import colorsys
import itertools
import os
import subprocess
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

from brainpainter.color.scale import ScaleOptions, make_scale
from brainpainter.errors import BrainPainterError
from brainpainter.maps.inputs import pair_of, read_maps
from brainpainter.maps.layers import GYRUS_GREY, PLAIN_GREY, SULCUS_GREY, map_scale, vertex_colors
from brainpainter.maps.options import MapOptions
from brainpainter.maps.resolution import LEVELS, N_FSAVERAGE, _family, masks, to_fsaverage

#: ../shared/data beside the repository (as tests/conftest.py), or $BRAINPAINTER_SHARED_DATA.
SHARED = Path(os.environ.get("BRAINPAINTER_SHARED_DATA",
                            Path(__file__).resolve().parents[1].parent / "shared" / "data"))
FS = SHARED / "freesurfer" / "subjects"
N5 = 10242


# -- the fsaverage family ----------------------------------------------------------------------
def test_counts_and_parents():
    parents = _family()["parents"]
    assert parents.shape == (N_FSAVERAGE - 12, 2)
    for lo, hi in itertools.pairwise(LEVELS):  # parents are vertices of the level below
        assert parents[lo - 12:hi - 12].max() < lo


def test_coarse_vertices_kept_and_constant_stays_constant():
    v = np.random.default_rng(0).normal(size=N5)
    up = to_fsaverage(v)
    assert up.shape == (1, N_FSAVERAGE)
    np.testing.assert_allclose(up[0, :N5], v, rtol=1e-6)
    np.testing.assert_allclose(to_fsaverage(np.full(642, 3.0)), 3.0)
    lo, hi = float(v.min()), float(v.max())
    assert lo - 1e-5 <= up.min() and up.max() <= hi + 1e-5  # interpolation never overshoots


def test_linear_field_is_interpolated_linearly():
    """A linear function of the unit vectors: interpolation errs by the sphere's curvature only."""
    sphere = FS / "fsaverage" / "surf" / "lh.sphere"
    if not sphere.is_file():
        pytest.skip("shared data not found")
    xyz, _ = nib.freesurfer.read_geometry(str(sphere))
    u = xyz / np.linalg.norm(xyz, axis=1, keepdims=True)
    up = to_fsaverage(u[:N5, 0])[0]
    assert np.abs(up - u[:, 0]).max() < 0.01


def test_nan_and_categories():
    v = np.full(642, np.nan)
    v[0] = 7
    up = to_fsaverage(v)[0]
    assert np.isfinite(up).sum() > 1 and np.nanmax(up) == 7  # NaN parents do not spread NaN
    cat = to_fsaverage(np.arange(642) % 3, categorical=True)[0]
    assert set(np.unique(cat)) <= {0.0, 1.0, 2.0}


def test_count_of_no_fsaverage_is_one_line():
    with pytest.raises(BrainPainterError, match=r"1000 values per hemisphere.*mri_surf2surf") as e:
        to_fsaverage(np.zeros(1000))
    assert "\n" not in str(e.value)


def test_masks():
    m = masks("lh")
    assert {k: v.shape for k, v in m.items()} == {k: (N_FSAVERAGE,) for k in ("cortex", "sulc", "curv")}
    assert 0.8 < m["cortex"].mean() < 0.95


# -- inputs -------------------------------------------------------------------------------
def _values(n=N5, k=1):
    return np.random.default_rng(k).normal(size=(k, n)).astype(np.float32)


def test_formats_read_alike(tmp_path):
    v = _values(k=2)
    nib.freesurfer.write_morph_data(str(tmp_path / "lh.thickness"), v[0])
    nib.save(nib.MGHImage(v[0].reshape(-1, 1, 1), np.eye(4)), tmp_path / "lh.x.mgh")
    nib.save(nib.Nifti1Image(v.T.reshape(N5, 1, 1, 2), np.eye(4)), tmp_path / "lh.x.nii.gz")
    gii = nib.gifti.GiftiImage(darrays=[nib.gifti.GiftiDataArray(a) for a in v])
    nib.save(gii, tmp_path / "hemi-L_x.func.gii")
    np.save(tmp_path / "lh.x.npy", v)
    np.savetxt(tmp_path / "lh.x.txt", v[0])
    one = [read_maps(lh=tmp_path / n).values["lh"] for n in ("lh.thickness", "lh.x.mgh", "lh.x.txt")]
    two = [read_maps(lh=tmp_path / n).values["lh"]
           for n in ("lh.x.nii.gz", "hemi-L_x.func.gii", "lh.x.npy")]
    for a in one:
        np.testing.assert_allclose(a[0], v[0], rtol=1e-5)
    for a in two:
        assert a.shape == (2, N5)  # kept at its own resolution
        np.testing.assert_allclose(a, v, rtol=1e-5)
    m = read_maps(lh=tmp_path / "lh.x.npy")
    assert m.on_fsaverage("lh", 1).shape == (N_FSAVERAGE,)
    np.testing.assert_allclose(m.on_fsaverage("lh", 1)[:N5], v[1], rtol=1e-6)
    assert read_maps(lh=tmp_path / "lh.thickness").images == ("thickness",)
    assert read_maps(lh=tmp_path / "lh.x.npy").images == ("x-1", "x-2")


def test_folded_nifti(tmp_path):
    """FreeSurfer writes fsaverage overlays to NIfTI folded (27307 x 1 x 6), first axis fastest."""
    v = np.arange(N_FSAVERAGE, dtype=np.float32)
    nib.save(nib.Nifti1Image(v.reshape((27307, 1, 6), order="F"), np.eye(4)), tmp_path / "lh.f.nii.gz")
    np.testing.assert_array_equal(read_maps(lh=tmp_path / "lh.f.nii.gz").values["lh"][0], v)


def test_pair_found_from_one_name(tmp_path):
    for hemi in ("lh", "rh"):
        nib.freesurfer.write_morph_data(str(tmp_path / f"{hemi}.thickness"), _values()[0])
    found = pair_of(tmp_path / "lh.thickness")
    assert found == {"lh": tmp_path / "lh.thickness", "rh": tmp_path / "rh.thickness"}
    assert set(read_maps(tmp_path / "rh.thickness").values) == {"lh", "rh"}
    with pytest.raises(BrainPainterError, match="hemisphere"):
        pair_of(tmp_path / "thickness.mgh")


@pytest.mark.parametrize(("lh", "rh"), [("rh.thickness", "lh.thickness"), ("lh.thickness", "lh.thickness"),
                                        ("sub-01_hemi-R_thickness.shape.gii", None),
                                        (None, "thick_left.gii")])
def test_a_file_whose_name_says_the_other_hemisphere_is_refused(tmp_path, lh, rh):
    """``--lh rh.thickness``: the right hemisphere's values were drawn on the left without a word."""
    given = {k: tmp_path / name for k, name in (("lh", lh), ("rh", rh)) if name is not None}
    for path in given.values():
        nib.freesurfer.write_morph_data(str(path), _values()[0])
    with pytest.raises(BrainPainterError, match=r"its name says the (right|left) hemisphere, but "
                                                r"--(lh|rh) takes the (left|right) one's values; give it "
                                                r"with --(rh|lh)"):
        read_maps(**given)


def test_a_file_named_for_its_own_hemisphere_or_for_none_is_read(tmp_path):
    for name in ("lh.thickness", "rh.thickness", "thickness_both"):
        nib.freesurfer.write_morph_data(str(tmp_path / name), _values()[0])
    assert set(read_maps(lh=tmp_path / "lh.thickness", rh=tmp_path / "rh.thickness").values) == {"lh", "rh"}
    assert set(read_maps(rh=tmp_path / "thickness_both").values) == {"rh"}


def test_label_maps(tmp_path):
    labels = np.arange(N5) % 3
    ctab = np.array([[25, 5, 25, 0, 0], [255, 0, 0, 0, 1], [0, 0, 255, 0, 2]])
    nib.freesurfer.write_annot(str(tmp_path / "lh.a.annot"), labels, ctab, ["unknown", "red", "blue"])
    m = read_maps(lh=tmp_path / "lh.a.annot")
    assert m.categories == ("unknown", "red", "blue") and np.isnan(m.values["lh"][0, 0])  # unknown: none
    np.testing.assert_allclose(m.category_colors[1], (1, 0, 0))
    (tmp_path / "lh.b.label").write_text("#!ascii\n2\n5 0 0 0 0\n9 0 0 0 0\n")
    m = read_maps(lh=tmp_path / "lh.b.label")
    assert m.values["lh"][0, 5] == 1 and m.values["lh"][0, 9] == 1


def test_python_inputs_and_errors(tmp_path):
    v = _values()[0]
    assert set(read_maps({"left": v, "right": v}).values) == {"lh", "rh"}
    with pytest.raises(BrainPainterError, match="different numbers of images"):
        read_maps({"lh": _values(k=2), "rh": v})
    with pytest.raises(BrainPainterError, match="does not exist"):
        read_maps(lh=tmp_path / "lh.none.mgh")
    (tmp_path / "lh.bad.mgh").write_bytes(b"not an mgh")
    with pytest.raises(BrainPainterError, match="cannot read"):
        read_maps(lh=tmp_path / "lh.bad.mgh")
    nib.save(nib.Nifti1Image(np.zeros((10, 10, 10), np.float32), np.eye(4)), tmp_path / "lh.vol.nii.gz")
    with pytest.raises(BrainPainterError, match="--volume"):
        read_maps(lh=tmp_path / "lh.vol.nii.gz")
    with pytest.raises(BrainPainterError, match="threshold"):
        MapOptions(threshold=-1)


# -- layers ---------------------------------------------------------------------------------
def test_threshold_medial_wall_and_underlay():
    v = np.linspace(-2, 2, N_FSAVERAGE)
    m = read_maps({"lh": v})
    sv = {"lh": np.arange(N_FSAVERAGE), "rh": np.arange(N_FSAVERAGE)}
    scale = map_scale(ScaleOptions(), m)
    assert scale.center == 0 and scale.vmin == -2 and scale.name == "RdBu_r"  # signed: symmetric
    rgb = vertex_colors(m, 0, sv, scale, "sulc", threshold=1.0)
    mk = masks("lh")
    grey = np.ptp(rgb["lh"], axis=1) < 1e-6
    assert grey[(np.abs(v) < 1.0) | ~mk["cortex"]].all()
    assert not grey[(np.abs(v) > 1.1) & mk["cortex"]].any()
    assert np.allclose(rgb["rh"][~masks("rh")["sulc"], 0], GYRUS_GREY)  # no rh map: the underlay
    assert np.allclose(rgb["rh"][masks("rh")["sulc"], 0], SULCUS_GREY)
    flat = vertex_colors(m, 0, sv, scale, "none")["rh"]
    assert np.allclose(flat, PLAIN_GREY)
    viridis = make_scale(cmap="viridis", vmin=0, vmax=1)
    half = vertex_colors(read_maps({"lh": np.stack([v * 0, v * 0 + 1])}), 0.5, sv, viridis, "none")["lh"]
    np.testing.assert_allclose(half[mk["cortex"]][0], viridis([0.5])[0, :3], atol=1e-6)  # a movie's blend


# -- pictures -------------------------------------------------------------------------------
def _saturation(px):
    return np.array([colorsys.rgb_to_hsv(*(p / 255.0))[1] for p in px])


def _brain(img):
    return (img[..., 3] > 0) & ~np.all(img[..., :3] == 255, axis=-1)


@pytest.mark.render
@pytest.mark.integration
def test_dk_map_matches_region_render():
    """Bar: every vertex of a DK region carries its value -> within 10 RGB units on >= 97 % of pixels
    (flat shading: a map's cortex is lit to read true, not with the regions' relief)."""
    from brainpainter.layers.vertex_map import VertexColors
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    label = FS / "fsaverage" / "label"
    if not label.is_dir():
        pytest.skip("shared data not found")
    rng = np.random.default_rng(0)
    values, maps = {}, {}
    for hemi, prefix in (("lh", "Left-"), ("rh", "Right-")):
        lab, _, names = nib.freesurfer.read_annot(str(label / f"{hemi}.aparc.annot"))
        v = np.full(len(lab), np.nan)
        for i, name in enumerate(n.decode() for n in names):
            if name not in ("unknown", "corpuscallosum"):
                values[prefix + name] = v[lab == i] = float(rng.uniform())
        maps[hemi] = v
    scale = make_scale(cmap="viridis", vmin=0, vmax=1)
    settings, view = RenderSettings(width=1200, height=900, shading="flat"), get_view("lateral-left")
    with Painter("dk", settings=settings) as p:
        region = p.paint(values, view, scale)
    with Painter("dk", settings=settings, coloring="vertices") as p:
        m = read_maps(maps)
        colors = vertex_colors(m, 0, p.scene.geometry.source_vertex, scale, "none")
        vertex = p.paint_colors(VertexColors({}, colors), view)
    brain = _brain(region) & _brain(vertex)
    diff = np.abs(region[..., :3].astype(int) - vertex[..., :3].astype(int)).max(-1)
    assert brain.sum() > 0.4 * 1200 * 900
    assert (diff[brain] <= 10).mean() >= 0.97


@pytest.mark.render
def test_a_constant_map_reads_true_under_the_default_lighting():
    """Bar (issue 33, item 12): 2.75 on a 1.5-4 viridis scale, each map pixel read back as the nearest
    colour of the colour map in CIELAB: >= 90 % within +-5 % of the range, while the folds still show
    (L* p90 - p10 >= 8); a region render of the same colour keeps its relief."""
    from scipy.ndimage import binary_erosion

    from brainpainter.layers.vertex_map import VertexColors
    from brainpainter.media.imagemetrics import lightness, read_values
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import get_view

    scale = make_scale(cmap="viridis", vmin=1.5, vmax=4.0)
    maps = read_maps({"lh": np.full(N5, 2.75), "rh": np.full(N5, 2.75)})
    views = [get_view(v) for v in ("lateral-left", "medial-left")]
    with Painter("dk", settings=RenderSettings(width=400, height=300), coloring="vertices") as p:
        colors = vertex_colors(maps, 0, p.scene.geometry.source_vertex, scale, "none")
        images = [p.paint_colors(VertexColors({}, colors), view)[..., :3] for view in views]
    # the map's pixels: coloured (not the grey medial wall, not the white background), off the edges
    shown = np.concatenate([img[binary_erosion(np.ptp(img.astype(int), axis=-1) > 40, iterations=2)]
                            for img in images])
    assert len(shown) > 0.2 * 2 * 400 * 300                      # the map, not the medial wall
    within = float(np.mean(np.abs(read_values(shown, "viridis", 1.5, 4.0) - 2.75) <= 0.05 * 2.5))
    p10, p90 = np.percentile(lightness(shown), [10, 90])
    assert within >= 0.90 and p90 - p10 >= 8, (within, p90 - p10)
    with Painter("dk", settings=RenderSettings(width=400, height=300)) as p:   # regions: relief as before
        region = p.paint({key: 2.75 for key in p.atlas.keys}, views[0], scale)
    p10, p90 = np.percentile(lightness(region[..., :3][_brain(region)]), [10, 90])
    assert p90 - p10 >= 25, p90 - p10


@pytest.mark.render
@pytest.mark.integration
def test_fsaverage5_map_threshold_and_single_vertex(tmp_path):
    """Bars: fsaverage5 renders without options; below --threshold is grey; one vertex is visible."""
    import brainpainter

    fsaverage5 = FS / "fsaverage5"
    if not fsaverage5.is_dir():
        pytest.skip("shared data not found")
    sulc = nib.freesurfer.read_morph_data(str(fsaverage5 / "surf" / "lh.sulc"))
    r = brainpainter.render({"lh": sulc}, views="lateral-left", width=400, height=300, progress=False)
    plain = next(iter(r.images.values()))
    r = brainpainter.render({"lh": sulc}, views="lateral-left", width=400, height=300, progress=False,
                            threshold=float(np.abs(sulc).max()) + 1)
    img = next(iter(r.images.values()))
    assert (_saturation(img[_brain(img)][::7, :3]) < 0.1).all()  # all below threshold: underlay
    brain = _brain(img) & _brain(plain)
    changed = np.abs(plain[..., :3].astype(int) - img[..., :3].astype(int)).max(-1)[brain] > 10
    assert changed.mean() > 0.5  # without a threshold the map colours most of the cortex
    one = np.zeros(N5)
    lateral = np.flatnonzero(nib.freesurfer.read_geometry(str(fsaverage5 / "surf" / "lh.inflated"))[0][:, 0]
                             < -40)
    one[lateral[len(lateral) // 2]] = 1.0
    r = brainpainter.render({"lh": one}, views="lateral-left", width=800, height=600, progress=False,
                            threshold=0.05, cmap="autumn", vmin=0, vmax=1, surface="inflated")
    img = next(iter(r.images.values()))
    spot = _brain(img) & (_saturation(img[..., :3].reshape(-1, 3)).reshape(img.shape[:2]) > 0.3)
    assert 3 <= spot.sum() < 0.01 * _brain(img).sum()


@pytest.mark.integration
def test_cli_count_of_no_fsaverage_exits_2(tmp_path):
    np.save(tmp_path / "lh.x.npy", np.zeros(1000))
    out = subprocess.run([sys.executable, "-m", "brainpainter", "render", "--lh", str(tmp_path / "lh.x.npy"),
                          "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and "1000" in out.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.render
def test_map_series_with_jobs_is_identical_to_serial(tmp_path):
    """A map run goes through the one paint loop: --jobs 2 writes the serial run's bytes."""
    import brainpainter

    v = np.random.default_rng(3).normal(size=(3, N5))
    kw = {"width": 160, "height": 120, "views": "lateral-left,medial-left", "progress": False}
    a = brainpainter.render({"lh": v}, out=tmp_path / "a", **kw)
    b = brainpainter.render({"lh": v}, out=tmp_path / "b", jobs=2, **kw)
    assert b.workers["backend"] == "LocalRunner" and len(a.files) == 6
    assert all(x.read_bytes() == y.read_bytes() for x, y in zip(a.files, b.files, strict=True))


def test_colorbar_greys_out_the_threshold_band():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from brainpainter.media.colorbar import THRESHOLD_GREY, draw_colorbar

    scale = map_scale(ScaleOptions(vmin=-3, vmax=3), read_maps({"lh": np.linspace(-3, 3, N5)}), threshold=1.0)
    assert scale.threshold == 1.0 and scale.to_dict()["threshold"] == 1.0
    fig, ax = plt.subplots(figsize=(4, 1), dpi=100)
    draw_colorbar(ax, scale, orientation="horizontal")
    ax.set_position((0, 0, 1, 1))
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3]
    middle, side = img[50, 200], img[50, 30]
    np.testing.assert_allclose(middle / 255, THRESHOLD_GREY, atol=0.02)  # |v| < 1: grey
    assert np.ptp(side) > 50  # outside the band: the colour map
    plt.close(fig)


@pytest.mark.render
@pytest.mark.integration
def test_figure_and_plot_of_a_map(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import brainpainter

    v = {"lh": np.random.default_rng(4).normal(size=(2, N5)), "rh": np.ones((2, N5))}
    f = brainpainter.figure(v, out=tmp_path / "f.png", width=160, height=120,
                            views="lateral-left,lateral-right", threshold=0.5, progress=False)
    assert f.path.is_file() and len(f.images) == 4
    assert f.scale.threshold == 0.5
    fig, ax = plt.subplots()
    p = brainpainter.plot(v, "lateral-right", ax=ax, width=160, height=120, vmin=-2, vmax=2, cmap="RdBu_r")
    brain = _brain(p.image)
    rgb = p.image[brain][:, :3].astype(float).mean(axis=0)
    assert rgb[0] > rgb[2] + 30  # rh is 1 everywhere: reds of RdBu_r
    plt.close(fig)


@pytest.mark.render
def test_movie_through_a_gifti_series(tmp_path):
    """A GIfTI series is a movie's key frames; in-between frames blend the values per vertex."""
    import brainpainter
    from brainpainter.rendering.maprun import prepare_map_run
    from brainpainter.rendering.options import Options

    v = np.linspace(-1, 1, N5).astype(np.float32)
    gii = nib.gifti.GiftiImage(darrays=[nib.gifti.GiftiDataArray(a) for a in (v, -v)])
    nib.save(gii, tmp_path / "lh.series.func.gii")
    run = prepare_map_run(None, None, Options.of({"lh": tmp_path / "lh.series.func.gii"}))
    mid = run.blend(0, 1, 0.5).vertices["lh"]
    cortex = masks("lh")["cortex"][run.base.source_vertex["lh"]]
    assert np.abs(mid[cortex] - run.scale([0.0])[0, :3]).max() < 1e-5  # v and -v blend to 0
    r = brainpainter.movie(None, lh=tmp_path / "lh.series.func.gii", out=tmp_path / "m.gif", width=160,
                           height=120, views="lateral-left", frames_per_step=4, progress=False)
    assert r.n_frames >= 5 and r.keys == ["series-1", "series-2"]


@pytest.mark.integration
def test_export_glb_has_per_vertex_colours(tmp_path):
    import trimesh

    import brainpainter

    v = np.linspace(-1, 1, N5)
    path = brainpainter.export({"lh": v}, tmp_path / "m.glb", threshold=0.2)
    scene = trimesh.load(path)
    cortex = scene.geometry["Left-cortex"]
    assert cortex.visual.kind == "vertex"
    assert len(np.unique(cortex.visual.vertex_colors[:, :3], axis=0)) > 100  # a map, not one colour
    html = brainpainter.export({"lh": v}, tmp_path / "m.html").read_text()
    assert "vertexColors: m.vertexColors" in html


def test_border_vertices_one_side():
    from brainpainter.maps.outlines import border_vertices, mesh_edges

    faces = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    edges = mesh_edges(faces)
    assert len(edges) == 7
    marked = border_vertices(np.array([0, 0, 1, 1, 1]), edges)
    assert marked.tolist() == [True, True, False, False, False]  # the smaller label's side only


@pytest.mark.render
@pytest.mark.integration
def test_outline_draws_dark_lines_over_a_map():
    import brainpainter

    v = np.ones(N5)
    kw = {"views": "lateral-left", "width": 400, "height": 300, "progress": False, "vmin": 0, "vmax": 2,
          "cmap": "viridis", "shading": "flat"}
    plain = next(iter(brainpainter.render({"lh": v}, **kw).images.values()))
    lined = next(iter(brainpainter.render({"lh": v}, outline="dk", **kw).images.values()))
    brain = _brain(plain) & _brain(lined)
    darker = (plain[..., :3].astype(int) - lined[..., :3].astype(int)).sum(-1) > 60
    assert 0.01 < darker[brain].mean() < 0.15  # thin lines, not areas
    brighter = ((lined[..., :3].astype(int) - plain[..., :3].astype(int)).max(-1) > 10)[brain]
    assert brighter.sum() <= 5  # lines only darken (but for a pixel or two of the silhouette's edge)


@pytest.mark.render
@pytest.mark.integration
def test_region_render_with_outline():
    import brainpainter

    table = {"Left-precentral": 1.0, "Left-postcentral": 2.0, "Left-superiorfrontal": 3.0}
    kw = {"views": "lateral-left", "progress": False, "shading": "flat"}
    darker = {}
    for width, height in ((400, 300), (1200, 900)):
        plain = next(iter(brainpainter.render(table, "dk", width=width, height=height, **kw).images.values()))
        lined = next(iter(brainpainter.render(table, "dk", outline="dk", width=width, height=height,
                                              **kw).images.values()))
        brain = _brain(plain) & _brain(lined)
        dark = (plain[..., :3].astype(int) - lined[..., :3].astype(int)).sum(-1) > 60
        darker[width] = dark[brain].mean()
        assert 0.005 < darker[width] < 0.15  # thin lines, not areas
    # lines of constant pixel width: 3x the image, 3x the line length but the same width, so the
    # share of the brain's pixels they cover falls about 3-fold (a border coloured into the mesh keeps it)
    assert 2.2 < darker[400] / darker[1200] < 3.8, darker
    white = next(iter(brainpainter.render(table, "dk", outline="dk", outline_color="white", outline_width=3,
                                          width=400, height=300, **kw).images.values()))
    assert (np.all(white[..., :3] == 255, axis=-1) & (white[..., 3] == 255)).sum() > 400
    with pytest.raises(BrainPainterError, match="outlines its own atlas"):
        brainpainter.render(table, "dk", outline="destrieux", **kw)


def test_map_run_on_a_dask_cluster_is_identical_to_serial(tmp_path, tiny):
    """The per-vertex scene rebuilds on Dask workers (PainterSpec carries coloring="vertices")."""
    distributed = pytest.importorskip("distributed")
    import brainpainter
    from brainpainter.testing import stand_in

    v = {"lh": np.random.default_rng(5).normal(size=(3, N5))}
    kw = {"width": 64, "height": 48, "views": "lateral-left,dorsal", "template": str(tiny), "progress": False}
    with stand_in() as renderer, distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
            dashboard_address="127.0.0.1:0") as c, distributed.Client(c, set_as_default=False) as client:
        a = brainpainter.render(v, out=tmp_path / "a", renderer=renderer, **kw)
        b = brainpainter.render(v, out=tmp_path / "b", renderer=renderer, client=client, **kw)
    assert b.workers["backend"] == "DaskRunner" and len(a.files) == 6
    assert all(x.read_bytes() == y.read_bytes() for x, y in zip(a.files, b.files, strict=True))
    from PIL import Image

    first = np.asarray(Image.open(a.files[0]))
    assert len(np.unique(first.reshape(-1, first.shape[-1]), axis=0)) > 5  # the stand-in drew vertex colours


def test_label_gifti(tmp_path):
    labels = (np.arange(N5) % 2 + 1).astype(np.int32)
    table = nib.gifti.GiftiLabelTable()
    for key, name, rgb in ((0, "???", (0, 0, 0)), (1, "A", (1, 0, 0)), (2, "B", (0, 0, 1))):
        lab = nib.gifti.GiftiLabel(key, *rgb, 1.0)
        lab.label = name
        table.labels.append(lab)
    img = nib.gifti.GiftiImage(labeltable=table, darrays=[nib.gifti.GiftiDataArray(
        labels, intent="NIFTI_INTENT_LABEL", datatype="NIFTI_TYPE_INT32")])
    nib.save(img, tmp_path / "lh.x.label.gii")
    m = read_maps(lh=tmp_path / "lh.x.label.gii")
    assert m.categories == ("???", "A", "B")
    assert m.values["lh"][0, 0] == 1 and m.values["lh"][0, 1] == 2  # vertex 0: key 1, "A"; vertex 1: "B"
    np.testing.assert_allclose(m.category_colors[1], (1, 0, 0))


def test_map_files_are_recognised_by_name():
    from brainpainter.maps.inputs import is_map_input

    for name in ("lh.thickness", "rh.sulc", "x.mgh", "hemi-L_x.func.gii", "lh.x.nii.gz", "lh.aparc.annot"):
        assert is_map_input(name), name
    for name in ("table.csv", "lh.stats.tsv", "regions.xlsx", "lh.values.txt", "lh.aparc.thickness.table"):
        assert not is_map_input(name), name
    assert is_map_input({"lh": np.zeros(3)}) and not is_map_input({"Left-insula": 1.0})


def test_mesh_edges_are_the_unique_sorted_edges():
    from brainpainter.maps.outlines import mesh_edges

    faces = np.random.default_rng(0).integers(0, 50, size=(200, 3))
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e.sort(axis=1)
    assert np.array_equal(mesh_edges(faces), np.unique(e, axis=0))
    assert mesh_edges(np.zeros((0, 3), int)).shape == (0, 2)


@pytest.mark.render
def test_a_map_over_region_colours_mixes_both_by_map_alpha(tmp_path):
    """Bar (issue 35): ``render table.csv --lh map --map-alpha 0.5``: the map's pixels are neither the
    regions' colour nor the map's alone, and the regions show where the map is thresholded away."""
    import json

    from click.testing import CliRunner
    from PIL import Image

    from brainpainter.cli.main import cli

    lateral = ("superiorfrontal", "caudalmiddlefrontal", "rostralmiddlefrontal", "precentral",
               "postcentral", "supramarginal", "superiorparietal", "inferiorparietal", "lateraloccipital",
               "superiortemporal", "middletemporal", "inferiortemporal", "parsopercularis",
               "parstriangularis", "insula")
    table = tmp_path / "regions.csv"
    table.write_text("Image-name-unique," + ",".join(f"lh_{r}" for r in lateral) + "\nctrl,"
                     + ",".join("1" for _ in lateral) + "\n")
    values = np.where(np.arange(N5) < N5 // 2, 1.0, 0.0).astype(np.float32)  # a patch of fsaverage5
    nib.MGHImage(values.reshape(-1, 1, 1), np.eye(4)).to_filename(tmp_path / "patch.mgh")
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [
        "render", str(table), "--lh", str(tmp_path / "patch.mgh"), "--threshold", "0.5",
        "--gradient", "blue,red", "--vmin", "0", "--vmax", "1", "--map-gradient", "white,blue",
        "--map-vmin", "0", "--map-vmax", "1", "--map-alpha", "0.5", "--views", "lateral-left",
        "--size", "240x180", "--shading", "flat", "--quality", "fast", "--out", str(out)])
    assert result.exit_code == 0, result.output
    img = np.asarray(Image.open(out / "ctrl_lateral-left.png").convert("RGB")).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 200) & (g < 40) & (b < 40)  # a region alone
    blue = (b > 200) & (r < 40) & (g < 40)  # the map alone
    mixed = (np.abs(r - 128) < 20) & (g < 40) & (np.abs(b - 128) < 20)  # half of each
    assert red.sum() > 500 and mixed.sum() > 500, (red.sum(), mixed.sum())
    assert blue.sum() == 0
    layers = json.loads((out / "manifest.json").read_text())["settings"]["layers"]
    assert [(la["kind"], la["opacity"]) for la in layers] == [("regions", 1.0), ("map", 0.5)]
    assert "input: wide" in result.output and "15/95 regions with values" in result.output  # the table's line


def test_sulcal_depth_greys_darken_with_depth_and_spread_with_contrast():
    from brainpainter.maps.layers import depth_greys

    depth = np.linspace(-2.0, 2.0, 101)  # FreeSurfer's sulc: positive in sulci
    grey = depth_greys(depth)
    assert np.all(np.diff(grey) <= 0) and len(np.unique(grey)) > 50  # deeper: darker, many greys
    assert grey.max() == pytest.approx(GYRUS_GREY) and grey.min() == pytest.approx(SULCUS_GREY)
    assert np.ptp(depth_greys(depth, 0.0)) == 0  # contrast 0: one grey
    assert np.ptp(depth_greys(depth, 2.0)) == pytest.approx(2 * (GYRUS_GREY - SULCUS_GREY))
    with pytest.raises(BrainPainterError, match="--underlay-contrast must be a number from 0"):
        MapOptions(underlay_contrast=-1)


@pytest.mark.render
def test_the_sulcal_underlay_is_many_greys_not_two(tmp_path):
    """Bar (issue 35): --underlay sulc, --shading flat, the map thresholded away: at most half of the
    underlay's pixels are its two commonest greys (two tones held nearly all of them)."""
    from brainpainter import render

    result = render(lh=np.zeros(N5), rh=np.zeros(N5), threshold=1.0, underlay="sulc", shading="flat",
                    quality="fast", views="lateral-left", width=240, height=180, progress=False)
    img = next(iter(result.images.values()))
    brain = _brain(img)
    greys, counts = np.unique(img[brain][:, :3], axis=0, return_counts=True)
    assert np.ptp(greys, axis=1).max() == 0  # the underlay only: greys
    assert brain.sum() > 10_000 and np.sort(counts)[-2:].sum() <= 0.5 * brain.sum()


def test_iso_lines_of_a_field_are_closed_and_on_the_level():
    import trimesh

    from brainpainter.atlas.mesh import vertex_normals
    from brainpainter.rendering.borders import iso_lines

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=50.0)
    v, f = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    seg = iso_lines(v, f, v[:, 2], 3.3, vertex_normals(v, f), lift=0.0)  # the plane z = 3.3 (no vertex on it)
    assert len(seg) > 20 and np.abs(seg[..., 2] - 3.3).max() < 1e-6  # on the level, interpolated
    ends = np.round(seg.reshape(-1, 3), 3)
    _, counts = np.unique(ends, axis=0, return_counts=True)
    assert (counts == 2).all()  # a closed line: every end joins the next segment
    assert len(iso_lines(v, f, np.full(len(v), np.nan), 0.0, vertex_normals(v, f))) == 0
    with pytest.raises(BrainPainterError, match="--contour-levels must be"):
        MapOptions(contour_levels="0.05,x")


@pytest.mark.render
def test_a_contour_is_a_line_of_constant_pixel_width(tmp_path):
    """Bar (issue 35): ``--contour`` of a mask draws its edge as a line of constant pixel width:
    twice the image size, about twice the line's pixels (as the outline conformance check)."""
    from brainpainter import render
    from brainpainter.atlas.template import load_template
    from brainpainter.maps.resolution import map_mesh

    mesh = map_mesh(load_template("fsaverage"), "dk", "lh")
    mask = np.zeros(N_FSAVERAGE, np.float32)
    mask[np.asarray(mesh.source_vertex)[mesh.vertices["pial"][:, 1] > -20]] = 1.0  # anterior of y = -20
    for hemi, values in (("lh", mask), ("rh", np.zeros(N_FSAVERAGE, np.float32))):
        nib.MGHImage(values.reshape(-1, 1, 1), np.eye(4)).to_filename(tmp_path / f"{hemi}.mask.mgh")
    contour = f"{tmp_path / 'lh.mask.mgh'},{tmp_path / 'rh.mask.mgh'}"
    dark = []
    for size in (240, 480):
        result = render(lh=np.zeros(N5), rh=np.zeros(N5), threshold=1.0, contour=contour, shading="flat",
                        outline_color="black", outline_width=2, quality="fast", views="lateral-left",
                        width=size, height=size * 3 // 4, progress=False)
        img = next(iter(result.images.values()))
        dark.append(int((img[..., :3].astype(int).max(axis=-1) < 40).sum()))  # the underlay is >= 0.52
    # measured 2.6x (the mask's edge zigzags along mesh edges, resolved more at 480 px); the same edge
    # painted into the mesh (--outline-threshold) gives 3.3x; the conformance check allows 1.3-3.0
    assert dark[0] > 100 and 1.5 <= dark[1] / dark[0] <= 3.0, dark
    from brainpainter.rendering.painter_spec import PainterSpec
    from brainpainter.rendering.run import prepare_run

    run = prepare_run(None, lh=np.zeros(N5), contour=contour, contour_levels="0.5,0.9")
    built = PainterSpec.of(run.painter()).build().scene.contours  # what --jobs and Dask workers draw
    assert built is not None and built.levels == (0.5, 0.9) and np.array_equal(built.values["lh"], mask)
    assert prepare_run({"lh_insula": [1.0]}, contour=contour).contours is not None  # over regions too


@pytest.mark.render
def test_layers_with_jobs_are_identical_to_serial(tmp_path):
    """Regions, a map over them and a contour (issue 35) through --jobs 2: the serial run's bytes."""
    import brainpainter

    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,lh_insula,lh_precentral\na,1,2\nb,2,1\n")
    mask = (np.arange(N5) % 7 == 0).astype(np.float32)
    kw = {"width": 160, "height": 120, "views": "lateral-left", "progress": False, "lh": np.zeros((2, N5)),
          "threshold": 0.5, "map_alpha": 0.5, "contour": {"lh": mask}, "cmap": "viridis"}
    a = brainpainter.render(table, out=tmp_path / "a", **kw)
    b = brainpainter.render(table, out=tmp_path / "b", jobs=2, **kw)
    assert b.workers["backend"] == "LocalRunner" and len(a.files) == 2
    assert all(x.read_bytes() == y.read_bytes() for x, y in zip(a.files, b.files, strict=True))
