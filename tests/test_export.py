"""Interactive 3D export: the .glb (read back with trimesh) and the HTML viewer (in headless Chromium)."""

from __future__ import annotations

import json
import os
import shutil
import struct
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

import brainpainter
from brainpainter.atlas.registry import get_atlas
from brainpainter.cli.main import main
from brainpainter.errors import BrainPainterError

pytestmark = pytest.mark.integration  # the bundled fsaverage template

VALUES = {"Left-superiorfrontal": 0.0, "Left-precentral": 1.0, "Left-superiortemporal": 2.0,
          "Left-Hippocampus": 2.0}
SCALE = {"gradient": "blue,lime,red", "vmin": 0, "vmax": 2}
EXPECTED = {"Left-superiorfrontal": (0, 0, 255), "Left-precentral": (0, 255, 0),
            "Left-superiortemporal": (255, 0, 0), "Left-Hippocampus": (255, 0, 0)}
MISSING = (0xD0, 0xD0, 0xD0)


def glb_json(data: bytes) -> dict:
    n = struct.unpack("<I", data[12:16])[0]
    return json.loads(data[20:20 + n])


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, dtype=float)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("export")
    glb = brainpainter.export(VALUES, out / "brain.glb", atlas="dk", hide=["cerebellum"], **SCALE)
    page = brainpainter.export(VALUES, out / "brain.html", atlas="dk", hide=["cerebellum"], label="z",
                               title="<test & page>", **SCALE)
    return glb, page


def test_glb_has_one_named_mesh_per_region_in_its_colour(exported):
    import trimesh

    glb, _ = exported
    scene = trimesh.load(glb, file_type="glb")
    atlas = get_atlas("dk")
    cortical = {r.key for r in atlas.regions if r.kind == "cortical"}
    hidden = {"Left-Cerebellum-Cortex", "Right-Cerebellum-Cortex", "Left-Cerebellum-White-Matter",
              "Right-Cerebellum-White-Matter"}
    names = set(scene.geometry)
    assert cortical <= names
    assert {"Left-medial-wall", "Right-medial-wall"} <= names
    assert "Left-Hippocampus" in names and "Brain-Stem" in names and not hidden & names
    assert len(scene.geometry) == len(scene.graph.nodes_geometry)  # one node per mesh
    for name, mesh in scene.geometry.items():
        rgb = np.round(linear_to_srgb(np.asarray(mesh.visual.material.baseColorFactor[:3]) / 255) * 255)
        want = EXPECTED.get(name, MISSING if name in {r.key for r in atlas.regions} else None)
        if want is not None:
            assert np.abs(rgb - want).max() <= 6, (name, rgb, want)  # 8-bit linear colour: rounding
        assert len(mesh.faces) > 0
    nodes = {n["name"]: n for n in glb_json(glb.read_bytes())["nodes"]}
    assert nodes["Left-precentral"]["extras"] == {"part": "lh", "color": "#00ff00", "value": "1"}
    assert nodes["Left-insula"]["extras"]["value"] == "no value"
    assert "value" not in nodes["Left-medial-wall"]["extras"]
    assert nodes["Right-insula"]["extras"]["part"] == "rh"
    # RAS millimetres turned y-up: the left hemisphere has x < 0, the top of the brain is +y
    lh = scene.geometry["Left-superiorfrontal"].vertices
    assert lh[:, 0].mean() < 0 and lh[:, 1].mean() > scene.geometry["Left-Hippocampus"].vertices[:, 1].mean()


def test_export_errors_are_one_line_and_write_nothing(tmp_path, capsys):
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula\na,1\nb,2\n")
    for args, message in [
        ([str(table), "--out", str(tmp_path / "x.glb")], "the table has 2 rows"),
        ([str(table), "--row", "c", "--out", str(tmp_path / "x.glb")], "'c' is not an image name"),
        ([str(table), "--row", "a", "--out", str(tmp_path / "x.obj")], "format must be one of"),
    ]:
        with pytest.raises(SystemExit) as exit_:
            main(["export", *args])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and message in err and err.count("\n") == 1
    assert not list(tmp_path.glob("x.*"))
    with pytest.raises(BrainPainterError, match="row= in Python"):
        brainpainter.export(table, tmp_path / "y.glb")


def test_export_cli_writes_glb_by_suffix(tmp_path, capsys):
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula\na,1\nb,2\n")
    with pytest.raises(SystemExit) as exit_:
        main(["export", str(table), "--row", "b", "--out", str(tmp_path / "b.glb"), "--cmap", "viridis"])
    assert exit_.value.code == 0 and "glb written to" in capsys.readouterr().out
    assert (tmp_path / "b.glb").read_bytes()[:4] == b"glTF"


CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")


@pytest.fixture(scope="module")
def browser():
    if not (CHROMIUM.exists() and CHROMEDRIVER.exists()) or not _has_selenium():
        if os.environ.get("CI"):
            pytest.fail("CI needs chromium, chromium-driver (apt) and selenium (the test extra)")
        pytest.skip("headless Chromium (Debian chromium + chromium-driver) or selenium not installed")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    profile = tempfile.mkdtemp(prefix="bp-chromium-")
    for arg in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--enable-unsafe-swiftshader", "--window-size=900,700", f"--user-data-dir={profile}"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def _has_selenium() -> bool:
    import importlib.util

    return importlib.util.find_spec("selenium") is not None


