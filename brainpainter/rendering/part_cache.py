"""A region scene's cortex parts, kept between runs in the user's cache folder and checked on reading.

Splitting a hemisphere by region, its normals, occlusion and borders are the same in every run
of a template, label set, surface and set of hidden regions (0.1-0.15 s of a cold first image on
an idle 2-core machine), and so is its edge table, which the default renderer's anti-aliasing
needs (:mod:`brainpainter.rendering.mesh_edges`, another ~0.1 s). :func:`cached_part` keeps the
finished :class:`~brainpainter.rendering.parts.PartGeometry` arrays and its edge table as one
uncompressed ``.npz`` in
``<user cache>/parts`` (:mod:`brainpainter.io.user_cache`), named by a key: the SHA-256 of the
template files the part is read from (their bytes, not their times), of everything else it
depends on (:func:`part_key`) and of the source of the modules that compute it (a new
release never reads an old result).

A file is used only when it loads without pickles, holds exactly the expected arrays with the
expected dtypes and consistent shapes, its triangles and edges index its vertices, its edges'
triangles its triangles, its palette slots lie in the scene's, and the SHA-256 of its arrays
matches the one it stores; anything else (a damaged, truncated, foreign or oversized file) is a
miss: the part is computed and the file written again (atomically). At most :data:`MAX_FILES`
files are kept (the newest). Maps (per-vertex scenes) are not kept: their mesh follows the map.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Iterable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.io import user_cache
from brainpainter.rendering.mesh_edges import EdgeTable, edge_table
from brainpainter.rendering.parts import PartGeometry

#: Folder of the part files in :func:`brainpainter.io.user_cache.cache_dir`.
FOLDER = "parts"
#: Part files kept at most (the newest; a cortex part of the default template and its edge table: 9.9 MB).
MAX_FILES = 16
#: Bumped when the file's layout changes (2: the edge table).
FORMAT = 2
#: Arrays every file holds: name -> (dtype, trailing shape); the first axis is checked against the others.
ARRAYS = {"vertices": ("float32", (3,)), "normals": ("float32", (3,)), "triangles": ("uint32", (3,)),
          "palette_index": ("int32", ()), "sulc": ("float32", ()),
          "edge_ends": ("int32", (2,)), "edge_faces": ("int32", (2,)), "edge_border": ("bool", ()),
          "face_normals": ("float32", (3,))}
#: Arrays whose first axis is not the vertices': name -> the array whose first axis it shares.
OTHER_AXIS = {"outline": "outline", "triangles": "triangles", "face_normals": "triangles",
              "edge_ends": "edge_ends", "edge_faces": "edge_ends", "edge_border": "edge_ends"}
#: Optional arrays: ``occlusion`` per vertex, ``outline`` segments.
OPTIONAL = {"occlusion": ("float32", ()), "outline": ("float32", (2, 3))}
#: Modules whose code makes a part: their source is part of the key.
SOURCES = ("brainpainter.atlas.mesh", "brainpainter.atlas.template", "brainpainter.atlas.occlusion",
           "brainpainter.rendering.parts", "brainpainter.rendering.geometry",
           "brainpainter.rendering.borders", "brainpainter.rendering.sulc",
           "brainpainter.rendering.mesh_edges")

_source_digest: list[str] = []


def _sources() -> str:
    if not _source_digest:
        import importlib.util

        h = hashlib.sha256()
        for name in SOURCES:
            spec = importlib.util.find_spec(name)
            origin = spec.origin if spec is not None else None
            h.update(name.encode() + b"\0" + (Path(origin).read_bytes() if origin else b"?") + b"\0")
        _source_digest.append(h.hexdigest())
    return _source_digest[0]


def template_files(template: Any, labels: str, hemi: str) -> list[Path]:
    """The files a region scene's cortex part is read from (the label set's, and its base mesh's for
    an overlay); none for a hemisphere without cortex."""
    entry = template.manifest["labels"].get(labels, {}).get("cortex", {}).get(hemi)
    if entry is None:
        return []
    files = [Path(template.path) / entry["file"]]
    if "base" in entry:
        files.append(Path(template.path) / template.manifest["labels"][entry["base"]]["cortex"][hemi]["file"])
    return files


def cortex_kept(scene: Any, hemi: str, label_slot: NDArray[Any],
                with_sulc: bool) -> tuple[list[Path], dict[str, Any]] | None:
    """What a region scene's cortex part of `hemi` is kept under: its template files and the facts
    it depends on (:func:`cached_part`); None where it is not kept (no cortex; a map's contours,
    whose lines join its outline)."""
    files = template_files(scene.template, scene.labels, hemi)
    if not files or getattr(scene, "contours", None) is not None:
        return None
    s = scene.settings
    return files, {"labels": scene.labels, "hemi": hemi, "surface": scene.surface, "sulc": with_sulc,
                   "occlusion": s.shading != "flat", "outline": s.outline_width > 0,
                   "slots": label_slot.tolist()}


def part_key(files: Iterable[str | Path], **facts: Any) -> str:
    """The key of a part: SHA-256 of the bytes of `files`, of `facts` (JSON-able) and of the code.

    Parameters
    ----------
    files : iterable of path
        The template files the part is read from.
    **facts
        Everything else it depends on (label set, hemisphere, surface, shading, the slot of each
        label, ...).
    """
    h = hashlib.sha256(f"brainpainter-part-{FORMAT}\0{_sources()}\0".encode())
    for file in files:
        with open(file, "rb") as f:
            h.update(hashlib.file_digest(f, "sha256").digest())
    h.update(json.dumps(facts, sort_keys=True, default=str).encode())
    return h.hexdigest()


def _digest(arrays: dict[str, NDArray[Any]]) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}\0".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _checked(arrays: dict[str, NDArray[Any]], n_slots: int) -> bool:
    """Whether `arrays` is a well-formed part: dtypes, shapes, indices in range."""
    names = set(arrays) - {"digest"}
    if not set(ARRAYS) <= names <= set(ARRAYS) | set(OPTIONAL):
        return False
    n = len(arrays["vertices"])
    for name in names:
        dtype, tail = {**ARRAYS, **OPTIONAL}[name]
        a = arrays[name]
        if a.dtype != np.dtype(dtype) or a.shape[1:] != tail:
            return False
        if len(a) != (len(arrays[OTHER_AXIS[name]]) if name in OTHER_AXIS else n):
            return False
    tri, pal = arrays["triangles"], arrays["palette_index"]
    if (tri.size and int(tri.max()) >= n) or (pal.size and (int(pal.min()) < 0 or int(pal.max()) >= n_slots)):
        return False
    ends, faces = arrays["edge_ends"], arrays["edge_faces"]
    if ends.size and (int(ends.min()) < 0 or int(ends.max()) >= n
                      or int(faces.min()) < -1 or int(faces.max()) >= len(tri)):
        return False
    return all(np.isfinite(arrays[k]).all() for k in ("vertices", "normals", "face_normals"))


def read_part(path: Path, name: str, kind: str, hemi: str | None, n_slots: int,
              max_bytes: int) -> PartGeometry | None:
    """The part stored in `path`, or None where the file is missing, too large or not a valid part."""
    try:
        with open(path, "rb") as f:  # opened here: np.load leaves a file it cannot read open
            if os.fstat(f.fileno()).st_size > max_bytes:
                return None
            with np.load(f, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
    except Exception:  # not a zip, not an npz, a pickle, a bad header...: a miss
        return None
    stored = arrays.pop("digest", None)
    if stored is None or stored.dtype.kind != "U" or stored.shape != ():
        return None
    try:
        if not _checked(arrays, n_slots) or str(stored) != _digest(arrays):
            return None
    except (ValueError, TypeError):
        return None
    v = arrays["vertices"]
    edges = EdgeTable(arrays["edge_ends"], arrays["edge_faces"], arrays["edge_border"],
                      arrays["face_normals"])
    return PartGeometry(name, kind, hemi, v, arrays["normals"], arrays["triangles"], arrays["palette_index"],
                        arrays["sulc"], v, arrays.get("occlusion"), arrays.get("outline"), edges=edges)


def write_part(path: Path, part: PartGeometry) -> None:
    """Store `part`'s arrays and edge table in `path` (atomically; nothing where the folder cannot be
    written; its edge table is built first where it has none)."""
    edges = part.edges or edge_table(part.vertices, part.triangles, part.palette_index)
    arrays = {"vertices": part.vertices, "normals": part.normals, "triangles": part.triangles,
              "palette_index": part.palette_index, "sulc": part.sulc, "edge_ends": edges.ends,
              "edge_faces": edges.faces, "edge_border": edges.border, "face_normals": edges.normals}
    if part.occlusion is not None:
        arrays["occlusion"] = part.occlusion
    if part.outline is not None:
        arrays["outline"] = np.asarray(part.outline, np.float32)
    arrays = {k: np.ascontiguousarray(v, dtype=ARRAYS.get(k, OPTIONAL.get(k, ("float32",)))[0])
              for k, v in arrays.items()}
    digest = np.array(_digest(arrays))
    user_cache.write_atomic(path, lambda f: np.savez(f, digest=digest, **arrays))


def cached_part(files: list[str | Path], facts: dict[str, Any], name: str, kind: str, hemi: str | None,
                n_slots: int, build: Callable[[], PartGeometry | None]) -> PartGeometry | None:
    """The part `build()` makes, read from the user's cache when a valid file of its key is there.

    Parameters
    ----------
    files : list of path
        The template files it is read from (their bytes are part of the key; a file more than 8
        times their size is not read).
    facts : dict
        Everything else the part depends on (:func:`part_key`).
    name, kind, hemi : str
        Of the part.
    n_slots : int
        Palette slots of the scene (every stored slot must be below it).
    build : callable
        Computes the part (None: nothing to draw; not stored); its edge table is built beside it.
    """
    folder = user_cache.cache_dir()
    if folder is None:
        return build()
    try:
        key = part_key(files, **facts)
        budget = 8 * sum(os.path.getsize(f) for f in files) + (1 << 20)
    except OSError:
        return build()
    path = folder / FOLDER / f"{key}.npz"
    part = read_part(path, name, kind, hemi, n_slots, budget)
    if part is None:
        part = build()
        if part is not None:
            part = replace(part, edges=edge_table(part.vertices, part.triangles, part.palette_index))
            write_part(path, part)
            prune(path.parent)
    return part


def prune(folder: Path, keep: int | None = None) -> None:
    """Remove all but the `keep` (default :data:`MAX_FILES`) newest part files of `folder` (many
    scenes, e.g. a server's requests hiding other regions, never fill the disk)."""
    keep = MAX_FILES if keep is None else keep
    try:
        files = sorted(folder.glob("*.npz"), key=lambda p: p.stat().st_mtime_ns, reverse=True)
        for old in files[keep:]:
            old.unlink()
    except OSError:
        pass  # another process removed one first
