"""The map options of a run (``--lh``, ``--rh``, ``--volume``, ``--underlay``, ...), defined once.

The CLI's click options and the keywords of ``brainpainter.render`` (and of
figure, movie, plot, export) are made from these fields
(:mod:`brainpainter.rendering.options`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, TypedDict

from brainpainter.errors import BrainPainterError, choice_error, within

#: What shows where a map has no value: sulcal-depth greys, curvature greys, or one grey.
UNDERLAYS = ("sulc", "curv", "none")
Projection = Literal["ribbon", "line", "point"]
#: How a volume is sampled at a vertex (``--projection``): over the cortical ribbon around it,
#: along its normal, or at its position alone (:mod:`brainpainter.maps.sheet`).
PROJECTIONS: tuple[Projection, ...] = ("ribbon", "line", "point")
RADIUS_MM = 3.0                 # default --projection-radius (nilearn's vol_to_surf: 3 mm)
MAX_RADIUS_MM = 10.0


def check_projection(projection: str | None, method: str, radius: float) -> Projection:
    """`projection` checked against `method` and `radius` (one line each), its default filled in."""
    if not within(radius, 0.5, MAX_RADIUS_MM):
        raise BrainPainterError(f"the projection radius must be 0.5 to {MAX_RADIUS_MM:g} mm; {radius!r} was "
                                f"given (default {RADIUS_MM:g}).")
    if projection is None:
        return "point" if method == "nearest" else "ribbon"
    if projection not in PROJECTIONS:
        raise choice_error("projection", projection, PROJECTIONS)
    if method == "nearest" and projection != "point":
        raise BrainPainterError(f"projection {projection!r} averages values, which would mix the labels of "
                                "method='nearest'; use projection='point' for a label volume.")
    return projection


class MapKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`MapOptions`."""

    lh: Any
    rh: Any
    volume: Any
    projection: str | None
    projection_radius: float | None
    underlay: str
    underlay_contrast: float
    threshold: float | None
    outline: str | None
    outline_threshold: bool
    space: str | None
    frames: Any
    lh_surface: Any
    rh_surface: Any
    contour: Any
    contour_levels: str | float | None


#: Contour levels at most (each is a line set drawn in every image).
MAX_LEVELS = 10


def contour_levels(levels: str | float | None) -> tuple[float, ...]:
    """``--contour-levels`` as numbers: ``"0.05,0.01"`` -> ``(0.05, 0.01)``; None -> ``(0.5,)``."""
    if levels is None:
        return (0.5,)
    items = [t for t in str(levels).replace(";", ",").split(",") if t.strip()] \
        if isinstance(levels, str) else [levels]
    try:
        out = tuple(float(t) for t in items)
    except (TypeError, ValueError):
        out = ()
    if not out or len(out) > MAX_LEVELS or not all(math.isfinite(v) for v in out):
        raise BrainPainterError(f"--contour-levels must be 1 to {MAX_LEVELS} finite numbers, comma-separated "
                                f"(e.g. 0.05 or 2.3,3.1); {levels!r} was given.")
    return out


