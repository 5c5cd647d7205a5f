"""The renderer conformance suite (``docs/renderers.md``): :func:`check_renderer`.

Renders :func:`~brainpainter.testing.templates.write_tiny_template` (two
labelled spheres, two boxes, glass spheres) and checks, without a GPU where
the renderer needs none:

``orientation``
    every preset view puts each region where core's camera
    (:meth:`brainpainter.rendering.geometry.SceneGeometry.camera`) projects it;
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
``tracts``
    white-matter tracts (parts of kind ``tract``: tubes of two bundles, one per
    hemisphere, one colour each) are drawn in their exact flat colour where the
    camera projects them, in the subcortical views, with the glass brain; a
    renderer's ``draws_tubes`` (absent: True) is a bool, and one that says False
    built no tubes (drew the centrelines);
``memory``
    resident memory does not grow per image (:func:`~brainpainter.testing.memory.growth_per_image`);
``vertex_colors``
    a per-vertex scene (``Scene(coloring="vertices")``, a map) draws each
    vertex's palette slot and interpolates between vertices: a colour ramp
    along the front-back axis is drawn as a smooth ramp, in the right direction.
``outlines``
    with ``outline_width`` set, each cortex part's border segments
    (``PartGeometry.outline``) are drawn in ``outline_color`` as lines of constant
    pixel width: twice the image size, about twice the outline pixels (not four times).
``connectome``
    node spheres and edge cylinders in their flat colours, where the camera puts them
    (:mod:`~brainpainter.testing.connectome_check`).
``clip``
    a view's cutaway planes (``View.clip``) remove the cortex on their side, the cut face is drawn
    closed in ``CAP_COLOR`` and the structure inside shows where the camera puts it
    (:mod:`~brainpainter.testing.clip_check`).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .clip_check import clip_check
from .connectome_check import connectome_check
from .memory import can_measure, growth_per_image
from .pixels import COLORS, WHITE, near
from .templates import write_tiny_template
from .tiny_tracts import tiny_tracts

RGB = tuple[float, float, float]
CONFORMANCE_CHECKS = ("orientation", "flat_colors", "nan_missing", "transparent", "glass", "no_holes",
                      "repeatable", "tracts", "memory", "vertex_colors", "outlines", "connectome", "clip")
#: Colours of the tracts check's two bundles (not among :data:`COLORS`).
TRACT_COLORS: dict[str, RGB] = {"tract:AF_left": (1.0, 0.0, 0.5), "tract:CST_right": (0.0, 0.5, 1.0)}
#: Largest resident-memory growth per image a renderer may show (MB).
MAX_MB_PER_IMAGE = 0.1


@dataclass
class _Run:
    """What every check needs: the renderer class, image size, template; collects problems."""

    cls: Any
    name: str
    registered: str
    width: int
    height: int
    template: Any
    checks: tuple[str, ...]
    problems: list[str] = field(default_factory=list)
    report: dict[str, Any] = field(default_factory=dict)

    def make(self, **settings: Any) -> tuple[Any, Any]:
        from brainpainter.rendering.scene import RenderSettings, Scene

        scene = Scene(self.template, "dk", settings=RenderSettings(width=self.width, height=self.height,
                                                                   **settings))
        return scene, self.cls(scene)

    def paint(self, scene: Any, renderer: Any, colors: Any, view: Any) -> NDArray[np.uint8]:
        from brainpainter.rendering.geometry import Palette

        img = np.asarray(renderer.render(Palette(colors, scene.geometry), view))
        if img.shape != (self.height, self.width, 4) or img.dtype != np.uint8:
            raise AssertionError(f"renderer {self.name!r} returned {img.dtype} {img.shape}, "
                                 f"not uint8 {(self.height, self.width, 4)}")
        return img

    def one_image(self, view_name: str, **settings: Any) -> NDArray[np.uint8]:
        from brainpainter.rendering.views import get_view

        scene, renderer = self.make(**settings)
        try:
            return self.paint(scene, renderer, COLORS, get_view(view_name))
        finally:
            renderer.close()


def _expected_layout(scene: Any, view: Any, width: int, height: int) -> dict[int, tuple[Any, float]]:
    """Per palette slot: area-weighted pixel centroid and pixel area of its faces facing the camera."""
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


def _orientation(run: _Run, scene: Any, view: Any, img: NDArray[np.uint8]) -> float:
    """Check that each visible slot's colour is centred where the camera puts it; the worst error (px)."""
    worst = 0.0
    rgb_of = scene.geometry.default_rgb.copy()
    for key, slot in scene.geometry.slot_of.items():
        if key in COLORS:
            rgb_of[slot] = COLORS[key]
    for slot, (centre, area) in _expected_layout(scene, view, run.width, run.height).items():
        mask = near(img, rgb_of[slot], 1)
        if mask.sum() < 0.6 * area or area < 30:  # hidden behind another part
            continue
        ys, xs = np.nonzero(mask)
        err = float(np.hypot(xs.mean() + 0.5 - centre[0], ys.mean() + 0.5 - centre[1]))
        worst = max(worst, err)
        if err > 0.04 * run.width:
            run.problems.append(f"orientation: {view.name}: the colour of slot {slot} is centred "
                                f"{err:.1f} px from where the camera puts it")
    if not (~near(img, WHITE, 0)).any():
        run.problems.append(f"orientation: {view.name}: nothing was drawn")
    return worst


