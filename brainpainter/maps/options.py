"""The map options of a run (``--lh``, ``--rh``, ``--underlay``, ``--threshold``), defined once.

The CLI's click options and the keywords of ``brainpainter.render`` (and of
figure, movie, plot, export) are made from these fields
(:mod:`brainpainter.rendering.options`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, TypedDict

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.maps.layers import UNDERLAYS


class MapKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`MapOptions`."""

    lh: Any
    rh: Any
    underlay: str
    threshold: float | None
    outline: str | None
    outline_threshold: bool


@dataclass(frozen=True)
class MapOptions:
    """How a per-vertex map is given and drawn (``docs/maps.md``).

    Attributes
    ----------
    lh, rh : path or ndarray, optional
        One hemisphere's map (a file of any map format, or values per vertex).
    underlay : {"sulc", "curv", "none"}
        What shows where the map has no value.
    threshold : float, optional
        Values with ``|v| < threshold`` show the underlay.
    outline : str, optional
        An atlas whose region borders are drawn over the map.
    outline_threshold : bool
        Draw the borders of the supra-threshold areas.
    """

    lh: Any = field(default=None, metadata={
        "help": "Left-hemisphere map: lh.thickness, .mgh/.mgz, .func.gii/.shape.gii, .nii (N x 1 x 1), .npy, "
                ".txt, .annot, .label.gii, .label; any fsaverage resolution. See docs/maps.md."})
    rh: Any = field(default=None, metadata={"help": "Right-hemisphere map (as --lh)."})
    underlay: str = field(default="sulc", metadata={
        "choices": UNDERLAYS, "help": "Map underlay: sulcal-depth or curvature greys, or one grey."})
    threshold: float | None = field(default=None, metadata={
        "help": "Map values with |v| below this show the underlay."})
    outline: str | None = field(default=None, metadata={
        "help": "Draw this atlas's region borders over the map (dk, destrieux, dkt, ...)."})
    outline_threshold: bool = field(default=False, metadata={
        "help": "Draw the borders of the areas above --threshold."})

    def __post_init__(self) -> None:
        if self.underlay not in UNDERLAYS:
            raise choice_error("underlay", self.underlay, UNDERLAYS)
        t = self.threshold
        if t is not None and (not isinstance(t, int | float) or not math.isfinite(t) or t < 0):
            raise BrainPainterError(f"--threshold must be a number >= 0; {t!r} was given.")

    @property
    def given(self) -> bool:
        """Whether a map was given through --lh/--rh."""
        return self.lh is not None or self.rh is not None
