"""The user's own surfaces (issue 34, item 3b): ``--lh-surface``/``--rh-surface`` draw maps as they are.

Unit tests write tiny surfaces with nibabel's own writers (an icosphere from
trimesh as GIfTI, gzipped GIfTI and FreeSurfer geometry); tests marked
``render`` draw nilearn's fsaverage5 pial surface with its thickness (the
bar of docs/maps.md) and check pixels.
"""

from __future__ import annotations

import gzip
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest

import brainpainter
from brainpainter.atlas.surfaces import read_surface, surface_template
from brainpainter.atlas.template import load_template
from brainpainter.errors import BrainPainterError
from brainpainter.maps.inputs import read_maps
from brainpainter.rendering.run import prepare_run

#: nilearn's fsaverage5 surfaces and maps (GIfTI, gzipped), in its installed package data.
NILEARN_FS5 = Path(nib.__file__).parents[1] / "nilearn" / "datasets" / "data" / "fsaverage5"
SHARED = Path(os.environ.get("BRAINPAINTER_SHARED_DATA",
                            Path(__file__).resolve().parents[1].parent / "shared" / "data"))


def _icosphere(x: float = 0.0, subdivisions: int = 2) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=30.0)
    return (np.asarray(s.vertices) + np.array([x, 0, 0])).astype(np.float32), np.asarray(s.faces, np.int32)


def _gifti_surface(vertices: np.ndarray, faces: np.ndarray) -> nib.GiftiImage:
    return nib.GiftiImage(darrays=[
        nib.gifti.GiftiDataArray(vertices.astype(np.float32), intent="NIFTI_INTENT_POINTSET"),
        nib.gifti.GiftiDataArray(faces.astype(np.int32), intent="NIFTI_INTENT_TRIANGLE")])


def _subject(root: Path, x: float = -40.0) -> Path:
    """A FreeSurfer subject folder: ``surf/lh.pial``, ``surf/lh.sulc``, ``label/lh.cortex.label``."""
    v, f = _icosphere(x)
    (root / "surf").mkdir(parents=True)
    (root / "label").mkdir()
    nib.freesurfer.write_geometry(str(root / "surf" / "lh.pial"), v.astype(float), f)
    nib.freesurfer.write_morph_data(str(root / "surf" / "lh.sulc"), (v[:, 2] > 0).astype(np.float32) - 0.5)
    cortex = np.flatnonzero(v[:, 1] > -20)  # the back of the sphere is "medial wall"
    with open(root / "label" / "lh.cortex.label", "w") as fh:
        fh.write(f"#!ascii label\n{len(cortex)}\n")
        fh.writelines(f"{i} {v[i, 0]:.3f} {v[i, 1]:.3f} {v[i, 2]:.3f} 0.0\n" for i in cortex)
    return root / "surf" / "lh.pial"


def test_surfaces_read_alike(tmp_path):
    """GIfTI, gzipped GIfTI and FreeSurfer geometry give the same vertices and faces."""
    v, f = _icosphere()
    nib.save(_gifti_surface(v, f), tmp_path / "lh.sphere.surf.gii")
    raw = (tmp_path / "lh.sphere.surf.gii").read_bytes()
    (tmp_path / "lh.sphere.surf.gii.gz").write_bytes(gzip.compress(raw))
    nib.freesurfer.write_geometry(str(tmp_path / "lh.white"), v.astype(float), f)
    for name in ("lh.sphere.surf.gii", "lh.sphere.surf.gii.gz", "lh.white"):
        rv, rf = read_surface(tmp_path / name)
        np.testing.assert_allclose(rv, v, atol=1e-5)
        np.testing.assert_array_equal(rf, f)


