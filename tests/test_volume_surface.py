"""Blobs as surfaces and cutaways (issue 45, items 1 and 2): ``--volume-surface FILE --threshold T`` draws a
volume's clusters as lit isosurfaces; ``--clip x<0`` cuts the cortex and glass open."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

import brainpainter
from brainpainter.errors import BrainPainterError
from brainpainter.maps.clusters import find_blobs
from brainpainter.rendering.clip import ClipPlane, parse_clips, removed
from brainpainter.testing.pixels import near

CENTRE, RADIUS = (40.0, -20.0, 50.0), 8.0
SPHERE_MM3 = 4 / 3 * np.pi * RADIUS**3


def _mni_grid() -> tuple[np.ndarray, tuple[int, ...]]:
    from nilearn import datasets

    template = datasets.load_mni152_template(resolution=2)
    return np.asarray(template.affine), tuple(template.shape)


def _sphere(path: Path, centre: tuple[float, ...] = CENTRE, value: float = 5.0) -> Path:
    affine, shape = _mni_grid()
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    data = np.where(np.linalg.norm(xyz - np.asarray(centre), axis=-1) <= RADIUS, value, 0.0)
    nib.save(nib.Nifti1Image(data.astype(np.float32), affine), path)
    return path


@pytest.fixture(scope="module")
def sphere(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _sphere(tmp_path_factory.mktemp("blob") / "sphere.nii.gz")


def test_the_sphere_s_cluster_is_where_and_as_large_as_the_sphere(sphere):
    blobs = find_blobs(sphere, 2.3)
    (cluster,) = blobs.clusters
    assert np.linalg.norm(np.subtract(cluster.centre, CENTRE)) < 2.0
    assert abs(cluster.volume_mm3 / SPHERE_MM3 - 1) < 0.10
    assert cluster.sign == 1 and cluster.peak == 5.0 and np.allclose(cluster.peak_mni, CENTRE)
    assert np.allclose(blobs.values, 5.0, atol=0.05)  # the value inside, not the threshold on the surface


def test_clusters_of_both_signs_and_the_minimum_size(tmp_path):
    path = _sphere(tmp_path / "neg.nii.gz", (-30.0, 10.0, 20.0), -4.0)
    (cluster,) = find_blobs(path, 2.3).clusters
    assert cluster.sign == -1 and cluster.peak == -4.0 and find_blobs(path, 2.3).values.max() < -2.3
    with pytest.raises(BrainPainterError, match="min-cluster-mm3 5000"):
        find_blobs(path, 2.3, 5000.0)


def _saturated(img: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """Pixels of hue near `rgb`'s (the blob's colour, lit and seen through glass), shape (h, w)."""
    import colorsys

    px = img[..., :3].astype(float) / 255
    chroma = px.max(-1) - px.min(-1)
    hue = np.vectorize(lambda r, g, b: colorsys.rgb_to_hsv(r, g, b)[0])(px[..., 0], px[..., 1], px[..., 2])
    target = colorsys.rgb_to_hsv(*rgb)[0]
    diff = np.minimum(abs(hue - target), 1 - abs(hue - target))
    return np.asarray((chroma > 0.2) & (diff < 0.06))


def test_the_sphere_is_drawn_in_the_right_half_of_a_dorsal_view(sphere):
    result = brainpainter.render(None, volume_surface=str(sphere), threshold=2.3, views="dorsal",
                                 width=400, height=300, progress=False)
    (cluster,) = result.manifest["blobs"]["clusters"]
    assert np.linalg.norm(np.subtract(cluster["centre_mni"], CENTRE)) < 2.0
    assert abs(cluster["volume_mm3"] / SPHERE_MM3 - 1) < 0.10
    (layer,) = result.layers
    assert layer.kind == "blobs"
    img = result.images[("sphere", "dorsal")]
    blob = _saturated(img, layer.scale(np.array([5.0]))[0][:3])
    cols = np.nonzero(blob)[1]
    assert blob.sum() > 100 and cols.min() > img.shape[1] / 2  # right of the midline, anterior up


SUBCORTICAL = {"Left-Thalamus": 3.0, "Left-Putamen": 3.0, "Left-Caudate": 3.0, "Left-Hippocampus": 3.0,
               "Left-Pallidum": 3.0, "Right-Thalamus": 0.0, "Left-insula": 0.0}
RED = (1.0, 0.0, 0.0)  # value 3 on the default gradient


@pytest.mark.parametrize("clip, seen", [(None, False), ("x<0", True)])
def test_a_cut_shows_the_left_structures_in_a_lateral_left_view(clip, seen):
    result = brainpainter.render(SUBCORTICAL, atlas="dk", views="lateral-left", clip=clip, shading="flat",
                                 width=320, height=240, progress=False)
    img = result.images[("1", "lateral-left")]
    red = int(near(img, RED, 2).sum())
    assert (red > 200) if seen else red == 0, red
    if seen:
        assert result.manifest["settings"]["views"][0]["clip"] == ["x<0"]


def test_a_cutaway_preset_caps_the_cut_cortex():
    result = brainpainter.render({"Left-insula": 3.0, "Right-insula": 1.0}, atlas="dk",
                                 views="cutaway-dorsal", shading="flat", width=320, height=240,
                                 progress=False)
    img = result.images[("1", "cutaway-dorsal")].astype(int)
    grey = (np.ptp(img[..., :3], axis=-1) <= 2) & (img[..., 0] > 40) & (img[..., 0] < 200)
    assert grey.sum() > 2000  # the cut face in the cap grey (lit as the plane), over both hemispheres


def test_clip_planes_parse_and_remove_a_wedge():
    planes = parse_clips(["x<0", "z > 20"])
    assert planes == (ClipPlane("x", "<", 0.0), ClipPlane("z", ">", 20.0))
    points = np.array([[-10.0, 0, 30], [-10.0, 0, 10], [10.0, 0, 30]])
    assert removed(points, planes).tolist() == [True, False, False]
    with pytest.raises(BrainPainterError, match="is not a plane"):
        parse_clips("left")


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "brainpainter", "render", *args], capture_output=True,
                          text=True, timeout=300)


def test_bad_input_is_one_line_exit_2_and_nothing_written(sphere, tmp_path):
    affine, _ = _mni_grid()
    far = tmp_path / "far.nii.gz"  # a volume 500 mm away from MNI152's brain
    nib.save(nib.Nifti1Image(np.asarray(nib.load(sphere).dataobj), affine + np.diag([0, 0, 0, 0]) +
                             np.array([[0, 0, 0, 500]] * 3 + [[0, 0, 0, 0]])), far)
    cases = {"not an MNI152 volume": [f"--volume-surface={far}", "--threshold=2.3"],
             "at or above the largest": [f"--volume-surface={sphere}", "--threshold=7"],
             "min-cluster-mm3": [f"--volume-surface={sphere}", "--threshold=2.3", "--min-cluster-mm3=9000"],
             "removes all the cortex and glass": [f"--volume-surface={sphere}", "--threshold=2.3",
                                                  "--clip=x<200", "--views=dorsal"]}
    for words, args in cases.items():
        out = tmp_path / words.replace(" ", "_")
        run = _cli(*args, "--out", str(out), "--size", "80x60")
        lines = run.stderr.strip().splitlines()
        assert run.returncode == 2 and len(lines) == 1 and words in lines[0], (words, run.stderr)
        assert not out.exists() or not any(out.iterdir())


def test_the_manifest_lists_the_clusters(sphere, tmp_path):
    out = tmp_path / "out"
    run = _cli(f"--volume-surface={sphere}", "--threshold=2.3", "--views=dorsal", "--size=80x60", "--out",
               str(out))
    assert run.returncode == 0, run.stderr
    blobs = json.loads((out / "manifest.json").read_text())["blobs"]
    assert blobs["threshold"] == 2.3 and blobs["clusters"][0]["sign"] == 1


def test_the_conformance_suite_holds_a_renderer_to_its_clip_planes():
    from dataclasses import replace

    from brainpainter.testing import check_renderer
    from brainpainter_blender.renderer import BlenderRenderer

    report = check_renderer("blender", checks=("clip",))
    assert report["clip_pixels"]["left_cortex_after"] == 0 and report["clip_inside_px"] < 2

    class _Uncut(BlenderRenderer):  # draws every view whole: fails
        def render(self, palette, view):
            return super().render(palette, replace(view, clip=()))

    with pytest.raises(AssertionError, match="clip:"):
        check_renderer(_Uncut, checks=("clip",))


def test_the_stand_in_draws_cut_faces_in_the_cap_colour_and_the_structures_inside(tiny):
    from brainpainter.atlas.template import load_template
    from brainpainter.rendering.clip import CAP_COLOR
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import View
    from brainpainter.testing.stand_in import StandInRenderer

    scene = Scene(load_template(tiny), "dk", settings=RenderSettings(width=400, height=20))
    colors = {"Left-insula": (1.0, 0.0, 0.0), "Left-Hippocampus": (0.0, 0.0, 1.0)}
    whole = View("v", "cortex", ("lh",), 180.0, 0.0)
    cut = View("v", "cortex", ("lh",), 180.0, 0.0, clip=(ClipPlane("x", "<", -60.0),))
    a, b = (StandInRenderer(scene).render(colors, v) for v in (whole, cut))
    assert not near(a, CAP_COLOR, 1).any() and near(b, CAP_COLOR, 1).sum() > 1000
    assert not near(a, (0, 0, 1), 1).any() and near(b, (0, 0, 1), 1).any()


def test_cycles_refuses_a_cut_view_in_one_line(tiny):
    from brainpainter.atlas.template import load_template
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import get_view
    from brainpainter_blender.renderer import BlenderRenderer

    scene = Scene(load_template(tiny), "dk", settings=RenderSettings(width=40, height=30, quality="high"))
    renderer = BlenderRenderer(scene)
    try:
        with pytest.raises(BrainPainterError, match=r"--clip.*not Cycles"):
            renderer.render(Palette({}, scene.geometry), get_view("cutaway-left"))
    finally:
        renderer.close()


def test_a_movie_sweeps_a_cut_through_the_brain(tmp_path):
    from PIL import Image, ImageSequence

    out = tmp_path / "sweep.gif"
    brainpainter.movie(SUBCORTICAL, atlas="dk", out=out, views="lateral-left", clip_sweep="x", shading="flat",
                       frames_per_step=4, width=320, height=240, progress=False)
    with Image.open(out) as gif:
        frames = [np.asarray(f.convert("RGB"))[:240] for f in ImageSequence.Iterator(gif)]
    red = [int(((f[..., 0] > 200) & (f[..., 1] < 60) & (f[..., 2] < 60)).sum()) for f in frames]
    assert len(frames) == 5 and red[0] == 0 and red[-1] > 200, red  # the cut passes the left structures
    with pytest.raises(BrainPainterError, match="clip-sweep 'w'"):
        brainpainter.movie(SUBCORTICAL, atlas="dk", out=tmp_path / "bad.gif", clip_sweep="w")


def test_a_scene_layer_and_a_map_run_draw_the_blobs_as_the_command_line_does(sphere):
    scene = brainpainter.Scene(views="dorsal", width=200, height=150, clip="z>60")
    scene.add(str(sphere), kind="volume-surface", threshold=2.3, cmap="autumn", label="z")
    result = scene.render(progress=False)
    (layer,) = result.layers
    assert layer.kind == "blobs" and layer.label == "z" and result.manifest["blobs"]["clusters"]
    assert result.manifest["settings"]["views"][0]["clip"] == ["z>60"]
    direct = brainpainter.render(None, volume_surface=str(sphere), threshold=2.3, blobs_cmap="autumn",
                                 blobs_label="z", views="dorsal", width=200, height=150, clip="z>60",
                                 progress=False)
    assert np.array_equal(result.images[("sphere", "dorsal")], direct.images[("sphere", "dorsal")])
    mapped = brainpainter.render(None, volume=str(sphere), volume_surface=str(sphere), threshold=2.3,
                                 views="dorsal", width=200, height=150, progress=False)
    assert [la.kind for la in mapped.layers] == ["map", "blobs"] and mapped.manifest["blobs"]["clusters"]


def test_a_gaussian_blob_s_surface_is_the_sphere_where_it_crosses_the_threshold(tmp_path):
    affine, shape = _mni_grid()
    ijk = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), axis=-1)
    xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
    sigma, peak, threshold = 6.0, 5.0, 2.3
    data = peak * np.exp(-((xyz - np.asarray(CENTRE)) ** 2).sum(-1) / (2 * sigma**2))
    nib.save(nib.Nifti1Image(data.astype(np.float32), affine), tmp_path / "gauss.nii.gz")
    (cluster,) = find_blobs(tmp_path / "gauss.nii.gz", threshold).clusters
    radius = sigma * np.sqrt(2 * np.log(peak / threshold))  # where the blob falls to the threshold
    assert abs(cluster.volume_mm3 / (4 / 3 * np.pi * radius**3) - 1) < 0.10
    assert np.linalg.norm(np.subtract(cluster.centre, CENTRE)) < 1.0


def test_the_export_holds_the_blobs_in_their_colours(sphere, tmp_path):
    import trimesh

    brainpainter.export(None, tmp_path / "b.glb", volume_surface=str(sphere), threshold=2.3)
    blob = trimesh.load(tmp_path / "b.glb").geometry["blobs"]
    rgb = np.asarray(blob.visual.vertex_colors)[:, :3] / 255
    import matplotlib

    top = np.asarray(matplotlib.colormaps["viridis"](1.0)[:3])  # value 5, the peak: the bar's top
    linear = np.where(top <= 0.04045, top / 12.92, ((top + 0.055) / 1.055) ** 2.4)  # glTF's COLOR_0
    assert np.abs(rgb - linear).max() < 0.03 and abs(blob.volume / SPHERE_MM3 - 1) < 0.10


def test_jobs_draw_the_serial_run_s_pixels(sphere):
    kwargs = {"volume_surface": str(sphere), "threshold": 2.3, "views": "dorsal,cutaway-left", "width": 160,
              "height": 120, "progress": False}
    one, two = brainpainter.render(None, **kwargs), brainpainter.render(None, jobs=2, **kwargs)
    for key, img in one.images.items():
        assert np.array_equal(img, two.images[key])


def test_dask_draws_the_serial_run_s_blobs_and_cuts(sphere):
    distributed = pytest.importorskip("distributed")
    kwargs = {"volume_surface": str(sphere), "threshold": 2.3, "clip": "z>60", "width": 120, "height": 90,
              "views": "dorsal,cutaway-left", "progress": False}
    one = brainpainter.render(None, **kwargs)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0") as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        two = brainpainter.render(None, client=client, **kwargs)
    assert list(two.images) == list(one.images)
    for key, img in one.images.items():
        assert np.array_equal(img, two.images[key]), key
    assert two.manifest["blobs"] == one.manifest["blobs"]
    assert one.manifest["settings"]["views"][0]["clip"] == ["z>60"]


def test_plot_draws_the_blobs_their_panel_and_a_cutaway_into_axes(sphere):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b, c) = plt.subplots(1, 3, figsize=(6, 2))
    blobs = brainpainter.plot(None, view="dorsal", ax=a, volume_surface=str(sphere), threshold=2.3,
                              crop=False, width=200, height=150)
    panel = brainpainter.plot(None, view="z=50", ax=b, volume_surface=str(sphere), threshold=2.3)
    cut = brainpainter.plot(SUBCORTICAL, view="lateral-left", ax=c, atlas="dk", clip="x<0", shading="flat",
                            colorbar=False, width=320, height=240)
    plt.close(fig)
    top = blobs.scale(np.array([5.0]))[0][:3]                  # the blobs' own bar, threshold to peak
    assert (blobs.scale.vmin, blobs.scale.vmax) == (panel.scale.vmin, panel.scale.vmax) == (2.3, 5.0)
    seen = _saturated(blobs.image, top)
    assert seen.sum() > 50 and np.nonzero(seen)[1].min() > blobs.image.shape[1] / 2
    assert blobs.colorbar_ax is not None and not blobs.colorbar_ax.texts      # no "not measured" swatch
    rgb = panel.image[..., :3].astype(int)
    coloured = (rgb.max(-1) - rgb.min(-1) > 40) & (panel.image[..., 3] > 0)
    assert coloured.sum() > 100 and np.nonzero(coloured)[1].mean() > panel.image.shape[1] / 2
    assert np.median(np.abs(panel.image[coloured][:, :3] - top * 255).max(-1)) < 10
    assert int(near(cut.image, RED, 2).sum()) > 200            # the left structures, seen through the cut
