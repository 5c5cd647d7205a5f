"""Helpers for testing brainpainter plugins (usable from any pytest suite).

``fake_distribution`` writes a minimal installed distribution (a package plus
its ``.dist-info`` with ``entry_points.txt``) into a folder, exactly what pip
would leave in site-packages; put that folder on ``sys.path`` and call
:func:`brainpainter.atlas.registry.reset_all` to make the registries see it.

For atlas plugin authors: :func:`check_atlas` runs every check brainpainter
makes of an atlas (it loads through the registry, its label set fits the
template, every region has faces or a subcortical mesh, a table naming every
region renders with 0 unmatched columns) using :class:`StandInRenderer`, a
renderer without Blender. In a plugin's ``tests/conftest.py``::

    pytest_plugins = ["brainpainter.testing"]   # fixtures: brainpainter_home, stand_in_renderer

and in a test::

    from brainpainter.testing import check_atlas

    def test_my_atlas(brainpainter_home):
        report = check_atlas("myatlas")
        assert report["n_cortical"] == {"lh": 7, "rh": 7}
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, ClassVar


def fake_distribution(
    root: Path,
    name: str,
    entry_points: Mapping[str, Mapping[str, str]],
    files: Mapping[str, str],
    version: str = "0.1.0",
) -> Path:
    """Write an installed distribution into `root`.

    Parameters
    ----------
    root : Path
        Folder that will go on ``sys.path`` (like site-packages).
    name : str
        Distribution name.
    entry_points : mapping
        ``{group: {entry name: "module:attr"}}``.
    files : mapping
        ``{relative path: text}`` of the package's files.
    """
    root.mkdir(parents=True, exist_ok=True)
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    dist = root / f"{name.replace('-', '_')}-{version}.dist-info"
    dist.mkdir(exist_ok=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    lines = []
    for group, entries in entry_points.items():
        lines.append(f"[{group}]")
        lines.extend(f"{k} = {v}" for k, v in entries.items())
        lines.append("")
    (dist / "entry_points.txt").write_text("\n".join(lines))
    return root


@contextmanager
def installed(root: Path) -> Iterator[None]:
    """Put `root` on ``sys.path`` and refresh the registries for the duration."""
    from brainpainter.atlas import registry
    sys.path.insert(0, str(root))
    registry.reset_all()
    try:
        yield
    finally:
        sys.path.remove(str(root))
        for mod in [m for m, v in sys.modules.items() if str(root) in str(getattr(v, "__file__", "") or "")]:
            del sys.modules[mod]
        registry.reset_all()


def pip_install(src: Path, target: Path, scratch: Path) -> Path:
    """Install the distribution in folder `src` into `target` with pip (no index, no dependencies).

    `src` is copied to `scratch` first (without build leftovers), so the
    source tree is left as it was. Returns `target`, for :func:`installed`.
    """
    import shutil
    import subprocess

    copy = Path(scratch) / Path(src).name
    shutil.copytree(src, copy, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--no-index", "--target", str(target), str(copy)],
        check=True, capture_output=True,
    )
    return Path(target)


def write_tiny_template(path: Path, labels: Mapping[str, tuple[str, ...]] | None = None) -> Path:
    """Write a small synthetic template (two icospheres, two boxes, glass spheres).

    Each hemisphere is an icosphere of radius 50 mm centred at x = -/+ 60 mm,
    split into the given label names by angle around the y axis (the first
    name on the anterior pole side). Subcortical: ``Left-Hippocampus`` and
    ``Right-Hippocampus`` boxes. Meant for fast tests of renderers and the
    core; coordinates are RAS millimetres like a real template.

    Parameters
    ----------
    path : Path
        Folder to create.
    labels : mapping of label-set name to label names, optional
        Default: ``{"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}``.
    """
    import json

    import numpy as np
    import trimesh

    from brainpainter.atlas.template import FORMAT, FORMAT_VERSION

    labels = labels or {"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}
    path.mkdir(parents=True, exist_ok=True)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=50.0)
    verts0 = np.asarray(sphere.vertices, dtype=np.float32)
    faces = np.asarray(sphere.faces, dtype=np.int32)
    centroids = verts0[faces].mean(axis=1)
    angle = np.arctan2(centroids[:, 2], centroids[:, 1])  # around the x axis, 0 = anterior
    manifest: dict = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "name": "tiny",
        "source": {"subject": "synthetic", "freesurfer_version": "none"},
        "space": "RAS millimetres", "surfaces": ["pial", "white", "inflated"],
        "labels": {}, "bounds": {}, "license": "CC0", "attribution": "synthetic",
    }
    offsets = {"lh": -60.0, "rh": 60.0}
    for name, names in labels.items():
        bins = np.linspace(-np.pi, np.pi, len(names) + 1)
        face_label = (np.clip(np.digitize(-angle, bins) - 1, 0, len(names) - 1)).astype(np.int16)
        manifest["labels"][name] = {"source": "synthetic", "cortex": {}}
        for hemi, dx in offsets.items():
            verts = verts0 + np.array([dx, 0, 0], np.float32)
            file = f"cortex-{hemi}-{name}.npz"
            np.savez_compressed(path / file, faces=faces, face_label=face_label, pial=verts,
                                white=verts * 0.95, inflated=verts + np.float32(np.sign(dx) * 10),
                                source_vertex=np.arange(len(verts), dtype=np.int32))
            manifest["labels"][name]["cortex"][hemi] = {
                "file": file, "names": list(names), "n_vertices": len(verts),
                "n_faces": len(faces), "open_edges": 0}
    boxes = [trimesh.creation.box(extents=(10, 20, 10)).apply_translation((dx / 3, 0, 0))
             for dx in offsets.values()]
    sub_v = np.concatenate([b.vertices for b in boxes]).astype(np.float32)
    sub_f = np.concatenate([boxes[0].faces, boxes[1].faces + len(boxes[0].vertices)]).astype(np.int32)
    sub_l = np.repeat(np.arange(2, dtype=np.int16), [len(b.faces) for b in boxes])
    np.savez_compressed(path / "subcortical.npz", vertices=sub_v, faces=sub_f, face_label=sub_l)
    manifest["subcortical"] = {"file": "subcortical.npz", "structures": [
        {"name": "Left-Hippocampus", "index": 17}, {"name": "Right-Hippocampus", "index": 53}]}
    manifest["glass"] = {}
    for hemi, dx in offsets.items():
        glass = trimesh.creation.icosphere(subdivisions=2, radius=52.0).apply_translation((dx, 0, 0))
        np.savez_compressed(path / f"glass-{hemi}.npz", vertices=glass.vertices.astype(np.float32),
                            faces=glass.faces.astype(np.int32))
        manifest["glass"][hemi] = {"file": f"glass-{hemi}.npz", "n_faces": len(glass.faces)}
    lo = (verts0 + np.array([-60, 0, 0])).min(axis=0).tolist()
    hi = (verts0 + np.array([60, 0, 0])).max(axis=0).tolist()
    manifest["bounds"] = {"pial": [lo, hi]}
    (path / "manifest.json").write_text(json.dumps(manifest, indent=1))
    return path


class StandInRenderer:
    """A renderer without Blender, for tests: paints what a real one would, as stripes.

    Loading checks what a real renderer needs: the scene's label set exists on
    both hemispheres and the surface is there. Each image shows the faces of
    the view's structures sampled evenly (grouped by label), each in the
    colour the real renderer would give it (medial wall / neutral grey when
    the key has no colour). ``StandInRenderer.calls`` records ``(colors, view)``.
    """

    calls: ClassVar[list[tuple[dict, Any]]] = []

    def __init__(self, scene: Any) -> None:
        import numpy as np

        self.scene = scene
        self.parts: dict[str, tuple[list[str], np.ndarray]] = {}
        for hemi in ("lh", "rh"):
            cm = scene.template.cortex(scene.labels, hemi)
            if scene.surface not in cm.vertices:
                raise AssertionError(f"template {scene.template.name!r} has no {scene.surface} surface")
            prefix = {"lh": "Left-", "rh": "Right-"}[hemi]
            self.parts[hemi] = ([prefix + n for n in cm.label_names], np.sort(cm.face_label))
        if scene.template.manifest.get("subcortical"):
            sub = scene.template.subcortical()
            self.parts["subcortical"] = (list(sub.label_names), np.sort(sub.face_label))

    def painted(self, colors: Mapping[str, Any], part: str) -> dict[str, Any]:
        """Label key -> colour drawn (None: default colour) for one part (``lh``, ``rh``, ``subcortical``)."""
        keys, labels = self.parts[part]
        return {keys[i]: colors.get(keys[i]) for i in sorted(set(labels.tolist()))
                if keys[i] not in self.scene.hidden}

    def render(self, colors: Mapping[str, Any], view: Any) -> Any:
        import numpy as np

        type(self).calls.append((dict(colors), view))
        s = self.scene.settings
        from brainpainter.rendering.framing import shows

        kinds = {"lh": ("cortex", "lh"), "rh": ("cortex", "rh"), "subcortical": ("subcortical", None)}
        parts = [p for p, (kind, hemi) in kinds.items() if shows(view, kind, hemi)]
        default = {"subcortical": (0.8, 0.8, 0.8)}
        stripes = []
        for part in parts:
            keys, labels = self.parts.get(part, ([], np.zeros(0, int)))
            for i in labels:
                if keys[i] in self.scene.hidden:
                    continue
                rgb = colors.get(keys[i]) or default.get(part, self.scene.medial_wall_color)
                stripes.append(rgb)
        img = np.zeros((s.height, s.width, 4), np.uint8)
        if stripes:
            cols = np.asarray(stripes, dtype=float)[np.linspace(0, len(stripes) - 1, s.width).astype(int)]
            img[..., :3] = np.round(cols[None, :, :3] * 255).astype(np.uint8)
            img[..., 3] = 255
        return img

    def close(self) -> None:
        pass


@contextmanager
def registered_renderer(name: str, cls: type) -> Iterator[str]:
    """Register renderer class `cls` under `name` for the duration; yields `name`."""
    from brainpainter.atlas import registry
    registry.renderers.register(name, lambda: cls, replace=True)
    try:
        yield name
    finally:
        registry.renderers.unregister(name)


@contextmanager
def stand_in(name: str = "stand-in") -> Iterator[str]:
    """Register :class:`StandInRenderer` as renderer `name` for the duration."""
    StandInRenderer.calls = []
    with registered_renderer(name, StandInRenderer) as registered:
        yield registered


def check_atlas(atlas: Any, template: str | Path = "fsaverage") -> dict[str, Any]:
    """Check an atlas the way brainpainter uses it; raise AssertionError listing every problem.

    Parameters
    ----------
    atlas : str or Atlas
        Registry name (loads it through the registry, as ``--atlas NAME`` does) or an Atlas.
    template : str or path
        Template to draw it on.

    Returns
    -------
    dict
        ``atlas``, ``template``, ``label_set``, ``n_cortical`` (per hemisphere),
        ``n_subcortical``, ``n_regions_matched``, ``unmatched_columns``.
    """
    import numpy as np

    from brainpainter.atlas import registry
    from brainpainter.atlas.model import Atlas
    from brainpainter.atlas.template import load_template, template_for
    from brainpainter.rendering.run import render

    a: Atlas = registry.atlases.get(atlas) if isinstance(atlas, str) else atlas
    problems: list[str] = []
    tpl = template_for(a, load_template(template))
    if a.template_labels not in tpl.label_sets:
        raise AssertionError(f"atlas {a.name!r}: template {tpl.name!r} has no label set "
                             f"{a.template_labels!r} (it has {tpl.label_sets}) and the atlas brings none "
                             "(labels.json)")
    with_faces: set[str] = set()
    for hemi, prefix in (("lh", "Left-"), ("rh", "Right-")):
        cm = tpl.cortex(a.template_labels, hemi)
        with_faces |= {prefix + cm.label_names[i] for i in np.unique(cm.face_label).tolist()}
    subcortical = set(tpl.subcortical().label_names) if tpl.manifest.get("subcortical") else set()
    for r in a.regions:
        drawn = with_faces if r.kind == "cortical" else subcortical
        missing = [k for k in a.member_keys(r.key) if k not in drawn]
        if missing:
            problems.append(f"region {r.key!r} has nothing to draw on template {tpl.name!r} "
                            f"({', '.join(missing)} missing)")
    data = {r.key: float(i) for i, r in enumerate(a.regions)}
    with stand_in() as renderer:
        result = render(data, a, template=tpl, renderer=renderer, width=32, height=24,
                        views="lateral-left,medial-right,subcortical", progress=False)
    summary = result.manifest["input"]
    if summary["unmatched_columns"]:
        problems.append(f"region keys that do not read back as regions: {summary['unmatched_columns']}")
    if summary["n_regions_matched"] != len(a.regions):
        problems.append(f"{summary['n_regions_matched']} of {len(a.regions)} region keys matched")
    if problems:
        raise AssertionError(f"atlas {a.name!r}: " + "; ".join(problems))
    return {
        "atlas": a.name, "template": tpl.name, "label_set": a.template_labels,
        "n_cortical": {h: len(a.cortical(h)) for h in ("lh", "rh")}, "n_subcortical": len(a.subcortical()),
        "n_regions_matched": summary["n_regions_matched"], "unmatched_columns": summary["unmatched_columns"],
    }


# -- renderer conformance ------------------------------------------------------------------
#: Distinct flat colours of the tiny template's regions (sRGB 0-1).
_CONFORMANCE_COLORS = {
    "Left-insula": (0.90, 0.10, 0.10), "Left-precuneus": (0.10, 0.75, 0.20),
    "Left-superiorfrontal": (0.15, 0.25, 0.95), "Left-unknown": (0.95, 0.85, 0.10),
    "Right-insula": (0.85, 0.15, 0.85), "Right-precuneus": (0.10, 0.80, 0.85),
    "Right-superiorfrontal": (1.00, 0.55, 0.05), "Right-unknown": (0.45, 0.20, 0.70),
    "Left-Hippocampus": (0.60, 0.05, 0.05), "Right-Hippocampus": (0.05, 0.35, 0.60),
}
CONFORMANCE_CHECKS = ("orientation", "flat_colors", "nan_missing", "transparent", "glass", "no_holes",
                      "repeatable", "memory")


def _near(img: Any, rgb: Any, tol: float) -> Any:
    import numpy as np

    target = np.round(np.asarray(rgb, dtype=float)[:3] * 255)
    return np.abs(img[..., :3].astype(float) - target).max(axis=-1) <= tol


def _expected_layout(scene: Any, view: Any, width: int, height: int) -> dict[int, tuple[Any, float]]:
    """Per palette slot: area-weighted pixel centroid and pixel area of its faces facing the camera."""
    import numpy as np

    from brainpainter.rendering import framing
    geometry = scene.geometry
    pose = geometry.camera(view, width / height)
    px_per_mm = width / pose.ortho_scale
    out: dict[int, tuple[Any, float]] = {}
    for part in geometry.visible(view):
        if part.kind == "glass":
            continue
        tri = part.triangles.astype(np.int64)
        v = part.vertices.astype(float)
        cross = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
        area = np.clip(cross @ pose.back, 0.0, None) / 2.0 * px_per_mm**2  # projected, pixels
        centre = framing.to_pixels(v[tri].mean(axis=1), pose, width, height)
        slot = part.palette_index[tri[:, 0]]
        for s in np.unique(slot):
            m = (slot == s) & (area > 0)
            if m.any():
                out[int(s)] = ((centre[m] * area[m, None]).sum(axis=0) / area[m].sum(), float(area[m].sum()))
    return out


def check_renderer(renderer: str | type, size: tuple[int, int] = (160, 120),
                   checks: tuple[str, ...] = CONFORMANCE_CHECKS, n_memory: int = 200) -> dict[str, Any]:
    """Check a renderer against the renderer contract (``docs/renderers.md``).

    Raises AssertionError listing every failure.

    Renders :func:`write_tiny_template` (two labelled spheres, two boxes, glass
    spheres) and checks, without a GPU where the renderer needs none:

    ``orientation``
        every preset view puts each region where core's camera
        (:meth:`brainpainter.rendering.geometry.SceneGeometry.camera`) projects it, and
        the drawn silhouette fills the framed rectangle;
    ``flat_colors``
        ``shading="flat"`` draws every colour exactly (to 1/255), also inside
        anti-aliased images;
    ``nan_missing``
        through :class:`brainpainter.rendering.painter.Painter`, NaN values and absent
        regions get the scale's colours exactly;
    ``transparent``
        ``background=None`` leaves the background at alpha 0 and the brain opaque;
    ``glass``
        the glass brain is visible and the structures show through it;
    ``no_holes``
        no background pixel inside a silhouette;
    ``repeatable``
        the same palette and view give the same pixels after other images;
    ``memory``
        resident memory stays flat over `n_memory` renders.

    Parameters
    ----------
    renderer : str or type
        Registry name (``"blender"``) or a renderer class.
    size : (int, int)
        Image width and height.
    checks : tuple of str
        Subset of :data:`CONFORMANCE_CHECKS`.
    n_memory : int

    Returns
    -------
    dict
        Check name -> a short measurement (for reports).
    """
    import os
    import tempfile

    import numpy as np
    from scipy import ndimage

    from brainpainter.atlas import registry
    from brainpainter.atlas.template import load_template
    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import PRESETS, get_view

    unknown = [c for c in checks if c not in CONFORMANCE_CHECKS]
    if unknown:
        raise ValueError(f"unknown checks {unknown}; choose from {CONFORMANCE_CHECKS}")
    cls = registry.renderers.get(renderer) if isinstance(renderer, str) else renderer
    name = renderer if isinstance(renderer, str) else getattr(cls, "__name__", str(cls))
    width, height = size
    white = (1.0, 1.0, 1.0)
    problems: list[str] = []
    report: dict[str, Any] = {}

    with tempfile.TemporaryDirectory(prefix="bp-conformance-") as tmp:
        template = load_template(write_tiny_template(Path(tmp) / "tiny"))

        def make(**kw: Any) -> tuple[Any, Any]:
            scene = Scene(template, "dk", settings=RenderSettings(width=width, height=height, **kw))
            return scene, cls(scene)

        def paint(scene: Any, r: Any, colors: Any, view: Any) -> Any:
            img = np.asarray(r.render(Palette(colors, scene.geometry), view))
            if img.shape != (height, width, 4) or img.dtype != np.uint8:
                raise AssertionError(f"renderer {name!r} returned {img.dtype} {img.shape}, "
                                     f"not uint8 {(height, width, 4)}")
            return img

        palette_rgb = [*_CONFORMANCE_COLORS.values()]
        if {"orientation", "no_holes", "repeatable", "flat_colors"} & set(checks):
            scene, r = make(quality="fast", shading="flat", glass_opacity=0.0, background=white)
            try:
                worst = 0.0
                for view in PRESETS.values():
                    img = paint(scene, r, _CONFORMANCE_COLORS, view)
                    brain = ~_near(img, white, 0)
                    if "orientation" in checks:
                        layout = _expected_layout(scene, view, width, height)
                        rgb_of = scene.geometry.default_rgb.copy()
                        for key, slot in scene.geometry.slot_of.items():
                            if key in _CONFORMANCE_COLORS:
                                rgb_of[slot] = _CONFORMANCE_COLORS[key]
                        for slot, (centre, area) in layout.items():
                            mask = _near(img, rgb_of[slot], 1)
                            if mask.sum() < 0.6 * area or area < 30:  # hidden behind another part
                                continue
                            ys, xs = np.nonzero(mask)
                            err = float(np.hypot(xs.mean() + 0.5 - centre[0], ys.mean() + 0.5 - centre[1]))
                            worst = max(worst, err)
                            if err > 0.04 * width:
                                problems.append(f"orientation: {view.name}: the colour of slot {slot} is "
                                                f"centred {err:.1f} px from where the camera puts it")
                        ys, xs = np.nonzero(brain)
                        if not len(xs):
                            problems.append(f"orientation: {view.name}: nothing was drawn")
                    if "no_holes" in checks and view.content == "cortex" and len(view.hemis) == 1:
                        holes = ndimage.binary_fill_holes(brain) & ~brain
                        if holes.sum():
                            problems.append(f"no_holes: {view.name}: {int(holes.sum())} background "
                                            "pixels inside the silhouette")
                    if "flat_colors" in checks:
                        allowed = np.round(np.array([*palette_rgb, *scene.geometry.default_rgb, white]) * 255)
                        dev = np.abs(img[..., :3].reshape(-1, 1, 3).astype(float) - allowed[None]).max(-1)
                        bad = int((dev.min(axis=1) > 1).sum())
                        if bad:
                            problems.append(f"flat_colors: {view.name}: {bad} pixels are none of the "
                                            "given colours (quality fast, flat shading)")
                report["orientation_worst_px"] = round(worst, 2)
                if "repeatable" in checks:
                    a = paint(scene, r, _CONFORMANCE_COLORS, get_view("lateral-left"))
                    paint(scene, r, {k: (0.5, 0.5, 0.5) for k in _CONFORMANCE_COLORS}, get_view("dorsal"))
                    if not np.array_equal(a, paint(scene, r, _CONFORMANCE_COLORS, get_view("lateral-left"))):
                        problems.append("repeatable: the same palette and view gave different pixels")
            finally:
                r.close()
        if "flat_colors" in checks:
            scene, r = make(quality="default", shading="flat", glass_opacity=0.0, background=white)
            try:
                img = paint(scene, r, _CONFORMANCE_COLORS, get_view("lateral-left"))
                for key in ("Left-insula", "Left-precuneus", "Left-superiorfrontal", "Left-unknown"):
                    rgb = _CONFORMANCE_COLORS[key]
                    core = ndimage.binary_erosion(_near(img, rgb, 40), iterations=3)
                    if core.sum() < 20:
                        problems.append(f"flat_colors: {key} hardly appears in lateral-left")
                    elif not _near(img, rgb, 1)[core].all():
                        problems.append(f"flat_colors: anti-aliased interior of {key} is not exact")
            finally:
                r.close()
        if "nan_missing" in checks:
            scale = make_scale(gradient=["blue", "red"], vmin=0, vmax=1, nan_color="#1f77b4",
                               missing_color="#2ca02c")
            with Painter("dk", template, settings=RenderSettings(width=width, height=height, shading="flat",
                                                                  glass_opacity=0.0),
                         renderer=name if isinstance(renderer, str) else _register_temp(cls)) as painter:
                img = painter.paint({"Left-insula": float("nan"), "Left-precuneus": 1.0},
                                    get_view("lateral-left"), scale)  # Left-superiorfrontal: missing
            for what, rgb in (("NaN", scale.nan_color), ("missing", scale.missing_color),
                              ("value 1", (1.0, 0.0, 0.0))):
                if ndimage.binary_erosion(_near(img, rgb, 1), iterations=2).sum() < 10:
                    problems.append(f"nan_missing: the {what} colour {rgb} is not drawn exactly")
        if "transparent" in checks:
            scene, r = make(quality="default", shading="flat", glass_opacity=0.0, background=None)
            try:
                img = paint(scene, r, _CONFORMANCE_COLORS, get_view("lateral-left"))
            finally:
                r.close()
            alpha = img[..., 3]
            opaque = ndimage.binary_erosion(alpha > 0, iterations=2)
            if alpha[0, 0] or alpha[-1, -1] or alpha[0, -1] or alpha[-1, 0]:
                problems.append("transparent: the background corners are not transparent")
            if opaque.sum() < 100 or (alpha[opaque] != 255).any():
                problems.append("transparent: the brain is not opaque")
            elif not _near(img, _CONFORMANCE_COLORS["Left-insula"], 1)[opaque].any():
                problems.append("transparent: colours change on a transparent background")
        if "glass" in checks:
            scene, bare = make(quality="fast", shading="flat", glass_opacity=0.0, background=white)
            view = get_view("subcortical")
            try:
                ref = paint(scene, bare, _CONFORMANCE_COLORS, view)
            finally:
                bare.close()
            scene, r = make(quality="fast", shading="flat", glass_opacity=0.12, background=white)
            try:
                img = paint(scene, r, _CONFORMANCE_COLORS, view)
            finally:
                r.close()
            inside = ~_near(ref, white, 0)
            glass_only = ~inside & ~_near(img, white, 0)
            report["glass_pixels"] = int(glass_only.sum())
            if glass_only.sum() < 0.05 * width * height:
                problems.append("glass: the glass brain is not drawn around the structures")
            if inside.sum() < 50:
                problems.append("glass: the structures are not drawn in the subcortical view")
            else:  # seen through the glass, each structure keeps its hue (dominant channel)
                kept = (img[..., :3].argmax(-1) == ref[..., :3].argmax(-1))[inside].mean()
                report["glass_hue_kept"] = round(float(kept), 3)
                if kept < 0.9:
                    problems.append(f"glass: the structures do not show through the glass ({kept:.0%} keep "
                                    "their hue)")
        if "memory" in checks and Path("/proc/self/statm").exists():
            def rss_mb() -> float:
                with open("/proc/self/statm") as fh:
                    return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20

            scene, r = make(quality="fast", glass_opacity=0.12, background=white)
            rng = np.random.default_rng(0)
            views = [get_view(n) for n in ("lateral-left", "dorsal", "subcortical")]
            try:
                for i in range(20):
                    paint(scene, r, {"Left-insula": tuple(rng.random(3))}, views[i % 3])
                before = rss_mb()
                for i in range(n_memory):
                    paint(scene, r, {"Left-insula": tuple(rng.random(3))}, views[i % 3])
                grown = rss_mb() - before
            finally:
                r.close()
            report["memory_growth_mb"] = round(grown, 1)
            if grown > 20:
                problems.append(f"memory: resident memory grew by {grown:.1f} MB over {n_memory} renders")
    if problems:
        raise AssertionError(f"renderer {name!r} fails the conformance suite:\n  " + "\n  ".join(problems))
    return report


def _register_temp(cls: type) -> str:
    from brainpainter.atlas import registry
    name = f"conformance-{id(cls)}"
    registry.renderers.register(name, lambda: cls, replace=True)
    return name


try:  # fixtures for plugin test suites: pytest_plugins = ["brainpainter.testing"]
    import pytest as _pytest
except ImportError:  # pragma: no cover - pytest is only needed by test suites
    _pytest = None

if _pytest is not None:

    @_pytest.fixture
    def brainpainter_home(tmp_path: Path, monkeypatch: Any) -> Iterator[Path]:
        """HOME and XDG folders in `tmp_path`: user atlases go there, never to the real home.

        Returns the (not yet created) user-atlas folder.
        """
        from brainpainter.atlas import registry
        from brainpainter.atlas.user import atlases_dir

        home = tmp_path / "home"
        monkeypatch.setenv("HOME", str(home))
        for var, sub in (("XDG_DATA_HOME", ".local/share"), ("XDG_CACHE_HOME", ".cache"),
                         ("XDG_CONFIG_HOME", ".config")):
            monkeypatch.setenv(var, str(home / sub))
        registry.reset_all()
        yield atlases_dir()
        registry.reset_all()

    @_pytest.fixture
    def stand_in_renderer() -> Iterator[str]:
        """Name of a registered :class:`StandInRenderer` (renders without Blender)."""
        with stand_in() as name:
            yield name