def _per_view(run: _Run, scene: Any, view: Any, img: NDArray[np.uint8]) -> float:
    """The checks made on every preset view (fast quality, flat shading); the orientation error (px)."""
    from scipy import ndimage

    brain = ~near(img, WHITE, 0)
    worst = _orientation(run, scene, view, img) if "orientation" in run.checks else 0.0
    if "no_holes" in run.checks and view.content == "cortex" and len(view.hemis) == 1:
        holes = ndimage.binary_fill_holes(brain) & ~brain
        if holes.sum():
            run.problems.append(f"no_holes: {view.name}: {int(holes.sum())} background pixels inside "
                                "the silhouette")
    if "flat_colors" in run.checks:
        allowed = np.round(np.array([*COLORS.values(), *scene.geometry.default_rgb, WHITE]) * 255)
        dev = np.abs(img[..., :3].reshape(-1, 1, 3).astype(float) - allowed[None]).max(-1)
        bad = int((dev.min(axis=1) > 1).sum())
        if bad:
            run.problems.append(f"flat_colors: {view.name}: {bad} pixels are none of the given colours "
                                "(quality fast, flat shading)")
    return worst


def _views(run: _Run) -> None:
    """orientation, no_holes, flat colours per view and repeatable, over every preset view but the flat
    maps' (the tiny template has none: they need fsaverage's)."""
    from brainpainter.rendering.views import PRESETS, get_view

    scene, r = run.make(quality="fast", shading="flat", glass_opacity=0.0, background=WHITE)
    try:
        worst = max(_per_view(run, scene, view, run.paint(scene, r, COLORS, view))
                    for view in PRESETS.values() if view.content != "flat")  # flat maps need fsaverage
        run.report["orientation_worst_px"] = round(worst, 2)
        if "repeatable" in run.checks:
            a = run.paint(scene, r, COLORS, get_view("lateral-left"))
            run.paint(scene, r, {k: (0.5, 0.5, 0.5) for k in COLORS}, get_view("dorsal"))
            if not np.array_equal(a, run.paint(scene, r, COLORS, get_view("lateral-left"))):
                run.problems.append("repeatable: the same palette and view gave different pixels")
    finally:
        r.close()


def _antialiased(run: _Run) -> None:
    """flat_colors with anti-aliasing: the interior of each region keeps its exact colour."""
    from scipy import ndimage

    img = run.one_image("lateral-left", quality="default", shading="flat", glass_opacity=0.0,
                        background=WHITE)
    for key in ("Left-insula", "Left-precuneus", "Left-superiorfrontal", "Left-unknown"):
        core = ndimage.binary_erosion(near(img, COLORS[key], 40), iterations=3)
        if core.sum() < 20:
            run.problems.append(f"flat_colors: {key} hardly appears in lateral-left")
        elif not near(img, COLORS[key], 1)[core].all():
            run.problems.append(f"flat_colors: anti-aliased interior of {key} is not exact")