def _load(driver, url: str) -> None:
    driver.get(url)
    deadline = time.monotonic() + 180  # software WebGL on a loaded 2-core machine
    while not driver.execute_script("return window.brainpainterReady === true"):
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
        assert time.monotonic() < deadline, "the viewer did not finish loading in 180 s"
        time.sleep(0.2)


def _screenshot(driver, path: Path) -> np.ndarray:
    from PIL import Image

    driver.save_screenshot(str(path))
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def _count(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int) -> int:
    return int((np.abs(pixels - np.array(rgb)).max(axis=-1) <= tol).sum())


def test_html_renders_in_headless_chromium(exported, browser, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    _, page = exported
    text = page.read_text(encoding="utf-8")
    assert "http://" not in text.split("<script>")[0] and "<script src" not in text  # nothing fetched
    assert "&lt;test &amp; page&gt;" in text
    _load(browser, page.as_uri() + "#flat")
    flat = _screenshot(browser, tmp_path / "flat.png")
    for name, rgb in EXPECTED.items():  # unlit: the exact colours of the regions
        if name.startswith("Left-superior") or name == "Left-precentral":
            assert _count(flat, rgb, 3) > 300, (name, rgb)
    assert _count(flat, MISSING, 3) > 1000
    browser.find_element(By.ID, "flat").click()  # lit: hues of the same colours
    lit = _screenshot(browser, tmp_path / "lit.png")
    for hue, c in {"red": 0, "green": 1, "blue": 2}.items():
        others = [lit[..., o] for o in range(3) if o != c]
        mask = (lit[..., c] > 120) & (lit[..., c] > 2 * others[0]) & (lit[..., c] > 2 * others[1])
        assert mask.sum() > 300, hue
    # the tooltip names the region under the mouse: aim at the superior temporal gyrus
    x, y = browser.execute_script("""
        const v = window.brainpainterViewer, T = window.BPTHREE;
        const m = v.meshes.find((o) => o.name === 'Left-superiortemporal');
        const box = new T.Box3().setFromObject(m), c = box.getCenter(new T.Vector3());
        const hit = m.geometry.attributes.position; let best = null, bd = 1e9;
        for (let i = 0; i < hit.count; i += 7) {  // the vertex nearest the camera near the centre
          const p = new T.Vector3().fromBufferAttribute(hit, i).applyMatrix4(m.matrixWorld);
          const d = p.distanceTo(v.camera.position) + 0.2 * p.distanceTo(c);
          if (d < bd) { bd = d; best = p; }
        }
        best.project(v.camera);
        const r = v.renderer.domElement.getBoundingClientRect();
        return [r.left + (best.x + 1) / 2 * r.width, r.top + (1 - best.y) / 2 * r.height];""")
    canvas = browser.find_element(By.TAG_NAME, "canvas")
    rect = canvas.rect
    ActionChains(browser).move_to_element_with_offset(
        canvas, round(x - rect["x"] - rect["width"] / 2), round(y - rect["y"] - rect["height"] / 2)).perform()
    tip = browser.find_element(By.ID, "tip")
    assert tip.is_displayed() and tip.text == "Left-superiortemporal: 2"  # the region and its value
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, errors


def test_html_of_a_map_shows_its_vertex_colours_in_headless_chromium(browser, tmp_path):
    from brainpainter.maps.regfusion import fsaverage_mni152

    # fsaverage5's left hemisphere: anterior vertices +1 (red), posterior -1 (blue)
    y = fsaverage_mni152()["lh"][:10242, 1]
    values = np.where(y > np.median(y), 1.0, -1.0)
    page = brainpainter.export({"lh": values}, tmp_path / "map.html", gradient="blue,red", vmin=-1, vmax=1)
    _load(browser, page.as_uri() + "#flat")
    flat = _screenshot(browser, tmp_path / "map.png")
    red, blue = _count(flat, (255, 0, 0), 3), _count(flat, (0, 0, 255), 3)
    assert red > 1000 and blue > 1000, (red, blue)  # per-vertex colours, unlit: exactly the scale's
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, errors


def test_compact_glb_is_quantised_without_normals_and_close_to_the_plain_one():
    from brainpainter.media.glb import RegionMesh, glb_bytes

    rng = np.random.default_rng(0)
    verts = rng.uniform(-70, 70, (300, 3)).astype(np.float32)
    faces = rng.integers(0, 300, (500, 3)).astype(np.int32)
    normals = np.tile(np.float32([0, 0, 1]), (300, 1))
    mesh = RegionMesh("Left-insula", "lh", verts, faces, normals, (1.0, 0.0, 0.0), value="2.5")
    plain, compact = glb_bytes([mesh]), glb_bytes([mesh], compact=True)
    doc = glb_json(compact)
    assert doc["extensionsRequired"] == ["KHR_mesh_quantization"]
    prim = doc["meshes"][0]["primitives"][0]
    assert set(prim["attributes"]) == {"POSITION"}  # normals: computed by the viewer
    position = doc["accessors"][prim["attributes"]["POSITION"]]
    assert position["componentType"] == 5122 and doc["bufferViews"][position["bufferView"]]["byteStride"] == 8
    assert doc["accessors"][prim["indices"]]["componentType"] == 5123  # uint16
    assert doc["nodes"][0]["extras"] == {"part": "lh", "color": "#ff0000", "value": "2.5"}
    assert len(compact) < 0.6 * len(plain)  # 8 bytes a vertex, not 24
    # decoded by hand: the same triangles, within half a quantisation step
    n = struct.unpack("<I", compact[12:16])[0]
    binary = compact[20 + n + 8:]
    view = doc["bufferViews"][position["bufferView"]]
    q = np.frombuffer(binary, np.int16, position["count"] * 4, view["byteOffset"]).reshape(-1, 4)[:, :3]
    iview = doc["bufferViews"][doc["accessors"][prim["indices"]]["bufferView"]]
    idx = np.frombuffer(binary, np.uint16, 1500, iview["byteOffset"]).reshape(-1, 3)
    node = doc["nodes"][0]
    got = q[idx] * node["scale"][0] + node["translation"]
    want = verts[faces] @ np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]).T
    step = 140 / 4096
    assert np.abs(got - want).max() <= 0.51 * step + 1e-4


