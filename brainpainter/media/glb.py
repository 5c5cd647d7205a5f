"""The glTF binary (``.glb``) of an export: one named, coloured node and mesh per drawn part.

Two encodings of the same scene. The plain one (float positions and
normals) opens in any glTF viewer: Blender, MeshLab, PowerPoint. The compact
one (``compact=True``, for the HTML viewer) quantises with the standard
``KHR_mesh_quantization`` extension: int16 positions with the node's scale
and offset (steps of 1/4096 of the scene's size: 0.04 mm for a human brain)
and no normals (the viewer computes them). Both write uint8 colours, and
uint16 indices where a mesh has fewer than 65,535 vertices. :func:`packed`
reorders a compact file's bytes so that gzip shrinks it further (the HTML
page's viewer undoes it).
"""

from __future__ import annotations

import json
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.settings import RGB

#: glTF is y-up; brainpainter's templates are RAS (x right, y anterior, z superior).
RAS_TO_GLTF = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
#: Quantisation steps across the scene's largest extent (int16 holds +-32,767).
POSITION_STEPS = 4096
_FLOAT, _UBYTE, _SHORT, _USHORT, _UINT = 5126, 5121, 5122, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


@dataclass(frozen=True)
class RegionMesh:
    """One drawn part of the brain.

    Attributes
    ----------
    name : str
        Region key (``"Left-insula"``), or ``"Left-medial-wall"`` for the
        cortex labels that are no region of the atlas.
    part : {"lh", "rh", "subcortical", "tracts", "connectome", "blobs"}
    vertices : ndarray of float32, shape (n_vertices, 3)
        RAS millimetres.
    faces : ndarray of int32, shape (n_faces, 3)
    normals : ndarray of float32, shape (n_vertices, 3)
        Unit vertex normals of the whole hemisphere or structure set (no
        seams at region borders).
    color : tuple of float, shape (3,)
        sRGB 0-1.
    vertex_colors : ndarray of float, shape (n_vertices, 3), optional
        sRGB 0-1 per vertex (a map, or white-matter tracts coloured along their length), written as the
        mesh's ``COLOR_0``; `color` is then a fallback (for tracts their mean).
    value : str, optional
        The region's value as shown in the viewer's tooltip (``"2.5"``,
        ``"no value"``); None: the mesh has none (the medial wall, tracts).
    """

    name: str
    part: str
    vertices: NDArray[Any]
    faces: NDArray[Any]
    normals: NDArray[Any]
    color: RGB
    vertex_colors: NDArray[Any] | None = None
    value: str | None = None


