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
(:attr:`SceneGeometry.keys`), then the tracts' keys (``tract:AF_left`` for a
bundle's one colour, ``tract:AF_left:17`` for node 17 of an along-tract
profile, ``tract-direction:i`` for the fixed direction colours).

White-matter tracts are parts of kind ``tract`` (``tracts-lh``, ``tracts-rh``
and ``tracts`` for commissural bundles): triangle tubes built here
(:func:`brainpainter.tracts.tubes.tube_mesh`), so a renderer draws them as it
draws any opaque part.
(:attr:`SceneGeometry.keys`).

A scene coloured per vertex (``Scene.coloring == "vertices"``, a map) keeps
one drawing path: its cortex parts are the template's stored meshes, not
split by region, and every cortex vertex has a palette slot of its own
(:attr:`SceneGeometry.vertex_slots`: lh's vertices from slot 3, then rh's;
region keys after them). The palette's colours of those slots are the map's
colours per vertex (:class:`VertexColors`), which renderers interpolate
across each triangle.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
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
    from brainpainter.tracts.model import Tracts


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
    def tracts(self) -> Tracts | None: ...
    @property
    def tract_nodes(self) -> tuple[tuple[str, int], ...]: ...
    @property
    def tract_radius(self) -> float | None: ...
    @property
    def coloring(self) -> str: ...

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
        ``cortex-lh``, ``cortex-rh``, ``subcortical``, ``glass-lh``, ``glass-rh``,
        ``tracts-lh``, ``tracts-rh``, ``tracts``.
    kind : {"cortex", "subcortical", "glass", "tract"}
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


#: Palette slots at most: a renderer's palette is a 2-D texture (the Blender renderer's: 4096 texels
#: a row) whose rows GPUs limit to 16384 (llvmpipe included); a scene needing more is refused with advice.
MAX_SLOTS = 4096 * 16_384
#: Palette key prefix of the direction colours' slots.
DIRECTION_KEY = "tract-direction:"


def _rgb(c: NDArray[Any]) -> RGB:
    return (float(c[0]), float(c[1]), float(c[2]))


SlotsFor = Callable[[list[str], "int | RGB", frozenset[str]], NDArray[Any]]


def tract_parts(tracts: Tracts, nodes: Mapping[str, int], slots_for: SlotsFor,
                radius: float | None = None) -> list[PartGeometry]:
    """The tubes of `tracts`, one part per hemisphere (``tracts-lh``, ``tracts-rh``; ``tracts`` for the rest).

    Parameters
    ----------
    tracts : Tracts
    nodes : mapping of str to int
        Bundle name -> 1 (one colour) or the number of nodes of its profile;
        bundles absent are coloured by direction.
    slots_for : callable
        ``slots_for(keys, default_colour, hidden)``: the palette slot of each key, made on first use.
    radius : float, optional
        Of the tubes, millimetres; default :func:`brainpainter.tracts.tubes.auto_radius`.

    Returns
    -------
    list of PartGeometry
    """
    from brainpainter.tracts.names import bundle_key, hemisphere
    from brainpainter.tracts.streamlines import direction_bins, resample
    from brainpainter.tracts.tubes import SIDES, auto_radius, points_for, tube_mesh

    lines = tracts.lines
    n_lines, n_points = lines.shape[:2]
    radius = auto_radius(n_lines) if radius is None else radius
    m = points_for(n_lines, n_points, SIDES)
    if m < n_points:  # level of detail: fewer points per streamline for many streamlines
        lines = resample(lines.reshape(-1, 3), np.arange(n_lines) * n_points, np.full(n_lines, n_points), m)
        n_points = m
    point_slot = np.zeros((n_lines, n_points), np.int64)
    direction = [i for i, name in enumerate(tracts.names) if nodes.get(name, 0) < 1]
    if direction:
        pick = np.isin(tracts.bundle, direction)
        bins, colors = direction_bins(lines[pick])
        used = np.unique(bins)
        slot = np.zeros(len(colors), np.int64)
        for b in used:
            slot[b] = slots_for([f"{DIRECTION_KEY}{b}"], _rgb(colors[b]), frozenset())[0]
        point_slot[pick] = slot[bins]
    for i, name in enumerate(tracts.names):
        n = nodes.get(name, 0)
        if n < 1:
            continue
        if n == 1:
            node_slot = slots_for([bundle_key(name)], NEUTRAL_SLOT, frozenset())
        else:
            node_slot = slots_for([bundle_key(name, k) for k in range(n)], NEUTRAL_SLOT, frozenset())
        # point j of n_points takes the node at the same fraction of the streamline's length
        node_of_point = np.rint(np.arange(n_points) * (n - 1) / max(n_points - 1, 1)).astype(np.int64)
        point_slot[tracts.bundle == i] = node_slot[node_of_point]
    hemis = np.array([hemisphere(n) or "" for n in tracts.names])[tracts.bundle]
    out = []
    for hemi, part in (("lh", "tracts-lh"), ("rh", "tracts-rh"), ("", "tracts")):
        pick = hemis == hemi
        if not np.any(pick):
            continue
        verts, normals, tris = tube_mesh(lines[pick], radius, SIDES)
        pal = np.repeat(point_slot[pick].ravel(), SIDES).astype(np.int32)
        out.append(PartGeometry(part, "tract", hemi or None, verts, normals, tris, pal,
                                np.zeros(len(verts), np.float32), lines[pick].reshape(-1, 3)))
    return out


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


