"""Reading region mesh files: every format one way, triangle soups welded, axes named by letters.

OBJ, PLY (ASCII and binary; polygons fan-triangulated, also where trimesh's
binary reader refuses a file that mixes triangles and quads), STL, OFF,
GLB/glTF through trimesh; GIfTI surfaces through nibabel. Used by
:mod:`brainpainter.atlas.meshfolder` and :mod:`brainpainter.atlas.brainglobe`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError

#: Mesh file endings read (longest first: ``.surf.gii`` before ``.gii``).
MESH_SUFFIXES = (".surf.gii.gz", ".gii.gz", ".surf.gii", ".gii", ".gltf", ".glb", ".ply", ".obj", ".stl",
                 ".off")
_AXIS = {"R": (0, 1.0), "L": (0, -1.0), "A": (1, 1.0), "P": (1, -1.0), "S": (2, 1.0), "I": (2, -1.0)}


def mesh_stem(path: Path) -> str:
    """File name without its mesh ending (``lh.pial.Mice.Auditory``, ``Left-Cerebellum``)."""
    low = path.name.lower()
    for suffix in MESH_SUFFIXES:
        if low.endswith(suffix):
            return path.name[: -len(suffix)]
    return path.stem


def mesh_files(folder: str | Path) -> list[Path]:
    """Mesh files of `folder` (not recursive), sorted; one-line error if there are none."""
    folder = Path(folder).expanduser()
    if not folder.is_dir():
        raise BrainPainterError(f"mesh folder {folder} does not exist; give a folder of region meshes "
                                f"({', '.join(MESH_SUFFIXES)})")
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.name.lower().endswith(MESH_SUFFIXES))
    if not files:
        raise BrainPainterError(f"{folder} holds no mesh file; give a folder with one region mesh per file "
                                f"({', '.join(MESH_SUFFIXES)})")
    return files


# -- reading ---------------------------------------------------------------------------
def _fan(polygons: list[NDArray[Any]]) -> NDArray[Any]:
    """Triangles of polygons given as index arrays (fan from each polygon's first vertex), shape (m, 3)."""
    tris = [np.column_stack([np.full(len(p) - 2, p[0]), p[1:-1], p[2:]]) for p in polygons if len(p) >= 3]
    return np.concatenate(tris).astype(np.int64) if tris else np.zeros((0, 3), np.int64)


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def read_ply_polygons(path: Path) -> tuple[NDArray[Any], NDArray[Any]]:
    """Read a PLY file whose faces mix triangles and larger polygons (which trimesh's binary reader refuses).

    Supports ASCII and binary PLY with a ``vertex`` element of scalar
    properties (``x y z`` and any others) and a ``face`` element with one list
    property; polygons are fan-triangulated.

    Returns
    -------
    vertices : ndarray of float64, shape (n, 3)
    faces : ndarray of int64, shape (m, 3)
    """
    data = path.read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ValueError("not a PLY file (no 'ply' magic or 'end_header')")
    body = data.index(b"\n", end) + 1
    fmt = ""
    elements: list[tuple[str, int, list[list[str]]]] = []
    for line in data[:end].decode("ascii", "replace").splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            elements[-1][2].append(words[1:])
    if [e[0] for e in elements] != ["vertex", "face"]:
        raise ValueError(f"PLY elements {[e[0] for e in elements]}; only 'vertex' and 'face' are read")
    (_, n_vert, vprops), (_, n_face, fprops) = elements
    if any(p[0] == "list" for p in vprops) or len(fprops) != 1 or fprops[0][0] != "list":
        raise ValueError("PLY vertex properties must be scalars and faces one list")
    names = [p[-1] for p in vprops]
    if fmt == "ascii":
        lines = data[body:].decode("ascii", "replace").split("\n")
        rows = np.array([ln.split() for ln in lines[:n_vert]], dtype=np.float64)
        verts = rows[:, [names.index(c) for c in "xyz"]]
        polys = [np.array(ln.split()[1:], dtype=np.int64) for ln in lines[n_vert:n_vert + n_face]]
        return verts, _fan(polys)
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
    vdtype = np.dtype([(p[-1], order + _PLY_TYPES[p[0]]) for p in vprops])
    table: Any = np.frombuffer(data, dtype=vdtype, count=n_vert, offset=body)
    verts = np.column_stack([table[c].astype(np.float64) for c in "xyz"])
    count_t, index_t = np.dtype(order + _PLY_TYPES[fprops[0][1]]), np.dtype(order + _PLY_TYPES[fprops[0][2]])
    pos = body + vdtype.itemsize * n_vert
    polys = []
    for _ in range(n_face):
        k = int(np.frombuffer(data, count_t, 1, pos)[0])
        pos += count_t.itemsize
        polys.append(np.frombuffer(data, index_t, k, pos).astype(np.int64))
        pos += index_t.itemsize * k
    return verts, _fan(polys)


def read_mesh(path: str | Path) -> tuple[NDArray[Any], NDArray[Any]]:
    """Vertices and triangles of one mesh file, as stored (not welded).

    Parameters
    ----------
    path : path-like
        OBJ, PLY, STL, OFF, GLB/glTF (all geometry of a scene, placed by its
        transforms) or a GIfTI surface.

    Returns
    -------
    vertices : ndarray of float64, shape (n, 3)
    faces : ndarray of int64, shape (m, 3)
    """
    path = Path(path)
    try:
        if path.name.lower().endswith((".gii", ".gii.gz")):
            from brainpainter.io.gifti import read_gifti

            img: Any = read_gifti(path, what="mesh file")
            pts = [d.data for d in img.darrays if d.data.ndim == 2 and d.data.shape[1] == 3
                   and np.issubdtype(d.data.dtype, np.floating)]
            tri = [d.data for d in img.darrays if d.data.ndim == 2 and d.data.shape[1] == 3
                   and np.issubdtype(d.data.dtype, np.integer)]
            if not pts or not tri:
                raise ValueError("no surface (a point set and a triangle array) in this GIfTI file")
            return np.asarray(pts[0], np.float64), np.asarray(tri[0], np.int64)
        import trimesh

        try:
            mesh: Any = trimesh.load(str(path), force="mesh", process=False, resolver=_in_folder(path))
        except ValueError:
            if path.name.lower().endswith(".ply"):  # mixed triangles and quads in a binary PLY
                return read_ply_polygons(path)
            raise
        return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64).reshape(-1, 3)
    except BrainPainterError:
        raise
    except Exception as exc:  # readers raise ValueError, KeyError, IndexError, OSError, ...
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise BrainPainterError(f"cannot read {path} as a mesh: {reason}; give OBJ, PLY, STL, OFF, "
                                "GLB/glTF or GIfTI surface files") from None


