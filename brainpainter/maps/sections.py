"""Sections of an MNI152 volume: slices at MNI coordinates and maximum-intensity projections.

A :class:`Section` is one 2-D panel of a volume: a slice (``z=50``: the plane z = 50 mm) or a
glass-brain projection along an axis (``glass-z``: for each ray along z, the value of largest
``|value|``, both signs, as nilearn's ``plot_glass_brain``). Every panel of one axis shares one
pixel grid over the ICBM152 2009 template's brain (:func:`panel_grid`, 0.5 mm pixels), so panels
line up and keep their scale. Columns run along x (axial, coronal; left on the left in the
neurological convention, on the right in the radiological one) or y (sagittal, anterior on the
right, as nilearn draws it); rows run from the top (anterior for axial, superior otherwise).

The sampling is scipy's (:func:`scipy.ndimage.map_coordinates`) and nibabel's
(:func:`nibabel.processing.resample_to_output` before a projection); the template is the one
nilearn's wheel carries (``nilearn.datasets.load_mni152_template`` reads the same file; nothing is
downloaded).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.maps.voxel_points import VOXEL_MEMO

Axis = Literal["x", "y", "z"]
AXES: tuple[Axis, ...] = ("x", "y", "z")
#: The plane each axis cuts (nilearn's display modes: x sagittal, y coronal, z axial).
PLANES: dict[Axis, str] = {"x": "sagittal", "y": "coronal", "z": "axial"}
#: Left on the left (nilearn's, the default) or on the right (radiological).
CONVENTIONS = ("neurological", "radiological")
PIXEL_MM = 0.5
MARGIN_MM = 4.0                 # around the template's brain
MAX_SECTIONS = 24
TEMPLATE_FILE = "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"
WHITE_MATTER_FILE = "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz"
#: A glass brain's inner lines: where the white matter's mean along the ray crosses these shares of its
#: largest (the white matter's edge, the midline, the cerebellum), as nilearn's glass brain sketches them.
GLASS_LEVELS = (0.12, 0.25)
#: Each axis's panel: its column axis and row axis (world axes 0, 1, 2 = x, y, z).
IN_PLANE = {"x": (1, 2), "y": (0, 2), "z": (0, 1)}


@dataclass(frozen=True)
class Section:
    """One panel of a volume.

    Attributes
    ----------
    axis : {"x", "y", "z"}
        The axis the plane is normal to (x: sagittal, y: coronal, z: axial).
    coord : float or None
        The slice's MNI coordinate, mm; None for a projection along `axis`.
    """

    axis: Axis
    coord: float | None = None

    @property
    def name(self) -> str:
        """``z=50`` for a slice, ``glass-z`` for a projection (the panel's view name in a figure)."""
        return f"glass-{self.axis}" if self.coord is None else f"{self.axis}={self.coord:g}"

    @property
    def title(self) -> str:
        """What the panel's caption says: ``z=50``, ``axial projection``."""
        return f"{PLANES[self.axis]} projection" if self.coord is None else self.name


def _numbers(text: str, given: str) -> list[float]:
    """``-20,0,20`` or ``-40:60:20`` (start:stop:step, stop included) as numbers."""
    out: list[float] = []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        bits = [float(b) for b in part.split(":")]
        if len(bits) == 1:
            out.extend(bits)
        elif len(bits) == 3 and bits[2] > 0 and bits[1] >= bits[0]:
            out.extend(bits[0] + bits[2] * k for k in range(int((bits[1] - bits[0]) / bits[2] + 1e-9) + 1))
        else:
            raise ValueError(given)
    if not out or not all(math.isfinite(v) for v in out):
        raise ValueError(given)
    return out


def parse_slices(specs: Sequence[str] | str | None) -> tuple[Section, ...]:
    """``--slices`` as sections: ``["z=-20,0,20,40", "x=40"]`` or ``"z=-40:60:20"`` (a mosaic).

    Raises
    ------
    BrainPainterError
        Not ``AXIS=NUMBERS``, or more than :data:`MAX_SECTIONS` panels.
    """
    items = [specs] if isinstance(specs, str) else list(specs or ())
    sections: list[Section] = []
    for item in items:
        match = re.fullmatch(r"\s*([xyzXYZ])\s*=\s*(.+)", str(item))
        try:
            if match is None:
                raise ValueError(item)
            axis: Axis = match.group(1).lower()  # type: ignore[assignment]
            sections.extend(Section(axis, v) for v in _numbers(match.group(2), str(item)))
        except ValueError:
            raise BrainPainterError(
                f"--slices {item!r} is not AXIS=MM[,MM...] (or AXIS=START:STOP:STEP); give e.g. "
                "--slices z=-20,0,20,40 or --slices x=40, the MNI coordinates in mm.") from None
    if len(sections) > MAX_SECTIONS:
        raise BrainPainterError(f"--slices asks for {len(sections)} panels; at most {MAX_SECTIONS} fit a "
                                "figure. Give fewer coordinates.")
    return tuple(sections)


def parse_projections(spec: str | None) -> tuple[Section, ...]:
    """``--projections`` as sections: ``"xyz"``, ``"z"``, ``"x,z"`` or ``"sagittal,axial"``."""
    if spec is None:
        return ()
    names: dict[str, Axis] = {**{a: a for a in AXES}, **{plane: a for a, plane in PLANES.items()}}
    text = str(spec).strip().lower()
    parts = [p.strip() for p in text.split(",") if p.strip()] if "," in text or text in names else list(text)
    axes = [names.get(p) for p in parts]
    if not parts or None in axes or len(set(axes)) != len(axes):
        raise choice_error("projections", spec, ("xyz", "x", "y", "z", "sagittal,coronal,axial"))
    return tuple(Section(a) for a in axes if a is not None)


def parse_panel(name: str) -> Section | None:
    """One panel named as a figure names it (``"z=50"``, ``"glass-x"``), or None for any other name
    (a 3-D view)."""
    text = str(name).strip().lower()
    if re.fullmatch(r"glass-[xyz]", text):
        return parse_projections(text[-1])[0]
    if re.fullmatch(r"[xyz]\s*=\s*[-+0-9.eE]+", text):
        return parse_slices(text)[0]
    return None


# -- the template ---------------------------------------------------------------------
@cache
def template(name: str = TEMPLATE_FILE) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
    """The ICBM152 2009 T1 template nilearn's wheel carries (or its white-matter map, `name`): its
    voxels (1 mm, shape (197, 233, 189), 0 outside the brain) and affine, shape (4, 4).

    Raises
    ------
    BrainPainterError
        nilearn is not installed (the message has the pip command).
    """
    import importlib.util

    import nibabel as nib

    spec = importlib.util.find_spec("nilearn")
    path = Path(spec.origin).parent / "datasets" / "data" / name if spec and spec.origin else None
    if path is None or not path.is_file():
        raise BrainPainterError("slice and glass-brain panels are drawn over the ICBM152 2009 template that "
                                "nilearn ships; install it: pip install 'brainpainter[panels]'.")
    image: Any = nib.load(str(path))
    data = np.asarray(image.dataobj, dtype=np.float32)
    data.flags.writeable = False
    return data, np.asarray(image.affine, dtype=np.float64)


@cache
def template_bright() -> float:
    """The template's 99th percentile inside the brain: the lightest grey of a slice."""
    data, _ = template()
    return float(np.percentile(data[data > 0], 99))


@cache
def brain_box() -> NDArray[np.float64]:
    """The template brain's extent with a margin, MNI mm: ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``."""
    data, affine = template()
    inside = data > 0
    spans = [np.flatnonzero(inside.any(axis=tuple(a for a in range(3) if a != k))) for k in range(3)]
    corners = np.array([[s[0] for s in spans], [s[-1] for s in spans]]) @ affine[:3, :3].T + affine[:3, 3]
    return np.stack([corners.min(axis=0) - MARGIN_MM, corners.max(axis=0) + MARGIN_MM])


def panel_grid(axis: Axis, convention: str = "neurological"
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The MNI coordinate of each pixel column and row of an `axis` panel, mm.

    Returns
    -------
    columns : ndarray, shape (w,)
        Along x (axial, coronal: increasing to the right, or decreasing when radiological) or y
        (sagittal, anterior on the right).
    rows : ndarray, shape (h,)
        Along y (axial) or z (coronal, sagittal), from the top (largest) down.
    """
    if convention not in CONVENTIONS:
        raise choice_error("convention", convention, CONVENTIONS)
    box = brain_box()
    c, r = IN_PLANE[axis]
    columns = np.arange(box[0, c], box[1, c] + 1e-9, PIXEL_MM)
    rows = np.arange(box[1, r], box[0, r] - 1e-9, -PIXEL_MM)
    if axis != "x" and convention == "radiological":
        columns = columns[::-1]
    return columns, rows


def plane_points(section: Section, convention: str = "neurological") -> NDArray[np.float64]:
    """The MNI position of every pixel of a slice, shape (3, h, w)."""
    assert section.coord is not None
    columns, rows = panel_grid(section.axis, convention)
    c, r = IN_PLANE[section.axis]
    points = np.empty((3, len(rows), len(columns)))
    points[c] = columns[None, :]
    points[r] = rows[:, None]
    points["xyz".index(section.axis)] = section.coord
    return points


def sample_plane(data: NDArray[Any], affine: NDArray[np.float64], section: Section, convention: str,
                 order: int = 1) -> NDArray[np.float32]:
    """A volume's values on a slice's pixels (NaN outside the volume), shape (h, w).

    `order` 1 interpolates trilinearly (values, the template), 0 takes the nearest voxel (labels).
    """
    from scipy.ndimage import map_coordinates

    def coordinates() -> NDArray[np.float64]:
        points = plane_points(section, convention)
        inverse = np.linalg.inv(affine)
        ijk: NDArray[np.float64] = np.tensordot(inverse[:3, :3], points, axes=1) + inverse[:3, 3, None, None]
        return ijk

    # the same pixels in every figure of a grid: worked out once (VOXEL_MEMO)
    key = ("plane", section, convention, np.asarray(affine, np.float64).tobytes())
    ijk = VOXEL_MEMO.get(key, coordinates)
    out: NDArray[np.float32] = map_coordinates(np.asarray(data, dtype=np.float32), ijk, order=order,
                                               mode="constant", cval=np.nan, prefilter=False)
    return out


def project(data: NDArray[Any], affine: NDArray[np.float64], axis: Axis, convention: str
            ) -> NDArray[np.float32]:
    """The glass-brain projection of a volume along `axis` on the panel's pixels, shape (h, w).

    Each ray takes the value of largest ``|value|`` along it (both signs, NaN as no value), the
    value of a voxel (nearest voxel: a projection holds the volume's values).
    """
    values = np.nan_to_num(np.asarray(data, dtype=np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    grid, ras_affine = _on_mni_axes(values, affine)
    k = "xyz".index(axis)
    peak = np.expand_dims(np.abs(grid).argmax(axis=k), k)
    return _on_panel(np.take_along_axis(grid, peak, axis=k).squeeze(k), ras_affine, axis, convention)


def _on_mni_axes(values: NDArray[np.float32], affine: NDArray[np.float64]
                 ) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
    """A volume with its axes along MNI's x, y, z, increasing (RAS), and its affine: axes swapped and
    flipped (:func:`nibabel.as_closest_canonical`), or, for an oblique volume, resampled at its
    finest voxel size, nearest voxel (:func:`nibabel.processing.resample_to_output`)."""
    import nibabel as nib
    from nibabel.processing import resample_to_output

    ras: Any = nib.as_closest_canonical(nib.Nifti1Image(values, affine))  # type: ignore[no-untyped-call]
    linear = np.asarray(ras.affine)[:3, :3]
    if not np.allclose(linear, np.diag(np.diag(linear))):
        sizes = np.linalg.norm(affine[:3, :3], axis=0)
        ras = resample_to_output(ras, voxel_sizes=float(sizes.min()), order=0)  # type: ignore[no-untyped-call]
    return np.asarray(ras.dataobj, dtype=np.float32), np.asarray(ras.affine, dtype=np.float64)


def _on_panel(flat: NDArray[Any], ras_affine: NDArray[np.float64], axis: Axis, convention: str
              ) -> NDArray[np.float32]:
    """A projection along `axis` (its axes: the panel's column axis, then its row axis) on the panel's
    pixels, nearest value, 0 outside; shape (h, w)."""
    from scipy.ndimage import map_coordinates

    columns, rows = panel_grid(axis, convention)
    c, r = IN_PLANE[axis]
    at_c = (columns - ras_affine[c, 3]) / ras_affine[c, c]
    at_r = (rows - ras_affine[r, 3]) / ras_affine[r, r]
    where = np.stack(np.broadcast_arrays(at_c[None, :], at_r[:, None]))
    out: NDArray[np.float32] = map_coordinates(np.asarray(flat, dtype=np.float32), where, order=0,
                                               mode="constant", cval=0.0)
    return out


@cache
def _template_inside() -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """The template's brain voxels along MNI's axes (RAS) and their affine."""
    data, affine = template()
    grid, ras_affine = _on_mni_axes(data, affine)
    return grid > 0, ras_affine


@cache
def silhouette(axis: Axis, convention: str) -> NDArray[np.bool_]:
    """The template brain seen along `axis` on the panel's pixels, shape (h, w)."""
    inside, ras_affine = _template_inside()
    return _on_panel(inside.any(axis="xyz".index(axis)), ras_affine, axis, convention) > 0


@cache
def glass_lines(axis: Axis, convention: str) -> NDArray[np.bool_]:
    """A glass brain's inner lines on the panel's pixels, shape (h, w): the edges of where the
    template's white matter, averaged along `axis`, exceeds :data:`GLASS_LEVELS` of its largest."""
    from scipy.ndimage import binary_erosion

    data, affine = template(WHITE_MATTER_FILE)
    grid, ras_affine = _on_mni_axes(data, affine)
    mean = _on_panel(grid.mean(axis="xyz".index(axis)), ras_affine, axis, convention)
    lines = np.zeros(mean.shape, dtype=bool)
    for level in GLASS_LEVELS:
        inside = mean > level * mean.max()
        lines |= inside & ~binary_erosion(inside, iterations=2)
    return lines


def check_inside(section: Section, affine: NDArray[np.float64], shape: Sequence[int], name: str) -> None:
    """Refuse a slice whose coordinate lies outside the volume's extent (one line)."""
    if section.coord is None:
        return
    k = "xyz".index(section.axis)
    corners = np.array([[i, j, m, 1.0] for i in (-0.5, shape[0] - 0.5) for j in (-0.5, shape[1] - 0.5)
                        for m in (-0.5, shape[2] - 0.5)]) @ affine.T
    lo, hi = float(corners[:, k].min()), float(corners[:, k].max())
    if not lo <= section.coord <= hi:
        raise BrainPainterError(
            f"slice {section.name} lies outside {name}, whose {section.axis} runs from {lo:.0f} to {hi:.0f} "
            f"mm (MNI); give --slices {section.axis}= coordinates in that range.")
