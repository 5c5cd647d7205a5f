"""Slice and glass-brain panels of a run's volume, on the run's map colour scale (figures, ``plot``).

``--slices z=-20,0,20,40`` adds axial slices at those MNI coordinates (``x=`` sagittal, ``y=``
coronal; repeatable) over the ICBM152 2009 template; ``--projections xyz`` adds glass-brain
panels, the maximum-intensity projection of both signs along each axis over the brain's outline
(:mod:`brainpainter.maps.sections`). The volume is thresholded as the cortex is (``|v| >=
--threshold`` is coloured) and coloured by the run's map scale, so the panels read on the same
colour bar as the 3-D views. Left is on the left (neurological, as nilearn) unless
``--convention radiological``; each panel is labelled with its orientation and coordinate.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from brainpainter.color.scale import ColourScale
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.io.memo import Memo
from brainpainter.maps.options import MapOptions, frame_rows
from brainpainter.maps.sections import (
    CONVENTIONS,
    Section,
    check_inside,
    glass_lines,
    parse_projections,
    parse_slices,
    project,
    sample_plane,
    silhouette,
    template,
    template_bright,
)

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

GLASS_LINE = (0.3, 0.3, 0.3)     # the brain's outline in a projection
GLASS_INNER = (0.8, 0.8, 0.8)    # its inner lines (white matter, midline, cerebellum)
GLASS_LINE_PX = 3                 # its width, pixels of 0.5 mm
GREYS = (0.2, 0.95)               # the template's darkest and lightest grey


class PanelKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`PanelOptions`."""

    slices: Sequence[str] | str
    projections: str | None
    convention: str
    slice_outline: Any
    volume_image: Any


@dataclass(frozen=True)
class PanelOptions:
    """Which panels of the run's volume a figure holds beside its 3-D views; checked when made.

    Attributes
    ----------
    slices : sequence of str
        ``AXIS=MM[,MM...]`` or ``AXIS=START:STOP:STEP`` (x sagittal, y coronal, z axial; MNI mm).
    projections : str, optional
        Glass-brain projections along these axes: ``"xyz"``, ``"z"``, ``"sagittal,axial"``.
    convention : {"neurological", "radiological"}
        Left on the left (default, as nilearn) or on the right, in axial and coronal panels.
    slice_outline : path or nibabel image, optional
        A label volume in MNI152 (an atlas) whose region borders are drawn on the slices.
    volume_image : path or nibabel image, optional
        The volume the panels show where the run's maps were read from it already (the web page's
        volume upload); default: the run's ``--volume``, or a volume given as INPUT.
    """

    slices: Sequence[str] | str = field(default=(), metadata={
        "help": "Slice panels beside the views: AXIS=MM[,MM...] at MNI coordinates (x sagittal, y coronal, "
                "z axial), or AXIS=START:STOP:STEP for a mosaic; repeatable, e.g. --slices z=-20,0,20,40 "
                "--slices x=40. The volume (--volume) over the ICBM152 2009 template, on the map's colour "
                "bar, |v| >= --threshold coloured."})
    projections: str | None = field(default=None, metadata={
        "help": "Glass-brain panels: the volume's maximum-intensity projections (both signs, the value of "
                "largest |v| along each ray, as nilearn's glass brain) along x (sagittal), y (coronal), "
                "z (axial), e.g. xyz or z."})
    convention: str = field(default="neurological", metadata={
        "choices": CONVENTIONS,
        "help": "Slice and projection panels: left on the left (neurological, as nilearn) or on the right "
                "(radiological); each panel is labelled L/R."})
    slice_outline: Any = field(default=None, metadata={
        "help": "A label volume in MNI152 (an atlas .nii.gz) whose region borders are drawn on the slices."})
    volume_image: Any = field(default=None, metadata={"cli": False})

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise choice_error("convention", self.convention, CONVENTIONS)
        self.sections  # noqa: B018 (a bad --slices or --projections fails now)
        if self.slice_outline is not None and not any(s.coord is not None for s in self.sections):
            raise BrainPainterError("--slice-outline draws region borders on slice panels; give --slices "
                                    "too.")

    @property
    def sections(self) -> tuple[Section, ...]:
        """The panels, slices first, in the order given."""
        return parse_slices(self.slices) + parse_projections(self.projections)


