"""Read and validate the FreeSurfer inputs of a template build.

A subject directory is what ``recon-all`` writes (or FreeSurfer's
``fsaverage``)::

    surf/{lh,rh}.{pial,white,inflated,sphere.reg}
    label/{lh,rh}.aparc.annot, {lh,rh}.aparc.a2009s.annot, [{lh,rh}.aparc.DKTatlas.annot]
    mri/aseg.mgz

Every reader checks what it reads and stops with a one-line
:class:`~brainpainter.errors.BrainPainterError` naming the file and what was
expected, so that a bad input never produces a half-made template.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.io.files import check_input

HEMIS = ("lh", "rh")

#: Built-in label sets: template label-set name -> annotation names tried in order.
ANNOTATIONS = {
    "dk": ("aparc",),
    "destrieux": ("aparc.a2009s",),
    "dkt": ("aparc.DKTatlas", "aparc.DKTatlas40"),
}

#: Classifier atlas (GCSA) used to derive a label set when its annotation is missing.
GCS_PATTERNS = {"dkt": "{hemi}.DKTaparc.atlas*.gcs*"}

#: Colour-table names that are not brain regions (medial wall, unlabelled cortex).
NON_REGIONS = frozenset({"unknown", "Unknown", "corpuscallosum", "Medial_wall"})


@dataclass(frozen=True)
class Annotation:
    """Cortical labels of one hemisphere.

    Attributes
    ----------
    labels : ndarray of int, shape (n_vertices,)
        Index into `names` for every vertex; never -1 (unlabelled vertices are
        mapped to ``"Medial_wall"`` / ``"unknown"``, see :func:`normalise_labels`).
    ctab : ndarray of int, shape (n_names, 5)
        FreeSurfer colour table (r, g, b, transparency, annotation value).
    names : tuple of str
        Colour-table names.
    source : str
        Where the labels came from, for the manifest.
    """

    labels: NDArray[Any]
    ctab: NDArray[Any]
    names: tuple[str, ...]
    source: str


def _missing(path: Path, what: str) -> BrainPainterError:
    return BrainPainterError(f"missing {what} {path}; a FreeSurfer subject directory needs it")


def _read_optional(path: Path, read: Callable[[str], Any], what: str, dtype: type) -> NDArray[Any] | None:
    """`read(path)` as an array of `dtype`; None when the file does not exist."""
    if not path.is_file():
        return None
    try:
        return np.asarray(read(str(path)), dtype=dtype)
    except Exception as exc:  # nibabel raises ValueError, struct.error, OSError...
        raise _unreadable(path, what, exc) from None


def _unreadable(path: Path, what: str, exc: Exception) -> BrainPainterError:
    reason = " ".join(str(exc).split()) or type(exc).__name__
    return BrainPainterError(f"cannot read {path} as {what}: {reason}")


def normalise_labels(labels: NDArray[Any], ctab: NDArray[Any], names: list[str]) -> tuple[
        np.ndarray, NDArray[Any], tuple[str, ...]]:
    """Map unlabelled vertices (-1) to a non-region name.

    ``nibabel.freesurfer.read_annot`` gives -1 where a vertex's annotation
    value is not in the colour table (fsaverage's medial wall). Those vertices
    get the colour-table entry ``"Medial_wall"``, else ``"unknown"`` /
    ``"Unknown"``; if there is none, ``"unknown"`` is appended (colour 25, 5, 25).

    Returns
    -------
    labels : ndarray of int64, shape (n_vertices,)
    ctab : ndarray of int64, shape (n_names, 5)
    names : tuple of str
    """
    labels = np.asarray(labels, dtype=np.int64)
    ctab = np.asarray(ctab, dtype=np.int64)
    names = list(names)
    if (labels < 0).any():
        for candidate in ("Medial_wall", "unknown", "Unknown"):
            if candidate in names:
                fill = names.index(candidate)
                break
        else:
            fill = len(names)
            names.append("unknown")
            ctab = np.vstack([ctab, [[25, 5, 25, 0, 25 + 5 * 2**8 + 25 * 2**16]]])
        labels = np.where(labels < 0, fill, labels)
    return labels, ctab, tuple(names)


class Subject:
    """A FreeSurfer subject directory, read lazily and checked on every read.

    Parameters
    ----------
    path : path-like
        The subject directory (``.../subjects/fsaverage``).
    gcs_dir : path-like, optional
        Folder with FreeSurfer's classifier atlases (``average/``), used to
        derive a label set whose annotation is missing (DKT on fsaverage).
        Default: ``SUBJECT/../../average``, then ``$FREESURFER_HOME/average``.
    """

    def __init__(self, path: str | Path, gcs_dir: str | Path | None = None) -> None:
        self.path = Path(path).expanduser()
        if not self.path.is_dir():
            raise BrainPainterError(
                f"FreeSurfer subject directory {self.path} does not exist; give the folder "
                "that holds surf/, label/ and mri/ (e.g. $SUBJECTS_DIR/fsaverage)."
            )
        for sub in ("surf", "label", "mri"):
            if not (self.path / sub).is_dir():
                raise BrainPainterError(
                    f"{self.path} is not a FreeSurfer subject directory: it has no {sub}/ folder "
                    "(expected surf/, label/ and mri/ as made by recon-all)."
                )
        self.gcs_dir = Path(gcs_dir).expanduser() if gcs_dir is not None else None
        self._n_vertices: dict[str, int] = {}

    @property
    def name(self) -> str:
        return self.path.absolute().name

    # -- surfaces -----------------------------------------------------------------
    def surface(self, hemi: str, surf: str) -> tuple[NDArray[Any], NDArray[Any]]:
        """Read ``surf/{hemi}.{surf}``.

        Returns
        -------
        vertices : ndarray of float64, shape (n_vertices, 3)
            tkr-RAS millimetres.
        faces : ndarray of int64, shape (n_faces, 3)
        """
        from nibabel.freesurfer import read_geometry

        path = self.path / "surf" / f"{hemi}.{surf}"
        if not path.is_file():
            raise _missing(path, "FreeSurfer surface")
        check_input(path, "subject file")  # a regular file within the size limit
        try:
            vertices, faces = read_geometry(str(path))
        except Exception as exc:  # nibabel raises ValueError, struct.error, OSError...
            raise _unreadable(path, "a FreeSurfer triangle surface", exc) from None
        vertices = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces, dtype=np.int64)
        if (vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3
                or len(faces) == 0 or faces.min() < 0 or faces.max() >= len(vertices)
                or not np.isfinite(vertices).all()):
            raise BrainPainterError(
                f"{path} is not a valid triangle surface: expected finite (n, 3) vertices and "
                f"(m, 3) faces indexing them; got {vertices.shape} vertices and {faces.shape} faces"
            )
        expected = self._n_vertices.setdefault(hemi, len(vertices))
        if len(vertices) != expected:
            raise BrainPainterError(
                f"{path} has {len(vertices)} vertices but the other {hemi} surfaces have "
                f"{expected}; all surfaces of a hemisphere must come from one recon-all run"
            )
        return vertices, faces

    def sulc(self, hemi: str) -> NDArray[Any] | None:
        """Sulcal depth ``surf/{hemi}.sulc`` (mm, positive in sulci), shape (n,); None if absent."""
        from nibabel.freesurfer import read_morph_data

        path = self.path / "surf" / f"{hemi}.sulc"
        values = _read_optional(path, read_morph_data, "a FreeSurfer curvature (morph) file", np.float64)
        if values is None:
            return None
        self._check_count(path, len(values), hemi, "values")
        if not np.isfinite(values).all():
            raise BrainPainterError(f"{path} has non-finite values; expected sulcal depths in mm")
        return values

    def n_vertices(self, hemi: str) -> int:
        """Vertex count of the hemisphere (read from its pial surface if needed)."""
        if hemi not in self._n_vertices:
            self.surface(hemi, "pial")
        return self._n_vertices[hemi]

    def _check_count(self, path: Path, n: int, hemi: str, what: str) -> None:
        expected = self.n_vertices(hemi)
        if n != expected:
            raise BrainPainterError(
                f"{path} has {n} {what} but surf/{hemi}.pial has {expected} vertices; "
                "use the file made for this subject"
            )

    def cortex_mask(self, hemi: str) -> NDArray[Any] | None:
        """Vertices of ``label/{hemi}.cortex.label`` as a mask, shape (n,); None if absent."""
        from nibabel.freesurfer import read_label

        path = self.path / "label" / f"{hemi}.cortex.label"
        index = _read_optional(path, read_label, "a FreeSurfer label", np.int64)
        if index is None:
            return None
        n = self.n_vertices(hemi)
        if index.size and (index.min() < 0 or index.max() >= n):
            raise BrainPainterError(f"{path} lists vertices outside surf/{hemi}.pial's {n}; "
                                    "use the file made for this subject")
        mask = np.zeros(n, dtype=bool)
        mask[index] = True
        return mask

    # -- cortical labels ----------------------------------------------------------
    def annotation_path(self, hemi: str, label_set: str) -> Path | None:
        """The annotation file for a label set, or None if the subject has none."""
        for annot in ANNOTATIONS.get(label_set, (label_set,)):
            path = self.path / "label" / f"{hemi}.{annot}.annot"
            if path.is_file():
                return check_input(path, "subject file")
        return None

    def gcs_path(self, hemi: str, label_set: str) -> Path | None:
        """The classifier atlas (``.gcs`` / ``.gcs.gz``) that can derive `label_set`."""
        pattern = GCS_PATTERNS.get(label_set)
        if pattern is None:
            return None
        for folder in self.gcs_dirs:
            hits = sorted(folder.glob(pattern.format(hemi=hemi)))
            if hits:
                return hits[-1]
        return None

    @cached_property
    def gcs_dirs(self) -> list[Path]:
        if self.gcs_dir is not None:
            return [self.gcs_dir]
        dirs = [self.path.resolve().parent.parent / "average"]
        if os.environ.get("FREESURFER_HOME"):
            dirs.append(Path(os.environ["FREESURFER_HOME"]) / "average")
        return [d for d in dirs if d.is_dir()]

    def available_label_sets(self) -> list[str]:
        """Label sets this subject can give on both hemispheres."""
        out = []
        names = set(ANNOTATIONS)
        builtin = {a for annots in ANNOTATIONS.values() for a in annots}
        for p in sorted((self.path / "label").glob("lh.*.annot")):
            if p.name[3:-6] not in builtin:
                names.add(p.name[3:-6])
        for name in sorted(names):
            if all(self.annotation_path(h, name) or self.gcs_path(h, name) for h in HEMIS):
                out.append(name)
        return out

    def check_label_set(self, label_set: str) -> None:
        """Fail early, with the allowed choices, if `label_set` cannot be made."""
        for hemi in HEMIS:
            if self.annotation_path(hemi, label_set) is None and self.gcs_path(hemi, label_set) is None:
                if label_set in GCS_PATTERNS:
                    wanted = (f"label/{hemi}.{ANNOTATIONS[label_set][0]}.annot or a classifier atlas "
                              f"{GCS_PATTERNS[label_set].format(hemi=hemi)} in "
                              f"{[str(d) for d in self.gcs_dirs] or 'SUBJECT/../../average'}")
                    raise BrainPainterError(
                        f"cannot make label set {label_set!r} for {self.path}: it needs {wanted} "
                        "(pass gcs_dir / set FREESURFER_HOME, or leave the atlas out)"
                    )
                if label_set in ANNOTATIONS:
                    raise _missing(self.path / "label" / f"{hemi}.{ANNOTATIONS[label_set][0]}.annot",
                                   f"{label_set!r} annotation")
                raise choice_error("'atlas'", label_set, self.available_label_sets(),
                                   f"(annotations found in {self.path / 'label'})")

    def annotation(self, hemi: str, label_set: str) -> Annotation:
        """Cortical labels of `hemi` for `label_set` (read, or classified from a GCS)."""
        path = self.annotation_path(hemi, label_set)
        if path is not None:
            return self._read_annot(path, hemi)
        gcs = self.gcs_path(hemi, label_set)
        if gcs is None:
            self.check_label_set(label_set)
        return self._classify(gcs, hemi)

    def _read_annot(self, path: Path, hemi: str) -> Annotation:
        from nibabel.freesurfer import read_annot

        try:
            labels, ctab, names = read_annot(str(path))
        except Exception as exc:
            raise _unreadable(path, "a FreeSurfer annotation", exc) from None
        self._check_count(path, len(labels), hemi, "labelled vertices")
        names = [n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n) for n in names]
        labels, ctab, names = normalise_labels(labels, ctab, names)
        return Annotation(labels, ctab, names, f"label/{path.name}")

    def _classify(self, gcs: Path, hemi: str) -> Annotation:
        try:
            from brainpainter_builder import gcsa
        except ImportError as exc:
            raise BrainPainterError(
                f"cannot derive labels from {gcs}: the GCSA reader is unavailable ({exc})"
            ) from None
        sphere, _ = self.surface(hemi, "sphere.reg")
        try:
            atlas = gcsa.read_gcsa(gcs)
        except BrainPainterError:
            raise
        except Exception as exc:
            raise _unreadable(gcs, "a FreeSurfer GCSA classifier atlas", exc) from None
        # FreeSurfer's most-likely-label ("prior") labelling; the cortex mask gives the
        # same medial wall as the subject's other annotations.
        labels, ctab, names = gcsa.label_vertices(atlas, sphere, cortex=self.cortex_mask(hemi))
        names = [n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n) for n in names]
        self._check_count(gcs, len(labels), hemi, "classified vertices")
        labels, ctab, names = normalise_labels(labels, ctab, names)
        return Annotation(labels, ctab, names, f"{gcs.name} (classified on surf/{hemi}.sphere.reg)")

    # -- volumes ------------------------------------------------------------------
    def aseg(self) -> tuple[NDArray[Any], NDArray[Any], float]:
        """Read ``mri/aseg.mgz``.

        Returns
        -------
        labels : ndarray of int32, shape (ni, nj, nk)
        vox2ras_tkr : ndarray of float64, shape (4, 4)
            Voxel index (i, j, k) to surface (tkr-RAS) millimetres.
        voxel_volume : float
            mm^3 per voxel.
        """
        import nibabel as nib

        path = self.path / "mri" / "aseg.mgz"
        if not path.is_file():
            raise _missing(path, "subcortical segmentation")
        check_input(path, "subject file")
        try:
            img = nib.load(str(path))
            data = np.asarray(img.dataobj)
            affine = np.asarray(img.header.get_vox2ras_tkr(), dtype=np.float64)
        except Exception as exc:
            raise _unreadable(path, "an MGH volume (mri/aseg.mgz)", exc) from None
        if data.ndim != 3 or not np.all(np.isfinite(data)) or np.any(data != np.round(data)):
            raise BrainPainterError(
                f"{path} is not a label volume: expected a 3-D volume of integer labels, "
                f"got shape {data.shape} dtype {data.dtype}"
            )
        voxel_volume = float(abs(np.linalg.det(affine[:3, :3])))
        return data.astype(np.int32), affine, voxel_volume


def freesurfer_version(subject_dir: str | Path) -> str:
    """FreeSurfer version that made the subject, or ``"unknown"``.

    Reads ``SUBJECT/../../build-stamp.txt`` (as in ``$FREESURFER_HOME``), then
    ``SUBJECT/scripts/build-stamp.txt`` (recon-all's copy), e.g.
    ``freesurfer-linux-ubuntu22_x86_64-7.3.2-20220804-6354275``.
    """
    subject_dir = Path(subject_dir).resolve()
    for stamp in (subject_dir.parent.parent / "build-stamp.txt",
                  subject_dir / "scripts" / "build-stamp.txt"):
        try:
            text = stamp.read_text(encoding="utf-8", errors="replace").strip()
        except OSError:
            continue
        if text:
            match = re.search(r"(\d+\.\d+\.\d+)", text)
            return f"freesurfer-{match.group(1)}" if match else text.splitlines()[0]
    return "unknown"
