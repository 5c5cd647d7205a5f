"""Ready-to-draw geometry of a scene: what core hands every renderer.

A renderer does not read templates. For a :class:`~brainpainter.rendering.scene.Scene` core builds,
once, one :class:`PartGeometry` per drawable part (cortex of each hemisphere, the subcortical
structures, each glass hull): vertices, normals, triangles and a per-vertex **palette index**. Every
image is then a :class:`Palette` (one colour per palette slot) plus a
:class:`~brainpainter.rendering.views.View`; recolouring never touches the geometry.

A vertex shared by faces of two regions is stored once per region, so each triangle's three vertices
carry its region's palette index (flat colours stay exact) while normals are those of the shared
surface (lighting stays smooth across region borders).

Palette slots ``0, 1, 2`` are fixed: the medial-wall colour (cortex labels without a colour), the
neutral grey (subcortical structures without a colour) and the glass colour; slots from 3 on are region
keys (:attr:`SceneGeometry.keys`), then the tracts' keys (``tract:AF_left`` for a bundle's one colour,
``tract:AF_left:17`` for node 17 of an along-tract profile, ``tract-direction:i`` for direction colours).

White-matter tracts are parts of kind ``tract`` (``tracts-lh``, ``tracts-rh`` and ``tracts`` for
commissural bundles): centrelines, and triangle tubes (:func:`brainpainter.tracts.tubes.tube_mesh`)
built when first read (:class:`~brainpainter.rendering.tract_parts.TractPart`), so a renderer that
draws tubes draws them as any opaque part; so are a connectome's ``nodes`` and ``edges``
(:mod:`.connectome_parts`) and a volume's ``blobs`` (:mod:`.blob_parts`, keys ``blob:0`` ...).

A scene coloured per vertex (``Scene.coloring == "vertices"``, a map) keeps
one drawing path: its cortex parts are the template's stored meshes, not
split by region, and every cortex vertex has a palette slot of its own
(:attr:`SceneGeometry.vertex_slots`: lh's vertices from slot 3, then rh's;
region keys after them). The palette's colours of those slots are the map's
colours per vertex (:class:`VertexColors`), which renderers interpolate
across each triangle.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.layers.vertex_map import VertexColors
from brainpainter.rendering import framing
from brainpainter.rendering.clip import check_cut
from brainpainter.rendering.lazy_parts import LazyParts, cortex_arrays
from brainpainter.rendering.part_cache import cortex_kept
from brainpainter.rendering.parts import (
    GLASS_COLOR,
    GLASS_SLOT,
    MAX_SLOTS,
    MEDIAL_SLOT,
    N_FIXED_SLOTS,
    NEUTRAL_GREY,
    NEUTRAL_SLOT,
    PartGeometry,
    check_slots,
    split_by_label,
)
from brainpainter.rendering.settings import RGB, SULC_LIGHTINGS, RenderSettings
from brainpainter.rendering.views import View

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template


# The parts and slots are defined in parts.py; named here for renderers and older imports.
__all__ = ["GLASS_COLOR", "GLASS_SLOT", "MAX_SLOTS", "MEDIAL_SLOT", "NEUTRAL_GREY", "NEUTRAL_SLOT",
           "N_FIXED_SLOTS", "Palette", "PartGeometry", "SceneGeometry", "SceneParts", "VertexColors",
           "split_by_label", "vertex_normals"]


class SceneParts(Protocol):
    """What :class:`SceneGeometry` reads of a :class:`~brainpainter.rendering.scene.Scene`.

    (A protocol, so that scene.py, whose ``Scene.geometry`` builds a
    :class:`SceneGeometry`, and this module do not import each other.)
    """

    @property
    def template(self) -> Template: ...
    @property
    def labels(self) -> str: ...
    @property
    def surface(self) -> str: ...
    @property
    def hidden(self) -> frozenset[str]: ...
    @property
    def settings(self) -> RenderSettings: ...
    @property
    def medial_wall_color(self) -> RGB: ...
    @property
    def coloring(self) -> str: ...
    @property
    def layers(self) -> tuple[Any, ...]: ...

class Palette(Mapping[str, RGB]):
    """The colours of one image: a mapping region key -> sRGB, and the slot array renderers draw.

    Behaves as the read-only mapping of the colours that were given (what a
    colour-mapping renderer reads); :attr:`rgb` is the array a geometry
    renderer uploads, built on first use.

    Parameters
    ----------
    colors : mapping of str to (r, g, b)
        sRGB 0-1 per region key.
    geometry : SceneGeometry, or a callable returning it
    vertex_rgb : mapping of str to ndarray of float, shape (n_vertices, 3), optional
        A per-vertex scene's cortex colours per hemisphere (sRGB 0-1), in the
        order of its vertex slots (:attr:`SceneGeometry.vertex_slots`).
    """

    def __init__(self, colors: Mapping[str, RGB],
                 geometry: SceneGeometry | Callable[[], SceneGeometry],
                 vertex_rgb: Mapping[str, NDArray[Any]] | None = None) -> None:
        self._colors = {k: tuple(float(c) for c in v[:3]) for k, v in colors.items()}
        self._geometry = geometry
        self._vertex_rgb = dict(vertex_rgb or {})
        self._rgb: NDArray[Any] | None = None

    def __getitem__(self, key: str) -> RGB:
        return self._colors[key]  # type: ignore[return-value]

    def __iter__(self) -> Iterator[str]:
        return iter(self._colors)

    def __len__(self) -> int:
        return len(self._colors)

    @property
    def geometry(self) -> SceneGeometry:
        if not isinstance(self._geometry, SceneGeometry):
            self._geometry = self._geometry()
        return self._geometry

    @property
    def rgb(self) -> NDArray[Any]:
        """sRGB 0-1 per palette slot, float32, shape (n_slots, 3)."""
        if self._rgb is None:
            g = self.geometry
            if any(key.startswith("flat-") for key in self._vertex_rgb):
                g.flat_slots()  # a run with a flat view: the sheets' slots (once)
            rgb = g.default_rgb.copy()
            for key, i in g.slot_of.items():
                c = self._colors.get(key)
                if c is not None:
                    rgb[i] = c
            for hemi, (start, n) in g.vertex_slots.items():
                if hemi in self._vertex_rgb:
                    rgb[start:start + n] = np.asarray(self._vertex_rgb[hemi], np.float32)[:, :3]
            self._rgb = np.clip(rgb, 0.0, 1.0).astype(np.float32)
        return self._rgb


def cortex_mode(setting: str, parts: list[PartGeometry]) -> str:
    """``RenderSettings.cortex`` resolved: ``auto`` is ``glass`` when `parts` hold tracts or a connectome."""
    if setting != "auto":
        return setting
    return "glass" if any(p.kind in framing.INSIDE for p in parts) else "opaque"


def _flat_able(template: Template, meshes: Mapping[str, Any]) -> bool:
    """Whether a per-vertex scene of these cortex meshes can draw the flat maps (fsaverage's meshes)."""
    from brainpainter.maps.resolution import own_vertex_count

    return all(len(m.source_vertex) for m in meshes.values()) and all(
        own_vertex_count(template, hemi) is None for hemi in meshes)


class SceneGeometry:
    """Every drawable part of a scene, each built once from its template when a view first shows it.

    Palette slots are numbered from the template's label names when the geometry is made; a
    part's meshes are read and split by :meth:`visible` for the first view that shows it (a
    lateral-left image never reads the right hemisphere, the structures or the glass), or by
    :attr:`parts` (every part: exporters, the Cycles path).

    Parameters
    ----------
    scene : brainpainter.rendering.scene.Scene

    Attributes
    ----------
    parts : tuple of PartGeometry
    cortex : {"opaque", "glass", "hull", "hidden"}
        How cortex views draw the cortex (``settings.cortex``; ``auto`` resolved:
        glass when the scene has tracts).
    keys : tuple of str
        Region key of palette slots 3, 4, ... (hidden regions are not drawn and have no slot).
    slot_of : dict of str to int
    part_keys : dict of str to tuple of str
        Region keys each region-coloured part draws (``cortex-lh``: its regions), by part name.
    default_rgb : ndarray of float32, shape (n_slots, 3)
        Colour of each slot when the palette gives none.
    vertex_slots : dict of str to (int, int)
        Per-vertex scenes: first slot and number of cortex vertices of each hemisphere (else empty),
        and of each flat map's once it has them (``flat-lh``, ``flat-rh``: :meth:`flat_slots`).
    source_vertex : dict of str to ndarray of int32, shape (n_vertices,)
        Per-vertex scenes: the fsaverage vertex of each cortex vertex, per hemisphere.
    """

    def __init__(self, scene: SceneParts) -> None:
        from brainpainter.atlas.model import HEMI_PREFIX
        from brainpainter.atlas.template import HEMIS

        template, hidden, settings = scene.template, frozenset(scene.hidden), scene.settings
        with_sulc = settings.shading != "flat" and settings.lighting in SULC_LIGHTINGS
        keys: list[str] = []
        defaults: list[RGB] = [tuple(scene.medial_wall_color), NEUTRAL_GREY, GLASS_COLOR]  # type: ignore[list-item]
        slot_of: dict[str, int] = {}
        per_vertex = getattr(scene, "coloring", "regions") == "vertices"
        # a map's meshes now (their vertex counts number the slots); a region scene's when first drawn
        meshes = {hemi: self._cortex_mesh(scene, hemi, per_vertex) for hemi in HEMIS} if per_vertex else {}
        self.vertex_slots: dict[str, tuple[int, int]] = {}
        self.source_vertex: dict[str, NDArray[Any]] = {}
        if per_vertex:
            self._vertex_slots(meshes, defaults)
        first_key = len(defaults)
        self._scene, self._first_key = scene, first_key
        self._flat_able = per_vertex and _flat_able(template, meshes)

        def slots_for(names: list[str], default: int | RGB, drop: frozenset[str]) -> NDArray[Any]:
            out = np.full(len(names), -1, dtype=np.int64)
            for i, key in enumerate(names):
                if key in drop:
                    continue
                if key not in slot_of:
                    slot_of[key] = first_key + len(keys)
                    keys.append(key)
                    defaults.append(defaults[default] if isinstance(default, int) else default)
                out[i] = slot_of[key]
            return out

        # Parts in drawing order, built or pending (built by the first visible() that shows it, or by
        # .parts); slots are numbered here from the label names, the same whichever parts are built.
        self._lazy = LazyParts(first_key, settings.shading != "flat", lambda: len(self.default_rgb))
        self._part_slots = self._lazy.part_slots  # part name -> the region slots of its faces
        if not per_vertex and scene.surface not in template.surfaces:
            raise choice_error("surface", scene.surface, list(template.surfaces),
                               f"Template {template.name!r} lacks it.")
        for hemi in HEMIS:
            names = [HEMI_PREFIX[hemi] + n for n in (meshes[hemi].label_names if per_vertex
                                                     else template.cortex_names(scene.labels, hemi))]
            label_slot = slots_for(names, MEDIAL_SLOT, hidden)

            if per_vertex and scene.surface not in meshes[hemi].vertices:
                raise choice_error("surface", scene.surface, list(meshes[hemi].vertices),
                                   f"Template {template.name!r} lacks it.")
            cortex = functools.partial(cortex_arrays, scene, hemi, label_slot, meshes.get(hemi), with_sulc,
                                       self._cortex_mesh, self._borders)
            self._lazy.later(f"cortex-{hemi}", "cortex", hemi, bool(set(names) - hidden), cortex,
                             None if per_vertex else cortex_kept(scene, hemi, label_slot, with_sulc),
                             first_slot=self.vertex_slots[hemi][0] if per_vertex else None)
        if template.manifest.get("subcortical"):
            self._lazy.later_subcortical(template, hidden, slots_for(list(template.subcortical_names()),
                                                                     NEUTRAL_SLOT, hidden))
        #: the kind of the scene layer (:attr:`Scene.layers`) each of their parts came from, by part name
        self.layer_of: dict[str, str] = {}
        for layer in scene.layers:  # tracts, a connectome, blobs, plugin layers
            made = layer.parts(template, slots_for)
            self.layer_of.update((part.name, layer.kind) for part in made)
            self._lazy.entries += made
        for hemi in HEMIS:
            if hemi in template.manifest.get("glass", {}):
                self._lazy.later_glass(template, hemi)
        check_slots(len(defaults))
        #: how cortex views draw the cortex: opaque, glass, hull or hidden (``settings.cortex`` resolved)
        self.cortex: str = cortex_mode(settings.cortex, self._lazy.built_parts())
        if self.cortex == "hull" and not template.manifest.get("glass"):
            self.cortex = "glass"  # a template without glass hulls (a mouse's, own surfaces'): its cortex
        #: rotation from the template's coordinates to RAS (its anterior and superior axes)
        self.to_ras: NDArray[Any] = np.asarray(template.to_ras, dtype=float)
        self.keys: tuple[str, ...] = tuple(keys)
        self.slot_of = slot_of
        self.default_rgb = np.asarray(defaults, dtype=np.float32)

    def _vertex_slots(self, meshes: Mapping[str, Any], defaults: list[RGB]) -> None:
        """A per-vertex scene's slots (appended to `defaults`): each cortex vertex's."""
        for hemi, cm in meshes.items():
            self.vertex_slots[hemi] = (len(defaults), len(cm.source_vertex))
            self.source_vertex[hemi] = np.asarray(cm.source_vertex, np.int32)
            defaults.extend([defaults[MEDIAL_SLOT]] * len(cm.source_vertex))

    def flat_slots(self) -> bool:
        """Give a per-vertex scene the flat maps' vertex slots (``vertex_slots["flat-lh"]``, ``"flat-rh"``:
        32492 each, after every other slot), once: when a palette first carries their colours
        (:class:`VertexColors` of a run with a flat view) or a flat view is first drawn, so that runs
        without one upload no larger palette. False where the scene has none (a region scene, a
        template not made from fsaverage)."""
        if "flat-lh" in self.vertex_slots:
            return True
        if not self._flat_able:
            return False
        from brainpainter.maps.flat import N_FLAT

        start = self.n_slots
        for i, hemi in enumerate(("lh", "rh")):
            self.vertex_slots[f"flat-{hemi}"] = (start + i * N_FLAT, N_FLAT)
        medial = np.repeat(self.default_rgb[MEDIAL_SLOT][None], 2 * N_FLAT, axis=0)
        self.default_rgb = np.concatenate([self.default_rgb, medial])
        check_slots(self.n_slots)
        return True

    @functools.cached_property
    def flat_parts(self) -> tuple[PartGeometry, ...]:
        """The flat maps as parts of kind ``flat`` (``flat-lh``, ``flat-rh``), built when a flat view first
        draws them (:func:`brainpainter.rendering.flat_parts.flat_parts`)."""
        from brainpainter.rendering.flat_parts import flat_parts

        per_vertex = self.flat_slots()
        parts = flat_parts(self._scene, self.slot_of, self.vertex_slots, self.to_ras)
        for part in parts:  # the regions drawn (a map's sheet: none, as a map's cortex)
            self._part_slots[part.name] = frozenset() if per_vertex else frozenset(
                int(i) for i in np.unique(part.palette_index) if i >= self._first_key)
        self.__dict__.pop("part_keys", None)  # computed again with the flat parts' regions
        return parts

    @property
    def parts(self) -> tuple[PartGeometry, ...]:
        """Every part of the scene (all built now; :meth:`visible` builds only those a view shows)."""
        return tuple(self._lazy.built(lambda kind, hemi: True))

    @property
    def part_keys(self) -> dict[str, tuple[str, ...]]:
        """Region keys each cortex, subcortical or glass part built so far draws (its faces' regions),
        by part name (every part :meth:`visible` returned is built)."""
        key_of = {slot: key for key, slot in self.slot_of.items()}
        return {name: tuple(key_of[i] for i in sorted(slots) if i in key_of)
                for name, slots in self._part_slots.items()}

    @staticmethod
    def _borders(scene: SceneParts, hemi: str, cm: Any, verts: NDArray[Any], face_slot: NDArray[Any],
                 per_vertex: bool) -> tuple[NDArray[Any] | None, NDArray[Any] | None]:
        """The region borders and the contour of a cortex part as segments (:mod:`.borders`).

        Per region, the edges between faces of two regions (hidden regions included); per vertex, the
        lines through the midpoints of the edges between vertices of two labels of the scene's label
        set; none with a contour unless ``contours.regions``. A second map's iso-lines
        (``scene.contours``): the contour, in its own line (:meth:`RenderSettings.line`), dashed where asked.
        """
        from brainpainter.rendering.borders import dashed, face_borders, vertex_borders

        contours = getattr(scene, "contours", None)
        lines = SceneGeometry._contour_lines(scene, hemi, cm if per_vertex else None)
        contour = None
        if contours is not None:
            contour = np.concatenate(lines) if lines else np.zeros((0, 2, 3), np.float32)
            contour = dashed(contour) if scene.settings.contour_style == "dashed" else contour
            if not contours.regions:
                return None, contour
        normals = vertex_normals(verts, cm.faces)
        if not per_vertex:
            regions: NDArray[Any] = face_borders(verts, cm.faces, np.asarray(cm.face_label), normals)
        else:
            from brainpainter.maps.outlines import mesh_labels

            labels = mesh_labels(scene.template, scene.labels, hemi, cm)
            if labels is None:
                raise BrainPainterError(f"template {scene.template.name!r} has no per-vertex labels for "
                                        f"{scene.labels!r}, so its region borders cannot be drawn.")
            regions = vertex_borders(verts, cm.faces, labels, normals)
        return (dashed(regions) if scene.settings.outline_style == "dashed" else regions), contour

    @staticmethod
    def _contour_lines(scene: SceneParts, hemi: str, cm: Any) -> list[NDArray[np.float32]]:
        """A second map's iso-lines on hemisphere `hemi` (``scene.contours``), one array per level.

        `cm`: the per-vertex cortex mesh drawn; None (regions drawn split at their borders): the
        iso-lines are traced on the unsplit mesh, whose surface the split one keeps.
        """
        from brainpainter.rendering.borders import iso_lines

        contours = getattr(scene, "contours", None)
        if contours is None or hemi not in contours.values:
            return []
        if cm is None:
            from brainpainter.maps.resolution import map_mesh

            cm = map_mesh(scene.template, scene.labels, hemi)
        if not len(cm.source_vertex):
            return []
        verts = cm.vertices[scene.surface]
        normals = vertex_normals(verts, cm.faces)
        values = np.asarray(contours.values[hemi])[np.asarray(cm.source_vertex, np.int64)]
        return [iso_lines(verts, cm.faces, values, level, normals) for level in contours.levels]

    @staticmethod
    def _cortex_mesh(scene: SceneParts, hemi: str, per_vertex: bool) -> Any:
        """The hemisphere's cortex mesh: split by region, or (per vertex) as stored, not split."""
        if per_vertex:
            from brainpainter.maps.resolution import map_mesh

            return map_mesh(scene.template, scene.labels, hemi)
        return scene.template.cortex(scene.labels, hemi)

    @property
    def n_slots(self) -> int:
        return len(self.default_rgb)

    def visible(self, view: View) -> list[PartGeometry]:
        """The parts `view` draws (:func:`brainpainter.rendering.framing.shows`), opaque parts first.

        With :attr:`cortex` ``"glass"`` a cortex view's cortex parts come as
        kind ``glass`` (same name and palette slots: drawn transparent in the
        regions' colours) and the tracts of its hemispheres as opaque parts.

        A template that lacks the part a view is about (a brain of region
        meshes with structures only, or with an outer surface only) draws its
        other part instead, so every view shows it. Renderers draw exactly
        these parts.

        Raises
        ------
        BrainPainterError
            If the view draws nothing (its parts are absent from the template or all hidden).
        """
        def shown(kind: str, hemi: str | None) -> bool:
            return framing.shows(view, kind, hemi, self.cortex)

        kinds = self._lazy.kinds()
        if view.content == "flat":  # the flat maps alone (all hidden: an error below)
            parts = [p for p in self.flat_parts if shown(p.kind, p.hemi)]
        elif view.content == "cortex" and "cortex" not in kinds:
            # a brain of region meshes without an outer surface: its structures stand for it
            parts = self._lazy.built(lambda kind, hemi: kind == "subcortical" or shown(kind, hemi))
        elif view.content == "subcortical" and "subcortical" not in kinds:
            # ... and one without structures shows its surface (both hemispheres, no glass over it)
            parts = self._lazy.built(lambda kind, hemi: kind == "cortex")
        else:
            parts = self._lazy.built(shown)
            if view.content == "cortex" and self.cortex == "glass":
                # the cortex as glass in its own colours (same name: a renderer's upload of it is reused)
                parts = [replace(p, kind="glass") if p.kind == "cortex" else p for p in parts]
        if not parts:
            raise BrainPainterError(
                f"view {view.name!r} shows nothing: content={view.content!r}, hemis={list(view.hemis)}, "
                f"glass={list(view.glass)}; the template or the hidden regions leave no part to draw"
                + (" (--cortex hidden draws no cortex: give --tracts, or --cortex opaque)."
                   if self.cortex == "hidden" and view.content == "cortex" else ".")
            )
        check_cut(parts, view.clip, view.name)  # a cut that leaves none of the cortex and glass: an error
        return sorted(parts, key=lambda p: p.kind == "glass")

    def view_points(self, view: View) -> NDArray[Any]:
        """Hull points of the parts `view` draws, in RAS (what the camera frames), shape (n, 3)."""
        points = np.vstack([p.hull for p in self.visible(view)])
        if np.array_equal(self.to_ras, np.eye(3)):
            return points
        rotated: NDArray[Any] = points @ self.to_ras.T
        return rotated

    def camera(self, view: View, aspect: float) -> framing.CameraPose:
        """The orthographic camera of `view` framing its visible parts (image width / height = `aspect`).

        Views are anatomical (:mod:`brainpainter.rendering.views`): the camera
        is placed in RAS and turned back into the template's coordinates
        (:attr:`brainpainter.atlas.template.Template.to_ras`), so a template
        whose anterior axis is not +y is still drawn the right way up.
        """
        pose = framing.frame(self.view_points(view), view.azimuth, view.elevation, view.zoom, aspect)
        if np.array_equal(self.to_ras, np.eye(3)):
            return pose
        m = self.to_ras
        return framing.CameraPose(location=m.T @ pose.location, rotation=m.T @ pose.rotation,
                                  ortho_scale=pose.ortho_scale, clip_start=pose.clip_start,
                                  clip_end=pose.clip_end)
