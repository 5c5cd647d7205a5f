"""The Blender renderer, checked as pictures: colours, orientation, cracks, glass.

A tiny synthetic template (ellipsoid hemispheres split by the signs of y and
z, boxes as subcortical structures, larger ellipsoids as glass) is written
with the real template format. Tests that render are marked ``render``.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy import ndimage

from brainpainter.atlas.template import load_template
from brainpainter.errors import BrainPainterError
from brainpainter.rendering import framing as camera
from brainpainter.rendering.scene import RenderSettings, Scene
from brainpainter.rendering.views import PRESETS, View, get_view
from brainpainter.testing import CortexMesh, Structure, growth_per_image, write_template
from brainpainter.testing.memory import can_measure

ROOT = Path(__file__).resolve().parents[1]
REGIONS = ("unknown", "antsup", "antinf", "postsup", "postinf")
CENTRES = {"lh": (-32.0, 0.0, 0.0), "rh": (32.0, 0.0, 0.0)}
RADII = np.array([24.0, 40.0, 30.0])  # x, y, z semi-axes: brain-like proportions
STRUCTURES = {  # name: (centre, size)
    "Left-Caudate": ((-30.0, 15.0, 10.0), 8.0),
    "Left-Hippocampus": ((-30.0, -15.0, -10.0), 8.0),
    "Right-Caudate": ((30.0, 15.0, 10.0), 8.0),
    "Right-Hippocampus": ((30.0, -15.0, -10.0), 8.0),
}
BACKGROUND = (1.0, 1.0, 1.0)

# Palette of well-separated flat colours (sRGB 0-1).
RED, GREEN, BLUE, YELLOW = (1.0, 0.0, 0.0), (0.0, 0.8, 0.0), (0.0, 0.0, 1.0), (1.0, 0.9, 0.0)
MAGENTA, CYAN, ORANGE, PURPLE = (1.0, 0.0, 1.0), (0.0, 0.9, 0.9), (1.0, 0.5, 0.0), (0.4, 0.0, 0.6)


def _ellipsoid(centre, radii, subdivisions=4) -> trimesh.Trimesh:
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return trimesh.Trimesh(m.vertices * radii + centre, m.faces, process=False)


def _write_template(path: Path) -> Path:
    """A two-hemisphere template of ellipsoids (label set "test"), written with the test template writer."""
    cortex, glass = {}, {}
    for hemi, centre in CENTRES.items():
        m = _ellipsoid(np.array(centre), RADII)
        v = m.vertices.astype(np.float32)
        c = (v[m.faces].mean(axis=1) - centre) / RADII
        medial = c[:, 0] > 0.8 if hemi == "lh" else c[:, 0] < -0.8
        label = 1 + (c[:, 1] < 0) * 2 + (c[:, 2] < 0)  # antsup, antinf, postsup, postinf
        label = np.where(medial, 0, label).astype(np.int16)
        shift = np.float32(-8 if hemi == "lh" else 8)
        cortex[hemi] = CortexMesh(v, m.faces.astype(np.int32), label, REGIONS, white=v * np.float32(0.9),
                                  inflated=v * np.float32(1.1) + np.array([shift, 0, 0], np.float32))
        g = _ellipsoid(np.array(centre), RADII * 1.06, subdivisions=3)
        glass[hemi] = (g.vertices.astype(np.float32), g.faces.astype(np.int32))
    boxes = {name: (trimesh.creation.box(extents=(size, size, size)), centre)
             for name, (centre, size) in STRUCTURES.items()}
    structures = [Structure(name, (box.vertices + centre).astype(np.float32), box.faces.astype(np.int32))
                  for name, (box, centre) in boxes.items()]
    return write_template(path, {"test": cortex}, structures, glass, name="synthetic")


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    return load_template(_write_template(tmp_path_factory.mktemp("template") / "synthetic"))


def _renderer(template, **settings):
    from brainpainter_blender import BlenderRenderer

    scene_kw = {k: settings.pop(k) for k in ("hidden", "surface") if k in settings}
    settings = {"width": 320, "height": 240, "background": BACKGROUND, **settings}
    return BlenderRenderer(Scene(template, "test", settings=RenderSettings(**settings), **scene_kw))


@pytest.fixture(scope="module")
def flat(template):
    # Invisible glass: exact flat colours in every view (glass has its own test).
    r = _renderer(template, quality="fast", shading="flat", glass_opacity=0.0)
    yield r
    r.close()


def _quadrant_colors() -> dict[str, tuple[float, float, float]]:
    """Distinct flat colours: per hemisphere, anterior/posterior x superior/inferior."""
    return {
        "Left-antsup": RED, "Left-antinf": GREEN, "Left-postsup": BLUE, "Left-postinf": YELLOW,
        "Right-antsup": MAGENTA, "Right-antinf": CYAN, "Right-postsup": ORANGE,
        "Right-postinf": PURPLE,
        "Left-Caudate": RED, "Left-Hippocampus": BLUE,
        "Right-Caudate": MAGENTA, "Right-Hippocampus": ORANGE,
    }


def _mask(img: np.ndarray, rgb, tol: float = 2) -> np.ndarray:
    target = np.round(np.asarray(rgb) * 255)
    return np.abs(img[..., :3].astype(float) - target).max(axis=-1) <= tol


def _centroid(img: np.ndarray, rgbs, tol: float = 2) -> np.ndarray:
    """(x, y) image centroid (x right, y DOWN) of pixels with any of the colours."""
    m = np.zeros(img.shape[:2], bool)
    for rgb in rgbs:
        m |= _mask(img, rgb, tol)
    assert m.sum() > 20, f"colours {rgbs} hardly appear"
    ys, xs = np.nonzero(m)
    return np.array([xs.mean(), ys.mean()])


# -- no Blender needed ----------------------------------------------------------


def test_tested_bpy_pins_match_pyproject():
    """The versions the blank-render message recommends are the ones pip installs."""
    import tomllib

    from brainpainter_blender._bpy import TESTED_BPY

    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    pins = {}
    for dep in deps:
        if dep.startswith("bpy"):
            spec, marker = (part.strip() for part in dep.split(";"))
            pins[tuple(int(x) for x in marker.split("'")[1].split("."))] = spec.removeprefix("bpy")
    assert pins == TESTED_BPY
    assert all("<" in spec for spec in pins.values()), "an untested future bpy must not be installed"


@pytest.mark.parametrize("background", [None, (1.0, 1.0, 1.0), (0.2, 0.4, 0.6)])
def test_nothing_drawn_sees_one_drawn_pixel(background):
    from brainpainter.rendering.scene import nothing_drawn

    img = np.zeros((90, 120, 4), np.uint8)
    if background is not None:
        img[..., :3] = np.round(np.asarray(background) * 255)
        img[..., 3] = 255
    assert nothing_drawn(img, background)
    img[45, 60] = (200, 10, 10, 255)
    assert not nothing_drawn(img, background)
    if background is None:  # colour under zero alpha is not a drawn pixel
        img[45, 60, 3] = 0
        assert nothing_drawn(img, background)


def test_import_does_not_import_bpy():
    code = "import sys, brainpainter, brainpainter_blender; print('bpy' in sys.modules)"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), str(ROOT / "plugins" / "renderers"), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True)
    assert out.stdout.strip() == "False"


def test_missing_bpy_is_a_one_line_error(monkeypatch):
    from brainpainter_blender import _bpy

    monkeypatch.setattr(_bpy, "_state", {})
    monkeypatch.setitem(sys.modules, "bpy", None)
    with pytest.raises(BrainPainterError, match="pip install bpy") as info:
        _bpy.import_bpy()
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("name", "right", "up"), [
    # image right and image up in RAS
    ("lateral-left", (0, -1, 0), (0, 0, 1)),
    ("medial-left", (0, 1, 0), (0, 0, 1)),
    ("lateral-right", (0, 1, 0), (0, 0, 1)),
    ("medial-right", (0, -1, 0), (0, 0, 1)),
    ("dorsal", (1, 0, 0), (0, 1, 0)),
    ("ventral", (-1, 0, 0), (0, 1, 0)),
    ("anterior", (-1, 0, 0), (0, 0, 1)),
    ("posterior", (1, 0, 0), (0, 0, 1)),
])
def test_view_axes_are_anatomical(name, right, up):
    v = PRESETS[name]
    r, u, b = camera.view_axes(v.azimuth, v.elevation)
    np.testing.assert_allclose(r, right, atol=1e-9)
    np.testing.assert_allclose(u, up, atol=1e-9)
    np.testing.assert_allclose(np.cross(r, u), b, atol=1e-9)


def test_frame_fits_points_with_margin_and_zoom():
    pts = np.array([[0, -50, -10], [0, 50, 10], [5, 0, 0]], float)
    pose = camera.frame(pts, 180.0, 0.0, 1.0, aspect=4 / 3)
    assert pose.ortho_scale == pytest.approx(100 * (1 + 2 * camera.MARGIN))
    tall = camera.frame(pts, 180.0, 0.0, 1.0, aspect=0.25)
    assert tall.ortho_scale * 4 >= 100  # the height fits too
    assert camera.frame(pts, 180.0, 0.0, 2.0, aspect=4 / 3).ortho_scale == pytest.approx(
        pose.ortho_scale / 2)


# -- renders --------------------------------------------------------------------


@pytest.mark.render
def test_flat_colours_are_exact(flat, template):
    rng = np.random.default_rng(7)
    colors = {f"Left-{n}": tuple(rng.integers(0, 256, 3) / 255) for n in REGIONS[1:]}
    img = flat.render(colors, get_view("lateral-left"))
    assert img.shape == (240, 320, 4) and img.dtype == np.uint8
    palette = [*colors.values(), flat.scene.medial_wall_color, BACKGROUND]
    px = img[..., :3].reshape(-1, 3).astype(float)
    dev = np.abs(px[:, None, :] - np.round(np.array(palette) * 255)[None]).max(-1).min(-1)
    assert dev.max() <= 1, "a pixel is none of the region, medial-wall or background colours"
    for rgb in colors.values():
        assert _mask(img, rgb, 1).sum() > 100


@pytest.mark.render
@pytest.mark.parametrize("quality", ["default", "high"])
def test_antialiased_flat_interiors_are_exact(template, quality):
    r = _renderer(template, quality=quality, shading="flat")
    try:
        colors = {"Left-antsup": (0.2, 0.5, 0.9), "Left-antinf": (0.95, 0.6, 0.1),
                  "Left-postsup": (0.3, 0.3, 0.3), "Left-postinf": (0.0, 0.7, 0.35)}
        img = r.render(colors, get_view("lateral-left"))
    finally:
        r.close()
    for rgb in colors.values():
        m = _mask(img, rgb, 1)
        core = ndimage.binary_erosion(_mask(img, rgb, 30), iterations=3)
        assert core.sum() > 100
        assert (m[core]).all(), "interior pixels differ from the given colour"


@pytest.mark.render
def test_default_quality_antialiases_edges_without_supersampling(template):
    """Issue 37: the default quality draws at output resolution and smooths region borders and
    silhouettes from the geometry (edge_aa), as smooth as 2x2 supersampling was."""
    from brainpainter.media.imagemetrics import border_ratio

    a, b, white = (230, 60, 40), (40, 90, 220), (255, 255, 255)
    colors = {f"Left-{n}": tuple(c / 255 for c in (a if n in ("antsup", "postinf") else b))
              for n in REGIONS[1:]}
    got = {}
    for quality in ("fast", "default"):
        r = _renderer(template, quality=quality, shading="flat", glass_opacity=0.0, width=640, height=480)
        try:
            img = r.render(colors, get_view("lateral-left"))
            factor = r._gpu.factor
        finally:
            r.close()
        got[quality] = (border_ratio(img, a, b)[0], border_ratio(img, a, white)[0], factor)
    assert got["default"][2] == 1  # no supersampling
    # the ellipsoid's borders follow whole triangles (a zigzag of the mesh itself): 2x2 supersampling
    # gave 1.071 there and 1.013 on the silhouettes, no anti-aliasing 1.122 and 1.060
    assert got["default"][0] <= 1.08 < got["fast"][0], got  # region borders
    assert got["default"][1] <= 1.03 < got["fast"][1], got  # silhouettes against the background


@pytest.mark.render
def test_leaving_out_the_back_faces_changes_no_pixel(template, monkeypatch):
    """Issue 37: each view draws only the triangles facing it (GpuDraw._front), not all of them
    for the rasteriser to cull; the images are the same."""
    from brainpainter_blender.gpu_draw import GpuDraw

    views = [get_view("lateral-left"), get_view("subcortical"),
             replace(get_view("lateral-left"), azimuth=130.0, elevation=35.0, hemis=("lh", "rh"))]
    colors = _quadrant_colors()

    def images():
        r = _renderer(template, glass_opacity=0.3)
        try:
            return [r.render(colors, v) for v in views]
        finally:
            r.close()

    culled = images()
    monkeypatch.setattr(GpuDraw, "_front", lambda self, part, aim, back=False: self._batch(part))
    for a, b in zip(culled, images(), strict=True):
        assert np.array_equal(a, b)


@pytest.mark.render
@pytest.mark.parametrize("quality", ["fast", "default"])
def test_outlines_leave_no_holes_in_an_opaque_image(template, quality):
    """The outline shader's anti-aliasing (coverage as alpha) is blended: written as it was, its
    alpha made see-through pixels along every border of an opaque brain."""
    r = _renderer(template, quality=quality, shading="flat", glass_opacity=0.0, background=None,
                  outline_width=2.0)
    try:
        img = r.render({f"Left-{n}": (0.9, 0.8, 0.1) for n in REGIONS[1:]}, get_view("lateral-left"))
    finally:
        r.close()
    inside = ndimage.binary_erosion(ndimage.binary_fill_holes(img[..., 3] > 0), iterations=3)
    dark = (img[..., :3].max(axis=-1) < 100) & inside
    assert dark.sum() > 200  # the borders are drawn
    assert (img[..., 3][inside] == 255).all(), np.unique(img[..., 3][inside])


@pytest.mark.render
@pytest.mark.parametrize("name", [n for n, v in PRESETS.items() if v.content != "flat"])  # test_flat.py
def test_orientation_of_every_preset(flat, name):
    view = PRESETS[name]
    img = flat.render(_quadrant_colors(), view)
    c = _quadrant_colors()
    tol = 2
    if view.content == "cortex":
        hemis = view.hemis
        pre = {"lh": "Left-", "rh": "Right-"}
        ant = [c[pre[h] + s] for h in hemis for s in ("antsup", "antinf")]
        post = [c[pre[h] + s] for h in hemis for s in ("postsup", "postinf")]
        sup = [c[pre[h] + s] for h in hemis for s in ("antsup", "postsup")]
        inf = [c[pre[h] + s] for h in hemis for s in ("antinf", "postinf")]
        left = [c["Left-" + s] for s in REGIONS[1:]]
        right = [c["Right-" + s] for s in REGIONS[1:]]
    else:
        ant = [c["Left-Caudate"], c["Right-Caudate"]]
        post = [c["Left-Hippocampus"], c["Right-Hippocampus"]]
        sup, inf = ant, post
        left = [c["Left-Caudate"], c["Left-Hippocampus"]]
        right = [c["Right-Caudate"], c["Right-Hippocampus"]]
    expected = {  # image direction of anterior; superior; right hemisphere (x right, y down)
        "lateral-left": ("left", "up", None), "medial-left": ("right", "up", None),
        "lateral-right": ("right", "up", None), "medial-right": ("left", "up", None),
        "dorsal": ("up", None, "right"), "ventral": ("up", None, "left"),
        "anterior": (None, "up", "left"), "posterior": (None, "up", "right"),
        "subcortical": ("left", "up", None), "subcortical-left": ("left", "up", None),
        "subcortical-dorsal": ("up", None, "right"), "subcortical-ventral": ("up", None, "left"),
    }[name]
    unit = {"left": (-1, 0), "right": (1, 0), "up": (0, -1), "down": (0, 1)}

    def points(d, direction):
        return np.dot(d, unit[direction]) > 0.1 * np.linalg.norm(d) and np.linalg.norm(d) > 5

    a, s, r = expected
    if a:
        d = _centroid(img, ant, tol) - _centroid(img, post, tol)
        assert points(d, a), f"{name}: anterior should be {a}, got offset {d}"
    if s:
        d = _centroid(img, sup, tol) - _centroid(img, inf, tol)
        assert points(d, s), f"{name}: superior should be {s}, got offset {d}"
    if r:
        d = _centroid(img, right, tol) - _centroid(img, left, tol)
        assert points(d, r), f"{name}: right hemisphere should be {r}, got offset {d}"


@pytest.mark.render
def test_object_fills_frame_with_margin_and_zoom(template):
    r = _renderer(template, quality="fast", shading="flat", background=None)
    try:
        sil = r.render({}, get_view("lateral-left"))[..., 3] > 0
        zoomed = r.render({}, View("z", "cortex", ("lh",), 180.0, 0.0, zoom=1.5))[..., 3] > 0
    finally:
        r.close()
    ys, xs = np.nonzero(sil)
    assert xs.min() > 0 and xs.max() < 319 and ys.min() > 0 and ys.max() < 239
    # the limiting dimension is framed tightly (4% margin per side)
    assert max((xs.max() - xs.min() + 1) / 320, (ys.max() - ys.min() + 1) / 240) > 0.85
    assert zoomed.sum() > 1.3 * sil.sum()


@pytest.mark.render
def test_no_background_holes_inside_the_silhouette(flat):
    grey = {f"{h}-{n}": (0.5, 0.5, 0.5) for h in ("Left", "Right") for n in REGIONS}
    for name in ("lateral-left", "dorsal", "medial-right"):
        img = flat.render(grey, get_view(name))
        brain = ~_mask(img, BACKGROUND, 0)
        holes = ndimage.binary_fill_holes(brain) & ~brain
        assert holes.sum() == 0, f"{name}: {holes.sum()} background pixels inside the brain"


@pytest.mark.render
def test_transparent_background(template):
    r = _renderer(template, quality="default", background=None)
    try:
        img = r.render({}, get_view("lateral-left"))
    finally:
        r.close()
    alpha = img[..., 3]
    assert (alpha[0, :] == 0).all() and (alpha[:, 0] == 0).all()
    assert (alpha[120, 160] == 255)
    assert ((alpha == 255).mean() > 0.3)


@pytest.mark.render
def test_background_colour_is_exact(template):
    bg = (0.2, 0.4, 0.6)
    r = _renderer(template, quality="default", background=bg)
    try:
        img = r.render({}, get_view("dorsal"))
    finally:
        r.close()
    corners = img[[0, 0, -1, -1], [0, -1, 0, -1]]
    assert np.abs(corners[:, :3].astype(int) - np.round(np.array(bg) * 255)).max() <= 1
    assert (corners[:, 3] == 255).all()


@pytest.mark.render
def test_glass_is_visible_and_structures_show_through(template):
    colors = {"Left-Caudate": RED, "Right-Caudate": RED,
              "Left-Hippocampus": BLUE, "Right-Hippocampus": BLUE}
    view = get_view("subcortical-dorsal")  # both hemispheres as glass, seen from above
    images = []
    for opacity in (0.2, 0.0):  # invisible glass: same framing, structures only
        r = _renderer(template, quality="fast", shading="flat", glass_opacity=opacity)
        try:
            images.append(r.render(colors, view).astype(float))
        finally:
            r.close()
    img, bare = images
    white = np.array([255, 255, 255])
    glass_only = (np.abs(img[..., :3] - white).max(-1) > 3) & (np.abs(bare[..., :3] - white).max(-1) == 0)
    assert glass_only.mean() > 0.2, "the glass brain is not drawn"
    assert (img[glass_only][:, :3].min(axis=1) > 150).all(), "the glass is too opaque"
    # Inside the boxes the structure colour dominates, tinted by the glass in front.
    red = _mask(bare, RED, 1)
    seen = img[red][:, :3]
    assert red.sum() > 50
    assert (seen[:, 0] > 150).all() and (seen[:, 0] - seen[:, 1:].max(axis=1) > 80).all()


@pytest.mark.render
def test_subcortical_without_colour_is_neutral_and_cortex_uses_medial_wall(flat):
    from brainpainter.rendering.geometry import NEUTRAL_GREY

    img = flat.render({}, get_view("subcortical-left"))
    assert _mask(img, NEUTRAL_GREY, 30).sum() > 50
    img = flat.render({}, get_view("lateral-left"))
    assert _mask(img, flat.scene.medial_wall_color, 1).sum() > 1000


@pytest.mark.render
def test_hidden_regions_are_never_drawn(template):
    r = _renderer(template, quality="fast", shading="flat",
                  hidden=frozenset({"Left-antsup", "Left-Caudate"}))
    try:
        img = r.render(_quadrant_colors(), get_view("lateral-left"))
        sub = r.render(_quadrant_colors(), get_view("subcortical-left"))
    finally:
        r.close()
    assert _mask(img, RED, 2).sum() == 0
    assert _mask(img, GREEN, 2).sum() > 100
    assert _mask(sub, RED, 40).sum() == 0


@pytest.mark.render
def test_deterministic_and_reusable(flat, template):
    view, other = get_view("lateral-left"), get_view("dorsal")
    c1 = _quadrant_colors()
    a = flat.render(c1, view)
    flat.render(c1, other)
    assert np.array_equal(a, flat.render(c1, view))
    c2 = {**c1, "Left-antsup": GREEN}
    b = flat.render(c2, view)
    assert not np.array_equal(a, b)
    assert _mask(b, RED, 2).sum() == 0
    # a second renderer with other settings coexists in the same process
    other_r = _renderer(template, quality="default", width=160, height=120)
    try:
        assert other_r.render(c1, view).shape == (120, 160, 4)
        assert np.array_equal(a, flat.render(c1, view))
    finally:
        other_r.close()
    assert np.array_equal(a, flat.render(c1, view))


def _blender_mb_per_image(template, leak_mb: float = 0.0) -> float:
    """Memory growth per image of the Blender renderer (plus `leak_mb` kept per image, to test the check)."""
    r = _renderer(template, quality="fast", width=160, height=120)
    rng = np.random.default_rng(0)
    views = [get_view(n) for n in ("lateral-left", "dorsal", "subcortical")]
    kept = []

    def one(i: int) -> None:
        r.render({"Left-antsup": tuple(rng.random(3))}, views[i % 3])
        if leak_mb:
            kept.append(np.ones(int(leak_mb * 2**20), np.uint8))

    try:
        return growth_per_image(one, n=120)
    finally:
        r.close()


@pytest.mark.render
def test_many_renders_do_not_grow_memory(template):
    if not can_measure():
        pytest.skip("needs /proc")
    grown = _blender_mb_per_image(template)
    assert grown < 0.1, f"memory grew by {grown:.3f} MB per image over 120 renders"


@pytest.mark.render
def test_the_memory_check_sees_a_small_leak_beside_blender(template):
    """The same measurement, with 0.3 MB kept per image, fails: the check would catch such a leak."""
    if not can_measure():
        pytest.skip("needs /proc")
    assert _blender_mb_per_image(template, leak_mb=0.3) > 0.2


@pytest.mark.render
def test_close_frees_blender_data_and_refuses_to_render(template):
    from brainpainter_blender import _bpy

    bpy = _bpy.import_bpy()  # Blender's full start (the gpu path's lean one skips its factory reset)
    gpu_path = _renderer(template, quality="fast")  # draws with the gpu module: no Blender objects
    gpu_path.close()  # (its process-wide 4x4 dummy scene stays, made once)
    with pytest.raises(BrainPainterError, match="closed"):
        gpu_path.render({}, get_view("dorsal"))
    before = (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials),
              len(bpy.data.scenes))
    r = _renderer(template, quality="high")  # Cycles builds objects, materials and a scene
    assert len(bpy.data.objects) > before[0]
    r.close()
    r.close()
    assert (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials),
            len(bpy.data.scenes)) == before
    with pytest.raises(BrainPainterError, match="closed"):
        r.render({}, get_view("dorsal"))


@pytest.mark.render
def test_surfaces_and_lighting_presets(template):
    for kw in ({"surface": "inflated", "lighting": "soft"}, {"lighting": "flat-studio"},
               {"surface": "white"}):
        r = _renderer(template, **kw)
        try:
            img = r.render({"Left-antsup": RED}, get_view("lateral-left"))
        finally:
            r.close()
        red = img[..., 0].astype(int) - img[..., 1:3].max(-1) > 60  # hue kept under lighting
        assert red.sum() > 200, kw


@pytest.mark.render
def test_default_shading_keeps_hue(template):
    r = _renderer(template, quality="default")
    try:
        img = r.render(_quadrant_colors(), get_view("lateral-left")).astype(int)
    finally:
        r.close()
    red = (img[..., 0] - img[..., 1:3].max(-1) > 60) & (img[..., 3] == 255)
    blue = (img[..., 2] - img[..., 0:2].max(-1) > 60) & (img[..., 3] == 255)
    assert red.sum() > 1000 and blue.sum() > 1000
    assert img[..., :3][img[..., 3] == 255].max(-1).min() > 10, "harsh black in the shading"


@pytest.mark.render
def test_cycles_high_quality(template):
    r = _renderer(template, quality="high", width=96, height=72)
    try:
        a = r.render({"Left-antsup": RED, "Left-postsup": BLUE}, get_view("lateral-left"))
        b = r.render({"Left-antsup": RED, "Left-postsup": BLUE}, get_view("lateral-left"))
    finally:
        r.close()
    assert np.array_equal(a, b)
    img = a.astype(int)
    assert (img[..., 0] - img[..., 1:3].max(-1) > 60).sum() > 50
    assert (img[..., 2] - img[..., 0:2].max(-1) > 60).sum() > 50


def _realistic_template():
    for candidate in (os.environ.get("BRAINPAINTER_TEST_TEMPLATE"),
                      ROOT / "plugins/atlases/brainpainter_atlases/templates/fsaverage",
                      "/tmp/bp_templates/fsaverage5"):
        if candidate and (Path(candidate) / "manifest.json").is_file():
            return load_template(Path(candidate))
    pytest.skip("no realistic template built yet (fsaverage or /tmp/bp_templates/fsaverage5)")


@pytest.mark.render
@pytest.mark.integration
def test_real_brain_has_no_cracks():
    from brainpainter_blender import BlenderRenderer

    tpl = _realistic_template()
    labels = tpl.label_sets[0]
    settings = RenderSettings(480, 360, quality="fast", shading="flat")
    grey = {f"{p}{n}": (0.5, 0.5, 0.5) for h, p in (("lh", "Left-"), ("rh", "Right-"))
            for n in tpl.cortex(labels, h).label_names}
    # One hemisphere at a time: the gap between hemispheres is real background.
    views = [get_view("lateral-left"), get_view("medial-left"), get_view("lateral-right"),
             View("dorsal-lh", "cortex", ("lh",), 0.0, 90.0),
             View("ventral-rh", "cortex", ("rh",), 0.0, -90.0)]
    renderer = BlenderRenderer(Scene(tpl, labels, settings=settings))
    try:
        for view in views:
            brain = ~_mask(renderer.render(grey, view), BACKGROUND, 0)
            holes = ndimage.binary_fill_holes(brain) & ~brain
            assert holes.sum() == 0, f"{view.name}: {holes.sum()} background pixels in the brain"
    finally:
        renderer.close()


@pytest.fixture(scope="module")
def bundled_lh():
    """Default settings on the bundled template: every left-hemisphere region key."""
    from brainpainter.rendering.painter import Painter

    painter = Painter("dk")
    keys = [r.key for r in painter.atlas.regions if r.key.startswith("Left-")]
    yield painter, keys
    painter.close()


def _brain(img: np.ndarray) -> np.ndarray:
    return img[~_mask(img, BACKGROUND, 0)][:, :3].astype(float)


@pytest.mark.render
@pytest.mark.integration
def test_default_lighting_keeps_the_legend_colours_and_shows_folds(bundled_lh):
    painter, keys = bundled_lh
    view = get_view("lateral-left")
    white = _brain(painter.paint_colors(dict.fromkeys(keys, (1.0, 1.0, 1.0)), view))
    assert (np.median(white, axis=0) >= 215).all(), np.median(white, axis=0)
    assert (np.percentile(white, 90, axis=0) >= 240).all()
    luminance = white @ np.array([0.2126, 0.7152, 0.0722])
    assert luminance.std() >= 12, "the folds do not show"
    yellow = _brain(painter.paint_colors(dict.fromkeys(keys, (1.0, 1.0, 0.0)), view))
    r, g, b = np.median(yellow, axis=0)
    assert r >= 215 and g >= 215 and b <= 15, (r, g, b)


@pytest.mark.render
@pytest.mark.integration
def test_sulcal_depth_lighting_darkens_sulci_slightly():
    from brainpainter.rendering.painter import Painter

    view = get_view("lateral-left")
    lum = {}
    for surface, lighting in (("pial", "studio"), ("pial", "sulc"), ("inflated", "studio"),
                              ("inflated", "sulc")):
        with Painter("dk", surface=surface, settings=RenderSettings(480, 360, lighting=lighting)) as painter:
            keys = [r.key for r in painter.atlas.regions if r.key.startswith("Left-")]
            img = painter.paint_colors(dict.fromkeys(keys, (1.0, 1.0, 1.0)), view)
            lum[surface, lighting] = img[..., :3].astype(float) @ np.array([0.2126, 0.7152, 0.0722])
    for surface in ("pial", "inflated"):
        darker = lum[surface, "studio"] - lum[surface, "sulc"]  # same pixels: only the shading differs
        p10, p50, p95 = np.percentile(darker[lum[surface, "studio"] < 254.5], [10, 50, 95])
        # crowns keep their colour, sulci darken slightly
        assert p10 < 1 and 8 < p95 < 60 and p50 < p95 - 5, (surface, p10, p50, p95)


@pytest.mark.render
@pytest.mark.integration
def test_flat_shading_is_exact_on_the_bundled_template():
    from brainpainter.rendering.painter import Painter

    rng = np.random.default_rng(1)
    with Painter("dk", settings=RenderSettings(600, 450, shading="flat")) as painter:
        colors = {r.key: tuple(rng.integers(0, 256, 3) / 255) for r in painter.atlas.regions}
        img = painter.paint_colors(colors, get_view("lateral-left"))
    exact = np.zeros(img.shape[:2], bool)
    for rgb in {*colors.values(), painter.scene.medial_wall_color, BACKGROUND}:
        exact |= _mask(img, rgb, 1)
    interior = ndimage.binary_erosion(~_mask(img, BACKGROUND, 0), iterations=2)
    # anti-aliased borders blend two colours; everything else is exact to 1/255
    assert exact[interior].mean() > 0.85


def test_a_draw_that_leaves_only_background_is_an_error(flat, monkeypatch):
    from brainpainter.rendering.scene import BlankRenderError

    s = flat.scene.settings
    blank = np.zeros((s.height, s.width, 4), np.uint8)
    blank[..., :3] = np.round(np.asarray(BACKGROUND) * 255)
    blank[..., 3] = 255
    monkeypatch.setattr(flat._gpu, "_draw", lambda rgb, aim, mark=None: blank)
    with pytest.raises(BlankRenderError, match=r"Blender \d+\.\d+.* drew nothing in view 'lateral-left'"):
        flat.render(_quadrant_colors(), get_view("lateral-left"))
    monkeypatch.undo()
    assert flat.render(_quadrant_colors(), get_view("lateral-left"))[..., 3].any()


@pytest.mark.render
def test_cycles_draws_a_glass_cortex_in_its_colours(template):
    """``--cortex glass`` with ``--quality high``: the cortex see-through in its regions' colours (as the
    draw path does), not the plain grey hull; opaque again in the next view that asks for it."""
    glass = _renderer(template, quality="high", width=96, height=72, cortex="glass", glass_opacity=0.4)
    opaque = _renderer(template, quality="high", width=96, height=72)
    try:
        colours = {"Left-antsup": RED, "Left-postsup": BLUE}
        seen = glass.render(colours, get_view("lateral-left")).astype(int)
        solid = opaque.render(colours, get_view("lateral-left")).astype(int)
    finally:
        glass.close()
        opaque.close()
    bg = 255 * np.asarray(BACKGROUND)
    red = seen[..., 0] - seen[..., 1:3].max(-1) > 25
    blue = seen[..., 2] - seen[..., 0:2].max(-1) > 25
    assert red.sum() > 50 and blue.sum() > 50  # the regions' colours, tinted
    # see-through: paler than the opaque cortex, nearer the background
    solid_red = solid[..., 0] - solid[..., 1:3].max(-1) > 60
    assert np.abs(seen[red][:, :3] - bg).sum(-1).mean() < np.abs(solid[solid_red][:, :3] - bg).sum(-1).mean()


def test_only_a_glass_of_many_triangles_is_kept_in_layers():
    """The subcortical views' hull (~6,000 triangles) is drawn per image: a layer would cost a region
    render 8.6 MB at 1200x900 (its peak memory bar is 500 MB) and save nothing; a glass cortex is kept."""
    from types import SimpleNamespace

    from brainpainter_blender.glass_layers import GlassLayers

    def parts(*sizes):
        return [SimpleNamespace(triangles=np.zeros((n, 3), np.uint32)) for n in sizes]

    assert not GlassLayers.worth(parts(3_000, 3_000))
    assert GlassLayers.worth(parts(120_000, 120_000))


@pytest.mark.render
def test_the_glass_is_drawn_once_per_view_and_glass_colours(template, monkeypatch, glass_draws):
    """Issue 36: a view's glass is drawn into a layer that later images of the view put over their
    opaque parts while the glass's colours stay (glass_layers); its pixels are an uncached draw's
    within a level, and every image of a view is the same whatever was drawn before it."""
    from brainpainter_blender import glass_layers

    drawn = glass_draws
    # room for two views' layers: a third view's drops the oldest
    monkeypatch.setattr(glass_layers, "MAX_LAYER_PIXELS", 2 * glass_layers.LAYERS_PER_VIEW * 320 * 240)
    lateral, dorsal, medial = get_view("lateral-left"), get_view("dorsal"), get_view("medial-left")
    sub = get_view("subcortical-dorsal")  # the glass hull over the structures
    colours = _quadrant_colors()
    glass = _renderer(template, cortex="glass", glass_opacity=0.3, outline_width=1.5)
    direct = _renderer(template, cortex="glass", glass_opacity=0.3, outline_width=1.5)
    direct._gpu._glass = None  # every image draws its glass
    try:
        first = glass.render(colours, lateral)
        assert len(drawn) == 1
        again = glass.render(colours, lateral)
        assert len(drawn) == 1, "the second image of the view drew its glass again"
        assert np.array_equal(first, again)
        ref = direct.render(colours, lateral)
        d = np.abs(again.astype(int) - ref.astype(int))
        assert d.max() <= 2 and (d.max(axis=-1) > 0).mean() < 0.01, (d.max(), (d.max(axis=-1) > 0).mean())
        assert (np.abs(again[..., :3].astype(int) - 255).max(axis=-1) > 30).mean() > 0.2  # the glass is seen

        recoloured = {**colours, "Left-antsup": CYAN}  # a glass colour: drawn again, in it
        n = len(drawn)
        cyan = glass.render(recoloured, lateral)
        assert len(drawn) == n + 1 and not np.array_equal(cyan, again)
        assert np.abs(cyan.astype(int) - direct.render(recoloured, lateral).astype(int)).max() <= 2

        # the structures' colours change, the glass hull's do not: it is drawn once
        n = len(drawn)
        caudate_blue = {**colours, "Left-Caudate": BLUE, "Right-Caudate": BLUE}
        red = glass.render(colours, sub)
        blue = glass.render(caudate_blue, sub)
        assert len(drawn) == n + 1
        def reddish(img):
            rgb = img[..., :3].astype(int)
            return (rgb[..., 0] - rgb[..., 1:].max(axis=-1) > 60).sum()

        assert reddish(red) > 50 and reddish(blue) < reddish(red) / 2, (reddish(red), reddish(blue))
        assert np.abs(blue.astype(int) - direct.render(caudate_blue, sub).astype(int)).max() <= 2

        # another view draws its own; two views' layers are kept, the oldest dropped for a third
        n = len(drawn)
        glass.render(colours, dorsal)
        glass.render(colours, medial)
        assert len(drawn) == n + 2
        glass.render(colours, medial)
        assert len(drawn) == n + 2
        assert np.array_equal(glass.render(colours, lateral), first)  # dropped: drawn again, the same
        assert len(drawn) == n + 3
    finally:
        glass.close()
        direct.close()
