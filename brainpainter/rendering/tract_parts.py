"""White-matter tubes as scene parts (kind ``tract``): one per hemisphere, coloured through palette slots."""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.parts import NEUTRAL_SLOT, Centrelines, PartGeometry
from brainpainter.rendering.settings import RGB
from brainpainter.tracts.values import MISSING_TRACT_KEY

if TYPE_CHECKING:
    from brainpainter.tracts.model import Tracts, TractSpec

#: Palette key prefix of the direction colours' slots.
DIRECTION_KEY = "tract-direction:"


def _rgb(c: NDArray[Any]) -> RGB:
    return (float(c[0]), float(c[1]), float(c[2]))


SlotsFor = Callable[[list[str], "int | RGB", frozenset[str]], NDArray[Any]]


@dataclass(frozen=True)
class TractLayer:
    """The tracts as a scene layer (:class:`~brainpainter.layers.kinds.PartsLayer`): their tubes and
    centrelines (:func:`tract_parts`).

    Parameters
    ----------
    spec : TractSpec, optional
        What to read (:meth:`for_template` reads it; every worker reads it again: the same subsample).
    nodes : tuple of (str, int)
        How each bundle is coloured: ``(name, 1)`` one colour (palette key ``tract:NAME``),
        ``(name, n)`` a profile of `n` nodes (``tract:NAME:0`` ...); the others by direction.
    radius : float, optional
        Of the tubes, millimetres; None: by the number of streamlines.
    tracts : Tracts, optional
        The bundles read, in the template's coordinates (given, or read from `spec`).
    """

    spec: TractSpec | None = None
    nodes: tuple[tuple[str, int], ...] = ()
    radius: float | None = None
    tracts: Tracts | None = None
    kind: str = "tracts"

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", tuple((str(n), int(k)) for n, k in self.nodes))
        object.__setattr__(self, "radius", None if self.radius is None else float(self.radius))

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the bundles read where a spec says what to read (a worker reads it again)."""
        return {**self.__dict__, "tracts": None if self.spec is not None else self.tracts}

    def for_template(self, template: Any) -> TractLayer:
        """The layer with its bundles read and placed in `template`'s coordinates."""
        if self.tracts is not None or self.spec is None:
            return self
        return replace(self, tracts=self.spec.load(template))

    def parts(self, template: Any, slots_for: SlotsFor) -> list[PartGeometry]:
        """The tubes and centrelines of the bundles read (:func:`tract_parts`)."""
        assert self.tracts is not None, "TractLayer.for_template reads the tracts first"
        return tract_parts(self.tracts, dict(self.nodes), slots_for, self.radius)

    def summary(self) -> dict[str, Any]:
        """The manifest's ``tracts``: each bundle's streamlines and how many were drawn."""
        assert self.tracts is not None, "TractLayer.for_template reads the tracts first"
        return self.tracts.summary()

    def digest(self) -> str:
        """A digest of what is drawn (the web's painters are keyed by it; the spec names its files)."""
        return hashlib.sha256(repr((self.spec, self.nodes, self.radius)).encode()).hexdigest()


def tract_parts(tracts: Tracts, nodes: Mapping[str, int], slots_for: SlotsFor,
                radius: float | None = None) -> list[PartGeometry]:
    """The tubes and centrelines of `tracts`, a part per hemisphere (``tracts-lh``, ``-rh``, ``tracts``).

    The tubes keep to :data:`~brainpainter.tracts.tubes.TRIANGLE_BUDGET` and are built
    on first use (:class:`TractPart`: a renderer that draws tubes, an export); the
    centrelines (:class:`~brainpainter.rendering.parts.Centrelines`, which the
    default renderer draws as lines) to the finer
    :data:`~brainpainter.tracts.tubes.LINE_SEGMENT_BUDGET`.

    Parameters
    ----------
    tracts : Tracts
    nodes : mapping of str to int
        Bundle name -> 1 (one colour) or the number of nodes of its profile; bundles absent are
        coloured by direction where none has values, else take :data:`MISSING_TRACT_KEY`'s slot.
    slots_for : callable
        ``slots_for(keys, default_colour, hidden)``: the palette slot of each key, made on first use.
    radius : float, optional
        Of the tubes, millimetres; default :func:`brainpainter.tracts.tubes.auto_radius`.

    Returns
    -------
    list of PartGeometry
        :class:`TractPart` each.
    """
    from brainpainter.tracts.names import hemisphere
    from brainpainter.tracts.tubes import SIDES, auto_radius, line_points_for, points_for

    n_lines, n_points = tracts.lines.shape[:2]
    radius = auto_radius(n_lines) if radius is None else radius
    # the tubes (for mesh renderers and export) within a triangle budget; the centrelines finer
    lines, point_slot = _points(tracts, nodes, slots_for, points_for(n_lines, n_points, SIDES))
    centres, centre_slot = _points(tracts, nodes, slots_for, line_points_for(n_lines, n_points))
    hemis = np.array([hemisphere(n) or "" for n in tracts.names])[tracts.bundle]
    out: list[PartGeometry] = []
    for hemi, part in (("lh", "tracts-lh"), ("rh", "tracts-rh"), ("", "tracts")):
        pick = hemis == hemi
        if not np.any(pick):
            continue
        centre = Centrelines(centres[pick].astype(np.float32), centre_slot[pick].astype(np.int32), radius)
        out.append(TractPart(part, hemi or None, lines[pick], point_slot[pick], centre))
    return out


