"""Mesh-folder atlases (brainpainter atlas add NAME --meshes DIR): reading every format, names and
hemispheres, welding triangle soups, checks, units and orientation, and renders without cracks."""

from __future__ import annotations

import json
from pathlib import Path

import nibabel as nib
import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from brainpainter.atlas import registry
from brainpainter.atlas.meshfiles import orientation_matrix, read_mesh, read_ply_polygons
from brainpainter.atlas.meshfolder import build_mesh_atlas, name_regions
from brainpainter.atlas.template import load_template
from brainpainter.cli.main import cli, main
from brainpainter.errors import BrainPainterError
from brainpainter.testing import StandInRenderer, stand_in

pytestmark = pytest.mark.usefixtures("fresh_registry")


def ball(centre, radius=1.0, subdivisions=2) -> trimesh.Trimesh:
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    m.apply_translation(centre)
    return m


def soup(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Every face with its own three vertices, as Blender's PLY export writes them."""
    v = mesh.vertices[mesh.faces].reshape(-1, 3)
    return trimesh.Trimesh(v, np.arange(len(v)).reshape(-1, 3), process=False)


def soup_folder(folder: Path, encoding: str = "binary") -> Path:
    """Two hemisphere balls and a midline box, as triangle-soup PLY files (Mice_atlas_pial style)."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, centre in (("lh.pial.Mice.Ball", (-2, 0, 0)), ("rh.pial.Mice.Ball", (2, 0, 0)),
                         ("lh.pial.Mice.Nose", (-1, 3, 0)), ("rh.pial.Mice.Nose", (1, 3, 0))):
        soup(ball(centre)).export(folder / f"{name}.ply", encoding=encoding)
    return folder


def add(*args: str) -> object:
    return CliRunner().invoke(cli, ["atlas", "add", *args])


def fails(*args: str) -> str:
    """Run ``brainpainter atlas add ARGS`` as the command line does; assert exit code 2, return stderr."""
    runner = CliRunner()
    with runner.isolation() as (out, err, _):
        with pytest.raises(SystemExit) as exc:
            main(["atlas", "add", *args])
    assert exc.value.code == 2
    text = (err.getvalue() if err else out.getvalue()).decode()
    assert len(text.strip().splitlines()) == 1 and "Traceback" not in text, text
    return text


# -- reading ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "off", "glb"])
def test_every_trimesh_format_reads_back_the_same_surface(tmp_path, ext):
    m = ball((1, 2, 3))
    path = tmp_path / f"x.{ext}"
    m.export(path)
    v, f = read_mesh(path)
    assert f.shape[1] == 3 and len(f) == len(m.faces)
    np.testing.assert_allclose(np.sort(v[np.unique(f)], axis=0).mean(0), m.vertices.mean(0), atol=1e-3)


def test_gifti_surface_reads(tmp_path):
    m = ball((0, 0, 0))
    img = nib.gifti.GiftiImage(darrays=[
        nib.gifti.GiftiDataArray(m.vertices.astype(np.float32), intent="NIFTI_INTENT_POINTSET"),
        nib.gifti.GiftiDataArray(m.faces.astype(np.int32), intent="NIFTI_INTENT_TRIANGLE")])
    nib.save(img, tmp_path / "lh.region.surf.gii")
    v, f = read_mesh(tmp_path / "lh.region.surf.gii")
    assert v.shape == m.vertices.shape and (f == m.faces).all()


def test_binary_ply_with_triangles_and_quads_is_fan_triangulated(tmp_path):
    verts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
              "property float z\nelement face 2\nproperty list uchar uint vertex_indices\nend_header\n")
    body = verts.tobytes() + bytes([4]) + np.array([0, 1, 2, 3], "<u4").tobytes() + bytes([3]) + np.array(
        [0, 1, 4], "<u4").tobytes()
    path = tmp_path / "Left-Quad.ply"
    path.write_bytes(header.encode() + body)
    v, f = read_ply_polygons(path)
    assert len(v) == 5 and f.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 4]]
    assert read_mesh(path)[1].tolist() == f.tolist()  # trimesh refuses it; read_mesh falls back


def test_hemispheres_and_names_from_every_usual_spelling(tmp_path):
    files = [tmp_path / n for n in ("lh.Visual.obj", "Right-Hippocampus.ply", "CA1_L.stl",
                                    "left_Amygdala.off", "Vermis.glb")]
    got = {(h, n) for _, h, n, _ in name_regions(files, {})}
    assert got == {("lh", "Visual"), ("rh", "Hippocampus"), ("lh", "CA1"), ("lh", "Amygdala"),
                   ("bilateral", "Vermis")}
    # the prefix every file shares after the hemisphere is dropped (the original's lh.pial.Mice.X)
    mice = [tmp_path / n for n in ("lh.pial.Mice.Auditory.ply", "rh.pial.Mice.Visual.ply")]
    assert [(h, n, a) for _, h, n, a in name_regions(mice, {})] == [
        ("lh", "Auditory", ("lh.pial.Mice.Auditory",)), ("rh", "Visual", ("rh.pial.Mice.Visual",))]


def test_orientation_letters_map_axes_to_ras():
    np.testing.assert_array_equal(orientation_matrix("ras"), np.eye(3))
    # BrainGlobe's asr (origin anterior-superior-right) increases towards posterior, inferior, left
    np.testing.assert_array_equal(orientation_matrix("PIL") @ [1, 2, 3], [-3, -1, -2])
    with pytest.raises(BrainPainterError, match="three letters"):
        orientation_matrix("RAR")


# -- the atlas -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_triangle_soup_folder_becomes_a_welded_atlas(tmp_path, encoding):
    folder = soup_folder(tmp_path / "meshes", encoding)
    result = add("blobs", "--meshes", str(folder))
    assert result.exit_code == 0, result.output
    assert "units: not given" in result.output and "orientation: not given" in result.output
    assert "left is on the left" in result.output and "4 meshes welded" in result.output
    atlas = registry.atlases.get("blobs")
    assert sorted(atlas.keys) == ["Left-Ball", "Left-Nose", "Right-Ball", "Right-Nose"]
    assert atlas.region("Left-Ball").aliases == ("lh.pial.Mice.Ball",) and atlas.template_dir is not None
    tpl = load_template(str(atlas.template_dir))
    cm = tpl.cortex("blobs", "lh")
    n_faces = len(cm.faces)
    assert len(cm.vertices["pial"]) < 0.5 * 3 * n_faces  # welded: a soup has 3 vertices per face
    assert trimesh.Trimesh(cm.vertices["pial"], cm.faces[cm.face_label == 0]).is_watertight
    meta = json.loads((atlas.template_dir.parent / "atlas.json").read_text())
    assert meta["regions"][0]["n_read_vertices"] == 3 * meta["regions"][0]["n_faces"]


def test_names_file_units_and_orientation(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    # micrometres, axes increasing towards posterior, inferior, left (BrainGlobe's asr)
    ball((0, 0, -2000), 500).export(folder / "a.stl")  # right (axis 2 increases to the left)
    ball((0, 0, 2000), 500).export(folder / "b.stl")
    ball((-3000, 0, 0), 500).export(folder / "c.obj")
    names = tmp_path / "names.csv"
    names.write_text("file,name,aliases\na.stl,Right-Ball,RB\nb,Left-Ball\nc.obj,Nose,olfactory bulb\n")
    out = tmp_path / "out"
    meta = build_mesh_atlas("x", [folder], names=names, units="um", orientation="PIL", out=_mk(out))
    assert [r["key"] for r in meta["regions"]] == ["Right-Ball", "Left-Ball", "Nose"]
    assert "left is on the left" in meta["report"][-1]
    tpl = load_template(out / "template")
    sub = tpl.subcortical()
    assert sub.label_names == ("Nose",)
    np.testing.assert_allclose(sub.vertices.mean(0), [0, 3, 0], atol=0.05)  # 3 mm anterior
    cm = tpl.cortex("x", "lh")
    np.testing.assert_allclose(cm.vertices["pial"].mean(0), [-2, 0, 0], atol=0.05)
    assert (out / "regions.tsv").read_text().count("olfactory bulb") == 1
    # a reflection (one axis flipped) keeps the faces wound outwards
    assert trimesh.Trimesh(sub.vertices, sub.faces).volume > 0


def _mk(p: Path) -> Path:
    p.mkdir()
    return p


def test_left_regions_on_the_right_are_reported(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    ball((2, 0, 0)).export(folder / "Left-A.stl")
    ball((-2, 0, 0)).export(folder / "Right-A.stl")
    meta = build_mesh_atlas("x", [folder], out=_mk(tmp_path / "o"))
    assert "LEFT REGIONS LIE ON THE RIGHT" in meta["report"][-1]


def test_stray_pieces_dropped_and_huge_meshes_decimated_with_notes(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    far = trimesh.util.concatenate([ball((2, 0, 0)), ball((1e5, 2e5, 0))])  # a copy at another scale
    far.export(folder / "Right-A.ply")
    ball((-2, 0, 0), subdivisions=5).export(folder / "Left-A.stl")
    meta = build_mesh_atlas("x", [folder], out=_mk(tmp_path / "o"), max_faces=2000)
    notes = {r["key"]: r["notes"] for r in meta["regions"]}
    assert any("dropped 1 piece" in n for n in notes["Right-A"])
    assert any(n.startswith("decimated from 20480") for n in notes["Left-A"])
    assert meta["regions"][0]["n_faces"] <= 2000 + 10


@pytest.mark.parametrize("content, message", [
    (b"", "cannot read"),
    (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
     b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 1 0\n0 0 1\n3 0 1 2\n",
     "non-finite"),
])
def test_bad_meshes_fail_with_one_line_and_leave_nothing(tmp_path, content, message):
    folder = tmp_path / "m"
    folder.mkdir()
    (folder / "Left-A.ply").write_bytes(content)
    assert message in fails("bad", "--meshes", str(folder))
    assert "bad" not in registry.atlases.names()


def test_options_of_other_sources_are_refused(tmp_path):
    (tmp_path / "v.nii").write_bytes(b"")
    assert "one of them" in fails("x", "--meshes", str(tmp_path), "--volume", str(tmp_path / "v.nii"))
    assert "go with --meshes" in fails("x", "--annot", "lh=a.annot", "--annot", "rh=b.annot", "--units", "um")
    assert "holds no mesh file" in fails("x", "--meshes", str(tmp_path))


def test_a_structures_only_brain_draws_in_surface_views_and_a_table_matches(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    ball((0, 0, 0)).export(folder / "CA1.stl")
    ball((0, 3, 0)).export(folder / "Thalamus.stl")
    assert add("bg", "--subcortical-meshes", str(folder)).exit_code == 0
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,CA1,Thalamus\nA,1,2\n")
    with stand_in() as renderer:
        result = CliRunner().invoke(cli, ["render", str(table), "--atlas", "bg", "--out", str(tmp_path / "o"),
                                          "--renderer", renderer, "--views", "dorsal,subcortical",
                                          "--size", "40x30", "-q"])
        assert result.exit_code == 0, result.output
        assert "0 unmatched" in result.output
        colors, _ = StandInRenderer.calls[-1]
    assert set(colors) == {"CA1", "Thalamus"}


@pytest.mark.render
def test_welded_soup_renders_without_cracks(tmp_path):
    """A triangle soup drawn as it is shows seams of background between faces; welded it shows none."""
    from PIL import Image

    from brainpainter.rendering.run import render

    folder = soup_folder(tmp_path / "meshes")
    assert add("soup", "--meshes", str(folder)).exit_code == 0
    out = tmp_path / "out"
    render({"Left-Ball": 0.0, "Right-Ball": 1.0, "Left-Nose": 0.0, "Right-Nose": 1.0}, "soup", out=out,
           views="dorsal", gradient=["#ff0000", "#0000ff"], width=300, height=300, shading="flat",
           quality="fast", progress=False)
    img = np.asarray(Image.open(out / "1_dorsal.png").convert("RGB")).astype(int)
    white = (img > 245).all(-1)
    red = (np.abs(img - (255, 0, 0)).max(-1) <= 3)
    blue = (np.abs(img - (0, 0, 255)).max(-1) <= 3)
    rows, cols = np.nonzero(red)
    assert red.sum() > 2000 and blue.sum() > 2000
    assert cols.mean() < np.nonzero(blue)[1].mean()  # left on the left from above
    # inside the left ball's disc (its central part), no background pixel shows through
    low = rows > img.shape[0] / 2  # the ball (the nose is anterior: up)
    cy, cx, r = rows[low].mean(), cols[low].mean(), np.ptp(cols[low]) / 2
    yy, xx = np.mgrid[: img.shape[0], : img.shape[1]]
    disc = (yy - cy) ** 2 + (xx - cx) ** 2 < (0.9 * r) ** 2
    assert disc.sum() > 200 and not white[disc].any()


def test_views_follow_the_template_axes_not_its_coordinates(tmp_path):
    """A template whose anterior is -z and superior +y (coordinates turned) is framed as the RAS one."""
    import shutil

    from brainpainter.atlas.writer import save_npz
    from brainpainter.rendering.framing import to_pixels
    from brainpainter.rendering.scene import Scene
    from brainpainter.rendering.settings import RenderSettings
    from brainpainter.rendering.views import PRESETS

    folder = soup_folder(tmp_path / "meshes")
    build_mesh_atlas("x", [folder], out=_mk(tmp_path / "ras"))
    turned = tmp_path / "turned"
    shutil.copytree(tmp_path / "ras" / "template", turned)
    m = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # RAS -> (x, superior, posterior): a rotation
    for f in turned.glob("cortex-*.npz"):
        z = dict(np.load(f))
        z["pial"] = (z["pial"] @ m.T).astype(np.float32)
        save_npz(f, z)
    manifest = json.loads((turned / "manifest.json").read_text())
    manifest["axes"] = {"anterior": "-z", "superior": "+y"}
    (turned / "manifest.json").write_text(json.dumps(manifest))
    ras, rot = load_template(tmp_path / "ras" / "template"), load_template(turned)
    np.testing.assert_allclose(rot.to_ras, m.T)
    point = ras.cortex("x", "lh").vertices["pial"][:50].astype(float)
    for name in ("dorsal", "lateral-left", "anterior", "subcortical"):
        px = [to_pixels(p, Scene(template=t, labels="x", surface="pial", hidden=frozenset(),
                                 settings=RenderSettings(), medial_wall_color=(0.7, 0.7, 0.7)
                                 ).geometry.camera(PRESETS[name], 4 / 3), 400, 300)
              for t, p in ((ras, point), (rot, point @ m.T))]
        np.testing.assert_allclose(px[0], px[1], atol=1e-6, err_msg=name)


def test_a_brain_longer_than_wide_gets_a_square_image_unless_a_size_is_given(tmp_path):
    """The atlas's ``image_aspect`` reshapes the default size (as many pixels); ``--size`` is kept."""
    from brainpainter.rendering.options import Options
    from brainpainter.rendering.settings import RenderSettings, with_aspect

    assert with_aspect(RenderSettings(), 1.0).size == "1040x1040"
    assert with_aspect(RenderSettings(width=800, height=600), 0.75).size == "600x800"
    assert not Options.of({}).size_given and Options.of({"width": 300}).size_given
    folder = tmp_path / "long"
    folder.mkdir()
    for name, centre in (("lh.Front", (-1, 4, 0)), ("rh.Front", (1, 4, 0)),
                         ("lh.Back", (-1, -4, 0)), ("rh.Back", (1, -4, 0))):
        ball(centre).export(folder / f"{name}.ply")
    assert add("long", "--meshes", str(folder)).exit_code == 0
    meta = json.loads((registry.atlases.get("long").template_dir.parent / "atlas.json").read_text())
    assert meta["image_aspect"] == 0.75  # 4 x 10: a portrait image, the narrowest allowed
    with stand_in() as renderer:
        for size, expected in ((None, (900, 1200)), ("400x300", (400, 300))):
            out = tmp_path / f"out-{size}"
            args = ["render", "--atlas", "long", "--views", "dorsal", "--renderer", renderer, "-q",
                    "--out", str(out), *(["--size", size] if size else [])]
            table = tmp_path / "t.csv"
            table.write_text("image,Left-Front\nA,1\n")
            result = CliRunner().invoke(cli, [args[0], str(table), *args[1:]])
            assert result.exit_code == 0, result.output
            manifest = json.loads((out / "manifest.json").read_text())
            assert (manifest["settings"]["width"], manifest["settings"]["height"]) == expected, manifest