def panel_volume(data: Any, maps: MapOptions, given: Any = None) -> Any:
    """The run's map volume the panels show (a path or nibabel image), or None: `given`
    (:attr:`PanelOptions.volume_image`), ``--volume``, else a volume given as INPUT."""
    from brainpainter.maps.volume import is_volume

    if given is not None or maps.volume is not None:
        return given if given is not None else maps.volume
    if data is not None and not isinstance(data, list) and is_volume(data):
        return data
    return None


def panel_layer(data: Any, run: Any, given: Any = None) -> tuple[Any, str]:
    """The panels' volume and the kind of the run's layer whose scale they are drawn on: ``"map"``,
    or ``"blobs"`` where the volume is ``--volume-surface``'s (the panels read on the blobs' bar)."""
    own = panel_volume(data, run.options.maps, given)
    if own is not None:
        return own, "map"
    blobs = run.options.scene.volume_surface
    return blobs, ("blobs" if blobs is not None else "map")


def volume_panels(data: Any, run: Any, opts: PanelOptions, rows: Sequence[int]
                  ) -> dict[tuple[str, str], NDArray[np.uint8]]:
    """Every panel of `opts` for each of `rows` of a map run: ``(image name, panel name) -> RGBA``.

    Parameters
    ----------
    data : any
        The run's input (a volume given as INPUT is the panels' volume).
    run : Run
        The prepared run: its map scale, threshold, opacity and background.
    opts : PanelOptions
    rows : sequence of int
        The run's images drawn.

    Returns
    -------
    dict of (str, str) to ndarray of uint8, shape (h, w, 4)

    Raises
    ------
    BrainPainterError
        No volume, a volume not in MNI152, a slice outside it, a threshold above its largest |value|.
    """
    from brainpainter.maps.volume import check_mni152, load_volume

    given, kind = panel_layer(data, run, opts.volume_image)
    if given is None:
        raise BrainPainterError("slice and glass-brain panels (--slices, --projections) show a volume in "
                                "MNI152; give one with --volume FILE (or --volume-surface FILE).")
    volume = load_volume(given)
    check_mni152(volume)
    for section in opts.sections:
        check_inside(section, volume.affine, volume.shape, volume.name)
    frames = frame_rows(run.options.maps.frames, volume.n_volumes, volume.name)
    which = {i: frames[i] if len(frames) > 1 else frames[0] for i in rows}
    threshold = run.options.maps.threshold
    grids = {i: volume.volume(v) for i, v in which.items()}
    _check_threshold(threshold, grids.values(), volume.name)
    labels = _outline_labels(opts)
    scale, background = run.scale_of(kind), run.settings.background
    opacity = next((layer.opacity for layer in run.layers if layer.kind == kind), 1.0)
    out: dict[tuple[str, str], NDArray[np.uint8]] = {}
    for i, grid in grids.items():
        for section in opts.sections:
            values = (project(grid, volume.affine, section.axis, opts.convention) if section.coord is None
                      else sample_plane(grid, volume.affine, section, opts.convention))
            out[(run.table.images[i], section.name)] = panel_rgba(
                section, values, scale, threshold, opts.convention, background, opacity, labels,
                run.settings.outline_color)
    return out


def _check_threshold(threshold: float | None, grids: Any, name: str) -> None:
    """Refuse a threshold above every |value| of the panels' volume (nothing would be coloured)."""
    if threshold is None:
        return
    top = max(float(np.nanmax(np.abs(g))) if np.isfinite(g).any() else 0.0 for g in grids)
    if threshold > top:
        raise BrainPainterError(f"--threshold {threshold:g} is above the largest |value| of {name} "
                                f"({top:.4g}), so the panels would show nothing; give a threshold below it.")


def _outline_labels(opts: PanelOptions) -> tuple[NDArray[Any], NDArray[np.float64]] | None:
    """The label volume of ``--slice-outline`` and its affine, checked to be in MNI152."""
    if opts.slice_outline is None:
        return None
    from brainpainter.maps.volume import check_mni152, load_volume

    labels = load_volume(opts.slice_outline)
    check_mni152(labels)
    return labels.volume(0), labels.affine


