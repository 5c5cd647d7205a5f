"""Start-up (issue 37): parts built when a view shows them, caches kept between runs and checked."""

from __future__ import annotations

import importlib
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from brainpainter.atlas import installed, registry
from brainpainter.atlas.template import Template, load_template
from brainpainter.io import user_cache
from brainpainter.rendering.mesh_edges import edge_table
from brainpainter.rendering.scene import Scene
from brainpainter.rendering.views import get_view
from brainpainter.testing import fake_distribution, write_tiny_template


@pytest.fixture
def loads(monkeypatch):
    """Which meshes of a template are read: ``[("cortex", "lh"), ("subcortical",), ...]``."""
    calls: list[tuple[str, ...]] = []
    for method in ("cortex", "subcortical", "glass"):
        real = getattr(Template, method)

        def spy(self, *args, _real=real, _name=method):
            calls.append((_name, *(a for a in args if a in ("lh", "rh"))))
            return _real(self, *args)

        monkeypatch.setattr(Template, method, spy)
    return calls


def test_a_lateral_left_view_reads_and_builds_the_left_cortex_only(tmp_path, loads):
    tpl = load_template(write_tiny_template(tmp_path / "tiny"))
    geometry = Scene(tpl, "dk").geometry
    assert loads == []  # palette slots come from the label names: no mesh read yet
    parts = geometry.visible(get_view("lateral-left"))
    assert [p.name for p in parts] == ["cortex-lh"]
    assert loads == [("cortex", "lh")]
    shown = {p.name for p in geometry.visible(get_view("subcortical"))}
    assert shown == {"subcortical", "glass-rh"} and ("cortex", "rh") not in loads


