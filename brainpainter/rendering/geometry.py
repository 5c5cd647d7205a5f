"""Ready-to-draw geometry of a scene: what core hands every renderer.

A renderer does not read templates. For a :class:`~brainpainter.rendering.scene.Scene`
core builds, once, one :class:`PartGeometry` per drawable part (cortex of
each hemisphere, the subcortical structures, each glass hull): vertices,
normals, triangles and a per-vertex **palette index**. Every image is then a
:class:`Palette` (one colour per palette slot) plus a
:class:`~brainpainter.rendering.views.View`; recolouring never touches the geometry.

A vertex shared by faces of two regions is stored once per region, so each
triangle's three vertices carry its region's palette index (flat colours
stay exact) while normals are those of the shared surface (lighting stays
smooth across region borders).

Palette slots ``0, 1, 2`` are fixed: the medial-wall colour (cortex labels
without a colour), the neutral grey (subcortical structures without a
colour) and the glass colour; slots from 3 on are region keys
(:attr:`SceneGeometry.keys`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.mesh import vertex_normals
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.rendering import framing
from brainpainter.rendering.settings import RGB, SULC_LIGHTINGS, RenderSettings
from brainpainter.rendering.views import View

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template


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

#: Colour of subcortical structures that have no colour in the mapping (sRGB).
NEUTRAL_GREY = (0.8, 0.8, 0.8)
#: Colour of the glass brain (sRGB).
GLASS_COLOR = (0.78, 0.80, 0.84)
MEDIAL_SLOT, NEUTRAL_SLOT, GLASS_SLOT = 0, 1, 2
N_FIXED_SLOTS = 3


@dataclass(frozen=True)
class PartGeometry:
    """One drawable part of a scene, indexed, ready for a vertex buffer.

    Renderers upload it once, when the scene loads.

    Attributes
    ----------
    name : str
        ``cortex-lh``, ``cortex-rh``, ``subcortical``, ``glass-lh``, ``glass-rh``.
    kind : {"cortex", "subcortical", "glass"}
    hemi : {"lh", "rh"} or None
    vertices : ndarray of float32, shape (n_vertices, 3)
        RAS millimetres.
    normals : ndarray of float32, shape (n_vertices, 3)
        Unit, outward, area-weighted over the surface's faces.
    triangles : ndarray of uint32, shape (n_triangles, 3)
        Counter-clockwise seen from outside.
    palette_index : ndarray of int32, shape (n_vertices,)
        Palette slot of each vertex (equal on the three vertices of a triangle).
    sulc : ndarray of float32, shape (n_vertices,)
        Sulcal depth 0 (crown of a gyrus) to 1 (deep in a sulcus), for
        optional darkening; zeros where unknown, off the cortex, and when the
        scene's lighting does not use it (:data:`brainpainter.rendering.scene.SULC_LIGHTINGS`).
    hull : ndarray of float, shape (n_points, 3)
        Points whose projections bound the part (here its vertices: projecting
        them costs about a millisecond, less than a convex hull, whose import
        alone costs a second at start-up).
    occlusion : ndarray of float32, shape (n_vertices,), or None
        Ambient occlusion baked into the template (1 = open sky, towards 0
        deep in a fold; :mod:`brainpainter.atlas.occlusion`), for the
        renderer's shading; None when the template has none (old templates,
        the glass) or the shading is flat.
    """

    name: str
    kind: str
    hemi: str | None
    vertices: NDArray[Any]
    normals: NDArray[Any]
    triangles: NDArray[Any]
    palette_index: NDArray[Any]
    sulc: NDArray[Any]
    hull: NDArray[Any]
    occlusion: NDArray[Any] | None = None


def convexity(vertices: NDArray[Any], faces: NDArray[Any], iterations: int = 60) -> NDArray[Any]:
    """Sulcal depth from the mesh alone: how far each vertex lies inside a smoothed copy.

    The surface is smoothed by `iterations` steps of uniform Laplacian
    averaging (a few millimetres on a template mesh, about a gyrus wide); the
    displacement of each vertex from its smoothed position along the normal
    is positive on gyral crowns and negative in sulci, like FreeSurfer's
    ``sulc`` with the opposite sign.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    iterations : int

    Returns
    -------
    ndarray of float32, shape (n_vertices,)
        0 on the outer 30 % (crowns), rising to 1 at the deepest 3 % of sulci.
    """
    from scipy import sparse

    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(v)
    if not len(f):
        return np.zeros(n, np.float32)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    adj = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    adj.data[:] = 1.0
    degree = np.asarray(adj.sum(axis=1)).ravel()
    step = sparse.diags(1.0 / np.maximum(degree, 1)) @ adj
    smooth = v.copy()
    for _ in range(iterations):
        smooth = step @ smooth
    d = np.einsum("ij,ij->i", v - smooth, vertex_normals(v, f).astype(np.float64))
    return _depth_0_1(-d)


def _depth_0_1(depth: NDArray[Any]) -> NDArray[Any]:
    """Map a sulcal-depth measure (larger = deeper) to 0-1 by its 30th and 97th percentiles."""
    lo, hi = np.percentile(depth, [30, 97])
    out: NDArray[Any] = np.clip((depth - lo) / max(hi - lo, 1e-9), 0.0, 1.0).astype(np.float32)
    return out


def split_by_label(vertices: NDArray[Any], faces: NDArray[Any], face_slot: NDArray[Any],
                   extra: tuple[NDArray[Any], ...] = ()) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any],
                                                              tuple[NDArray[Any], ...]]:
    """One vertex per (vertex, slot) pair used by `faces`: the indexed mesh a renderer draws.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
    face_slot : ndarray of int, shape (n_faces,)
        Palette slot of each face.
    extra : tuple of ndarray, each shape (n_vertices, ...)
        Per-vertex arrays (normals, sulc) carried to the new vertices.

    Returns
    -------
    vertices : ndarray, shape (n_new, 3)
    triangles : ndarray of uint32, shape (n_faces, 3)
    palette_index : ndarray of int32, shape (n_new,)
    extra : tuple of ndarray, each shape (n_new, ...)
    """
    f = np.asarray(faces, dtype=np.int64)
    slot = np.asarray(face_slot, dtype=np.int64)
    n_slots = int(slot.max()) + 1 if len(slot) else 1
    pair = f * n_slots + slot[:, None]
    unique, inverse = np.unique(pair.ravel(), return_inverse=True)
    src, pal = unique // n_slots, unique % n_slots
    return (np.asarray(vertices)[src], inverse.reshape(-1, 3).astype(np.uint32),
            pal.astype(np.int32), tuple(np.asarray(e)[src] for e in extra))


def _template_sulc(template: Template, labels: str, hemi: str, cm: Any) -> NDArray[Any] | None:
    """A per-vertex ``sulc`` (or ``curv``) array the template ships, if any (normalised to 0-1 depth)."""
    raw = getattr(cm, "sulc", None)
    if raw is None:
        entry = template.manifest["labels"][labels]["cortex"][hemi]
        z = template._npz(entry["file"]) if "base" not in entry else {}
        raw = z.get("sulc")
    if raw is None or len(raw) != len(cm.source_vertex):
        return None
    return _depth_0_1(np.asarray(raw, dtype=np.float64))  # FreeSurfer's sulc: sulci positive


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
    """

    def __init__(self, colors: Mapping[str, RGB],
                 geometry: SceneGeometry | Callable[[], SceneGeometry]) -> None:
        self._colors = {k: tuple(float(c) for c in v[:3]) for k, v in colors.items()}
        self._geometry = geometry
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
            rgb = g.default_rgb.copy()
            for key, i in g.slot_of.items():
                c = self._colors.get(key)
                if c is not None:
                    rgb[i] = c
            self._rgb = np.clip(rgb, 0.0, 1.0).astype(np.float32)
        return self._rgb