def _nan_missing(run: _Run) -> None:
    """NaN values and absent regions get the scale's colours exactly, through the Painter."""
    from scipy import ndimage

    from brainpainter.color.scale import make_scale
    from brainpainter.rendering.painter import Painter
    from brainpainter.rendering.scene import RenderSettings
    from brainpainter.rendering.views import get_view

    scale = make_scale(gradient=["blue", "red"], vmin=0, vmax=1, nan_color="#1f77b4", missing_color="#2ca02c")
    settings = RenderSettings(width=run.width, height=run.height, shading="flat", glass_opacity=0.0)
    with Painter("dk", run.template, settings=settings, renderer=run.registered) as painter:
        img = painter.paint({"Left-insula": float("nan"), "Left-precuneus": 1.0},
                            get_view("lateral-left"), scale)  # Left-superiorfrontal: missing
    expected = (("NaN", scale.nan_color), ("missing", scale.missing_color), ("value 1", (1.0, 0.0, 0.0)))
    for what, rgb in expected:
        if ndimage.binary_erosion(near(img, rgb, 1), iterations=2).sum() < 10:
            run.problems.append(f"nan_missing: the {what} colour {rgb} is not drawn exactly")


def _transparent(run: _Run) -> None:
    """A transparent background leaves alpha 0 around an opaque brain of unchanged colours."""
    from scipy import ndimage

    img = run.one_image("lateral-left", quality="default", shading="flat", glass_opacity=0.0, background=None)
    alpha = img[..., 3]
    opaque = ndimage.binary_erosion(alpha > 0, iterations=2)
    if alpha[0, 0] or alpha[-1, -1] or alpha[0, -1] or alpha[-1, 0]:
        run.problems.append("transparent: the background corners are not transparent")
    if opaque.sum() < 100 or (alpha[opaque] != 255).any():
        run.problems.append("transparent: the brain is not opaque")
    elif not near(img, COLORS["Left-insula"], 1)[opaque].any():
        run.problems.append("transparent: colours change on a transparent background")


def _glass(run: _Run) -> None:
    """The glass brain is drawn around the structures, which keep their hue through it."""
    ref = run.one_image("subcortical", quality="fast", shading="flat", glass_opacity=0.0, background=WHITE)
    img = run.one_image("subcortical", quality="fast", shading="flat", glass_opacity=0.12, background=WHITE)
    inside = ~near(ref, WHITE, 0)
    glass_only = ~inside & ~near(img, WHITE, 0)
    run.report["glass_pixels"] = int(glass_only.sum())
    if glass_only.sum() < 0.05 * run.width * run.height:
        run.problems.append("glass: the glass brain is not drawn around the structures")
    if inside.sum() < 50:
        run.problems.append("glass: the structures are not drawn in the subcortical view")
        return
    kept = (img[..., :3].argmax(-1) == ref[..., :3].argmax(-1))[inside].mean()  # dominant channel
    run.report["glass_hue_kept"] = round(float(kept), 3)
    if kept < 0.9:
        run.problems.append(f"glass: the structures do not show through the glass ({kept:.0%} keep "
                            "their hue)")


def _tracts(run: _Run) -> None:
    """Tubes of two value-coloured bundles: exact flat colour, where the camera projects them (also
    in a cortex view, through the cortex drawn as glass: only the view's hemisphere's bundle)."""
    from brainpainter.rendering import framing
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.tract_parts import TractLayer
    from brainpainter.rendering.views import get_view

    settings = RenderSettings(width=run.width, height=run.height, quality="fast", shading="flat",
                              glass_opacity=0.0, background=WHITE)
    scene = Scene(run.template, "dk", settings=settings,
                  layers=(TractLayer(None, (("AF_left", 1), ("CST_right", 1)), 1.5, tiny_tracts()),))
    renderer = run.cls(scene)
    worst = 0.0
    try:
        # lateral-left: the cortex is glass (default with tracts; clear here), AF_left inside, CST_right not
        for name in ("subcortical-dorsal", "subcortical", "lateral-left"):
            view = get_view(name)
            img = run.paint(scene, renderer, {**COLORS, **TRACT_COLORS}, view)
            pose = scene.geometry.camera(view, run.width / run.height)
            shown = {_tract_slot(p) for p in scene.geometry.visible(view) if p.kind == "tract"}
            for key, rgb in TRACT_COLORS.items():
                mask = near(img, rgb, 1)
                if scene.geometry.slot_of[key] not in shown:
                    if mask.sum() >= 30:
                        run.problems.append(f"tracts: {name}: bundle {key} is drawn; the view hides it")
                    continue
                if mask.sum() < 20:  # a renderer may blend the edges (anti-aliasing): the core counts
                    run.problems.append(f"tracts: {name}: bundle {key} is not drawn in its flat colour {rgb}")
                    continue
                part = next(p for p in scene.geometry.parts if p.kind == "tract"
                            and _tract_slot(p) == scene.geometry.slot_of[key])
                expected = framing.to_pixels(part.hull, pose, run.width, run.height).mean(axis=0)
                ys, xs = np.nonzero(mask)
                err = float(np.hypot(xs.mean() + 0.5 - expected[0], ys.mean() + 0.5 - expected[1]))
                worst = max(worst, err)
                if err > 0.05 * run.width:
                    run.problems.append(f"tracts: {name}: bundle {key} is centred {err:.1f} px from where "
                                        "the camera puts it")
        _tubes(run, scene, renderer)
    finally:
        renderer.close()
    run.report["tracts_worst_px"] = round(worst, 2)


