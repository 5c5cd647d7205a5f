"""Tracts as core holds them: every bundle's streamlines resampled, oriented and placed in the template.

:class:`TractSpec` says what to load (small, picklable: it travels to worker
processes and Dask workers, which load the files themselves and draw the same
subsample); :class:`Tracts` is what was loaded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brainpainter.errors import BrainPainterError

__all__ = ["DEFAULT_SPACE", "MAX_STREAMLINES", "N_POINTS", "SUFFIXES", "TractSpec", "Tracts", "bundle_files",
           "read_affine"]

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from brainpainter.atlas.template import Template
    from brainpainter.tracts.bundles import Tracts


def __getattr__(name: str) -> Any:
    # numpy-free at import (the CLI's options import this module): Tracts comes on first use
    if name == "Tracts":
        from brainpainter.tracts.bundles import Tracts

        return Tracts
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

#: Tractogram file suffixes read (.trx needs the optional trx-python).
SUFFIXES = (".trk", ".tck", ".trx")
#: Points per streamline after resampling (the tube's rings; node colours are interpolated onto them).
N_POINTS = 32
#: Streamlines drawn at most, over all bundles; more are subsampled at random (with a note).
#: 5,000 keep a figure legible and an image within a few region renders on a CPU rasteriser.
MAX_STREAMLINES = 5_000
#: Default coordinate space of tractogram files (population bundles are in MNI152).
DEFAULT_SPACE = "MNI152NLin2009cAsym"


@dataclass(frozen=True)
class TractSpec:
    """What tracts to load and how: the ``--tracts*`` options.

    Attributes
    ----------
    paths : tuple of str
        Tractogram files (.trk, .tck, .trx) or folders of them; one file per
        bundle (the file name is the bundle name), a .trx's groups are bundles.
    space : str
        Coordinate space of the files (:data:`brainpainter.atlas.model.SPACES`):
        MNI152 files are mapped to the fsaverage template (MNI305) by
        FreeSurfer's affine; ``template``: already in the template's coordinates.
    affine : path or None
        A 4x4 matrix as a text file (numpy's or FSL's) applied to the files'
        RAS millimetres first (e.g. to place bundles that are not in MNI152).
    max_streamlines : int
        Drawn at most over all bundles (a random subsample, the same in every process).
    n_points : int
        Points per resampled streamline.
    seed : int
        Of the subsample.
    """

    paths: tuple[str, ...]
    space: str = DEFAULT_SPACE
    affine: str | None = None
    max_streamlines: int = MAX_STREAMLINES
    n_points: int = N_POINTS
    seed: int = 0
    _files: tuple[Path, ...] = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        from brainpainter.atlas.model import SPACES
        from brainpainter.errors import choice_error

        if self.space not in SPACES:
            raise choice_error("--tracts-space", self.space, SPACES)
        if int(self.max_streamlines) < 1 or int(self.n_points) < 2:
            raise BrainPainterError(
                f"--max-streamlines must be >= 1 and points per streamline >= 2; {self.max_streamlines} and "
                f"{self.n_points} were given.")
        object.__setattr__(self, "_files", tuple(bundle_files(self.paths)))
        if self.affine is not None:
            read_affine(self.affine)

    @property
    def files(self) -> tuple[Path, ...]:
        """The tractogram files, folders expanded (sorted)."""
        return self._files

    def load(self, template: Template) -> Tracts:
        """Read, subsample, resample, orient and place every bundle (see :mod:`brainpainter.tracts.read`)."""
        from brainpainter.atlas.volumes import space_transform
        from brainpainter.tracts.read import read_bundles

        to_template = space_transform(self.space, template)
        if self.affine is not None:
            to_template = to_template @ read_affine(self.affine)
        tracts = read_bundles(self.files, to_template, self.max_streamlines, self.n_points, self.seed)
        warn_outside(tracts, template.bounds, self.space, self.affine is not None)
        return tracts


def bundle_files(paths: tuple[str, ...] | list[str]) -> list[Path]:
    """The tractogram files of `paths` (files, or folders: their .trk/.tck/.trx files, sorted).

    Raises
    ------
    BrainPainterError
        A path that does not exist, a file of another type, or a folder without tractograms.
    """
    out: list[Path] = []
    for given in paths:
        p = Path(given).expanduser()
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.suffix.lower() in SUFFIXES and f.is_file())
            if not found:
                raise BrainPainterError(
                    f"--tracts folder {str(given)!r} holds no tractogram ({', '.join(SUFFIXES)} files); "
                    "give a folder with one file per bundle, or the files themselves.")
            out += found
        elif p.is_file():
            if p.suffix.lower() not in SUFFIXES:
                raise BrainPainterError(
                    f"--tracts {str(given)!r} is not a tractogram: allowed are {list(SUFFIXES)} files or a "
                    "folder of them; convert other formats with nibabel or dipy first.")
            out.append(p)
        else:
            raise BrainPainterError(f"--tracts {str(given)!r} does not exist; give tractogram files "
                                    f"({', '.join(SUFFIXES)}) or a folder of them.")
    if not out:
        raise BrainPainterError("--tracts was given no file; give tractogram files or a folder of them.")
    return out


def read_affine(path: str | Path) -> NDArray[Any]:
    """A 4x4 (or 3x4) matrix from a text file as numpy's ``savetxt`` or FSL writes one.

    Raises
    ------
    BrainPainterError
        The file is missing or does not hold a 4x4 / 3x4 matrix of numbers with last row 0 0 0 1.
    """
    import numpy as np

    try:
        m = np.loadtxt(Path(path).expanduser(), dtype=float, ndmin=2)
    except (OSError, ValueError) as exc:
        raise BrainPainterError(
            f"--tracts-affine {str(path)!r} could not be read as a matrix ({exc}); give a text file of 4 "
            "rows of 4 numbers (numpy.savetxt or an FSL .mat).") from None
    if m.shape == (3, 4):
        m = np.vstack([m, [0.0, 0.0, 0.0, 1.0]])
    if m.shape != (4, 4) or not np.all(np.isfinite(m)) or not np.allclose(m[3], [0, 0, 0, 1]):
        raise BrainPainterError(
            f"--tracts-affine {str(path)!r} holds a {m.shape[0]}x{m.shape[1] if m.ndim > 1 else 1} matrix; "
            "allowed is a finite 4x4 affine with last row 0 0 0 1 (or its first 3 rows).")
    return m


#: Points this far (mm) beyond the template's pial bounding box still count as inside (the brainstem, the
#: cerebellum's bundles reach below the cortex).
OUTSIDE_MARGIN = 20.0
#: A warning where more than this share of the streamlines' points lie outside.
OUTSIDE_SHARE = 0.25


def warn_outside(tracts: Tracts, bounds: Any, space: str, affine_given: bool) -> None:
    """Warn where most of the streamlines lie outside the brain: their points beyond the template's pial
    bounding box (`bounds`, shape (2, 3)) by more than :data:`OUTSIDE_MARGIN` mm (dipy's bundles read
    without their affine: voxel coordinates, drawn beside the brain, in silence)."""
    import warnings

    import numpy as np

    box = np.asarray(bounds, dtype=np.float64)
    points = tracts.lines.reshape(-1, 3)
    outside = np.any((points < box[0] - OUTSIDE_MARGIN) | (points > box[1] + OUTSIDE_MARGIN), axis=1)
    share = float(outside.mean()) if len(points) else 0.0
    if share <= OUTSIDE_SHARE:
        return
    low, high = points.min(axis=0), points.max(axis=0)
    extent = ", ".join(f"{axis} {a:.0f}..{b:.0f}" for axis, a, b in zip("xyz", low, high, strict=True))
    brain = ", ".join(f"{axis} {a:.0f}..{b:.0f}" for axis, a, b in zip("xyz", box[0], box[1], strict=True))
    how = "Check --tracts-affine" if affine_given else "Give their affine (--tracts-affine)"
    warnings.warn(
        f"{share:.0%} of the streamlines' points lie outside the brain: they span {extent} mm, the template "
        f"{brain} (+-{OUTSIDE_MARGIN:.0f}); voxel coordinates or another space? {how} or their "
        f"--tracts-space (now {space}).",
        UserWarning, stacklevel=3)