def srgb_to_linear(c: NDArray[Any]) -> NDArray[Any]:
    """sRGB 0-1 -> linear 0-1 (glTF material and vertex colours are linear)."""
    c = np.asarray(c, dtype=float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


class _Buffer:
    """The binary chunk being written: its bytes, buffer views and accessors."""

    def __init__(self) -> None:
        self.chunks: list[bytes] = []
        self.size = 0
        self.views: list[dict[str, Any]] = []
        self.accessors: list[dict[str, Any]] = []

    def add(self, array: NDArray[Any], component: int, kind: str, *, columns: int | None = None,
            target: int = _ARRAY_BUFFER, normalized: bool = False, bounds: bool = False) -> int:
        """Append `array` (shape (n,) or (n, k), rows padded to 4 bytes) as one accessor; its index.

        `columns` is how many of the k columns the accessor reads (the rest pad each row).
        """
        data = np.ascontiguousarray(array).tobytes()
        view: dict[str, Any] = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data),
                                "target": target}
        if array.ndim == 2 and target == _ARRAY_BUFFER:
            view["byteStride"] = array.shape[1] * array.itemsize
        self.chunks.append(data + b"\0" * (-len(data) % 4))
        self.size += len(data) + (-len(data) % 4)
        self.views.append(view)
        accessor: dict[str, Any] = {"bufferView": len(self.views) - 1, "componentType": component,
                                    "count": len(array), "type": kind}
        if normalized:
            accessor["normalized"] = True
        if bounds:
            used = array[:, :columns]
            accessor["min"], accessor["max"] = used.min(axis=0).tolist(), used.max(axis=0).tolist()
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def _first_use(faces: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
    """Renumber vertices in the order the faces first use them (indices then compress better):
    ``(faces renumbered, old index of each new vertex)``."""
    flat = np.asarray(faces).reshape(-1)
    used, first = np.unique(flat, return_index=True)
    order = used[np.argsort(first)]
    new = np.zeros(int(used.max()) + 1 if len(used) else 0, np.int64)
    new[order] = np.arange(len(order))
    return new[flat].reshape(np.shape(faces)), order


def _add_mesh(buf: _Buffer, m: RegionMesh, node: dict[str, Any], origin: NDArray[Any], step: float | None,
              ) -> dict[str, Any]:
    """Write the arrays of `m` to `buf`; the glTF primitive's attributes and indices.

    Quantised when `step` is given (`node` gets the scale and offset): int16
    positions, vertices in the order of first use and no normals (the viewer
    computes them across the part, so region borders show no seam).
    """
    faces, order = np.asarray(m.faces), np.arange(len(m.vertices))
    if step is not None:
        faces, order = _first_use(faces)
    verts = np.asarray(m.vertices, float)[order] @ RAS_TO_GLTF.T
    attrs: dict[str, int] = {}
    if step is None:
        attrs["POSITION"] = buf.add(verts.astype(np.float32), _FLOAT, "VEC3", bounds=True)
        normals = np.asarray(m.normals, float) @ RAS_TO_GLTF.T
        attrs["NORMAL"] = buf.add(normals.astype(np.float32), _FLOAT, "VEC3")
    else:
        node["translation"], node["scale"] = origin.tolist(), [step] * 3
        q = np.zeros((len(verts), 4), np.int16)  # rows padded to 8 bytes (vertex data is 4-byte aligned)
        q[:, :3] = np.round((verts - origin) / step)
        attrs["POSITION"] = buf.add(q, _SHORT, "VEC3", columns=3, bounds=True)
    if m.vertex_colors is not None:
        rgba = np.full((len(verts), 4), 255, np.uint8)
        rgba[:, :3] = np.round(srgb_to_linear(np.asarray(m.vertex_colors)[order]) * 255)
        attrs["COLOR_0"] = buf.add(rgba, _UBYTE, "VEC4", normalized=True)
    small = len(verts) < 65535  # uint16 indices are core glTF
    index = buf.add(faces.reshape(-1).astype(np.uint16 if small else np.uint32), _USHORT if small else _UINT,
                    "SCALAR", target=_ELEMENT_ARRAY_BUFFER)
    return {"attributes": attrs, "indices": index, "mode": 4}


def glb_bytes(meshes: Sequence[RegionMesh], *, compact: bool = False) -> bytes:
    """A glTF binary: one node and mesh per region, named by its key, with a PBR colour.

    The scene is y-up (glTF's convention) with the template's millimetres; each
    node's ``extras`` holds its ``part`` (``lh``, ``rh``, ``subcortical`` or
    ``tracts``, ``connectome``), its sRGB colour as ``#rrggbb`` and, where it has one, its
    ``value`` as text; a connectome's nodes and edges also their ``name`` as given (three.js
    renames nodes whose names repeat a region's or hold spaces: ``Left-precentral_1``).

    Parameters
    ----------
    meshes : sequence of RegionMesh
    compact : bool
        Quantise (``KHR_mesh_quantization``, required by the file) and leave
        out the normals: for the HTML viewer (three.js reads it, and
        computes the normals; some viewers do not).
    """
    step, origin = None, np.zeros(3)
    if compact and meshes:
        allv = np.concatenate([np.asarray(m.vertices, float) for m in meshes]) @ RAS_TO_GLTF.T
        lo, hi = allv.min(axis=0), allv.max(axis=0)
        origin = (lo + hi) / 2
        step = max(float((hi - lo).max()), 1e-6) / POSITION_STEPS
    buf = _Buffer()
    nodes: list[dict[str, Any]] = []
    gl_meshes: list[dict[str, Any]] = []
    materials: list[dict[str, Any]] = []
    for i, m in enumerate(meshes):
        hex_color = "#{:02x}{:02x}{:02x}".format(*(round(float(v) * 255) for v in m.color))
        extras: dict[str, Any] = {"part": m.part, "color": hex_color}
        if m.value is not None:
            extras["value"] = m.value
        if m.part == "connectome":
            extras["name"] = m.name
        node: dict[str, Any] = {"name": m.name, "mesh": i, "extras": extras}
        primitive = _add_mesh(buf, m, node, origin, step)
        if m.vertex_colors is None or compact:  # plain: vertex colours alone (trimesh reads them so)
            base = [1.0] * 3 if m.vertex_colors is not None else srgb_to_linear(np.asarray(m.color)).tolist()
            primitive["material"] = len(materials)
            materials.append({"name": m.name, "doubleSided": True, "pbrMetallicRoughness": {
                "baseColorFactor": [*base, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.75}})
        gl_meshes.append({"name": m.name, "primitives": [primitive]})
        nodes.append(node)
    doc: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": "brainpainter"}, "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": gl_meshes,
        "materials": materials, "accessors": buf.accessors, "bufferViews": buf.views,
        "buffers": [{"byteLength": buf.size}]}
    if step is not None:
        doc["extensionsUsed"] = doc["extensionsRequired"] = ["KHR_mesh_quantization"]
    return _glb(doc, b"".join(buf.chunks))


def _glb(doc: dict[str, Any], binary: bytes) -> bytes:
    """The GLB container of a glTF document and its binary chunk (4-byte aligned)."""
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(text), b"JSON") + text
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)