def test_html_of_the_example_table_is_a_few_mb(tmp_path):
    page = brainpainter.export(Path(__file__).parents[1] / "examples" / "brainpainter_dk.csv",
                               tmp_path / "stage-1.html", row="stage-1")
    assert page.stat().st_size < 4_000_000  # was 12.8 MB: float32 arrays, no compression


def test_viewer_reads_the_packed_glb_exactly_in_headless_chromium(browser, tmp_path):
    from brainpainter.media.export import html_page
    from brainpainter.media.glb import RegionMesh, glb_bytes, packed

    rng = np.random.default_rng(1)
    meshes = []
    for name, n in (("small", 300), ("large", 72_000)):  # uint16 and uint32 indices
        start = np.concatenate([np.arange(0, n, 3), rng.integers(0, n - 2, n // 3)])
        faces = (start[rng.permutation(len(start))][:, None] + np.arange(3)).astype(np.int32)
        # a random walk: each triangle small on screen (software WebGL draws it fast)
        verts = np.cumsum(rng.normal(0, 0.05, (n, 3)), axis=0).astype(np.float32)
        meshes.append(RegionMesh(name, "lh", verts, faces, np.tile(np.float32([0, 0, 1]), (n, 1)), (1, 0, 0)))
    frame = np.float32([[-70, -70, -70], [70, 70, 70], [70, -70, 0]])
    meshes.append(RegionMesh("frame", "lh", frame, np.int32([[0, 1, 2]]), frame, (0, 0, 1)))
    compact = glb_bytes(meshes, compact=True)
    page = tmp_path / "packed.html"
    page.write_text(html_page(packed(compact), title="packed", meshes=meshes, background=None),
                    encoding="utf-8")
    _load(browser, page.as_uri())
    got = browser.execute_script("""
        const hash = (values) => values.reduce((h, v) => (h * 31 + v + 40000) % 1000000007, 0);
        return window.brainpainterViewer.meshes.map((m) => {
          const p = m.geometry.attributes.position, xyz = [];
          for (let i = 0; i < p.count; i++) xyz.push(p.getX(i), p.getY(i), p.getZ(i));
          return [m.name, hash(m.geometry.index.array), hash(xyz), m.geometry.index.array.BYTES_PER_ELEMENT];
        });""")
    doc, n = glb_json(compact), struct.unpack("<I", compact[12:16])[0]
    binary = compact[20 + n + 8:]
    assert [g[0] for g in got] == ["small", "large", "frame"] and [g[3] for g in got] == [2, 4, 2]
    for (_, index, xyz, size), mesh in zip(got, doc["meshes"], strict=True):
        prim = mesh["primitives"][0]
        ia, pa = doc["accessors"][prim["indices"]], doc["accessors"][prim["attributes"]["POSITION"]]
        want_index = np.frombuffer(binary, np.uint16 if size == 2 else np.uint32, ia["count"],
                                   doc["bufferViews"][ia["bufferView"]]["byteOffset"])
        want_xyz = np.frombuffer(binary, np.int16, 4 * pa["count"],
                                 doc["bufferViews"][pa["bufferView"]]["byteOffset"]).reshape(-1, 4)[:, :3]
        assert (index, xyz) == (_hash(want_index), _hash(want_xyz.reshape(-1)))


def _hash(values: np.ndarray) -> int:
    """The page's hash of a list of integers (as exact as comparing them, without sending them)."""
    h = 0
    for v in values.tolist():
        h = (h * 31 + v + 40000) % 1_000_000_007
    return h