@dataclass(frozen=True)
class MapOptions:
    """How a per-vertex map is given and drawn (``docs/maps.md``).

    Attributes
    ----------
    lh, rh : path or ndarray, optional
        One hemisphere's map (a file of any map format, or values per vertex).
    volume : path or nibabel image, optional
        An MNI152 volume (3-D, or 4-D: one image per volume) projected onto the cortex by
        registration fusion; the subcortical structures take its mean inside each.
    projection : {"ribbon", "line", "point"}, optional
        How the volume is sampled at each vertex (default ``ribbon``; see
        :func:`brainpainter.maps.volume.project_volume`).
    projection_radius : float, optional
        Its radius in mm (default 3).
    underlay : {"sulc", "curv", "none"}
        What shows where the map has no value.
    underlay_contrast : float
        0-4: how far the sulcal-depth greys spread (0: one grey; 1: 0.52 in the deepest sulci to
        0.74 on the crowns).
    threshold : float, optional
        Values with ``|v| < threshold`` show the underlay.
    outline : str, optional
        An atlas whose region borders are drawn over the map.
    outline_threshold : bool
        Draw the borders of the supra-threshold areas.
    space : {"fsaverage", "fsLR"}, optional
        The mesh of a 163,842-vertex map that does not say (fsaverage when neither says).
    frames : str or sequence of int, optional
        The images of a series to draw (``"0:100:10"``, ``"3"``, ``"0,5,9"``).
    lh_surface, rh_surface : path, optional
        The user's own surface of a hemisphere (GIfTI ``.surf.gii`` or FreeSurfer ``lh.pial``, ...):
        the maps, of its vertex count, are drawn on it as they are (:mod:`brainpainter.atlas.surfaces`).
    contour : path, or "LH,RH" paths, optional
        A second map whose iso-lines are drawn over the map (a cluster mask, a p-map).
    contour_levels : str or float, optional
        The iso-lines' values, comma-separated (default 0.5: a mask's edge).
    """

    lh: Any = field(default=None, metadata={
        "help": "Left-hemisphere map: lh.thickness, .mgh/.mgz, .func.gii/.shape.gii, .nii (N x 1 x 1), .npy, "
                ".txt, .annot, .label.gii, .label; any fsaverage resolution. See docs/maps.md."})
    rh: Any = field(default=None, metadata={"help": "Right-hemisphere map (as --lh)."})
    volume: Any = field(default=None, metadata={
        "help": "An MNI152 volume (.nii/.nii.gz, 3-D or 4-D = one image per volume: an SPM/FSL/AFNI stat "
                "map, a PET image) projected onto the cortex; the subcortical structures show its mean "
                "inside each. See docs/maps.md."})
    projection: str | None = field(default=None, metadata={"choices": PROJECTIONS, "help": (
        "How --volume is sampled at each vertex: ribbon (default), the mean over the grey-matter ribbon "
        "within --projection-radius; line, along the normal (nilearn's vol_to_surf); point, at its "
        "position alone.")})
    projection_radius: float | None = field(default=None, metadata={
        "help": f"Radius of --projection in mm (default {RADIUS_MM:g})."})
    underlay: str = field(default="sulc", metadata={
        "choices": UNDERLAYS, "help": "Map underlay: sulcal-depth greys (scaled from the depth), curvature "
                                      "greys (two tones), or one grey."})
    underlay_contrast: float = field(default=1.0, metadata={
        "help": "How far the sulcal-depth greys spread, 0 (one grey) to 4 (1: darkest 0.52, lightest 0.74)."})
    threshold: float | None = field(default=None, metadata={
        "help": "Map values with |v| below this show the underlay."})
    outline: str | None = field(default=None, metadata={
        "help": "Draw this atlas's region borders over the map (dk, destrieux, dkt, ...)."})
    outline_threshold: bool = field(default=False, metadata={
        "help": "Draw the borders of the areas above --threshold."})
    space: str | None = field(default=None, metadata={
        "choices": ("fsaverage", "fsLR"),
        "help": "Mesh of a 163842-vertex map (fsaverage or fsLR 164k) when its file does not say; 32492 "
                "vertices is always fsLR 32k. Default: the file's metadata, else fsaverage; a --space that "
                "contradicts the file's metadata is refused."})
    frames: Any = field(default=None, metadata={
        "help": "Images of a map series to draw (a CIFTI dtseries' frames): start:stop:step or a comma list, "
                "e.g. 0:100:10."})
    lh_surface: Any = field(default=None, metadata={
        "help": "Draw the maps on this left-hemisphere surface of your own, as they are (no resampling): "
                "GIfTI .surf.gii (HCP, fMRIPrep) or FreeSurfer lh.pial, lh.inflated, ...; the maps have "
                "its vertex count. See docs/maps.md."})
    rh_surface: Any = field(default=None, metadata={"help": "Right-hemisphere surface of your own (as "
                                                            "--lh-surface)."})
    contour: Any = field(default=None, metadata={
        "help": "A second map (FILE, or LH,RH files) whose iso-lines are drawn over the map at constant "
                "pixel width (--outline-width): a cluster mask, a p-map."})
    contour_levels: str | float | None = field(default=None, metadata={
        "help": "Values of the --contour lines, comma-separated (default 0.5: a mask's edge; p-map: 0.05)."})

    def __post_init__(self) -> None:
        if self.underlay not in UNDERLAYS:
            raise choice_error("underlay", self.underlay, UNDERLAYS)
        c = self.underlay_contrast
        if not isinstance(c, int | float) or not math.isfinite(c) or not 0 <= c <= 4:
            raise BrainPainterError(f"--underlay-contrast must be a number from 0 (one grey) to 4; {c!r} was "
                                    "given.")
        t = self.threshold
        if t is not None and (not isinstance(t, int | float) or not math.isfinite(t) or t < 0):
            raise BrainPainterError(f"--threshold must be a number >= 0; {t!r} was given.")
        if self.space is not None:
            spelt = {s.lower(): s for s in ("fsaverage", "fsLR")}.get(str(self.space).lower())
            if spelt is None:
                raise choice_error("space", self.space, ("fsaverage", "fsLR"))
            object.__setattr__(self, "space", spelt)  # fslr, FSLR: fsLR
        if (self.projection is not None or self.projection_radius is not None) and self.volume is None \
                and (self.lh is not None or self.rh is not None):
            raise BrainPainterError("--projection and --projection-radius sample a volume (--volume); "
                                    "surface maps (--lh/--rh) are not projected. Leave them out.")
        check_projection(self.projection, "linear", RADIUS_MM if self.projection_radius is None
                         else self.projection_radius)
        self.levels  # noqa: B018 (a bad level fails now)
        if self.volume is not None and (self.lh is not None or self.rh is not None):
            raise BrainPainterError("give a volume (--volume) or surface maps (--lh/--rh), not both: the "
                                    "volume is projected onto both hemispheres.")
        if self.surfaces and self.outline is not None:
            raise BrainPainterError(f"--outline {self.outline} draws an atlas's borders on fsaverage; your "
                                    "own surfaces (--lh-surface/--rh-surface) have no atlas labels: leave "
                                    "out --outline, or the surfaces.")

    @property
    def surfaces(self) -> dict[str, Any]:
        """The user's own surfaces given, ``{"lh": path, "rh": path}`` (either, both or none)."""
        return {hemi: s for hemi, s in (("lh", self.lh_surface), ("rh", self.rh_surface)) if s is not None}

    @property
    def levels(self) -> tuple[float, ...]:
        """The contour levels, as numbers (default: 0.5)."""
        return contour_levels(self.contour_levels)

    @property
    def given(self) -> bool:
        """Whether a map was given through --lh/--rh or --volume (or a surface of the user's own)."""
        return self.lh is not None or self.rh is not None or self.volume is not None or bool(self.surfaces)