def packed(glb: bytes) -> bytes:
    """`glb` (compact, from :func:`glb_bytes`) with its positions and indices reordered for deflate.

    Same size, but gzip makes it ~30 % smaller: each int16 position column
    becomes deltas between consecutive vertices, each index the distance
    below the highest index before it (``hwm``); then the low bytes of
    all values come before the high bytes. Each such buffer view's
    ``extras.filter`` names its filter; the HTML viewer undoes them before
    three.js reads the file (no glTF viewer knows them).
    """
    n = struct.unpack("<I", glb[12:16])[0]
    doc = json.loads(glb[20:20 + n])
    binary = bytearray(glb[20 + n + 8:])
    kinds = {}
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            kinds[doc["accessors"][prim["attributes"]["POSITION"]]["bufferView"]] = "delta"
            kinds[doc["accessors"][prim["indices"]]["bufferView"]] = "hwm"
    for i, kind in kinds.items():
        view, acc = doc["bufferViews"][i], next(a for a in doc["accessors"] if a["bufferView"] == i)
        start, end = view["byteOffset"], view["byteOffset"] + view["byteLength"]
        if kind == "delta" and acc["componentType"] == _SHORT:
            binary[start:end] = _delta_planes(np.frombuffer(binary, np.int16, (end - start) // 2, start))
        elif kind == "hwm" and (planes := _hwm_planes(np.frombuffer(
                binary, np.uint16 if acc["componentType"] == _USHORT else np.uint32, acc["count"], start))):
            binary[start:end] = planes
        else:
            continue
        view["extras"] = {"filter": kind}
    return _glb(doc, bytes(binary))


def _planes(values: NDArray[Any]) -> bytes:
    """``(k, n)`` integers -> bytes: for each row, the low bytes of its values, then the next bytes."""
    v = np.ascontiguousarray(values)
    return np.ascontiguousarray(v.view(np.uint8).reshape(len(v), -1, v.itemsize).transpose(0, 2, 1)).tobytes()


def _delta_planes(flat: NDArray[Any]) -> bytes:
    """int16 rows ``(x, y, z, pad)`` (flattened, shape (4 n,)) -> each column's differences, in planes."""
    rows = flat.reshape(-1, 4).astype(np.int32)
    return _planes(np.diff(rows, axis=0, prepend=0).astype(np.int16).T)


def _hwm_planes(index: NDArray[Any]) -> bytes | None:
    """Indices, shape (m,), each at most one above all before it (vertices in the order of first use)
    -> the distance below that, in planes; None where an index is higher."""
    f = index.astype(np.int64)
    high = np.maximum.accumulate(np.concatenate([[-1], f[:-1]]))
    if len(f) and (f > high + 1).any():
        return None
    return _planes((high + 1 - f).astype(index.dtype)[None])