def test_bad_surfaces_are_one_line(tmp_path):
    v, f = _icosphere()
    nib.save(nib.GiftiImage(darrays=[nib.gifti.GiftiDataArray(v[:, 0])]), tmp_path / "lh.x.func.gii")
    bad_faces = f.copy()
    bad_faces[0, 0] = len(v) + 5
    nib.save(_gifti_surface(v, bad_faces), tmp_path / "lh.broken.surf.gii")
    (tmp_path / "lh.text").write_text("not a surface\n")
    for name, words in (("lh.x.func.gii", "no point set"), ("lh.broken.surf.gii", "name vertices it lacks"),
                        ("lh.text", "cannot read surface file"), ("lh.missing", "does not exist")):
        with pytest.raises(BrainPainterError, match=words) as err:
            read_surface(tmp_path / name)
        assert "\n" not in str(err.value)


def test_template_of_a_freesurfer_subject(tmp_path):
    """The template holds the surface as it is, its own vertex numbers, the sulc and cortex beside it."""
    pial = _subject(tmp_path / "subj")
    v, f = _icosphere(-40.0)
    folder = surface_template({"lh": pial}, "dk", root=tmp_path / "cache")
    assert surface_template({"lh": pial}, "dk", root=tmp_path / "cache") == folder  # written once
    tpl = load_template(folder)
    mesh = tpl.base_cortex("dk", "lh")
    np.testing.assert_allclose(mesh.vertices["pial"], v, atol=1e-4)
    np.testing.assert_array_equal(mesh.faces, f)
    np.testing.assert_array_equal(mesh.source_vertex, np.arange(len(v)))
    z = np.load(folder / "cortex-lh.npz")
    np.testing.assert_array_equal(z["sulc"] > 0, v[:, 2] > 0)
    np.testing.assert_array_equal(z["cortex"] > 0, v[:, 1] > -20)
    assert tpl.cortex_names("dk", "rh") == ()  # no rh surface given: no rh cortex


def test_hcp_names_find_sulc_and_atlasroi_and_turn_hcp_sulc_back(tmp_path):
    """Beside 100307.L.midthickness.32k_fs_LR.surf.gii: its sulc (HCP's sign, sulci negative) and atlasroi."""
    v, f = _icosphere()
    nib.save(_gifti_surface(v, f), tmp_path / "100307.L.midthickness.32k_fs_LR.surf.gii")
    for word, values in (("sulc", v[:, 2]), ("atlasroi", (v[:, 1] > 0).astype(np.float32))):
        nib.save(nib.GiftiImage(darrays=[nib.gifti.GiftiDataArray(values.astype(np.float32))]),
                 tmp_path / f"100307.L.{word}.32k_fs_LR.shape.gii")
    folder = surface_template({"lh": tmp_path / "100307.L.midthickness.32k_fs_LR.surf.gii"}, "dk",
                              root=tmp_path / "cache")
    z = np.load(folder / "cortex-lh.npz")
    np.testing.assert_allclose(z["sulc"], -v[:, 2])  # FreeSurfer's sign: sulci positive
    np.testing.assert_array_equal(z["cortex"] > 0, v[:, 1] > 0)


def test_overlapping_hemispheres_are_moved_apart(tmp_path):
    """Inflated hemispheres (each centred at 0) end up 10 mm apart; pial ones that touch stay put."""
    v, f = _icosphere(0.0)
    for hemi in ("lh", "rh"):
        nib.freesurfer.write_geometry(str(tmp_path / f"{hemi}.inflated"), v.astype(float), f)
        shift = np.array([31.0 if hemi == "rh" else -31.0, 0, 0])
        nib.freesurfer.write_geometry(str(tmp_path / f"{hemi}.pial"), (v + shift).astype(float), f)
    for word, moved in (("inflated", True), ("pial", False)):
        tpl = load_template(surface_template({h: tmp_path / f"{h}.{word}" for h in ("lh", "rh")}, "dk",
                                             root=tmp_path / "cache"))
        lh, rh = (tpl.base_cortex("dk", h).vertices["pial"] for h in ("lh", "rh"))
        if moved:
            assert lh[:, 0].max() == pytest.approx(-5, abs=1e-4)
            assert rh[:, 0].min() == pytest.approx(5, abs=1e-4)
        else:
            np.testing.assert_allclose(lh, v + np.array([-31.0, 0, 0]), atol=1e-4)