class TractPart(PartGeometry):
    """A ``tract`` part whose tubes (vertices, normals, triangles, palette_index, sulc) are built
    when first read: a renderer that draws the centrelines as lines never builds them.

    Parameters
    ----------
    name : str
    hemi : {"lh", "rh"} or None
    lines : ndarray of float, shape (n_streamlines, n_points, 3)
        The streamlines at the tubes' level of detail (also the part's hull).
    point_slot : ndarray of int, shape (n_streamlines, n_points)
        Palette slot of each point.
    centrelines : Centrelines
        Its radius is the tubes'.
    """

    def __init__(self, name: str, hemi: str | None, lines: NDArray[Any], point_slot: NDArray[Any],
                 centrelines: Centrelines) -> None:
        for key, value in (("name", name), ("kind", "tract"), ("hemi", hemi),
                           ("hull", lines.reshape(-1, 3)), ("centrelines", centrelines)):
            object.__setattr__(self, key, value)
        object.__setattr__(self, "_lines", (lines, point_slot))

    def __repr__(self) -> str:
        return f"TractPart({self.name!r}, tubes {'built' if self.tubes_built else 'not built'})"

    @property
    def tubes_built(self) -> bool:
        """Whether the tubes' arrays were built (read by someone)."""
        return "_tubes" in self.__dict__

    @cached_property
    def _tubes(self) -> tuple[NDArray[Any], ...]:
        from brainpainter.tracts.tubes import SIDES, tube_mesh

        lines, point_slot = self.__dict__["_lines"]
        assert self.centrelines is not None
        verts, normals, tris = tube_mesh(lines, self.centrelines.radius, SIDES)
        pal = np.repeat(point_slot.ravel(), SIDES).astype(np.int32)
        return verts, normals, tris, pal, np.zeros(len(verts), np.float32)

    @property
    def vertices(self) -> NDArray[Any]:
        """Of the tubes, float32, shape (n_streamlines * n_points * SIDES, 3)."""
        return self._tubes[0]

    @property
    def normals(self) -> NDArray[Any]:
        """Of the tubes, unit, radial; float32, same shape as vertices."""
        return self._tubes[1]

    @property
    def triangles(self) -> NDArray[Any]:
        """Of the tubes, uint32, shape (n_triangles, 3)."""
        return self._tubes[2]

    @property
    def palette_index(self) -> NDArray[Any]:
        """Palette slot of each tube vertex, int32."""
        return self._tubes[3]

    @property
    def sulc(self) -> NDArray[Any]:
        """Zeros, float32, one per tube vertex."""
        return self._tubes[4]


def _points(tracts: Tracts, nodes: Mapping[str, int], slots_for: SlotsFor,
            m: int) -> tuple[NDArray[Any], NDArray[Any]]:
    """The streamlines at `m` points each (fewer than read: level of detail) and each point's palette slot.

    Returns
    -------
    lines : ndarray of float, shape (n_streamlines, m, 3)
    slots : ndarray of int64, shape (n_streamlines, m)
    """
    from brainpainter.tracts.names import bundle_key
    from brainpainter.tracts.streamlines import direction_bins, resample

    lines = tracts.lines
    n_lines, n_points = lines.shape[:2]
    if m < n_points:
        lines = resample(lines.reshape(-1, 3), np.arange(n_lines) * n_points, np.full(n_lines, n_points), m)
        n_points = m
    point_slot = np.zeros((n_lines, n_points), np.int64)
    direction = [i for i, name in enumerate(tracts.names) if nodes.get(name, 0) < 1]
    if direction and any(n >= 1 for n in nodes.values()):  # values for others: the missing colour
        point_slot[np.isin(tracts.bundle, direction)] = slots_for([MISSING_TRACT_KEY], NEUTRAL_SLOT,
                                                                  frozenset())[0]
    elif direction:
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
    return lines, point_slot
