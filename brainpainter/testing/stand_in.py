"""The stand-in renderer: renders without Blender, for tests of the core and of plugins.

One class, :class:`StandInRenderer`, with parameters (class attributes) for
what a test needs: how it draws (``layout``), how long an image takes
(``delay``), where it fails on purpose (``fail``), noisy pixels
(``noise``) and extra memory kept per image (``leak_mb``, to prove a memory
check can fail). :meth:`StandInRenderer.with_` makes a configured subclass;
a module-level subclass setting the same attributes is what worker processes
can import. Every class counts its scenes and images and records
``(colors, view)`` per image in ``calls``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]
LAYOUTS = ("faces", "band", "solid", "keys")


class StandInRenderer:
    """A renderer without Blender: paints the colours a real one would, in a simple layout.

    Loading checks what a real renderer needs: the scene's label set exists on
    both hemispheres and the surface is there. The parameters are class
    attributes: set them on a subclass or with :meth:`with_`.

    Parameters
    ----------
    scene : Scene
        What to draw (template, label set, surface, settings, hidden keys).

    Attributes
    ----------
    layout : {"faces", "band", "solid", "keys"}
        ``faces`` (default): full-height stripes, one per face of the view's
        structures sampled evenly (grouped by label), each in its colour
        (medial wall / neutral grey where the key has no colour), then one per
        value-coloured bundle (or node) of the view's tracts, then one per connectome node and edge,
        then one per blob level. A cutaway view (``view.clip``) draws each cortex face its planes
        remove in the cut face's colour (:data:`~brainpainter.rendering.clip.CAP_COLOR`), and the
        structures, tracts, nodes and blobs inside.
        ``band``: the background (transparent when ``background`` is None)
        with a "brain" in the middle half of the rows and the middle 3/4 of the
        columns, one stripe per key of `regions` (a smaller band in
        subcortical views). ``solid``: the whole image in the colour of
        ``regions[0]``. ``keys``: pixel ``(0, k)`` has the k-th given colour.
    regions : tuple of str
        Region keys drawn by the ``band`` and ``solid`` layouts.
    delay : float
        Seconds each image takes.
    noise : bool
        Random pixels (incompressible PNGs; fills a small disk quickly).
    fail : callable, optional
        ``fail(n)`` -> an exception to raise at this class's n-th image in this process (1-based), or None.
    leak_mb : float
        Memory kept for ever per image (a leak, for testing memory checks).
    record : bool
        Whether ``calls`` records each image (off for memory measurements).
    draws_tubes : bool
        The renderer contract's capability: whether it draws the tract parts' tubes. True: loading
        reads them (``tube_triangles``: their number), as a mesh renderer uploads them.
    calls : list of (dict, View)
        ``(colors, view)`` of every image of this class.
    scenes, images : int
        Renderers made and images drawn by this class in this process.
    """

    layout: ClassVar[str] = "faces"
    regions: ClassVar[tuple[str, ...]] = ("Left-insula",)
    delay: ClassVar[float] = 0.0
    noise: ClassVar[bool] = False
    fail: ClassVar[Callable[[int], BaseException | None] | None] = None
    leak_mb: ClassVar[float] = 0.0
    record: ClassVar[bool] = True
    draws_tubes: ClassVar[bool] = False
    calls: ClassVar[list[tuple[dict[str, Any], Any]]] = []
    scenes: ClassVar[int] = 0
    images: ClassVar[int] = 0
    kept: ClassVar[list[Image]] = []

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.reset()

    @classmethod
    def reset(cls) -> None:
        """Forget the calls, counts and leaked memory of this class."""
        cls.calls, cls.scenes, cls.images, cls.kept = [], 0, 0, []

    @classmethod
    def with_(cls, **params: Any) -> type[StandInRenderer]:
        """A subclass with the given parameters (see the class attributes), e.g. ``with_(delay=0.1)``."""
        unknown = sorted(set(params) - {"layout", "regions", "delay", "noise", "fail", "leak_mb",
                                        "record", "draws_tubes"})
        if unknown or params.get("layout", cls.layout) not in LAYOUTS:
            raise ValueError(f"unknown stand-in parameters {unknown} or layout; layouts: {LAYOUTS}")
        if params.get("fail") is not None:
            params["fail"] = staticmethod(params["fail"])
        return type(f"{cls.__name__}Configured", (cls,), params)

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.parts: dict[str, tuple[list[str], NDArray[Any]]] = {}
        self.centres: dict[str, NDArray[Any]] = {}  # each cortex face's centre, in the order of its labels
        for hemi in ("lh", "rh"):
            cm = scene.template.cortex(scene.labels, hemi)
            if scene.surface not in cm.vertices:
                raise AssertionError(f"template {scene.template.name!r} has no {scene.surface} surface")
            prefix = {"lh": "Left-", "rh": "Right-"}[hemi]
            order = np.argsort(cm.face_label, kind="stable")
            self.parts[hemi] = ([prefix + n for n in cm.label_names], np.asarray(cm.face_label)[order])
            corners = np.asarray(cm.vertices[scene.surface])[np.asarray(cm.faces)[order]]
            self.centres[hemi] = corners.mean(axis=1)
        if scene.template.manifest.get("subcortical"):
            sub = scene.template.subcortical()
            self.parts["subcortical"] = (list(sub.label_names), np.sort(sub.face_label))
        # value-coloured tracts: (hemisphere, palette key) per bundle or node (direction colours: none)
        self.tract_keys: list[tuple[str | None, str]] = []
        tract_layer = next((la for la in getattr(scene, "layers", ()) if la.kind == "tracts"), None)
        if tract_layer is not None:
            from brainpainter.tracts.names import bundle_key, hemisphere

            for name, n in tract_layer.nodes:
                if name in tract_layer.tracts.names:
                    keys = [bundle_key(name)] if n == 1 else [bundle_key(name, k) for k in range(n)]
                    self.tract_keys += [(hemisphere(name), k) for k in keys]
        self.tube_triangles = 0
        if self.draws_tubes and scene.tracts is not None:
            self.tube_triangles = sum(len(p.triangles) for p in scene.geometry.parts if p.kind == "tract")
        connectome = getattr(scene, "connectome", None)
        #: (kind, hemisphere, key) of a connectome's nodes and edges: a stripe each where a view draws them
        self.connectome_keys: list[tuple[str, str | None, str]] = []
        if connectome is not None:
            from brainpainter.connectome.model import edge_keys, node_keys
            from brainpainter.rendering.connectome_parts import node_hemis

            sides = node_hemis(connectome.positions)
            source, target, weight = connectome.edges()
            self.connectome_keys = [("node", str(h), k) for h, k in zip(sides, node_keys(connectome.n_nodes),
                                                                           strict=True)]
            self.connectome_keys += [("edge", str(sides[a]) if sides[a] == sides[b] else None, k)
                                     for a, b, k in zip(source, target, edge_keys(len(weight)), strict=True)]
        # how cortex views draw the cortex (scene.geometry.cortex, resolved without building the geometry)
        cortex = getattr(getattr(scene, "settings", None), "cortex", "opaque")
        inside = getattr(scene, "tracts", None) is not None or connectome is not None
        self.cortex = ("glass" if inside else "opaque") if cortex == "auto" else cortex
        type(self).scenes += 1

    def painted(self, colors: Mapping[str, Any], part: str) -> dict[str, Any]:
        """Label key -> colour drawn (None: default colour) for one part (``lh``, ``rh``, ``subcortical``)."""
        keys, labels = self.parts[part]
        return {keys[i]: colors.get(keys[i]) for i in sorted(set(labels.tolist()))
                if keys[i] not in self.scene.hidden}

    def render(self, colors: Mapping[str, Any], view: Any) -> Image:
        """Draw one image, shape (height, width, 4), uint8 RGBA."""
        cls = type(self)
        cls.images += 1
        if cls.record:
            cls.calls.append((dict(colors), view))
        failure = cls.fail(cls.images) if cls.fail is not None else None
        if failure is not None:
            raise failure
        if cls.delay:
            time.sleep(cls.delay)
        if cls.leak_mb:
            cls.kept.append(np.ones(int(cls.leak_mb * 2**20), np.uint8))
        s = self.scene.settings
        if cls.noise:
            img = np.random.default_rng(cls.images).integers(0, 256, (s.height, s.width, 4), dtype=np.uint8)
            img[..., 3] = 255
            return img
        layouts = {"faces": self._faces, "band": self._band, "solid": self._solid, "keys": self._keys}
        draw = layouts[cls.layout]
        return draw(colors, view, s.height, s.width)

    def _faces(self, colors: Mapping[str, Any], view: Any, height: int, width: int) -> Image:
        from brainpainter.rendering.clip import CAP_COLOR, removed
        from brainpainter.rendering.framing import shows

        kinds = {"lh": ("cortex", "lh"), "rh": ("cortex", "rh"), "subcortical": ("subcortical", None)}
        default = {"subcortical": (0.8, 0.8, 0.8)}
        stripes = []
        for part, (kind, hemi) in kinds.items():
            if not (shows(view, kind, hemi, self.cortex) or (hemi and shows(view, "flat", hemi))):
                continue  # a flat view: the stripes of its hemispheres' cortex
            keys, labels = self.parts.get(part, ([], np.zeros(0, int)))
            slots = getattr(getattr(self.scene, "geometry", None), "vertex_slots", {}) if hemi else {}
            if view.content == "flat" and hemi and self.scene.geometry.flat_slots():
                hemi = f"flat-{hemi}"  # a map on a flat view: the sheet's per-vertex colours
            if getattr(self.scene, "coloring", "regions") == "vertices" and hemi in slots:
                start, n = slots[hemi]  # a map: the cortex's per-vertex colours, in vertex order
                stripes += [tuple(c) for c in colors.rgb[start:start + n]]  # type: ignore[attr-defined]
                continue
            cut = removed(self.centres[part], getattr(view, "clip", ())) if part in self.centres else ()
            stripes += [CAP_COLOR if len(cut) and cut[k] else
                        colors.get(keys[i]) or default.get(part, self.scene.medial_wall_color)
                        for k, i in enumerate(labels) if keys[i] not in self.scene.hidden]
        stripes += [colors.get(key) or default["subcortical"] for hemi, key in self.tract_keys
                    if shows(view, "tract", hemi, self.cortex)]
        stripes += [colors.get(key) or default["subcortical"] for kind, hemi, key in self.connectome_keys
                    if shows(view, kind, hemi, self.cortex)]
        img = np.zeros((height, width, 4), np.uint8)
        if stripes:
            cols = np.asarray(stripes, dtype=float)[np.linspace(0, len(stripes) - 1, width).astype(int)]
            img[..., :3] = np.round(cols[None, :, :3] * 255).astype(np.uint8)
            img[..., 3] = 255
        return img

    def _band(self, colors: Mapping[str, Any], view: Any, height: int, width: int) -> Image:
        background = self.scene.settings.background
        img = np.zeros((height, width, 4), np.uint8)
        if background is not None:
            img[..., :3] = np.round(np.array(background) * 255)
            img[..., 3] = 255
        top, bottom = (height // 3, 2 * height // 3) if view.content == "subcortical" else (
            height // 4, 3 * height // 4)
        edges = band_edges(width, len(self.regions))
        for k, key in enumerate(self.regions):
            img[top:bottom, edges[k]:edges[k + 1], :3] = np.round(np.array(colors[key]) * 255)
            img[top:bottom, edges[k]:edges[k + 1], 3] = 255
        return img

    def _solid(self, colors: Mapping[str, Any], view: Any, height: int, width: int) -> Image:
        img = np.zeros((height, width, 4), np.uint8)
        img[..., :3] = np.round(np.array(colors[self.regions[0]]) * 255).astype(np.uint8)
        img[..., 3] = 255
        return img

    def _keys(self, colors: Mapping[str, Any], view: Any, height: int, width: int) -> Image:
        img = np.zeros((height, width, 4), np.uint8)
        rgb = np.round(np.array(list(colors.values())) * 255).astype(np.uint8)[:width]
        img[0, : len(rgb), :3] = rgb
        img[..., 3] = 255
        return img

    def close(self) -> None:
        """Nothing to free."""


def band_edges(width: int, n: int) -> NDArray[np.int_]:
    """Column edges of the ``band`` layout's `n` stripes, shape (n + 1,)."""
    return np.linspace(width // 8, width - width // 8, n + 1).astype(int)


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
def stand_in(name: str = "stand-in", cls: type[StandInRenderer] = StandInRenderer) -> Iterator[str]:
    """Register `cls` (default :class:`StandInRenderer`) as renderer `name`, counts reset; yields `name`."""
    cls.reset()
    with registered_renderer(name, cls) as registered:
        yield registered
