"""Cortex meshes and how a label set splits them: faces cut along region boundaries.

A label set stores one label per vertex of a template's base mesh;
:func:`split_mesh` cuts every face whose vertices carry different labels
through points on its edges (:func:`split_faces`, "marching triangles"), so
region borders follow the boundary instead of the triangles. Where on an edge
the border crosses (:func:`smooth_crossings`) is computed when a label set is
written and stored, so loading only splits.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray


def vertex_normals(vertices: NDArray[Any], faces: NDArray[Any],
                   dtype: type[np.floating[Any]] = np.float32) -> NDArray[Any]:
    """Area-weighted unit vertex normals: the one normals function of brainpainter.

    Parameters
    ----------
    vertices : ndarray of float, shape (n_vertices, 3)
    faces : ndarray of int, shape (n_faces, 3)
        Counter-clockwise seen from outside (normals then point outwards).
    dtype : numpy float type
        Of the result (float32 for drawing; float64 where geometry is changed by them).

    Returns
    -------
    ndarray, shape (n_vertices, 3)
        Unit length; zero for a vertex no face uses.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = np.zeros_like(v)
    if len(f):
        fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        # corner by corner (all first corners, then all second, ...): the order in which the
        # builder's meshing always summed, so rebuilt templates stay byte-identical
        idx = f.T.ravel()
        for c in range(3):
            n[:, c] = np.bincount(idx, weights=np.tile(fn[:, c], 3), minlength=len(v))
    length = np.linalg.norm(n, axis=1, keepdims=True)
    unit: NDArray[Any] = (n / np.where(length > 0, length, 1.0)).astype(dtype)
    return unit


def faces_digest(faces: NDArray[Any]) -> str:
    """SHA-256 of a face array (as little-endian int32), to recognise a mesh."""
    return hashlib.sha256(np.ascontiguousarray(faces, dtype="<i4").tobytes()).hexdigest()


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
        Index of each vertex in the full-resolution FreeSurfer surface; -1 for
        a vertex added on an edge or face where a region boundary was split.
    sulc : ndarray of float32, shape (n_vertices,), or None
        Sulcal depth (FreeSurfer ``?h.sulc``, mm; positive in sulci, negative
        on gyral crowns), when the template has it.
    occlusion : dict of str to ndarray of float32, shape (n_vertices,), or None
        Ambient occlusion per surface (1 = open sky, towards 0 deep in a fold;
        :mod:`brainpainter.atlas.occlusion`), when the template has it baked.
    """

    hemi: str
    labels: str
    faces: NDArray[Any]
    face_label: NDArray[Any]
    label_names: tuple[str, ...]
    vertices: dict[str, NDArray[Any]]
    source_vertex: NDArray[Any]
    sulc: NDArray[Any] | None = None
    occlusion: dict[str, NDArray[Any]] | None = None


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
    occlusion : ndarray of float32, shape (n_vertices,), or None
        Ambient occlusion of the structures together (1 = open sky), when baked.
    """

    vertices: NDArray[Any]
    faces: NDArray[Any]
    face_label: NDArray[Any]
    label_names: tuple[str, ...]
    occlusion: NDArray[Any] | None = None


def labels_at_vertices(source_label: NDArray[Any], base: CortexMesh) -> NDArray[Any]:
    """Labels of `base`'s vertices from one label per full-resolution source vertex.

    Parameters
    ----------
    source_label : ndarray of int, shape (n_source_vertices,)
    base : CortexMesh
        Its ``source_vertex`` (shape (n,)) indexes `source_label`; a vertex
        with no source vertex (-1, added on an edge by a mesh builder) takes
        the label of a neighbour that has one.

    Returns
    -------
    ndarray of int16, shape (n,)
    """
    sv = np.asarray(base.source_vertex, dtype=np.int64)
    out = np.where(sv >= 0, np.asarray(source_label)[np.maximum(sv, 0)], -1).astype(np.int64)
    edges = np.concatenate([base.faces[:, [0, 1]], base.faces[:, [1, 2]], base.faces[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]]).astype(np.int64)
    while (out < 0).any():
        known = out[edges[:, 1]] >= 0
        todo = known & (out[edges[:, 0]] < 0)
        if not todo.any():
            out[out < 0] = 0
            break
        out[edges[todo, 0]] = out[edges[todo, 1]]
    return out.astype(np.int16)