def _tract_slot(part: Any) -> int:
    """The palette slot of a one-colour tract part (from its centrelines: reading it builds no tubes)."""
    return int(part.centrelines.slots[0, 0])


def _tubes(run: _Run, scene: Any, renderer: Any) -> None:
    """A renderer's ``draws_tubes`` (absent: True) is a bool, and one that draws none built none."""
    draws = getattr(renderer, "draws_tubes", True)
    if not isinstance(draws, bool):
        run.problems.append(f"tracts: {run.name}: draws_tubes must be True or False; {draws!r} was given")
        return
    built = [p.name for p in scene.geometry.parts if p.kind == "tract" and getattr(p, "tubes_built", True)]
    if not draws and built:
        run.problems.append(f"tracts: {run.name}: says draws_tubes=False but built the tubes of {built} "
                            "(draw part.centrelines; read no tract part's vertices, triangles, "
                            "palette_index)")


def _vertex_colors(run: _Run) -> None:
    """A per-vertex scene: a red-to-blue ramp from back to front is drawn smooth and the right way round."""
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import get_view

    settings = RenderSettings(width=run.width, height=run.height, quality="fast", shading="flat",
                              glass_opacity=0.0, background=WHITE)
    scene = Scene(run.template, "dk", settings=settings, coloring="vertices")
    geometry = scene.geometry
    ramps = {}
    for part in geometry.parts:
        if part.kind == "cortex" and part.hemi is not None:
            y = part.vertices[:, 1].astype(float)
            t = (y - y.min()) / max(float(np.ptp(y)), 1e-9)  # 0 at the back, 1 at the front
            ramps[part.hemi] = np.stack([1.0 - t, np.full_like(t, 0.2), t], axis=1)
    renderer = run.cls(scene)
    try:
        img = np.asarray(renderer.render(Palette({}, geometry, ramps), get_view("lateral-left")))
    finally:
        renderer.close()
    brain = ~near(img, WHITE, 0)
    if brain.sum() < 50:
        run.problems.append("vertex_colors: a per-vertex scene draws nothing in lateral-left")
        return
    ys, xs = np.nonzero(brain)
    blue = img[ys, xs, 2].astype(float)
    distinct = len(np.unique(blue))
    corr = float(np.corrcoef(xs, blue)[0, 1]) if np.ptp(blue) else 0.0
    run.report["vertex_colors_distinct"] = distinct
    if distinct < 20:
        run.problems.append(f"vertex_colors: a colour ramp over the vertices gave {distinct} distinct "
                            "colours; per-vertex colours must be interpolated across triangles")
    if corr > -0.8:  # lateral-left: the front (blue) is on the left of the image
        run.problems.append(f"vertex_colors: the ramp is not drawn front (left) to back (correlation "
                            f"{corr:.2f})")