def test_a_ciftis_subcortical_structures_on_own_surfaces_are_left_out_with_a_note(tmp_path):
    """No subcortical view of the own surfaces (it showed no structure): the cortex is drawn, the note says
    why the structures are not and where to see them."""
    from nibabel.cifti2 import cifti2_axes as axes

    pial = _subject(tmp_path / "subj")
    n = len(_icosphere()[0])
    mask = np.zeros((4, 4, 4), bool)
    mask.flat[:3] = True
    cols = (axes.BrainModelAxis.from_surface(np.arange(n), n, "CortexLeft")
            + axes.BrainModelAxis.from_mask(mask, name="thalamus_left", affine=np.eye(4)))
    path = tmp_path / "x.dscalar.nii"
    img = nib.Cifti2Image(np.ones((1, n + 3), np.float32), header=(axes.ScalarAxis(["z"]), cols))
    img.to_filename(str(path))
    run = prepare_run(path, lh_surface=str(pial), cmap="viridis", vmin=0, vmax=1)
    assert [view.name for view in run.views] == ["lateral-left", "medial-left"]
    assert not run.table.maps.regions
    (note,) = run.table.maps.notes
    assert "Left-Thalamus" in note and "not drawn on your own surfaces" in note and "\n" not in note


def test_map_run_colours_each_surface_vertex_with_its_own_value(tmp_path):
    """No resampling: the drawn mesh is the surface, and vertex i shows map value i (underlay off cortex)."""
    from brainpainter.maps.layers import GYRUS_GREY, SULCUS_GREY
    from brainpainter.rendering.geometry import SceneGeometry
    from brainpainter.testing import stand_in

    pial = _subject(tmp_path / "subj")
    v, _ = _icosphere(-40.0)
    values = v[:, 0] + v[:, 1]  # any field, one value per vertex of this 162-vertex surface
    with stand_in() as renderer:
        run = prepare_run({"lh": values}, lh_surface=str(pial), cmap="viridis", vmin=-80, vmax=40,
                          renderer=renderer)
        colors = run.colors(0).vertices["lh"]
        painter = run.painter()
        geometry = SceneGeometry(painter.scene)
    cortex = v[:, 1] > -20
    np.testing.assert_allclose(colors[cortex], run.scale(values[cortex])[:, :3], atol=1e-6)
    grey = np.where(v[:, 2] > 0, SULCUS_GREY, GYRUS_GREY)  # lh.sulc > 0: the darker grey
    np.testing.assert_allclose(colors[~cortex], np.repeat(grey[~cortex, None], 3, axis=1), atol=1e-6)
    part = next(p for p in geometry.parts if p.name == "cortex-lh")
    np.testing.assert_allclose(part.vertices, v, atol=1e-4)  # the surface as given
    assert geometry.vertex_slots["lh"][1] == len(v) and [view.name for view in run.views] == [
        "lateral-left", "medial-left"]  # one surface: its hemisphere's views


def test_counts_that_differ_and_other_refusals_are_one_line(tmp_path):
    pial = _subject(tmp_path / "subj")
    v, _ = _icosphere(-40.0)
    cases = [
        (dict(data={"lh": np.zeros(10242)}, lh_surface=str(pial)), "10242 values per hemisphere, but the"),
        (dict(data={"lh": np.zeros(len(v)), "rh": np.zeros(len(v))}, lh_surface=str(pial)), "--rh-surface"),
        (dict(data={"lh": np.zeros(len(v))}, lh_surface=str(pial), surface="inflated"), "--surface inflated"),
        (dict(data=None, volume=str(tmp_path / "x.nii.gz"), lh_surface=str(pial)), "onto fsaverage"),
    ]
    nib.save(nib.Nifti1Image(np.zeros((4, 4, 4), np.float32), np.eye(4)), tmp_path / "x.nii.gz")
    for kwargs, words in cases:
        with pytest.raises(BrainPainterError, match=words) as err:
            prepare_run(kwargs.pop("data"), **kwargs)
        assert "\n" not in str(err.value)
    with pytest.raises(BrainPainterError, match="have no atlas labels"):
        prepare_run({"lh": np.zeros(len(v))}, lh_surface=str(pial), outline="dk")
    with pytest.raises(BrainPainterError, match="a region table is drawn"):
        prepare_run({"Left-insula": [1.0]}, lh_surface=str(pial))
    from brainpainter.rendering.painter import Painter
    from brainpainter.testing import stand_in

    with stand_in() as renderer, Painter(renderer=renderer, coloring="vertices") as painter:
        with pytest.raises(BrainPainterError, match="the painter draws template 'fsaverage'"):
            brainpainter.render({"lh": np.zeros(len(v))}, lh_surface=str(pial), painter=painter)


