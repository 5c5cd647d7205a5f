"""The foci layer: read (:func:`read_foci`), drawn (:class:`Foci`: its spheres, colours and legend)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.rgb import to_rgb
from brainpainter.color.scale import ColourScale, ScaleOptions
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.blob_parts import template_points
from brainpainter.rendering.connectome_parts import node_hemis, sphere_mesh
from brainpainter.rendering.layers import Layer
from brainpainter.rendering.parts import PartGeometry

RGB = tuple[float, float, float]
#: Radius of a focus where neither the file nor ``radius=`` gives one, millimetres.
RADIUS = 4.0
COLOR = "#d62728"
KEY = "foci:"


@dataclass(frozen=True)
class FociTable:
    """Foci as read: positions in MNI152 millimetres, shape (n, 3); names, values (NaN: none),
    colours (None: by value) and radii (NaN: the default), each of length n."""

    source: str
    positions: NDArray[np.float64]
    names: tuple[str, ...]
    values: NDArray[np.float64]
    colors: tuple[RGB | None, ...]
    radii: NDArray[np.float64]


def read_foci(path: str | Path) -> FociTable:
    """A foci CSV: columns ``x,y,z`` (MNI152 mm), optional ``name``, ``value``, ``color``, ``radius``."""
    import pandas as pd

    try:
        table = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"foci file {str(path)!r} cannot be read as CSV ({exc}); give a CSV with "
                                "columns x,y,z.") from None
    table.columns = [str(c).strip().lower() for c in table.columns]
    missing = [c for c in ("x", "y", "z") if c not in table.columns]
    if missing or table.empty:
        raise BrainPainterError(f"foci file {str(path)!r} has columns {list(table.columns)}; a foci file "
                                "has x,y,z (MNI152 mm) and one row per focus (optional name,value,color,"
                                "radius).")
    try:
        xyz = table[["x", "y", "z"]].to_numpy(dtype=float)
        values = (table["value"].to_numpy(dtype=float) if "value" in table else np.full(len(table), np.nan))
        radii = table["radius"].to_numpy(dtype=float) if "radius" in table else np.full(len(table), np.nan)
    except ValueError as exc:
        raise BrainPainterError(f"foci file {str(path)!r}: {exc}; x, y, z, value and radius are numbers.") \
            from None
    if not np.isfinite(xyz).all():
        raise BrainPainterError(f"foci file {str(path)!r} has a focus without x, y or z; give all three.")
    names = tuple(str(n) for n in table["name"]) if "name" in table else tuple(
        f"focus {i + 1}" for i in range(len(table)))
    colors = tuple(None if not isinstance(c, str) or not c.strip() else to_rgb(c.strip())
                   for c in (table["color"] if "color" in table else [None] * len(table)))
    return FociTable(str(path), xyz, names, values, colors, radii)


@dataclass(frozen=True)
class Foci:
    """The foci drawn: spheres in the template's coordinates, coloured on their own scale.

    Implements :class:`brainpainter.layers.kinds.DrawnLayer`.
    """

    table: FociTable
    scale: ColourScale
    label: str
    radius: float
    color: RGB
    kind: str = "foci"

    def keys(self) -> list[str]:
        """Palette keys of the foci, ``foci:0`` ..."""
        return [f"{KEY}{i}" for i in range(len(self.table.names))]

    def parts(self, template: Any, slots_for: Callable[..., Any]) -> list[PartGeometry]:
        """The spheres, a part per hemisphere (kind ``node``: drawn as a connectome's nodes are)."""
        centres = template_points(self.table.positions, template)
        radii = np.where(np.isfinite(self.table.radii), self.table.radii, self.radius)
        hemis, keys, parts = node_hemis(self.table.positions), self.keys(), []
        for side in ("lh", "rh"):
            mine = np.flatnonzero(hemis == side)
            if len(mine):
                slots = slots_for([keys[i] for i in mine], self.color, frozenset())
                verts, normals, tris, pal = sphere_mesh(centres[mine], radii[mine], slots)
                parts.append(PartGeometry(f"foci-{side}", "node", side, verts, normals, tris, pal,
                                          np.zeros(len(verts), np.float32), verts))
        return parts

    def colors(self, row: int) -> dict[str, RGB]:
        """Each focus's colour (the same in every image): its own, else its value's, else the default."""
        rgb = self.scale(np.nan_to_num(self.table.values, nan=self.scale.vmin))
        out: dict[str, RGB] = {}
        for key, own, value, c in zip(self.keys(), self.table.colors, self.table.values, rgb, strict=True):
            out[key] = own if own is not None else self.color if np.isnan(value) else (
                float(c[0]), float(c[1]), float(c[2]))
        return out

    def layer(self) -> Layer:
        """Its colour bar (foci with values) or key (the named foci in their colours)."""
        return Layer("foci", self.scale, 1.0, self.label)

    def summary(self) -> dict[str, Any]:
        """The manifest's ``foci``: how many, and each one's name and MNI152 position."""
        return {"source": self.table.source, "n_foci": len(self.table.names),
                "foci": [{"name": n, "mni": [float(v) for v in p]}
                         for n, p in zip(self.table.names, self.table.positions, strict=True)]}


def _number(options: Mapping[str, Any], name: str) -> float | None:
    if options.get(name) is None:
        return None
    try:
        return float(options[name])
    except (TypeError, ValueError):
        raise BrainPainterError(f"--layer-opt foci.{name} takes a number; {options[name]!r} was given.") \
            from None


def open_foci(path: str | Path, options: Mapping[str, Any]) -> Foci:
    """The foci layer of `path` with its options (``cmap``, ``vmin``, ``vmax``, ``radius``, ``color``,
    ``label``)."""
    table = read_foci(path)
    radius = _number(options, "radius") or RADIUS
    color = to_rgb(str(options.get("color", COLOR)))
    label = str(options.get("label") or Path(path).name)
    if np.isfinite(table.values).any():
        scale = ScaleOptions(cmap=str(options.get("cmap", "viridis")), vmin=_number(options, "vmin"),
                             vmax=_number(options, "vmax")).scale(table.values[np.isfinite(table.values)])
    else:  # no values: a key of the foci's names in their colours
        scale = ScaleOptions(cmap=str(options.get("cmap", "viridis"))).scale(np.zeros(1))
        named = dict.fromkeys(table.names)
        own = {n: c for n, c in zip(table.names, table.colors, strict=True) if c is not None}
        scale = replace(scale, categories=tuple((n, own.get(n, color)) for n in named))
    return Foci(table, scale, label, float(radius), color)
