"""Cutaways: planes that remove the cortex and the glass on one side (``--clip x<0``, ``z>20``).

A :class:`ClipPlane` names an axis of RAS millimetres (x right, y anterior, z superior), a side
(``<`` or ``>``) and a value; the points on that side are removed. With several planes a point is
removed when it lies on the named side of every one of them (``x<0,z>20`` cuts the upper left
quarter out: a wedge). Only the parts of kinds :data:`CLIPPED` (the cortex and the glass) are cut;
what lies inside (subcortical structures, blobs, tracts, a connectome) stays whole and is drawn
in every clipped view. A renderer draws the cut face closed: where a cut cortex is seen from
inside, in :data:`CAP_COLOR`, lit as a plane facing out of the cut.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError

#: Kinds of parts a clip cuts.
CLIPPED = ("cortex", "glass")
#: Colour of a cut face (sRGB): the underlay's grey.
CAP_COLOR = (0.62, 0.62, 0.62)
#: Planes a view holds at most (a renderer's fixed-size uniform).
MAX_PLANES = 4
AXES = ("x", "y", "z")
_SPEC = re.compile(r"^\s*([xyzXYZ])\s*([<>])\s*([-+]?(?:\d+\.?\d*|\.\d+))\s*(?:mm)?\s*$")


@dataclass(frozen=True)
class ClipPlane:
    """Remove what lies on one side of an axis-aligned plane.

    Attributes
    ----------
    axis : {"x", "y", "z"}
    side : {"<", ">"}
        ``<``: the points with a smaller coordinate are removed.
    value : float
        Millimetres, in the template's RAS coordinates.
    """

    axis: str
    side: str
    value: float

    def __str__(self) -> str:
        return f"{self.axis}{self.side}{self.value:g}"

    @property
    def plane(self) -> tuple[float, float, float, float]:
        """``(a, b, c, d)``: a point p is on the removed side when ``a*x + b*y + c*z + d > 0``; (a, b, c) is
        the unit normal pointing into the removed side (out of what is kept)."""
        normal = [0.0, 0.0, 0.0]
        sign = 1.0 if self.side == ">" else -1.0
        normal[AXES.index(self.axis)] = sign
        return (normal[0], normal[1], normal[2], -sign * float(self.value))


def parse_clips(spec: str | Sequence[str] | None) -> tuple[ClipPlane, ...]:
    """``"x<0,z>20"`` (or a list of such) as planes; None or empty: none.

    Raises
    ------
    BrainPainterError
        A plane not written AXIS<VALUE or AXIS>VALUE, or more than :data:`MAX_PLANES`.
    """
    if spec is None:
        return ()
    items = spec.split(",") if isinstance(spec, str) else [p for s in spec for p in str(s).split(",")]
    planes: list[ClipPlane] = []
    for item in (i for i in items if i.strip()):
        m = _SPEC.match(item)
        if m is None:
            raise BrainPainterError(f"--clip {item.strip()!r} is not a plane; write AXIS<MM or AXIS>MM with "
                                    "axis x (right), y (anterior) or z (superior), e.g. --clip x<0 or "
                                    "--clip z>20.")
        planes.append(ClipPlane(m.group(1).lower(), m.group(2), float(m.group(3))))
    if len(planes) > MAX_PLANES:
        raise BrainPainterError(f"--clip takes at most {MAX_PLANES} planes; {len(planes)} were given "
                                f"({', '.join(map(str, planes))}).")
    return tuple(dict.fromkeys(planes))


def parse_sweep(spec: str) -> tuple[str, str]:
    """``"x"``, ``"x<"`` or ``"x>"`` (a movie's ``--clip-sweep``) as (axis, side); ``"x"`` is ``"x<"``: a
    plane sweeping from left to right, removing what lies left of it.

    Raises
    ------
    BrainPainterError
        Anything else.
    """
    text = str(spec).strip().lower()
    if len(text) in (1, 2) and text[0] in AXES and text[1:] in ("", "<", ">"):
        return text[0], text[1:] or "<"
    raise BrainPainterError(f"--clip-sweep {spec!r} must be an axis and the side removed: x, x<, x>, "
                            "y<, z>, ... (x right, y anterior, z superior); e.g. --clip-sweep x sweeps a cut "
                            "from left to right.")


def removed(points: NDArray[Any], planes: Sequence[ClipPlane]) -> NDArray[np.bool_]:
    """Which `points` (shape (n, 3), RAS mm) the planes remove (on the named side of every one),
    shape (n,)."""
    out = np.ones(len(points), bool) if planes else np.zeros(len(points), bool)
    for plane in planes:
        a, b, c, d = plane.plane
        out &= np.asarray(points, float) @ np.array([a, b, c]) + d > 0
    return out


def check_cut(parts: Sequence[Any], planes: Sequence[ClipPlane], view: str) -> None:
    """Refuse a clip that leaves none of the cortex and glass of `parts` (each with ``kind`` and ``vertices``,
    shape (n, 3): :class:`~brainpainter.rendering.parts.PartGeometry`) drawn in `view` (:func:`check_kept`);
    the vertices of no other part are read (a tract part builds its tubes when they are)."""
    if planes:
        cut = [p.vertices for p in parts if p.kind in CLIPPED]
        check_kept(np.vstack(cut) if cut else np.zeros((0, 3)), planes, view)


def check_kept(points: NDArray[Any], planes: Sequence[ClipPlane], view: str) -> None:
    """Refuse a clip that removes every one of the cortex's or glass's `points` (RAS mm, shape (n, 3)).

    Raises
    ------
    BrainPainterError
        Naming the planes and the brain's extent on their axes.
    """
    if not planes or not len(points) or not removed(points, planes).all():
        return
    lo, hi = np.asarray(points).min(axis=0), np.asarray(points).max(axis=0)
    extent = ", ".join(f"{a} {lo[AXES.index(a)]:.0f}..{hi[AXES.index(a)]:.0f}"
                       for a in dict.fromkeys(p.axis for p in planes))
    raise BrainPainterError(f"--clip {','.join(map(str, planes))} removes all the cortex and glass of "
                            f"view {view!r} (they span {extent} mm), so nothing is cut open; give a plane "
                            "that cuts through them, e.g. --clip x<0, or a view that draws more "
                            "(cutaway-left).")
