"""The user's own surfaces (``--lh-surface``/``--rh-surface``) as a template: maps drawn on them as they are.

A surface file, GIfTI (``.surf.gii``, also gzipped) or FreeSurfer geometry
(``lh.pial``, ``lh.inflated``, ...), read with nibabel, becomes the cortex of
a template (:mod:`brainpainter.atlas.template`) whose ``source_vertex`` is
the surface's own vertex index: a map with one value per vertex of that
surface is drawn on it with no resampling, through the same scene parts as
fsaverage's. Beside the surface, when present and of the same vertex count:

* ``sulc``: FreeSurfer's ``lh.sulc`` in the same folder or in ``../surf/``,
  or the surface's name with its surface word replaced by ``sulc``
  (``100307.L.midthickness.32k_fs_LR.surf.gii`` ->
  ``100307.L.sulc.32k_fs_LR.shape.gii``, whose sign HCP turned: turned back, so
  sulci are positive as in FreeSurfer; fMRIPrep's ``..._hemi-L_sulc.shape.gii``);
  the underlay greys and the shading;
* ``curv``: FreeSurfer's ``lh.curv`` (the ``curv`` underlay);
* the cortex: FreeSurfer's ``../label/lh.cortex.label``, or HCP's
  ``atlasroi`` (``100307.L.atlasroi.32k_fs_LR.shape.gii``); the medial
  wall outside it shows the underlay, not the map.

Hemispheres whose x ranges overlap (inflated surfaces, each centred at 0) are
moved apart, 10 mm between them. The template is written once per content
into the user's cache folder (``platformdirs``), so workers load it by path.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.template import FORMAT, FORMAT_VERSION, HEMIS
from brainpainter.atlas.writer import save_npz
from brainpainter.errors import BrainPainterError
from brainpainter.io.gifti import read_gifti

#: The one region of a surface template's label set: the whole surface.
SURFACE_REGION = "surface"
#: Space between the hemispheres when overlapping ones are moved apart, mm.
GAP_MM = 10.0
#: Hemispheres are moved apart when their x ranges overlap by more than this fraction of the narrower one.
OVERLAP = 0.25
#: The surface word of a file name, replaced to find the files beside it (longest first).
_SURFACE_WORD = re.compile(r"very_inflated|veryinflated|midthickness|inflated|smoothwm|pial|white|orig|"
                           r"sphere")
_FREESURFER = re.compile(r"^([lr]h)\.")
#: In the names of HCP Pipelines' files, whose sulc is FreeSurfer's times -1 (Caret's sign: sulci negative).
HCP_NAME = "fs_LR"
#: Bump when what a surface template holds changes (its cache key).
_VERSION = 1


def read_surface(path: str | Path) -> tuple[NDArray[np.float32], NDArray[np.int32]]:
    """Vertices and triangles of one surface file: GIfTI (``.gii``, ``.gii.gz``) or FreeSurfer geometry.

    GIfTI files are read by :func:`brainpainter.io.gifti.read_gifti` (data kept in
    another file is read only from inside the surface's own folder).

    Returns
    -------
    vertices : ndarray of float32, shape (n_vertices, 3)
    faces : ndarray of int32, shape (n_faces, 3)

    Raises
    ------
    BrainPainterError
        A missing or unreadable file, or one that is no valid triangle mesh.
    """
    p = Path(path)
    if not p.is_file():
        raise BrainPainterError(f"surface file {str(p)!r} does not exist; give a GIfTI .surf.gii or a "
                                "FreeSurfer surface (lh.pial, lh.inflated, ...).")
    try:
        if _is_gifti(p):
            img = read_gifti(p, what="surface file")
            pts = img.agg_data("NIFTI_INTENT_POINTSET")
            tri = img.agg_data("NIFTI_INTENT_TRIANGLE")
            if not isinstance(pts, np.ndarray) or not isinstance(tri, np.ndarray):
                raise ValueError("it holds no point set and triangle array (a .func.gii or .shape.gii is "
                                 "a map: give it with --lh/--rh)")
            v, f = pts, tri
        else:
            from nibabel.freesurfer import read_geometry  # type: ignore[attr-defined]

            v, f = read_geometry(str(p))[:2]  # type: ignore[no-untyped-call]
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel's many errors for a file that is not what its name says
        text = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise BrainPainterError(f"cannot read surface file {p.name!r}: {text}. Surfaces are GIfTI "
                                "(.surf.gii, .gii.gz) or FreeSurfer geometry (lh.pial, ...).") from None
    v, f = np.asarray(v), np.asarray(f)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or not len(f) or len(v) < 3:
        raise BrainPainterError(f"surface file {p.name!r} has vertices of shape {v.shape} and faces of shape "
                                f"{f.shape}; a surface has (n, 3) vertices and (m, 3) triangles.")
    if not np.isfinite(v).all() or f.min() < 0 or f.max() >= len(v):
        raise BrainPainterError(f"surface file {p.name!r} has non-finite coordinates or faces that name "
                                f"vertices it lacks (0 to {len(v) - 1}); give an intact surface file.")
    return v.astype(np.float32), f.astype(np.int32)


def _is_gifti(path: Path) -> bool:
    return path.name.lower().endswith((".gii", ".gii.gz"))


def _read_values(path: Path) -> NDArray[Any]:
    """One value per vertex from a FreeSurfer morphometry file or a GIfTI's first data array, shape (n,)."""
    if _is_gifti(path):
        return np.asarray(read_gifti(path).darrays[0].data).ravel()
    from nibabel.freesurfer import read_morph_data  # type: ignore[attr-defined]

    return np.asarray(read_morph_data(str(path))).ravel()  # type: ignore[no-untyped-call]


def beside(path: str | Path, hemi: str, what: str) -> list[Path]:
    """Where a `what` file (``sulc``, ``curv``, ``cortex``) of surface `path` may lie, first found wins.

    FreeSurfer names (``lh.pial``): ``lh.{what}`` in the same folder, then in
    ``../surf/`` (``cortex``: ``../label/lh.cortex.label``); other names: the
    surface word replaced by `what` (``cortex``: by ``atlasroi``), and
    ``.surf.gii`` by ``.shape.gii``.
    """
    p = Path(path)
    if _FREESURFER.match(p.name):
        if what == "cortex":
            return [p.parent.parent / "label" / f"{hemi}.cortex.label", p.parent / f"{hemi}.cortex.label"]
        return [p.parent / f"{hemi}.{what}", p.parent.parent / "surf" / f"{hemi}.{what}"]
    if not _SURFACE_WORD.search(p.name):
        return []
    name = _SURFACE_WORD.sub("atlasroi" if what == "cortex" else what, p.name, count=1)
    return [p.with_name(name.replace(".surf.gii", ".shape.gii")), p.with_name(name)]


def _extras(path: Path, hemi: str, n: int) -> dict[str, NDArray[Any]]:
    """The ``sulc``, ``curv`` and ``cortex`` arrays found beside the surface that fit its `n` vertices."""
    out: dict[str, NDArray[Any]] = {}
    for what in ("sulc", "curv", "cortex"):
        for file in beside(path, hemi, what):
            if not file.is_file() or file == path:
                continue
            try:
                if file.name.endswith(".label"):
                    from nibabel.freesurfer import read_label  # type: ignore[attr-defined]

                    idx = np.asarray(read_label(str(file)), np.int64)  # type: ignore[no-untyped-call]
                    if len(idx) and (idx.min() < 0 or idx.max() >= n):
                        continue
                    values = np.zeros(n, np.float32)
                    values[idx] = 1.0
                else:
                    values = _read_values(file)
            except Exception:  # an unreadable neighbour is no neighbour: the next one is tried
                continue
            if len(values) == n and np.isfinite(values).all():
                if what == "sulc" and HCP_NAME in file.name:  # HCP's sulc is FreeSurfer's times -1
                    values = -values
                out[what] = (values > 0).astype(np.uint8) if what == "cortex" else values.astype(np.float32)
                break
    return out


def _apart(vertices: dict[str, NDArray[Any]]) -> dict[str, NDArray[Any]]:
    """The hemispheres moved apart along x when they overlap (inflated ones), else as they are."""
    if set(vertices) != set(HEMIS):
        return vertices
    lh, rh = vertices["lh"], vertices["rh"]
    overlap = float(lh[:, 0].max() - rh[:, 0].min())
    narrower = min(float(np.ptp(lh[:, 0])), float(np.ptp(rh[:, 0])))
    if overlap <= OVERLAP * narrower:
        return vertices
    return {"lh": lh - np.array([GAP_MM / 2 + lh[:, 0].max(), 0, 0], np.float32),
            "rh": rh + np.array([GAP_MM / 2 - rh[:, 0].min(), 0, 0], np.float32)}


def cache_root() -> Path:
    """The folder of surface templates (in the user's cache folder)."""
    import platformdirs

    return Path(platformdirs.user_cache_dir("brainpainter", appauthor=False)) / "surfaces"


@dataclass(frozen=True)
class Surface:
    """One hemisphere's surface as read, with what was found beside it.

    Attributes
    ----------
    path : Path
    vertices : ndarray of float32, shape (n_vertices, 3)
    faces : ndarray of int32, shape (n_faces, 3)
    extras : dict of str to ndarray, shape (n_vertices,)
        ``sulc``, ``curv`` (float32) and ``cortex`` (uint8, 1 = cortex) where found (:func:`beside`).
    """

    path: Path
    vertices: NDArray[np.float32]
    faces: NDArray[np.int32]
    extras: dict[str, NDArray[Any]]

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)