def _in_folder(path: Path) -> Any:
    """A trimesh resolver for the files a mesh names (glTF buffers, OBJ materials and textures) that
    reads only inside the mesh's own folder (trimesh 4 read ``../`` and absolute names anywhere)."""
    from trimesh.resolvers import FilePathResolver

    class InFolder(FilePathResolver):
        def get(self, name: str) -> bytes:
            folder = Path(self.parent).resolve()
            if not (folder / name.strip()).resolve().is_relative_to(folder):
                raise BrainPainterError(f"mesh file {path.name!r} names {name.strip()[:80]!r}, outside its "
                                        "own folder; a mesh's buffers and materials are read only from it.")
            data: bytes = super().get(name)
            return data

    return InFolder(str(path))


def weld(vertices: NDArray[Any], faces: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
    """Merge vertices at the same position (trimesh ``merge_vertices``) and drop degenerate faces.

    Returns
    -------
    vertices : ndarray of float64, shape (n', 3)
    faces : ndarray of int64, shape (m', 3)
    """
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)


def orientation_matrix(code: str) -> NDArray[Any]:
    """3 x 3 matrix from axes that increase towards `code` (``"PIL"``) to RAS.

    Raises
    ------
    BrainPainterError
        Not three letters naming each of the left-right, anterior-posterior
        and superior-inferior axes once.
    """
    letters = str(code).strip().upper()
    axes = [_AXIS.get(c) for c in letters]
    if len(letters) != 3 or None in axes or len({a[0] for a in axes if a}) != 3:
        raise BrainPainterError(
            f"--orientation must be three letters, one of R/L, A/P and S/I each, naming where each axis "
            f"increases (RAS, LPS, PIL, ...); {code!r} was given (BrainGlobe's 'asr' names the origin "
            "corner: it is PIL here)")
    m = np.zeros((3, 3))
    for i, a in enumerate(axes):
        assert a is not None
        m[a[0], i] = a[1]
    return m