def test_export_of_a_map_on_an_own_surface(tmp_path):
    """GLB and HTML: the surface's own mesh in the map's colours (a brain without subcortical structures)."""
    import trimesh

    pial = _subject(tmp_path / "subj")
    v, _ = _icosphere(-40.0)
    path = brainpainter.export({"lh": v[:, 1]}, tmp_path / "m.glb", lh_surface=str(pial))
    cortex = trimesh.load(path).geometry["Left-cortex"]
    assert cortex.visual.kind == "vertex" and len(cortex.vertices) == len(v)
    assert len(np.unique(cortex.visual.vertex_colors[:, :3], axis=0)) > 10  # a map, not one colour
    html = brainpainter.export({"lh": v[:, 1]}, tmp_path / "m.html", lh_surface=str(pial)).read_text()
    assert "vertexColors: m.vertexColors" in html


def _subject_template(path: Path, n_source: int = 500) -> tuple[Path, np.ndarray]:
    """A template as the builder makes it from a subject: a mesh keeping every 3rd of `n_source` vertices."""
    from brainpainter.testing.templates import CortexMesh, save_arrays, write_template

    v, f = _icosphere()
    cortex = {"dk": {hemi: CortexMesh(v + np.float32(dx), f, np.zeros(len(f), np.int16), ("insula",), v, v)
                     for hemi, dx in (("lh", -40), ("rh", 40))}}
    write_template(path, cortex, name="subject")
    sv = (np.arange(len(v)) * 3).astype(np.int32)
    manifest = json.loads((path / "manifest.json").read_text())
    for hemi in ("lh", "rh"):
        file = path / f"cortex-{hemi}-dk.npz"
        arrays = dict(np.load(file))
        save_arrays(file, {**arrays, "source_vertex": sv, "sulc": v[:, 2] - 5})
        manifest["labels"]["dk"]["cortex"][hemi]["n_source_vertices"] = n_source
    (path / "manifest.json").write_text(json.dumps(manifest))
    return path, sv


def test_a_template_built_from_a_subject_takes_maps_of_the_subject(tmp_path):
    """Maps of the subject's vertex count, vertex i of the template showing value source_vertex[i]."""
    folder, sv = _subject_template(tmp_path / "subject")
    values = np.random.default_rng(1).normal(size=500)
    run = prepare_run({"lh": values, "rh": -values}, template=str(folder), cmap="viridis", vmin=-3, vmax=3)
    colors = run.colors(0).vertices
    np.testing.assert_allclose(colors["lh"], run.scale(values[sv])[:, :3], atol=1e-6)
    np.testing.assert_allclose(colors["rh"], run.scale(-values[sv])[:, :3], atol=1e-6)
    assert run.base.mesh_masks is not None and run.base.mesh_masks["lh"]["sulc"].shape == (500,)
    with pytest.raises(BrainPainterError, match="10242 values per hemisphere, but the surface it is"):
        prepare_run({"lh": np.zeros(10242)}, template=str(folder))
    from brainpainter.testing import stand_in

    with stand_in() as renderer:  # the per-vertex scene of the subject's mesh is drawn
        r = brainpainter.render({"lh": values}, template=str(folder), renderer=renderer, views="lateral-left",
                                width=32, height=32, progress=False)
    assert len(r.images) == 1


