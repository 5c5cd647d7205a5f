"""Templates: everything a renderer needs to draw one brain.

A template is a directory::

    manifest.json                  metadata (see below)
    cortex-{hemi}-{labels}.npz     one hemisphere split by one label set
    subcortical.npz                aseg structures
    glass-{hemi}.npz               smooth hull of the pial surface
    LICENSE.FreeSurfer.txt         licence Part B and attribution (derived data)

All arrays are plain ``.npz`` (loaded with ``allow_pickle=False``); all
coordinates are FreeSurfer tkr-RAS millimetres (x right, y anterior, z
superior). Cortex files hold one mesh per hemisphere whose faces carry a
region label: the per-region meshes are ``faces[face_label == i]``, so
neighbouring regions share their boundary vertices exactly. The pial, white
and inflated surfaces share one topology (``faces``) and differ in vertex
positions; inflated positions are already offset so hemispheres never overlap.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from brainpainter.errors import BrainPainterError

FORMAT = "brainpainter-template"
FORMAT_VERSION = 1
SURFACES = ("pial", "white", "inflated")
HEMIS = ("lh", "rh")


@dataclass(frozen=True)
class CortexMesh:
    """One hemisphere, split into regions by one label set.

    Attributes
    ----------
    hemi : {"lh", "rh"}
    labels : str
        Label-set name (``"dk"``, ``"destrieux"``, ``"dkt"``).
    faces : ndarray of int32, shape (n_faces, 3)
    face_label : ndarray of int16, shape (n_faces,)
        Index into `label_names` for every face.
    label_names : tuple of str
        Names from the annotation colour table (``"insula"``, ``"unknown"``).
    vertices : dict of str to ndarray of float32, shape (n_vertices, 3)
        One entry per surface (``"pial"``, ``"white"``, ``"inflated"``).
    source_vertex : ndarray of int32, shape (n_vertices,)
        Index of each vertex in the full-resolution FreeSurfer surface.
    """

    hemi: str
    labels: str
    faces: np.ndarray
    face_label: np.ndarray
    label_names: tuple[str, ...]
    vertices: dict[str, np.ndarray]
    source_vertex: np.ndarray


@dataclass(frozen=True)
class LabelledMesh:
    """Meshes of several structures in one array set.

    Attributes
    ----------
    vertices : ndarray of float32, shape (n_vertices, 3)
    faces : ndarray of int32, shape (n_faces, 3)
    face_label : ndarray of int16, shape (n_faces,)
        Index into `label_names`.
    label_names : tuple of str
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_label: np.ndarray
    label_names: tuple[str, ...]


@dataclass
class Template:
    """A loaded template directory. Arrays are read on first use and cached."""

    path: Path
    manifest: dict
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def name(self) -> str:
        return self.manifest["name"]

    @property
    def label_sets(self) -> list[str]:
        return sorted(self.manifest["labels"])

    @property
    def surfaces(self) -> list[str]:
        return list(self.manifest["surfaces"])

    def _npz(self, file: str) -> dict[str, np.ndarray]:
        if file not in self._cache:
            with np.load(self.path / file, allow_pickle=False) as z:
                self._cache[file] = {k: z[k] for k in z.files}
        return self._cache[file]

    def cortex(self, labels: str, hemi: str) -> CortexMesh:
        """The hemisphere `hemi` split by label set `labels`."""
        if labels not in self.manifest["labels"]:
            raise BrainPainterError(
                f"template {self.name!r} has no label set {labels!r}; it has {self.label_sets}. "
                "Build the template with that atlas (brainpainter template build --atlas ...)."
            )
        entry = self.manifest["labels"][labels]["cortex"][hemi]
        z = self._npz(entry["file"])
        return CortexMesh(
            hemi=hemi,
            labels=labels,
            faces=z["faces"],
            face_label=z["face_label"],
            label_names=tuple(entry["names"]),
            vertices={s: z[s] for s in self.surfaces if s in z},
            source_vertex=z["source_vertex"],
        )

    def subcortical(self) -> LabelledMesh:
        """All subcortical structures (names as in FreeSurfer's aseg LUT)."""
        entry = self.manifest["subcortical"]
        z = self._npz(entry["file"])
        return LabelledMesh(z["vertices"], z["faces"], z["face_label"],
                            tuple(s["name"] for s in entry["structures"]))

    def glass(self, hemi: str) -> tuple[np.ndarray, np.ndarray]:
        """Glass-brain hull of one hemisphere: ``(vertices (n, 3), faces (m, 3))``."""
        z = self._npz(self.manifest["glass"][hemi]["file"])
        return z["vertices"], z["faces"]

    @cached_property
    def bounds(self) -> np.ndarray:
        """Bounding box of the pial surfaces, shape (2, 3): min and max corner."""
        return np.asarray(self.manifest["bounds"]["pial"], dtype=float)

    def files(self) -> list[Path]:
        return sorted(p for p in self.path.iterdir() if p.is_file())


def load_template(name_or_path: str | Path = "fsaverage") -> Template:
    """Load a template by registry name or directory path.

    Parameters
    ----------
    name_or_path : str or path-like
        ``"fsaverage"`` (the bundled default), another registered template
        name, or a directory made by ``brainpainter template build``.
    """
    path = Path(name_or_path)
    if not (path / "manifest.json").is_file():
        if isinstance(name_or_path, str) and "/" not in name_or_path and "\\" not in name_or_path:
            from brainpainter import registry

            path = registry.templates.get(name_or_path)
        else:
            raise BrainPainterError(
                f"template {str(name_or_path)!r} is not a directory with a manifest.json; "
                "give a registered template name (e.g. 'fsaverage') or a folder made by "
                "'brainpainter template build'."
            )
    manifest_file = path / "manifest.json"
    try:
        manifest = json.loads(manifest_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"cannot read template manifest {manifest_file}: {exc}") from None
    if manifest.get("format") != FORMAT or manifest.get("format_version") != FORMAT_VERSION:
        raise BrainPainterError(
            f"{manifest_file} is not a {FORMAT} version {FORMAT_VERSION} manifest; "
            "rebuild it with 'brainpainter template build'."
        )
    return Template(path=path, manifest=manifest)
