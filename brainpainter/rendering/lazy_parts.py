"""A scene's parts in drawing order, each built when a view first shows it (:class:`LazyParts`).

:class:`~brainpainter.rendering.geometry.SceneGeometry` numbers every palette slot from the
template's label names when it is made, then registers here how to build each part; a
lateral-left image builds the left cortex only (not the right one, the structures or the glass).
A region scene's cortex part may be read from the user's cache instead
(:mod:`brainpainter.rendering.part_cache`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.parts import GLASS_SLOT, PartGeometry, PendingPart, build_part

if TYPE_CHECKING:
    from brainpainter.atlas.template import Template


class LazyParts:
    """Parts built or still to build, in drawing order.

    Parameters
    ----------
    first_key : int
        First palette slot of a region key (the regions a part draws are its slots from here on).
    shaded : bool
        Whether the scene is shaded (baked occlusion kept; flat shading drops it).
    n_slots : callable
        The scene's number of palette slots (a part read from the cache must stay below it).

    Attributes
    ----------
    entries : list of PartGeometry or PendingPart
    part_slots : dict of str to frozenset of int
        Region slots of each built part's faces, by part name.
    """

    def __init__(self, first_key: int, shaded: bool, n_slots: Callable[[], int]) -> None:
        self.entries: list[PartGeometry | PendingPart] = []
        self.part_slots: dict[str, frozenset[int]] = {}
        self._first_key, self._shaded, self._n_slots = first_key, shaded, n_slots

    def later(self, name: str, kind: str, hemi: str | None, drawn: bool, mesh: Callable[[], dict[str, Any]],
              kept: tuple[list[Any], dict[str, Any]] | None = None, **fixed: Any) -> None:
        """A part to build when first shown: `mesh()` gives build_part's arrays (and ao, outline);
        with `kept` (its template files and what else it depends on), kept in the user's cache."""
        def build() -> PartGeometry | None:
            m = mesh()
            part = build_part(name, kind, hemi, m.pop("verts"), m.pop("faces"), m["face_slot"],
                              m.pop("sulc"), occlusion=self._shaded, **fixed,
                              **{k: v for k, v in m.items() if k != "face_slot"})
            if part is not None:
                self.part_slots[name] = self._regions(m["face_slot"])
            return part

        def build_or_read() -> PartGeometry | None:
            from brainpainter.rendering.part_cache import cached_part

            assert kept is not None
            part = cached_part(*kept, name, kind, hemi, self._n_slots(), build)
            if part is not None and name not in self.part_slots:  # read: its slots from its vertices
                self.part_slots[name] = self._regions(part.palette_index)
            return part

        self.entries.append(PendingPart(name, kind, hemi, drawn, build if kept is None else build_or_read))

    def _regions(self, slots: NDArray[Any]) -> frozenset[int]:
        return frozenset(int(i) for i in np.unique(slots) if i >= self._first_key)

    def later_subcortical(self, template: Template, hidden: frozenset[str], sub_slot: NDArray[Any]) -> None:
        """The subcortical part (`sub_slot`: the slot of each structure, -1 hidden)."""
        def subcortical() -> dict[str, Any]:
            sub = template.subcortical()
            return {"verts": sub.vertices, "faces": sub.faces,
                    "face_slot": sub_slot[np.asarray(sub.face_label, np.int64)],
                    "sulc": np.zeros(len(sub.vertices), np.float32),
                    "ao": template.subcortical_occlusion(hidden)}

        self.later("subcortical", "subcortical", None, bool((sub_slot >= 0).any()), subcortical)

    def later_glass(self, template: Template, hemi: str) -> None:
        """A glass hull (one slot: the glass's)."""
        def glass() -> dict[str, Any]:
            verts, faces = template.glass(hemi)
            return {"verts": verts, "faces": faces, "face_slot": np.full(len(faces), GLASS_SLOT),
                    "sulc": np.zeros(len(verts), np.float32)}

        self.later(f"glass-{hemi}", "glass", hemi, True, glass)

    def built(self, wanted: Callable[[str, str | None], bool]) -> list[PartGeometry]:
        """The parts (of kind and hemisphere) `wanted`, built now where they were not yet, in order."""
        out: list[PartGeometry] = []
        for i, entry in enumerate(self.entries):
            if not wanted(entry.kind, entry.hemi):
                continue
            if isinstance(entry, PendingPart):
                part = entry.build()
                self.entries[i] = entry = part if part is not None else replace(entry, drawn=False)
            if isinstance(entry, PartGeometry):
                out.append(entry)
        return out

    def built_parts(self) -> list[PartGeometry]:
        """The parts built so far (none built now)."""
        return [e for e in self.entries if isinstance(e, PartGeometry)]

    def kinds(self) -> set[str]:
        """Kinds of the parts that draw something (built, or pending with faces to draw)."""
        return {e.kind for e in self.entries if isinstance(e, PartGeometry) or e.drawn}


def cortex_arrays(scene: Any, hemi: str, label_slot: NDArray[Any], mesh: Any, with_sulc: bool,
                  cortex_mesh: Callable[[Any, str, bool], Any],
                  borders: Callable[..., tuple[NDArray[Any] | None, NDArray[Any] | None]]) -> dict[str, Any]:
    """A cortex part's arrays for :func:`build_part` (`mesh`: a map's, else ``cortex_mesh(scene, hemi,
    False)``, the template's split one); `borders` gives its outline and contour
    (``SceneGeometry._borders``)."""
    from brainpainter.errors import choice_error
    from brainpainter.rendering.sulc import part_sulc

    cm = mesh if mesh is not None else cortex_mesh(scene, hemi, False)
    if scene.surface not in cm.vertices:
        raise choice_error("surface", scene.surface, list(cm.vertices),
                           f"Template {scene.template.name!r} lacks it.")
    face_slot = label_slot[np.asarray(cm.face_label, np.int64)]
    verts = cm.vertices[scene.surface]
    occlusion = getattr(cm, "occlusion", None)
    outline, contour = (borders(scene, hemi, cm, verts, face_slot, mesh is not None)
                        if scene.settings.outline_width > 0 else (None, None))
    return {"verts": verts, "faces": cm.faces, "face_slot": face_slot,
            "sulc": part_sulc(scene.template, scene.labels, hemi, cm, verts, with_sulc),
            "ao": None if occlusion is None else occlusion.get(scene.surface),
            "outline": outline, "contour": contour}