def _outlines(run: _Run) -> None:
    """Region borders as lines of constant pixel width, in the outline colour, where the regions meet."""
    from brainpainter.rendering.geometry import Palette
    from brainpainter.rendering.scene import RenderSettings, Scene
    from brainpainter.rendering.views import get_view

    black: RGB = (0.0, 0.0, 0.0)
    counts = []
    for scale in (1, 2):
        settings = RenderSettings(width=run.width * scale, height=run.height * scale, quality="fast",
                                  shading="flat", glass_opacity=0.0, background=WHITE, outline_width=2.0,
                                  outline_color=black)
        scene = Scene(run.template, "dk", settings=settings)
        geometry = scene.geometry
        if not any(p.outline is not None and len(p.outline) for p in geometry.parts):
            run.problems.append("outlines: core gave the tiny template's cortex no border segments")
            return
        renderer = run.cls(scene)
        try:
            img = np.asarray(renderer.render(Palette(COLORS, geometry), get_view("lateral-left")))
        finally:
            renderer.close()
        counts.append(int(near(img, black, 40).sum()))
    run.report["outline_pixels"] = counts
    if counts[0] < 10:
        run.problems.append(f"outlines: {counts[0]} pixels in the outline colour at "
                            f"{run.width}x{run.height}; the borders between regions must be drawn as lines")
    elif not 1.3 <= counts[1] / counts[0] <= 3.0:
        run.problems.append(f"outlines: twice the image size gave {counts[1] / counts[0]:.1f}x the outline "
                            "pixels; lines of constant pixel width give about 2x (a border painted "
                            "into the mesh gives 4x)")


def _memory(run: _Run, n_memory: int) -> None:
    """Resident memory does not grow per image over `n_memory` renders (after 20 to warm up)."""
    from brainpainter.rendering.views import get_view

    scene, r = run.make(quality="fast", glass_opacity=0.12, background=WHITE)
    rng = np.random.default_rng(0)
    views = [get_view(n) for n in ("lateral-left", "dorsal", "subcortical")]
    try:
        per_image = growth_per_image(
            lambda i: run.paint(scene, r, {"Left-insula": tuple(rng.random(3))}, views[i % 3]), n=n_memory)
    finally:
        r.close()
    run.report["memory_mb_per_image"] = round(per_image, 4)
    if per_image > MAX_MB_PER_IMAGE:
        run.problems.append(f"memory: resident memory grew by {per_image:.2f} MB per image over {n_memory} "
                            f"renders (at most {MAX_MB_PER_IMAGE})")


def check_renderer(renderer: str | type, size: tuple[int, int] = (160, 120),
                   checks: tuple[str, ...] = CONFORMANCE_CHECKS, n_memory: int = 200) -> dict[str, Any]:
    """Check a renderer against the renderer contract (``docs/renderers.md``; the checks: module docstring).

    Parameters
    ----------
    renderer : str or type
        Registry name (``"blender"``) or a renderer class.
    size : (int, int)
        Image width and height.
    checks : tuple of str
        Subset of :data:`CONFORMANCE_CHECKS`.
    n_memory : int
        Images rendered by the memory check.

    Returns
    -------
    dict
        Check name -> a short measurement (for reports).

    Raises
    ------
    AssertionError
        Listing every failure.
    """
    from brainpainter.atlas import registry
    from brainpainter.atlas.template import load_template

    unknown = [c for c in checks if c not in CONFORMANCE_CHECKS]
    if unknown:
        raise ValueError(f"unknown checks {unknown}; choose from {CONFORMANCE_CHECKS}")
    cls = registry.renderers.get(renderer) if isinstance(renderer, str) else renderer
    name = renderer if isinstance(renderer, str) else getattr(cls, "__name__", str(cls))
    registered = renderer if isinstance(renderer, str) else _register_temp(cls)
    with tempfile.TemporaryDirectory(prefix="bp-conformance-") as tmp:
        template = load_template(write_tiny_template(Path(tmp) / "tiny"))
        run = _Run(cls, name, registered, size[0], size[1], template, checks)
        if {"orientation", "no_holes", "repeatable", "flat_colors"} & set(checks):
            _views(run)
        for check, step in (("flat_colors", _antialiased), ("nan_missing", _nan_missing),
                            ("transparent", _transparent), ("glass", _glass), ("tracts", _tracts),
                            ("vertex_colors", _vertex_colors), ("outlines", _outlines),
                            ("connectome", connectome_check), ("clip", clip_check)):
            if check in checks:
                step(run)
        if "memory" in checks and can_measure():
            _memory(run, n_memory)
    if run.problems:
        raise AssertionError(f"renderer {name!r} fails the conformance suite:\n  "
                             + "\n  ".join(run.problems))
    return run.report


def _register_temp(cls: type) -> str:
    from brainpainter.atlas import registry

    name = f"conformance-{id(cls)}"
    registry.renderers.register(name, lambda: cls, replace=True)
    return name