class VertexColors(Mapping[str, RGB]):
    """One image of a map: region colours (a mapping, as for a region image) plus per-vertex cortex colours.

    Parameters
    ----------
    regions : mapping of str to (r, g, b)
        Colours of region keys (the subcortical structures).
    vertices : mapping of str to ndarray of float32, shape (n_vertices, 3)
        sRGB 0-1 per cortex vertex of each hemisphere (:attr:`SceneGeometry.vertex_slots`).
    """

    def __init__(self, regions: Mapping[str, RGB], vertices: Mapping[str, NDArray[Any]]) -> None:
        self.regions = dict(regions)
        self.vertices = dict(vertices)

    def __getitem__(self, key: str) -> RGB:
        return self.regions[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.regions)

    def __len__(self) -> int:
        return len(self.regions)


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
    vertex_slots : dict of str to (int, int)
        Per-vertex scenes: first slot and number of cortex vertices of each hemisphere (else empty).
    source_vertex : dict of str to ndarray of int32, shape (n_vertices,)
        Per-vertex scenes: the fsaverage vertex of each cortex vertex, per hemisphere.
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
        parts: list[PartGeometry] = []
        per_vertex = getattr(scene, "coloring", "regions") == "vertices"
        meshes = {hemi: self._cortex_mesh(scene, hemi, per_vertex) for hemi in HEMIS}
        self.vertex_slots: dict[str, tuple[int, int]] = {}
        self.source_vertex: dict[str, NDArray[Any]] = {}
        if per_vertex:
            for hemi, cm in meshes.items():
                self.vertex_slots[hemi] = (len(defaults), len(cm.source_vertex))
                self.source_vertex[hemi] = np.asarray(cm.source_vertex, np.int32)
                defaults.extend([defaults[MEDIAL_SLOT]] * len(cm.source_vertex))
        first_key = len(defaults)

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

        def add(name: str, kind: str, hemi: str | None, verts: NDArray[Any], faces: NDArray[Any],
                face_slot: NDArray[Any], sulc: NDArray[Any], first_slot: int | None = None,
                ao: NDArray[Any] | None = None) -> None:
            keep = face_slot >= 0
            faces, face_slot = np.asarray(faces)[keep], face_slot[keep]
            if not len(faces):
                return
            normals = vertex_normals(verts, faces)
            if settings.shading == "flat" or ao is None or len(ao) != len(verts):
                ao = None  # flat colours stay exact; a template without occlusion draws without it
            per_vertex: tuple[NDArray[Any], ...] = (normals, sulc) if ao is None else (normals, sulc, ao)
            extra: tuple[NDArray[Any], ...]
            if first_slot is not None:  # per vertex: the mesh as stored, one slot per vertex
                v, tri, extra = verts, np.asarray(faces, np.uint32), per_vertex
                pal = (first_slot + np.arange(len(verts))).astype(np.int32)
            else:
                v, tri, pal, extra = split_by_label(verts, faces, face_slot, per_vertex)
            parts.append(PartGeometry(name, kind, hemi, v.astype(np.float32), extra[0].astype(np.float32),
                                      tri, pal, extra[1].astype(np.float32), v,
                                      None if ao is None else extra[2].astype(np.float32)))

        for hemi in HEMIS:
            cm = meshes[hemi]
            if scene.surface not in cm.vertices:
                raise choice_error("surface", scene.surface, list(cm.vertices),
                                   f"Template {template.name!r} lacks it.")
            names = [HEMI_PREFIX[hemi] + n for n in cm.label_names]
            face_slot = slots_for(names, MEDIAL_SLOT, hidden)[np.asarray(cm.face_label, np.int64)]
            verts = cm.vertices[scene.surface]
            sulc = _template_sulc(template, scene.labels, hemi, cm) if with_sulc else None
            if sulc is None:
                sulc = (convexity(cm.vertices.get("pial", verts), cm.faces) if with_sulc
                        else np.zeros(len(verts), np.float32))
            occlusion = getattr(cm, "occlusion", None)
            add(f"cortex-{hemi}", "cortex", hemi, verts, cm.faces, face_slot, sulc,
                self.vertex_slots[hemi][0] if per_vertex else None,
                None if occlusion is None else occlusion.get(scene.surface))
        if template.manifest.get("subcortical"):
            sub = template.subcortical()
            face_slot = slots_for(list(sub.label_names), NEUTRAL_SLOT, hidden)[
                np.asarray(sub.face_label, np.int64)]
            add("subcortical", "subcortical", None, sub.vertices, sub.faces, face_slot,
                np.zeros(len(sub.vertices), np.float32), ao=getattr(sub, "occlusion", None))
        if scene.tracts is not None:
            parts += tract_parts(scene.tracts, dict(scene.tract_nodes), slots_for, scene.tract_radius)
        for hemi in HEMIS:
            if hemi not in template.manifest.get("glass", {}):
                continue
            verts, faces = template.glass(hemi)
            add(f"glass-{hemi}", "glass", hemi, verts, faces, np.full(len(faces), GLASS_SLOT),
                np.zeros(len(verts), np.float32))
        if len(defaults) > MAX_SLOTS:
            raise BrainPainterError(
                f"the scene needs {len(defaults):,} palette slots (regions, vertices, bundles and "
                f"along-tract nodes); at most {MAX_SLOTS:,} fit a palette texture; give profiles with fewer "
                "nodes or fewer bundles.")
        #: rotation from the template's coordinates to RAS (its anterior and superior axes)
        self.to_ras: NDArray[Any] = np.asarray(template.to_ras, dtype=float)
        self.parts: tuple[PartGeometry, ...] = tuple(parts)
        self.keys: tuple[str, ...] = tuple(keys)
        self.slot_of = slot_of
        self.default_rgb = np.asarray(defaults, dtype=np.float32)

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

        A template that lacks the part a view is about (a brain of region
        meshes with structures only, or with an outer surface only) draws its
        other part instead, so every view shows it. Renderers draw exactly
        these parts.

        Raises
        ------
        BrainPainterError
            If the view draws nothing (its parts are absent from the template or all hidden).
        """
        parts = [p for p in self.parts if framing.shows(view, p.kind, p.hemi)]
        kinds = {p.kind for p in self.parts}
        if view.content == "cortex" and "cortex" not in kinds:
            # a brain of region meshes without an outer surface: its structures stand for it
            parts = [p for p in self.parts if p.kind == "subcortical" or framing.shows(view, p.kind, p.hemi)]
        elif view.content == "subcortical" and "subcortical" not in kinds:
            # ... and one without structures shows its surface (both hemispheres, no glass over it)
            parts = [p for p in self.parts if p.kind == "cortex"]
        if not parts:
            raise BrainPainterError(
                f"view {view.name!r} shows nothing: content={view.content!r}, hemis={list(view.hemis)}, "
                f"glass={list(view.glass)}; the template or the hidden regions leave no part to draw."
            )
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