def test_a_cifti_file_on_own_surfaces_is_drawn_as_it_is(tmp_path):
    """A dscalar's cortex (brain models of the surfaces' vertex count) colours the surfaces' vertices."""
    from nibabel.cifti2 import cifti2_axes as axes

    pial = _subject(tmp_path / "subj")
    n = len(_icosphere()[0])
    cols = (axes.BrainModelAxis.from_surface(np.arange(100), n, "CortexLeft")
            + axes.BrainModelAxis.from_surface(np.arange(n), n, "CortexRight"))
    data = np.arange(100 + n, dtype=np.float32)[None]
    path = tmp_path / "x.dscalar.nii"
    nib.Cifti2Image(data, header=(axes.ScalarAxis(["z"]), cols)).to_filename(str(path))
    run = prepare_run(path, lh_surface=str(pial), cmap="viridis", vmin=0, vmax=400)
    assert run.table.maps.own_mesh and sorted(run.table.maps.values) == ["lh"]  # rh has no surface: not drawn
    rgb, cortex = run.colors(0).vertices["lh"], run.base.mesh_masks["lh"]["cortex"]
    shown = cortex & (np.arange(n) < 100)  # vertices 100.. are absent from the file: the underlay
    np.testing.assert_allclose(rgb[shown], run.scale(data[0, :100][shown[:100]])[:, :3], atol=1e-6)
    assert (np.ptp(rgb[100:], axis=1) < 1e-6).all()


def test_read_maps_of_own_counts(tmp_path):
    """A map of any vertex count reads when a surface of that count is given (else it is refused)."""
    n = 1234
    np.save(tmp_path / "lh.x.npy", np.arange(n, dtype=float))
    with pytest.raises(BrainPainterError, match="fits no known mesh"):
        read_maps(lh=tmp_path / "lh.x.npy")
    m = read_maps(lh=tmp_path / "lh.x.npy", mesh={"lh": n})
    assert m.own_mesh and m.values["lh"].shape == (1, n)
    np.testing.assert_array_equal(m.on_surface("lh", 0), np.arange(n))
    np.save(tmp_path / "rh.x.npy", np.arange(n, dtype=float))  # the partner beside it: only with its surface
    assert sorted(read_maps(tmp_path / "lh.x.npy", mesh={"lh": n}).values) == ["lh"]
    assert sorted(read_maps(tmp_path / "lh.x.npy", mesh={"lh": n, "rh": n}).values) == ["lh", "rh"]


@pytest.mark.integration
def test_hcp_32k_map_on_the_fslr_sphere_with_its_atlasroi():
    """A 32,492-vertex fsLR map on HCP's 32k sphere as it is; HCP's atlasroi beside it is the cortex."""
    fslr = SHARED / "fslr"
    if not (fslr / "L.sphere.32k_fs_LR.surf.gii").is_file():
        pytest.skip("shared fsLR data not found")
    area = fslr / "resample_fsaverage" / "fs_LR.L.midthickness_va_avg.32k_fs_LR.shape.gii"
    run = prepare_run(None, lh=str(area), lh_surface=str(fslr / "L.sphere.32k_fs_LR.surf.gii"))
    roi = np.asarray(nib.load(fslr / "L.atlasroi.32k_fs_LR.shape.gii").darrays[0].data) > 0
    assert len(roi) == 32492 and run.base.mesh_masks is not None
    np.testing.assert_array_equal(run.base.mesh_masks["lh"]["cortex"], roi)
    rgb = run.colors(0).vertices["lh"]
    values = np.asarray(nib.load(area).darrays[0].data, float)
    np.testing.assert_allclose(rgb[roi], run.scale(values[roi])[:, :3], atol=1e-6)
    assert (np.ptp(rgb[~roi], axis=1) < 1e-6).all()  # the medial wall: the grey underlay