def test_parts_built_for_one_view_equal_those_built_all_at_once(tmp_path):
    """Slots, order and arrays do not depend on which view came first (hidden regions included)."""
    tpl = load_template(write_tiny_template(tmp_path / "tiny"))
    scene = dict(labels="dk", hidden=frozenset({"Left-precuneus", "Right-Hippocampus"}))
    lazy = Scene(tpl, **scene).geometry
    lazy.visible(get_view("medial-right"))
    eager = Scene(load_template(tpl.path), **scene).geometry
    eager_parts = eager.parts
    assert lazy.slot_of == eager.slot_of and lazy.keys == eager.keys
    np.testing.assert_array_equal(lazy.default_rgb, eager.default_rgb)
    assert [p.name for p in lazy.parts] == [p.name for p in eager_parts]
    for a, b in zip(lazy.parts, eager_parts, strict=True):
        for field in ("vertices", "normals", "triangles", "palette_index", "sulc"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert lazy.part_keys == eager.part_keys


def test_a_view_of_hidden_structures_only_still_falls_back_to_the_cortex(tmp_path):
    tpl = load_template(write_tiny_template(tmp_path / "tiny"))
    hidden = frozenset(tpl.subcortical_names())
    parts = Scene(tpl, "dk", hidden=hidden).geometry.visible(get_view("subcortical"))
    assert {p.kind for p in parts} == {"cortex"}


@pytest.mark.render
def test_a_lateral_left_render_is_the_image_of_the_whole_scene():
    """The default template, lateral-left: built lazily, the same pixels as with every part built."""
    pytest.importorskip("bpy")
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings

    colors = {"Left-precentral": (1.0, 0.9, 0.0), "Left-insula": (0.1, 0.3, 0.9)}
    images = []
    for build_all in (False, True):
        with Painter("dk", settings=RenderSettings(320, 240)) as painter:
            if build_all:
                assert len(painter.scene.geometry.parts) == 5
            images.append(painter.paint_colors(colors, get_view("lateral-left")))
    assert (images[0][..., 3] > 0).mean() > 0.3  # a brain was drawn
    np.testing.assert_array_equal(images[0], images[1])


@pytest.mark.render
def test_a_cortex_read_from_the_cache_draws_the_pixels_of_one_computed(monkeypatch):
    """Default template, lateral-left: the part and its edge table read back from the cache give the
    image of a run with no cache (which builds the edge table in the renderer)."""
    pytest.importorskip("bpy")
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.settings import RenderSettings

    colors = {"Left-precentral": (1.0, 0.9, 0.0), "Left-insula": (0.1, 0.3, 0.9)}
    images = []
    for cache in ("off", "on", "on"):  # none; computed and written; read
        monkeypatch.setenv(user_cache.SWITCH_ENV, cache)
        with Painter("dk", settings=RenderSettings(320, 240)) as painter:
            images.append(painter.paint_colors(colors, get_view("lateral-left")))
            (part,) = painter.scene.geometry.visible(get_view("lateral-left"))
            assert (part.edges is None) == (cache == "off")
    assert (images[0][..., 3] > 0).mean() > 0.3  # a brain was drawn
    np.testing.assert_array_equal(images[0], images[1])
    np.testing.assert_array_equal(images[0], images[2])


# -- Blender's lean start (the gpu path) ---------------------------------------------------------

#: Renders the tiny template's lateral-left in one fresh process, a renderer per quality kept open,
#: in the order of argv[2:]; prints, per image, Blender's state after it and the image's digest.
_RENDER_SEQUENCE = """
import hashlib, json, sys
from brainpainter.atlas.template import load_template
from brainpainter.rendering.scene import RenderSettings, Scene
from brainpainter.rendering.views import get_view
from brainpainter_blender import BlenderRenderer

template, renderers, out = load_template(sys.argv[1]), {}, []
for quality in sys.argv[2:]:
    if quality not in renderers:
        renderers[quality] = BlenderRenderer(Scene(template, "dk", settings=RenderSettings(
            96, 72, quality=quality, background=(1.0, 1.0, 1.0))))
    img = renderers[quality].render({"Left-insula": (1.0, 0.0, 0.0), "Left-precuneus": (0.0, 0.0, 1.0)},
                                    get_view("lateral-left")).astype(int)
    import addon_utils, bpy
    from brainpainter_blender import _bpy
    out.append({"ui": hasattr(bpy.types, "VIEW3D_HT_header"), "cycles": addon_utils.check("cycles")[1],
                "blender's own": [bpy.utils.load_scripts.__qualname__,
                                  bpy.utils.load_scripts_extensions.__qualname__,
                                  any(isinstance(f, _bpy._DeferScripts) for f in sys.meta_path)],
                "red": int((img[..., 0] - img[..., 1:3].max(-1) > 60).sum()),
                "blue": int((img[..., 2] - img[..., 0:2].max(-1) > 60).sum()),
                "sha": hashlib.sha256(img.tobytes()).hexdigest()})
for renderer in renderers.values():
    renderer.close()
print(json.dumps(out))
"""


def _render_sequence(tiny: Path, *qualities: str) -> list[dict]:
    import subprocess

    proc = subprocess.run([sys.executable, "-c", _RENDER_SEQUENCE, str(tiny), *qualities],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.render
def test_the_gpu_path_starts_blender_without_its_ui_scripts_or_add_ons(tiny):
    pytest.importorskip("bpy")
    (image,) = _render_sequence(tiny, "default")
    assert (image["ui"], image["cycles"]) == (False, False)
    assert image["blender's own"] == ["load_scripts", "load_scripts_extensions", False]  # the finder gone
    assert image["red"] > 50 and image["blue"] > 50


@pytest.mark.render
def test_cycles_renders_before_and_after_the_gpu_path_in_one_process(tiny):
    """A lean start completed for Cycles draws Cycles' image of a full start; the gpu renderer kept
    open across Blender's factory reset draws its first image again."""
    pytest.importorskip("bpy")
    lean_first = _render_sequence(tiny, "default", "high", "default")
    cycles_first = _render_sequence(tiny, "high", "default")
    assert [(i["ui"], i["cycles"]) for i in lean_first] == [(False, False), (True, True), (True, True)]
    assert lean_first[0]["sha"] == lean_first[2]["sha"] == cycles_first[1]["sha"]
    assert lean_first[1]["sha"] == cycles_first[0]["sha"] != lean_first[0]["sha"]
    assert lean_first[1]["red"] > 50 and lean_first[1]["blue"] > 50


def test_a_run_without_a_progress_bar_does_not_import_tqdm(tiny, tmp_path):
    """``tqdm.auto`` takes ~25 ms CPU to import (its asyncio part): a ``-q`` run needs no bar."""
    import subprocess

    code = ("import sys\n"
            "from brainpainter.rendering.run import render\n"
            "from brainpainter.testing import StandInRenderer, stand_in\n"
            "with stand_in('solid', StandInRenderer.with_(layout='solid', regions=('Left-insula',))) as r:\n"
            "    render({'Left-insula': [0.5]}, 'dk', out=sys.argv[2], template=sys.argv[1], renderer=r,\n"
            "           width=16, height=16, views='lateral-left', progress=sys.argv[3] == 'bar')\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'tqdm'))\n")
    loaded = {}
    for progress in ("quiet", "bar"):
        proc = subprocess.run([sys.executable, "-c", code, str(tiny), str(tmp_path / progress), progress],
                              capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert (tmp_path / progress / "1_lateral-left.png").is_file()
        loaded[progress] = proc.stdout.strip().splitlines()[-1]
    assert loaded["quiet"] == "[]"
    assert "tqdm.auto" in loaded["bar"]


# -- the user's cache folder ---------------------------------------------------------------------
def test_a_cache_file_is_read_back_for_its_key_only():
    user_cache.write("x.json", "key-1", {"a": [1, 2]})
    assert user_cache.read("x.json", "key-1") == {"a": [1, 2]}
    assert user_cache.read("x.json", "key-2") is None
    assert user_cache.read("absent.json", "key-1") is None


@pytest.mark.parametrize("damage", ["value", "truncated", "not json", "huge", "digest"])
def test_a_damaged_cache_file_reads_as_a_miss(damage):
    user_cache.write("x.json", "k", {"a": 1})
    path = user_cache.cache_dir() / "x.json"
    doc = json.loads(path.read_text())
    if damage == "value":  # changed without its digest
        doc["value"] = {"a": 2}
        path.write_text(json.dumps(doc))
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[:20])
    elif damage == "not json":
        path.write_bytes(b"\x00\xff" * 10)
    elif damage == "huge":
        path.write_bytes(b" " * (user_cache.MAX_BYTES + 1))
    else:
        doc["sha256"] = "0" * 64
        path.write_text(json.dumps(doc))
    assert user_cache.read("x.json", "k") is None


def test_caches_off_read_and_write_nothing(monkeypatch):
    monkeypatch.setenv(user_cache.SWITCH_ENV, "off")
    assert user_cache.cache_dir() is None
    user_cache.write("x.json", "k", 1)
    assert user_cache.read("x.json", "k") is None
    monkeypatch.delenv(user_cache.SWITCH_ENV)
    assert user_cache.read("x.json", "k") is None and not (user_cache.cache_dir() / "x.json").exists()


@pytest.mark.skipif(sys.platform != "linux", reason="the shortcut is Linux's")
def test_the_cache_folder_is_platformdirs_one(monkeypatch):
    import platformdirs

    for xdg in (None, "/somewhere/cache"):
        if xdg is None:
            monkeypatch.delenv("XDG_CACHE_HOME")
        else:
            monkeypatch.setenv("XDG_CACHE_HOME", xdg)
        assert str(user_cache.cache_dir()) == platformdirs.user_cache_dir("brainpainter", appauthor=False)


# -- entry points, cached per environment -------------------------------------------------------
@pytest.fixture
def site_folder(tmp_path, monkeypatch):
    """An empty folder on ``sys.path`` (a site-packages), the registries forgotten before and after."""
    folder = tmp_path / "site"
    folder.mkdir()
    monkeypatch.syspath_prepend(str(folder))
    registry.reset_all()
    yield folder
    registry.reset_all()


def _toy(folder, name="toy", target="toy_mod:make"):
    return fake_distribution(folder, "toy-plugin", {"brainpainter.renderers": {name: target}}, {})


def test_a_second_start_reads_no_distribution_metadata(site_folder, monkeypatch):
    import importlib.metadata as md

    _toy(site_folder)
    assert "toy" in registry.renderers.names()
    assert (user_cache.cache_dir() / installed.CACHE_FILE).is_file()
    registry.reset_all()  # as a new process: the cache file only

    def refuse(**kwargs):
        raise AssertionError("importlib.metadata was asked")

    monkeypatch.setattr(md, "entry_points", refuse)
    assert "toy" in registry.renderers.names() and "dk" in registry.atlases.names()
    assert registry.renderers.entries()[-1].distribution == "toy-plugin"


@pytest.mark.parametrize("change", ["install", "edit", "remove"])
def test_the_entry_point_cache_follows_installs(site_folder, change):
    dist = _toy(site_folder) / "toy_plugin-0.1.0.dist-info"
    assert "toy" in registry.renderers.names()
    if change == "install":
        fake_distribution(site_folder, "other", {"brainpainter.renderers": {"other": "o:x"}}, {})
        expected = {"toy", "other"}
    elif change == "edit":  # the same folder, its entry_points.txt rewritten
        text = (dist / "entry_points.txt").read_text().replace("toy = ", "toy2 = ")
        st = os.stat(dist / "entry_points.txt")
        (dist / "entry_points.txt").write_text(text)
        os.utime(dist / "entry_points.txt", ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
        expected = {"toy2"}
    else:
        for f in dist.iterdir():
            f.unlink()
        dist.rmdir()
        expected = set()
    # importlib.metadata keeps a folder's listing by the folder's mtime, which the kernel's coarse clock
    # (a few ms) may leave unchanged by a change this fast: a new process would not have that listing
    importlib.invalidate_caches()
    registry.reset_all()
    # (other tests' renderers registered in this process, e.g. the conformance suite's, are not ours)
    assert set(registry.renderers.names()) & {"toy", "toy2", "other"} == expected


def test_a_corrupt_entry_point_cache_is_read_again(site_folder):
    _toy(site_folder)
    registry.renderers.names()
    path = user_cache.cache_dir() / installed.CACHE_FILE
    doc = json.loads(path.read_text())
    doc["value"]["brainpainter.renderers"].append(["evil", "os:system", "x"])  # digest no longer fits
    path.write_text(json.dumps(doc))
    registry.reset_all()
    assert "evil" not in registry.renderers.names() and "toy" in registry.renderers.names()
    assert "evil" not in path.read_text()  # written again


def test_a_cache_of_the_wrong_shape_is_read_again(site_folder):
    _toy(site_folder)
    registry.renderers.names()
    key = f"{'|'.join(registry.GROUPS)}:{installed.environment_key()}"
    user_cache.write(installed.CACHE_FILE, key, {"brainpainter.renderers": [["toy"]]})  # a valid digest
    registry.reset_all()
    assert "toy" in registry.renderers.names() and "dk" in registry.atlases.names()


# -- the command line: Mesa's compiled shaders in the user's cache folder -----------------------
def test_a_run_keeps_mesas_shaders_in_brainpainters_cache_folder(monkeypatch):
    from brainpainter.cli.guard import private_temp

    for var in ("MESA_SHADER_CACHE_DIR", "MESA_SHADER_CACHE_DISABLE", user_cache.CACHE_ENV, "XDG_CACHE_HOME"):
        monkeypatch.delenv(var, raising=False)
    folder = user_cache.cache_dir()
    assert str(folder).startswith(os.environ["HOME"])
    with private_temp() as root:
        assert os.environ["MESA_SHADER_CACHE_DIR"] == str(folder / "mesa-shaders")
        assert "MESA_SHADER_CACHE_DISABLE" not in os.environ
        assert os.environ["XDG_CACHE_HOME"].startswith(root)
        assert user_cache.cache_dir() == folder  # not the run's temporary folder
    assert "MESA_SHADER_CACHE_DIR" not in os.environ and user_cache.CACHE_ENV not in os.environ
    monkeypatch.setenv(user_cache.SWITCH_ENV, "off")
    with private_temp():
        assert os.environ["MESA_SHADER_CACHE_DISABLE"] == "true" and "MESA_SHADER_CACHE_DIR" not in os.environ


# -- memory --------------------------------------------------------------------------------------
def test_a_serial_run_holds_one_painted_image_besides_the_png_writers(tmp_path, tiny, monkeypatch):
    """A chunk's images were all held until the chunk ended (8 of 1200x900: 35 MB of the peak)."""
    import weakref

    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.run import render
    from brainpainter.testing import stand_in

    alive, most = [0], [0]
    real = Painter.paint_colors

    def counted(self, colors, view):
        pixels = real(self, colors, view)
        alive[0] += 1
        most[0] = max(most[0], alive[0])
        weakref.finalize(pixels, lambda: alive.__setitem__(0, alive[0] - 1))
        return pixels

    monkeypatch.setattr(Painter, "paint_colors", counted)
    table = {f"r{i}": {"Left-insula": float(i)} for i in range(20)}
    with stand_in("solid"):
        render(table, "dk", out=tmp_path / "o", template=str(tiny), renderer="solid", progress=False,
               views=["lateral-left", "medial-left"])
    assert len(list((tmp_path / "o").glob("*.png"))) == 40
    assert most[0] <= 3  # the one just painted and the PNG writer's two


# -- a region scene's cortex parts, kept between runs --------------------------------------------
def _left(path, **scene):
    """The tiny template's left cortex part, from a new template object (as a new process)."""
    return Scene(load_template(path), "dk", **scene).geometry.visible(get_view("lateral-left"))[0]


@pytest.fixture
def builds(monkeypatch):
    """How many parts were computed (not read from the cache)."""
    from brainpainter.rendering import lazy_parts

    count = [0]
    real = lazy_parts.build_part

    def counted(*args, **kwargs):
        count[0] += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(lazy_parts, "build_part", counted)
    return count


def _same(a, b):
    for field in ("vertices", "normals", "triangles", "palette_index", "sulc", "hull", "occlusion",
                  "outline"):
        x, y = getattr(a, field), getattr(b, field)
        assert (x is None) == (y is None), field
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=field)
            assert x.dtype == y.dtype or field == "hull", field
    for part in (a, b):  # a part from the cache holds its edge table: the one its arrays give
        if part.edges is not None:
            _same_edges(part.edges, edge_table(part.vertices, part.triangles, part.palette_index))


def _same_edges(a, b):
    for field in ("ends", "faces", "border", "normals"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)


def test_a_second_run_reads_the_cortex_part_it_computed(tmp_path, builds):
    path = write_tiny_template(tmp_path / "tiny")
    first = _left(path)
    assert builds[0] == 1 and len(list((user_cache.cache_dir() / "parts").glob("*.npz"))) == 1
    again = _left(path)
    assert builds[0] == 1  # read, not computed
    _same(first, again)


def test_a_cortex_part_keeps_its_edge_table(tmp_path, builds, monkeypatch):
    """The anti-aliasing's edge table is read with the part, not built again by the renderer."""
    from brainpainter_blender import edge_aa

    path = write_tiny_template(tmp_path / "tiny")
    first = _left(path)
    again = _left(path)
    assert builds[0] == 1 and first.edges is not None and again.edges is not None
    _same_edges(again.edges, edge_table(again.vertices, again.triangles, again.palette_index))
    monkeypatch.setattr(edge_aa, "edge_table", lambda *a: pytest.fail("edge table built again"))
    assert edge_aa.EdgeAA(8, 8, None)._table(again) is again.edges


@pytest.mark.parametrize("change", ["template file", "hidden", "surface", "shading"])
def test_the_part_cache_follows_what_the_part_depends_on(tmp_path, builds, change):
    from brainpainter.rendering.settings import RenderSettings

    path = write_tiny_template(tmp_path / "tiny")
    _left(path)
    scene: dict = {}
    if change == "template file":  # the same name, size and time: the bytes differ
        file = path / "cortex-lh-dk.npz"
        st = os.stat(file)
        with np.load(file) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["pial"] = arrays["pial"] * np.float32(1.5)
        np.savez(file, **arrays)
        os.utime(file, ns=(st.st_atime_ns, st.st_mtime_ns))
    elif change == "hidden":
        scene["hidden"] = frozenset({"Left-insula"})
    elif change == "surface":
        scene["surface"] = "inflated"
    else:
        scene["settings"] = RenderSettings(shading="flat")
    got = _left(path, **scene)
    assert builds[0] == 2
    with pytest.MonkeyPatch.context() as m:
        m.setenv(user_cache.SWITCH_ENV, "off")
        _same(got, _left(path, **scene))  # as computed without any cache


@pytest.mark.parametrize("damage", ["truncated", "noise", "changed array", "slot out of range",
                                   "triangle out of range", "edge out of range",
                                   "edge triangle out of range", "no edge table", "pickle", "huge"])
def test_a_damaged_part_file_is_computed_again(tmp_path, builds, damage):
    from brainpainter.rendering import part_cache

    path = write_tiny_template(tmp_path / "tiny")
    first = _left(path)
    (file,) = (user_cache.cache_dir() / "parts").glob("*.npz")
    with np.load(file) as z:
        arrays = {k: z[k] for k in z.files if k != "digest"}
    if damage == "truncated":
        file.write_bytes(file.read_bytes()[:1000])
    elif damage == "noise":
        file.write_bytes(os.urandom(5000))
    elif damage == "changed array":  # the old digest
        data = file.read_bytes()
        with np.load(file) as z:
            digest = z["digest"]
        arrays["vertices"][0] += 1
        np.savez(file, digest=digest, **arrays)
        assert data != file.read_bytes()
    elif damage in ("slot out of range", "triangle out of range", "edge out of range",
                    "edge triangle out of range", "no edge table"):  # a digest that fits: checked anyway
        if damage == "slot out of range":
            arrays["palette_index"][0] = 10**6
        elif damage == "triangle out of range":
            arrays["triangles"][0, 0] = len(arrays["vertices"])
        elif damage == "edge out of range":
            arrays["edge_ends"][0, 1] = len(arrays["vertices"])
        elif damage == "edge triangle out of range":
            arrays["edge_faces"][-1, 1] = len(arrays["triangles"])
        else:  # a file of the first format
            arrays = {k: v for k, v in arrays.items() if k not in ("edge_ends", "edge_faces", "edge_border",
                                                                   "face_normals")}
        np.savez(file, digest=np.array(part_cache._digest(arrays)), **arrays)
    elif damage == "pickle":
        np.savez(file, digest=np.array("x"), **{**arrays, "vertices": np.array([object()], dtype=object)})
    else:
        file.write_bytes(b"\0" * (9 * (path / "cortex-lh-dk.npz").stat().st_size + (1 << 20)))
    again = _left(path)
    assert builds[0] == 2
    _same(first, again)
    _left(path)
    assert builds[0] == 2  # written again, valid


def test_caches_off_keep_no_part(tmp_path, builds, monkeypatch):
    monkeypatch.setenv(user_cache.SWITCH_ENV, "off")
    path = write_tiny_template(tmp_path / "tiny")
    _left(path)
    _left(path)
    assert builds[0] == 2 and not (Path(os.environ["XDG_CACHE_HOME"]) / "brainpainter").exists()


def test_the_part_cache_keeps_the_newest_files_only(tmp_path, monkeypatch):
    from brainpainter.rendering import part_cache

    monkeypatch.setattr(part_cache, "MAX_FILES", 2)
    path = write_tiny_template(tmp_path / "tiny")
    for hidden in ("insula", "precuneus", "superiorfrontal"):
        _left(path, hidden=frozenset({f"Left-{hidden}"}))
    assert len(list((user_cache.cache_dir() / "parts").glob("*.npz"))) == 2