def split_faces(faces: NDArray[Any], vertex_label: NDArray[Any],
                crossing: NDArray[Any] | None = None) -> tuple[
        NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any]]:
    """Split faces whose vertices carry different labels ("marching triangles").

    Parameters
    ----------
    faces : ndarray of int, shape (m, 3)
    vertex_label : ndarray of int, shape (n,)
    crossing : ndarray of float, shape (n_edges,), optional
        Where the boundary crosses each label-crossing edge, as a fraction of
        the way from its lower-numbered to its higher-numbered vertex, for the
        edges in the order of :func:`crossing_edges`. Default 0.5 (midpoints).

    Returns
    -------
    faces : ndarray of int64, shape (m2, 3)
        Faces with one label each; indices ``>= n`` are new vertices. Winding kept.
    face_label : ndarray of int64, shape (m2,)
    parents : ndarray of int64, shape (k, 3)
        For new vertex ``n + i``: the vertices it lies between (an edge
        crossing repeats its second vertex).
    weights : ndarray of float64, shape (k, 3)
        Interpolation weights over `parents` (``1 - t, t, 0`` on an edge,
        ``1/3`` each at a centroid).

    Notes
    -----
    A face with two labels, rotated to ``(o, a, b)`` with ``o`` the odd one,
    becomes ``(o, m_oa, m_ob)`` and the quad ``(m_oa, a, b, m_ob)``; a face
    with three labels becomes three quads around its centroid. Only
    label-crossing edges get a new vertex, and both faces on such an edge
    are split, so no T-junction appears.
    """
    faces = np.asarray(faces, dtype=np.int64)
    vl = np.asarray(vertex_label, dtype=np.int64)
    n = len(vl)
    lab = vl[faces]
    e01, e12, e20 = lab[:, 0] == lab[:, 1], lab[:, 1] == lab[:, 2], lab[:, 2] == lab[:, 0]
    pure = e01 & e12
    three = ~(e01 | e12 | e20)
    two = ~pure & ~three
    f2 = faces[two]
    odd = np.where(e12[two], 0, np.where(e20[two], 1, 2))
    idx = np.arange(len(f2))
    o, a, b = f2[idx, odd], f2[idx, (odd + 1) % 3], f2[idx, (odd + 2) % 3]
    f3 = faces[three]
    edges = np.concatenate([np.stack([o, a], 1), np.stack([o, b], 1),
                            f3[:, [0, 1]], f3[:, [1, 2]], f3[:, [2, 0]]]).reshape(-1, 2)
    key = np.sort(edges, axis=1)
    uniq, inv = np.unique(key[:, 0] * n + key[:, 1], return_inverse=True)
    mid = n + inv.ravel()
    k2, k3 = len(f2), len(f3)
    m_oa, m_ob = mid[:k2], mid[k2:2 * k2]
    m_ab, m_bc, m_ca = (mid[2 * k2 + i * k3: 2 * k2 + (i + 1) * k3] for i in range(3))
    g = n + len(uniq) + np.arange(k3)
    p, q, r = f3[:, 0], f3[:, 1], f3[:, 2]
    out_faces = np.concatenate([
        faces[pure],
        np.stack([o, m_oa, m_ob], 1), np.stack([m_oa, a, b], 1), np.stack([m_oa, b, m_ob], 1),
        np.stack([p, m_ab, g], 1), np.stack([p, g, m_ca], 1),
        np.stack([q, m_bc, g], 1), np.stack([q, g, m_ab], 1),
        np.stack([r, m_ca, g], 1), np.stack([r, g, m_bc], 1),
    ]).reshape(-1, 3)
    out_label = np.concatenate([lab[pure, 0], vl[o], vl[a], vl[a], vl[p], vl[p], vl[q], vl[q], vl[r], vl[r]])
    t = np.full(len(uniq), 0.5) if crossing is None else np.asarray(crossing, dtype=np.float64)
    if t.shape != (len(uniq),):
        raise ValueError(f"crossing has shape {t.shape}; expected ({len(uniq)},), one per crossing edge")
    parents = np.concatenate([np.stack([uniq // n, uniq % n, uniq % n], 1),
                              np.stack([p, q, r], 1)]).reshape(-1, 3)
    weights = np.concatenate([np.stack([1.0 - t, t, np.zeros_like(t)], 1),
                              np.full((k3, 3), 1.0 / 3.0)]).reshape(-1, 3)
    return out_faces, out_label, parents, weights


def crossing_edges(faces: NDArray[Any], vertex_label: NDArray[Any]) -> NDArray[Any]:
    """Edges whose two vertices carry different labels, shape (n_edges, 2), sorted, lower vertex first."""
    faces = np.asarray(faces, dtype=np.int64)
    vl = np.asarray(vertex_label, dtype=np.int64)
    n = len(vl)
    e = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    e = e[vl[e[:, 0]] != vl[e[:, 1]]]
    uniq = np.unique(e[:, 0] * n + e[:, 1])
    return np.stack([uniq // n, uniq % n], 1)


#: Smoothing steps of the label indicators that place boundary crossings (:func:`smooth_crossings`).
CROSSING_SMOOTHING = 3
#: Crossings stay this far (fraction of the edge) from either end, so no face degenerates.
CROSSING_CLAMP = 0.05


def smooth_crossings(faces: NDArray[Any], vertex_label: NDArray[Any],
                     steps: int = CROSSING_SMOOTHING) -> NDArray[Any]:
    """Where a smooth label boundary crosses each label-crossing edge.

    For an edge ``(u, v)`` with labels ``A`` at ``u`` and ``B`` at ``v``, the
    indicator functions of ``A`` and ``B`` (1 on the label's vertices, 0
    elsewhere) are smoothed by `steps` steps of neighbour averaging over the
    mesh; the boundary crosses the edge where their difference, linear along
    the edge, is zero. This is the iso-line of a blurred label map: it keeps
    the label of every vertex but no longer zigzags from edge midpoint to
    edge midpoint. Where both ends fall on one side (a vertex whose label
    its neighbourhood outvotes: a spike of a noisy label map), the crossing
    goes as close to the outvoted vertex as allowed.

    Parameters
    ----------
    faces : ndarray of int, shape (m, 3)
    vertex_label : ndarray of int, shape (n,)
    steps : int
        Smoothing steps (each reaches one ring of neighbours further); 0 gives midpoints.

    Returns
    -------
    t : ndarray of float64, shape (n_edges,)
        For the edges of :func:`crossing_edges`: fraction of the way from the
        lower- to the higher-numbered vertex, within
        ``[CROSSING_CLAMP, 1 - CROSSING_CLAMP]``.
    """
    from scipy import sparse

    edges = crossing_edges(faces, vertex_label)
    if steps <= 0 or len(edges) == 0:
        return np.full(len(edges), 0.5)
    faces = np.asarray(faces, dtype=np.int64)
    vl = np.asarray(vertex_label, dtype=np.int64)
    n = len(vl)
    ij = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    rows = np.concatenate([ij[:, 0], ij[:, 1], np.arange(n)])
    cols = np.concatenate([ij[:, 1], ij[:, 0], np.arange(n)])
    adj = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    adj.data[:] = 1.0  # duplicate edges summed: back to 0/1
    step = sparse.diags(1.0 / np.asarray(adj.sum(axis=1)).ravel()) @ adj
    ends = np.unique(edges)
    reach = step[ends]
    for _ in range(steps - 1):
        reach = reach @ step
    names, compact = np.unique(vl, return_inverse=True)
    onehot = sparse.csr_matrix((np.ones(n), (np.arange(n), compact)), shape=(n, len(names)))
    smooth = (reach @ onehot).tocsr()  # smoothed indicators at the edge ends, shape (len(ends), n_labels)
    row = np.searchsorted(ends, edges)
    la, lb = compact[edges[:, 0]], compact[edges[:, 1]]

    def diff(r: NDArray[Any]) -> NDArray[np.float64]:
        d: NDArray[np.float64] = np.asarray(smooth[r, la]).ravel() - np.asarray(smooth[r, lb]).ravel()
        return d

    du, dv = diff(row[:, 0]), diff(row[:, 1])  # A - B at u (expected > 0) and at v (< 0)
    ok = (du > 0) & (dv < 0)
    t = np.where(ok, du / np.where(ok, du - dv, 1.0), 0.5)
    # Both ends look like B after smoothing: u is a lone spike of A, so the border hugs u
    # (and hugs v in the mirror case); the spike shrinks instead of showing as a tooth.
    t = np.where(~ok & (du <= 0) & (dv < 0), 0.0, np.where(~ok & (du > 0) & (dv >= 0), 1.0, t))
    return t.clip(CROSSING_CLAMP, 1.0 - CROSSING_CLAMP)


def split_mesh(base: CortexMesh, vertex_label: NDArray[Any], labels: str,
               names: tuple[str, ...], crossing: NDArray[Any] | None = None) -> CortexMesh:
    """`base` with faces labelled (and split where needed) by `vertex_label`, all surfaces.

    Boundary crossings are `crossing` (stored ``boundary_t``, one per edge of
    :func:`crossing_edges`, as :func:`smooth_crossings` computed them when
    the file was written) or, when not given or not matching, computed now
    with :func:`smooth_crossings`. Per-vertex arrays (positions of every
    surface, `sulc`, `occlusion`) are interpolated at the new vertices.
    """
    n_edges = len(crossing_edges(base.faces, vertex_label)) if crossing is not None else -1
    if crossing is not None and np.shape(crossing) == (n_edges,):
        t = np.asarray(crossing, dtype=np.float64)
    else:
        t = smooth_crossings(base.faces, vertex_label)
    faces, face_label, parents, weights = split_faces(base.faces, vertex_label, t)

    def extend(values: NDArray[Any]) -> NDArray[Any]:
        v = np.asarray(values)
        added = np.einsum("kj,kj...->k...", weights, v[parents].astype(np.float64))
        out: NDArray[np.float32] = np.concatenate([v, added]).astype(np.float32)
        return out

    source = np.concatenate([base.source_vertex, np.full(len(parents), -1, dtype=np.int32)]).astype(np.int32)
    return CortexMesh(hemi=base.hemi, labels=labels, faces=faces.astype(np.int32),
                      face_label=face_label.astype(np.int16), label_names=names,
                      vertices={s: extend(v) for s, v in base.vertices.items()},
                      source_vertex=source, sulc=None if base.sulc is None else extend(base.sulc),
                      occlusion=None if base.occlusion is None else {
                          k: extend(v) for k, v in base.occlusion.items()})