def frame_rows(frames: Any, n: int, what: str) -> list[int]:
    """The rows of `n` that `frames` picks: ``None`` (all), ``"0:100:10"``, ``"3"``, ``"0,5,9"`` or ints.

    Raises
    ------
    BrainPainterError
        A spelling of none of these, or a row outside ``0..n-1``.
    """
    if frames is None:
        return list(range(n))
    hint = f"give rows 0 to {n - 1}, e.g. --frames 0:{n}:10 or --frames 0,{n - 1}."
    rows: list[int] = []
    try:
        parts = (frames.split(",") if isinstance(frames, str)
                 else [frames] if isinstance(frames, int) else frames)
        for part in parts:
            if isinstance(part, str) and ":" in part:
                bits = [int(b) if b.strip() else None for b in part.split(":")]
                if len(bits) > 3 or any(b is not None and b < 0 for b in bits) or bits[-1] == 0:
                    raise ValueError(part)
                rows.extend(range(n)[slice(*bits)])
            else:
                row = int(part)
                if not 0 <= row < n:
                    raise BrainPainterError(f"--frames {frames!r}: row {row} is outside {what}'s {n} rows; "
                                            f"{hint}")
                rows.append(row)
    except (TypeError, ValueError):
        raise BrainPainterError(f"--frames {frames!r} is not a list of rows or a start:stop:step range; "
                                f"{hint}") from None
    if not rows:
        raise BrainPainterError(f"--frames {frames!r} picks none of {what}'s {n} rows; {hint}")
    return rows
