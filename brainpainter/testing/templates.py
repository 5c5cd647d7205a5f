"""Synthetic templates for tests: one writer of the template format, and the tiny template built with it.

:func:`write_template` writes meshes (arrays) as a template folder
(``manifest.json`` plus ``.npz`` files) the way ``brainpainter template build``
lays it out; :func:`write_tiny_template` builds two labelled icospheres, two
boxes and glass spheres and writes them with it. Tests that need other
shapes (the Blender renderer's ellipsoids) build their meshes and call
:func:`write_template` too, so the format is written in one place.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.writer import save_npz

HEMIS = ("lh", "rh")
DEFAULT_LABELS = {"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}


@dataclass(frozen=True)
class CortexMesh:
    """One hemisphere's cortex in one label set.

    Attributes
    ----------
    pial : ndarray of float32, shape (n_vertices, 3)
        RAS millimetres.
    faces : ndarray of int32, shape (n_faces, 3)
    face_label : ndarray of int16, shape (n_faces,)
        Index into `names` per face.
    names : tuple of str
        Label names (without ``Left-``/``Right-``).
    white, inflated : ndarray of float32, shape (n_vertices, 3)
        The other surfaces.
    """

    pial: NDArray[np.float32]
    faces: NDArray[np.int32]
    face_label: NDArray[np.int16]
    names: tuple[str, ...]
    white: NDArray[np.float32]
    inflated: NDArray[np.float32]


@dataclass(frozen=True)
class Structure:
    """A subcortical structure: a closed mesh with a name (and an optional aseg index)."""

    name: str
    vertices: NDArray[np.float32]
    faces: NDArray[np.int32]
    index: int | None = None


def save_arrays(path: Path, arrays: Mapping[str, NDArray[Any]]) -> None:
    """Write `arrays` as one ``.npz`` file as the builder does (the one place test templates write arrays)."""
    save_npz(path, arrays)


def _cortex_entries(path: Path, cortex: Mapping[str, Mapping[str, CortexMesh]]) -> dict[str, Any]:
    labels: dict[str, Any] = {}
    for label_set, hemis in cortex.items():
        labels[label_set] = {"source": "synthetic", "cortex": {}}
        for hemi, m in hemis.items():
            file = f"cortex-{hemi}-{label_set}.npz"
            save_arrays(path / file, {"faces": m.faces, "face_label": m.face_label, "pial": m.pial,
                                      "white": m.white, "inflated": m.inflated,
                                      "source_vertex": np.arange(len(m.pial), dtype=np.int32)})
            labels[label_set]["cortex"][hemi] = {"file": file, "names": list(m.names),
                                                 "n_vertices": len(m.pial), "n_faces": len(m.faces),
                                                 "open_edges": 0}
    return labels


def _subcortical_entry(path: Path, structures: Sequence[Structure]) -> dict[str, Any]:
    offsets = np.cumsum([0] + [len(s.vertices) for s in structures])
    save_arrays(path / "subcortical.npz", {
        "vertices": np.concatenate([s.vertices for s in structures]).astype(np.float32),
        "faces": np.concatenate([s.faces + off for s, off in zip(structures, offsets, strict=False)]
                                ).astype(np.int32),
        "face_label": np.repeat(np.arange(len(structures)), [len(s.faces) for s in structures]
                                ).astype(np.int16)})
    listed = [{"name": s.name, **({} if s.index is None else {"index": s.index})} for s in structures]
    return {"file": "subcortical.npz", "structures": listed}


def write_template(path: Path, cortex: Mapping[str, Mapping[str, CortexMesh]],
                   structures: Sequence[Structure] = (),
                   glass: Mapping[str, tuple[NDArray[np.float32], NDArray[np.int32]]] | None = None,
                   name: str = "tiny") -> Path:
    """Write meshes as a template folder that :func:`brainpainter.atlas.template.load_template` reads.

    Parameters
    ----------
    path : Path
        Folder to create.
    cortex : mapping
        ``{label set: {"lh" | "rh": CortexMesh}}``; every label set has the same pial meshes.
    structures : sequence of Structure
        Subcortical structures (none: the template has no subcortical part).
    glass : mapping, optional
        ``{"lh" | "rh": (vertices (n, 3), faces (m, 3))}``: the glass brain.
    name : str
        The template's name.

    Returns
    -------
    Path
        `path`.
    """
    from brainpainter.atlas.template import FORMAT, FORMAT_VERSION

    path.mkdir(parents=True, exist_ok=True)
    manifest: dict[str, Any] = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "name": name,
        "source": {"subject": "synthetic", "freesurfer_version": "none"},
        "space": "RAS millimetres", "surfaces": ["pial", "white", "inflated"],
        "labels": _cortex_entries(path, cortex), "license": "CC0", "attribution": "synthetic", "glass": {},
    }
    if structures:
        manifest["subcortical"] = _subcortical_entry(path, structures)
    for hemi, (vertices, faces) in (glass or {}).items():
        save_arrays(path / f"glass-{hemi}.npz", {"vertices": np.asarray(vertices, np.float32),
                                                 "faces": np.asarray(faces, np.int32)})
        manifest["glass"][hemi] = {"file": f"glass-{hemi}.npz", "n_faces": len(faces)}
    pial = np.concatenate([m.pial for m in next(iter(cortex.values())).values()])
    manifest["bounds"] = {"pial": [pial.min(axis=0).tolist(), pial.max(axis=0).tolist()]}
    (path / "manifest.json").write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    return path


def write_tiny_template(path: Path, labels: Mapping[str, tuple[str, ...]] | None = None) -> Path:
    """Write a small synthetic template (two icospheres, two boxes, glass spheres).

    Each hemisphere is an icosphere of radius 50 mm centred at x = -/+ 60 mm,
    split into the given label names by angle around the x axis (the first
    name on the anterior pole side). Subcortical: ``Left-Hippocampus`` and
    ``Right-Hippocampus`` boxes. Meant for fast tests of renderers and the
    core; coordinates are RAS millimetres like a real template.

    Parameters
    ----------
    path : Path
        Folder to create.
    labels : mapping of label-set name to label names, optional
        Default: ``{"dk": ("insula", "precuneus", "superiorfrontal", "unknown")}``.

    Returns
    -------
    Path
        `path`.
    """
    import trimesh

    labels = labels or DEFAULT_LABELS
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=50.0)
    verts0 = np.asarray(sphere.vertices, dtype=np.float32)
    faces = np.asarray(sphere.faces, dtype=np.int32)
    centroids = verts0[faces].mean(axis=1)
    angle = np.arctan2(centroids[:, 2], centroids[:, 1])  # around the x axis, 0 = anterior
    offsets = {"lh": -60.0, "rh": 60.0}
    cortex: dict[str, dict[str, CortexMesh]] = {}
    for label_set, names in labels.items():
        bins = np.linspace(-np.pi, np.pi, len(names) + 1)
        face_label = np.clip(np.digitize(-angle, bins) - 1, 0, len(names) - 1).astype(np.int16)
        cortex[label_set] = {}
        for hemi, dx in offsets.items():
            verts = verts0 + np.array([dx, 0, 0], np.float32)
            cortex[label_set][hemi] = CortexMesh(verts, faces, face_label, tuple(names),
                                                 white=verts * np.float32(0.95),
                                                 inflated=verts + np.float32(np.sign(dx) * 10))
    structures = []
    for (hemi, dx), index in zip(offsets.items(), (17, 53), strict=True):
        box = trimesh.creation.box(extents=(10, 20, 10)).apply_translation((dx / 3, 0, 0))
        side = "Left" if hemi == "lh" else "Right"
        structures.append(Structure(f"{side}-Hippocampus", np.asarray(box.vertices, np.float32),
                                    np.asarray(box.faces, np.int32), index))
    glass = {}
    for hemi, dx in offsets.items():
        g = trimesh.creation.icosphere(subdivisions=2, radius=52.0).apply_translation((dx, 0, 0))
        glass[hemi] = (np.asarray(g.vertices, np.float32), np.asarray(g.faces, np.int32))
    return write_template(path, cortex, structures, glass)