def read_surfaces(surfaces: Mapping[str, str | Path | None]) -> dict[str, Surface]:
    """The surfaces given (``{"lh": path, "rh": path}``, one or both), read and checked; nothing written."""
    given = {hemi: Path(surfaces[hemi]) for hemi in HEMIS if surfaces.get(hemi) is not None}  # type: ignore[arg-type]
    if not given:
        raise BrainPainterError("no surface given: give --lh-surface FILE and/or --rh-surface FILE.")
    out = {}
    for hemi, path in given.items():
        v, f = read_surface(path)
        out[hemi] = Surface(path, v, f, _extras(path, hemi, len(v)))
    return out


def surface_template(surfaces: Mapping[str, Surface | str | Path], labels: str,
                     root: Path | None = None) -> Path:
    """The template folder of the user's surfaces, written once per content.

    Parameters
    ----------
    surfaces : mapping of {"lh", "rh"} to Surface or path
        One surface per hemisphere drawn (one or both), read (:func:`read_surfaces`) or a file.
    labels : str
        The name of the template's one label set (the run's atlas's ``template_labels``); its one
        region, :data:`SURFACE_REGION`, is the whole surface.
    root : Path, optional
        Where templates are kept (default :func:`cache_root`).

    Returns
    -------
    Path
        A folder :func:`brainpainter.atlas.template.load_template` reads: per hemisphere
        ``cortex-{hemi}.npz`` with ``faces``, ``face_label`` (zeros), ``pial`` (the surface),
        ``source_vertex`` (0..n-1), and ``sulc``, ``curv``, ``cortex`` where found (:func:`beside`).
    """
    read = {hemi: s for hemi, s in surfaces.items() if isinstance(s, Surface)}
    read.update(read_surfaces({hemi: s for hemi, s in surfaces.items() if not isinstance(s, Surface)})
                if len(read) < len(surfaces) else {})
    placed = _apart({hemi: s.vertices for hemi, s in read.items()})
    digest = hashlib.sha256(json.dumps([_VERSION, labels]).encode())
    for hemi, surface in sorted(read.items()):
        for array in (placed[hemi], surface.faces, *surface.extras.values()):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(json.dumps([hemi, sorted(surface.extras)]).encode())
    folder = (root or cache_root()) / digest.hexdigest()[:24]
    if (folder / "manifest.json").is_file():
        return folder
    folder.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=".stage-", dir=folder.parent))
    try:
        cortex: dict[str, Any] = {}
        for hemi, surface in sorted(read.items()):
            v, faces = placed[hemi], surface.faces
            save_npz(stage / f"cortex-{hemi}.npz", {
                "faces": faces, "face_label": np.zeros(len(faces), np.int16), "pial": v,
                "source_vertex": np.arange(len(v), dtype=np.int32), **surface.extras})
            cortex[hemi] = {"file": f"cortex-{hemi}.npz", "names": [SURFACE_REGION], "n_vertices": len(v),
                            "n_source_vertices": len(v), "n_faces": len(faces),
                            "found": sorted(surface.extras)}
        points = np.concatenate(list(placed.values()))
        manifest = {
            "format": FORMAT, "format_version": FORMAT_VERSION, "name": f"surfaces-{folder.name[:8]}",
            "source": {"builder": "brainpainter.atlas.surfaces",
                       **{hemi: str(s.path.absolute()) for hemi, s in sorted(read.items())}},
            "space": "the surfaces' own coordinates (millimetres, x right, y anterior, z superior)",
            "own_vertices": True, "surfaces": ["pial"],
            "labels": {labels: {"source": "the user's surfaces", "cortex": cortex}}, "glass": {},
            "bounds": {"pial": [points.min(axis=0).tolist(), points.max(axis=0).tolist()]},
        }
        (stage / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
        try:
            os.rename(stage, folder)
        except OSError:  # another process wrote the same template first: use it
            if not (folder / "manifest.json").is_file():
                raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return folder