def _part(name: str, kind: str, hemi: str | None, verts: NDArray[Any], faces: NDArray[Any],
          face_slot: NDArray[Any], sulc: NDArray[Any], ao: NDArray[Any] | None = None, *,
          with_occlusion: bool = True) -> PartGeometry | None:
    """One part from its mesh and per-face slots (faces of slot -1 are hidden); None when nothing is left."""
    keep = face_slot >= 0
    faces, face_slot = np.asarray(faces)[keep], face_slot[keep]
    if not len(faces):
        return None
    normals = vertex_normals(verts, faces)
    if not with_occlusion or ao is None or len(ao) != len(verts):
        ao = None
    per_vertex = (normals, sulc) if ao is None else (normals, sulc, ao)
    v, tri, pal, extra = split_by_label(verts, faces, face_slot, per_vertex)
    return PartGeometry(name, kind, hemi, v.astype(np.float32), extra[0].astype(np.float32),
                        tri, pal, extra[1].astype(np.float32), v,
                        None if ao is None else extra[2].astype(np.float32))


class SceneGeometry:
    """Every drawable part of a scene, built once from its template.

    Parameters
    ----------
    scene : brainpainter.rendering.scene.Scene

    Attributes
    ----------
    parts : tuple of PartGeometry
    keys : tuple of str
        Region key of palette slots 3, 4, ... (hidden regions are not drawn and have no slot).
    slot_of : dict of str to int
    default_rgb : ndarray of float32, shape (n_slots, 3)
        Colour of each slot when the palette gives none.
    """

    def __init__(self, scene: SceneParts) -> None:
        from brainpainter.atlas.model import HEMI_PREFIX
        from brainpainter.atlas.template import HEMIS

        template, hidden = scene.template, frozenset(scene.hidden)
        settings = scene.settings
        with_sulc = settings.shading != "flat" and settings.lighting in SULC_LIGHTINGS
        keys: list[str] = []
        defaults: list[RGB] = [tuple(scene.medial_wall_color), NEUTRAL_GREY, GLASS_COLOR]  # type: ignore[list-item]
        slot_of: dict[str, int] = {}

        def slots_for(names: list[str], default: int) -> NDArray[Any]:
            out = np.full(len(names), -1, dtype=np.int64)
            for i, key in enumerate(names):
                if key in hidden:
                    continue
                if key not in slot_of:
                    slot_of[key] = N_FIXED_SLOTS + len(keys)
                    keys.append(key)
                    defaults.append(defaults[default])
                out[i] = slot_of[key]
            return out

        def part(*args: Any) -> PartGeometry | None:
            return _part(*args, with_occlusion=settings.shading != "flat")

        def cortex(hemi: str, slots: NDArray[Any]) -> PartGeometry | None:
            cm = template.cortex(scene.labels, hemi)
            if scene.surface not in cm.vertices:
                raise choice_error("surface", scene.surface, list(cm.vertices),
                                   f"Template {template.name!r} lacks it.")
            verts = cm.vertices[scene.surface]
            sulc = _template_sulc(template, scene.labels, hemi, cm) if with_sulc else None
            if sulc is None:
                sulc = (convexity(cm.vertices.get("pial", verts), cm.faces) if with_sulc
                        else np.zeros(len(verts), np.float32))
            ao = None if cm.occlusion is None else cm.occlusion.get(scene.surface)
            return part(f"cortex-{hemi}", "cortex", hemi, verts, cm.faces,
                        slots[np.asarray(cm.face_label, np.int64)], sulc, ao)

        def subcortical(slots: NDArray[Any]) -> PartGeometry | None:
            sub = template.subcortical()
            return part("subcortical", "subcortical", None, sub.vertices, sub.faces,
                        slots[np.asarray(sub.face_label, np.int64)],
                        np.zeros(len(sub.vertices), np.float32), sub.occlusion)

        def glass(hemi: str) -> PartGeometry | None:
            verts, faces = template.glass(hemi)
            return part(f"glass-{hemi}", "glass", hemi, verts, faces, np.full(len(faces), GLASS_SLOT),
                        np.zeros(len(verts), np.float32))

        if scene.surface not in template.surfaces:
            raise choice_error("surface", scene.surface, template.surfaces,
                               f"Template {template.name!r} lacks it.")
        # Palette slots come from the region names alone (the manifest): a part's mesh is loaded and
        # built when a view first shows it, so a one-hemisphere figure never pays for the other.
        builders: dict[str, tuple[str, str | None, Callable[[], PartGeometry | None]]] = {}
        for hemi in HEMIS:
            slots = slots_for([HEMI_PREFIX[hemi] + n for n in template.cortex_names(scene.labels, hemi)],
                              MEDIAL_SLOT)
            builders[f"cortex-{hemi}"] = ("cortex", hemi, partial(cortex, hemi, slots))
        if template.manifest.get("subcortical"):
            slots = slots_for(list(template.subcortical_names()), NEUTRAL_SLOT)
            builders["subcortical"] = ("subcortical", None, partial(subcortical, slots))
        for hemi in HEMIS:
            if hemi in template.manifest.get("glass", {}):
                builders[f"glass-{hemi}"] = ("glass", hemi, partial(glass, hemi))
        self._builders = builders
        self._built: dict[str, PartGeometry | None] = {}
        self._lock = threading.Lock()
        self.keys: tuple[str, ...] = tuple(keys)
        self.slot_of = slot_of
        self.default_rgb = np.asarray(defaults, dtype=np.float32)

    def _parts(self, names: list[str]) -> list[PartGeometry]:
        """The named parts, built now if not yet (in a fixed order; empty parts left out)."""
        with self._lock:
            for name in names:
                if name not in self._built:
                    self._built[name] = self._builders[name][2]()
        return [p for name in names if (p := self._built[name]) is not None]

    @property
    def parts(self) -> tuple[PartGeometry, ...]:
        """Every drawable part: cortex-lh, cortex-rh, subcortical, glass-lh, glass-rh (those present)."""
        return tuple(self._parts(list(self._builders)))

    @property
    def n_slots(self) -> int:
        return N_FIXED_SLOTS + len(self.keys)

    def visible(self, view: View) -> list[PartGeometry]:
        """The parts `view` draws (:func:`brainpainter.rendering.framing.shows`), opaque parts first.

        Raises
        ------
        BrainPainterError
            If the view draws nothing (its parts are absent from the template or all hidden).
        """
        parts = self._parts([name for name, (kind, hemi, _) in self._builders.items()
                             if framing.shows(view, kind, hemi)])
        if not parts:
            raise BrainPainterError(
                f"view {view.name!r} shows nothing: content={view.content!r}, hemis={list(view.hemis)}, "
                f"glass={list(view.glass)}; the template or the hidden regions leave no part to draw."
            )
        return sorted(parts, key=lambda p: p.kind == "glass")

    def camera(self, view: View, aspect: float) -> framing.CameraPose:
        """The orthographic camera of `view` framing its visible parts (image width / height = `aspect`)."""
        points = np.vstack([p.hull for p in self.visible(view)])
        return framing.frame(points, view.azimuth, view.elevation, view.zoom, aspect)