@pytest.mark.integration
def test_cli_count_mismatch_exits_2_without_output(tmp_path):
    pial = _subject(tmp_path / "subj")
    n = len(_icosphere()[0])
    np.save(tmp_path / "lh.x.npy", np.zeros(10242))
    out = subprocess.run([sys.executable, "-m", "brainpainter", "render", "--lh", str(tmp_path / "lh.x.npy"),
                          "--lh-surface", str(pial), "--out", str(tmp_path / "o")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("\n") == 1 and f"has {n} vertices" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "o").exists()


def _brain(img: np.ndarray) -> np.ndarray:
    return (img[..., 3] > 0) & ~np.all(img[..., :3] == 255, axis=-1)


@pytest.mark.render
@pytest.mark.integration
def test_nilearn_pial_with_its_thickness_renders_as_given(tmp_path):
    """Bar: nilearn's fsaverage5 pial_left.gii.gz, thick_left.gii.gz as given; left seen from the left."""
    if not (NILEARN_FS5 / "pial_left.gii.gz").is_file():
        pytest.skip("nilearn's fsaverage5 data not installed")
    thick, surface = NILEARN_FS5 / "thick_left.gii.gz", NILEARN_FS5 / "pial_left.gii.gz"
    values = np.asarray(nib.load(thick).darrays[0].data, float)
    verts = read_surface(surface)[0]
    anterior = 4.0 * (verts[:, 1] > np.median(verts[:, 1]))  # top of the scale (yellow) in front, 0 behind
    r = brainpainter.render({"lh": np.stack([values, anterior])}, lh_surface=str(surface), width=400,
                            height=300, views="lateral-left,medial-left", cmap="viridis", vmin=0, vmax=4,
                            progress=False)
    thickness, front = r.images[("map-1", "lateral-left")], r.images[("map-2", "lateral-left")]
    brain = _brain(thickness)
    assert brain.mean() > 0.35  # the hemisphere fills the view
    px = thickness[brain][:, :3].astype(float) / 255
    assert (px.max(1) - px.min(1) > 0.15).mean() > 0.9  # coloured by the map, not the grey underlay
    # the anterior half (value 1) lies on the left of the lateral-left image, the posterior (0) on the right
    cols = np.nonzero(_brain(front))[1]
    hot = front[..., 1].astype(int) > front[..., 2].astype(int)  # viridis' yellow end, not its purple one
    mid = (cols.min() + cols.max()) / 2
    rows, cs = np.nonzero(_brain(front))
    assert hot[rows, cs][cs < mid].mean() > 0.8 > 0.2 > hot[rows, cs][cs > mid].mean()


@pytest.mark.render
@pytest.mark.integration
def test_freesurfer_subject_inflated_with_jobs(tmp_path):
    """A FreeSurfer subject's own lh/rh.inflated with lh/rh.curv, through two workers: the same images."""
    surf = SHARED / "freesurfer" / "subjects" / "fsaverage5" / "surf"
    if not surf.is_dir():
        pytest.skip("shared data not found")
    kw = dict(lh=str(surf / "lh.curv"), rh=str(surf / "rh.curv"), lh_surface=str(surf / "lh.inflated"),
              rh_surface=str(surf / "rh.inflated"), views="dorsal,lateral-right", width=320, height=240,
              progress=False)
    serial = brainpainter.render(out=tmp_path / "a", **kw)
    jobs = brainpainter.render(out=tmp_path / "b", jobs=2, **kw)
    for a, b in zip(sorted(serial.files), sorted(jobs.files), strict=True):
        assert a.read_bytes() == b.read_bytes()
    from PIL import Image

    dorsal = np.asarray(Image.open(next(p for p in serial.files if "dorsal" in p.name)))
    brain = _brain(dorsal)
    middle = brain[:, dorsal.shape[1] // 2 - 2:dorsal.shape[1] // 2 + 3]
    assert brain.mean() > 0.3 and middle.mean() < 0.05  # both hemispheres, apart (a gap down the middle)
    shutil.rmtree(tmp_path / "a")