def panel_rgba(section: Section, values: NDArray[Any], scale: ColourScale, threshold: float | None,
               convention: str, background: Any, opacity: float = 1.0,
               labels: tuple[NDArray[Any], NDArray[np.float64]] | None = None,
               line_color: Any = (0.0, 0.0, 0.0)) -> NDArray[np.uint8]:
    """One panel's pixels: the template (a slice) or the brain's outline (a projection), the values
    at or above `threshold` in `scale`'s colours by `opacity`, and the label borders.

    Parameters
    ----------
    values : ndarray of float, shape (h, w)
        The volume on the panel's pixels (:func:`~brainpainter.maps.sections.sample_plane`,
        :func:`~brainpainter.maps.sections.project`); NaN and 0 are no value.

    Returns
    -------
    ndarray of uint8, shape (h, w, 4)
        Transparent (or `background`) outside the brain.
    """
    key = (section, convention, None if background is None else tuple(float(c) for c in background))
    rgba = PANEL_MEMO.get(key, lambda: underlay(section, convention, background)).copy()
    if rgba.shape[:2] != values.shape:  # pragma: no cover - every panel of an axis has one grid
        raise ValueError(f"panel {section.name}: values {values.shape} on a grid of {rgba.shape[:2]}")
    with np.errstate(invalid="ignore"):
        shown = np.isfinite(values) & (values != 0) & (np.abs(values) >= (threshold or 0.0))
    rgba[shown, :3] = opacity * scale(values[shown]) + (1.0 - opacity) * rgba[shown, :3]
    rgba[shown, 3] = 1.0
    if labels is not None and section.coord is not None:
        ids = np.nan_to_num(sample_plane(labels[0], labels[1], section, convention, order=0))
        border = np.zeros(ids.shape, dtype=bool)
        border[:, 1:] |= ids[:, 1:] != ids[:, :-1]
        border[1:, :] |= ids[1:, :] != ids[:-1, :]
        rgba[border] = (*line_color, 1.0)
    out: NDArray[np.uint8] = np.round(rgba * 255).astype(np.uint8)
    return out


#: Each panel's template underlay (:func:`underlay`), the same in every figure: kept in the process
#: (~5 MB a panel; resampling the template and eroding the outline cost ~0.02 s a figure before).
PANEL_MEMO = Memo(max_bytes=64 * 1024 * 1024)


def underlay(section: Section, convention: str, background: Any) -> NDArray[np.float64]:
    """A panel's pixels under the values: the template's greys (a slice) or the brain's outline and
    inner lines (a projection), on `background` (None: transparent) outside the brain.

    Returns
    -------
    ndarray of float, shape (h, w, 4)
        RGBA, 0-1.
    """
    from scipy.ndimage import binary_erosion

    if section.coord is None:
        inside = silhouette(section.axis, convention)
        rgba = _background(inside.shape, background)
        edge = inside & ~binary_erosion(inside, iterations=GLASS_LINE_PX)
        rgba[glass_lines(section.axis, convention) & inside] = (*GLASS_INNER, 1.0)
        rgba[edge] = (*GLASS_LINE, 1.0)
        return rgba
    t1, affine = template()
    grey = sample_plane(t1, affine, section, convention)
    rgba = _background(grey.shape, background)
    inside = np.isfinite(grey) & (grey > 0)
    level = np.clip(grey[inside] / template_bright(), 0.0, 1.0)
    rgba[inside, :3] = (GREYS[0] + (GREYS[1] - GREYS[0]) * level)[:, None]
    rgba[inside, 3] = 1.0
    return rgba


def _background(shape: tuple[int, ...], background: Any) -> NDArray[np.float64]:
    rgba = np.zeros((*shape, 4))
    if background is not None:
        rgba[...] = (*background, 1.0)
    return rgba


def orientation_marks(section: Section, convention: str) -> tuple[str, str]:
    """The letters at a panel's left and right edges: ``("L", "R")`` (neurological), ``("R", "L")``
    (radiological), ``("P", "A")`` for a sagittal panel."""
    if section.axis == "x":
        return "P", "A"
    return ("L", "R") if convention == "neurological" else ("R", "L")


def label_panel(ax: Axes, section: Section, convention: str, color: Any, fontsize: float) -> None:
    """The orientation letters at the top corners of a panel and its coordinate (or plane) at the
    bottom left."""
    left, right = orientation_marks(section, convention)
    style = {"transform": ax.transAxes, "fontsize": fontsize, "color": color, "va": "top"}
    ax.text(0.02, 0.98, left, ha="left", **style)
    ax.text(0.98, 0.98, right, ha="right", **style)
    ax.text(0.02, 0.02, section.title, ha="left", **{**style, "va": "bottom"})


def label_panels(axes: Mapping[tuple[str, str], Axes], opts: PanelOptions, color: Any,
                 fontsize: float) -> None:
    """:func:`label_panel` on every panel of a figure (``(image name, panel name) -> Axes``)."""
    sections = {s.name: s for s in opts.sections}
    for (_, name), ax in axes.items():
        if name in sections:
            label_panel(ax, sections[name], opts.convention, color, fontsize)
