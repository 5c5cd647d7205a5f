"""Label sets for a template made from a per-vertex label map (``.annot`` or GIFTI).

A template's cortex meshes are decimated, but every vertex they keep is a
vertex of the full-resolution FreeSurfer surface (``source_vertex``). A label
map made for that surface (FreeSurfer ``?h.NAME.annot`` or a GIFTI
``.label.gii`` on fsaverage, e.g. the Yeo 2011 networks) therefore gives a
label to every template vertex. No geometry is stored: the new label set is
``vertex_label`` for the vertices of one of the template's own label-set
meshes (the *base*), kept in a label-set overlay folder (``labels.json`` +
``cortex-{hemi}-{name}.npz``, see :mod:`brainpainter.atlas.template`), about 12 kB
per hemisphere for the Yeo networks on fsaverage.

Faces: a face whose three vertices share a label gets that label. A face whose
vertices differ is split when the mesh is loaded (:func:`split_mesh`,
"marching triangles"): the boundary crosses each label-crossing edge once
(and runs through the face's centroid when all three labels differ). The
crossing point is shared by both faces on that edge, so the mesh stays
closed, without T-junctions. Where on the edge it lies comes from
:func:`smooth_crossings`: the zero of the difference of the two labels'
indicator functions after a few steps of mesh smoothing, i.e. the boundary
is the iso-line of a smoothed label map, not the zigzag through edge
midpoints (or the staircase of whole triangles) that vertex labels alone
give. The same code splits the built-in atlases (their template files carry
``vertex_label``) and the label sets added from label maps (overlays).

Which base: all label-set meshes of a template have about the same vertex
count, but each keeps its own region boundaries at full resolution. The base
chosen is the one whose triangles straddle the new label boundaries least
(smallest pial area of faces whose three vertices do not share one label). On
the bundled fsaverage every Yeo 7-network region comes out within 0.5 % of its
full-resolution pial area.

Validation: a label map must have exactly one label per vertex of the surface
the template was built from. That count is read from the template manifest
(``n_source_vertices``, or derived from ``n_source_faces`` as ``F / 2 + 2``,
true for the closed, genus-0 triangulations FreeSurfer makes); it is never
guessed from the vertices the template happens to keep.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from brainpainter.atlas.model import HEMI_PREFIX, Region, write_regions_tsv
from brainpainter.atlas.template import (
    FORMAT_VERSION,
    HEMIS,
    LABELS_FILE,
    LABELS_FORMAT,
    CortexMesh,
    Template,
    faces_digest,
)
from brainpainter.errors import BrainPainterError

#: Colour-table names that are not regions (compared in lower case), besides any "medial ... wall".
NON_REGION_NAMES = frozenset({"", "unknown", "???", "corpuscallosum", "medial_wall", "medial.wall"})
LABEL_SUFFIXES = (".annot", ".label.gii", ".gii")


def is_non_region(name: str) -> bool:
    """True for colour-table entries such as ``unknown``, ``???`` or ``FreeSurfer_Defined_Medial_Wall``."""
    n = str(name).strip().lower()
    return n in NON_REGION_NAMES or ("medial" in n and "wall" in n)


@dataclass(frozen=True)
class LabelMap:
    """Labels of one hemisphere's full-resolution vertices.

    Attributes
    ----------
    hemi : {"lh", "rh"}
    source : Path
    labels : ndarray of int64, shape (n_vertices,)
        Index into `names`; never -1 (unlabelled vertices get a non-region name).
    names : tuple of str
        Colour-table names.
    colors : ndarray of uint8, shape (n_names, 3)
        Colour-table colours.
    """

    hemi: str
    source: Path
    labels: np.ndarray
    names: tuple[str, ...]
    colors: np.ndarray


def hemi_of(path: str | Path) -> str | None:
    """Hemisphere named by a label-map file name (``lh.x.annot``, ``x.L.label.gii``, ``hemi-R``)."""
    name = Path(path).name
    low = name.lower()
    if low.startswith(("lh.", "lh_")) or "hemi-l_" in low or "hemi-l." in low or ".l." in low:
        return "lh"
    if low.startswith(("rh.", "rh_")) or "hemi-r_" in low or "hemi-r." in low or ".r." in low:
        return "rh"
    return None


def read_label_map(path: str | Path, hemi: str) -> LabelMap:
    """Read a FreeSurfer ``.annot`` or a GIFTI label file (``.label.gii``).

    Parameters
    ----------
    path : path-like
    hemi : {"lh", "rh"}

    Raises
    ------
    BrainPainterError
        Missing or unreadable file, or no colour table.
    """
    from brainpainter.io.files import check_input
    from brainpainter.io.readers import has_control

    path = Path(path).expanduser()
    check_input(path, "label map", hint="give a FreeSurfer .annot or a GIFTI .label.gii file made for the "
                                        "template's surface")
    low = path.name.lower()
    if not low.endswith(LABEL_SUFFIXES):
        raise BrainPainterError(f"label map {path} must be a FreeSurfer .annot or a GIFTI .label.gii file "
                                f"(allowed endings: {list(LABEL_SUFFIXES)})")
    named = hemi_of(path)
    if named is not None and named != hemi:
        raise _swapped(path, hemi, named, "its file name")
    try:
        if low.endswith(".annot"):
            from nibabel.freesurfer import read_annot

            labels, ctab, raw_names = read_annot(str(path))
            names = [n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n) for n in raw_names]
            colors = np.asarray(ctab, dtype=np.int64)[:, :3]
            labels = np.asarray(labels, dtype=np.int64)
        else:
            labels, names, colors = _read_gifti_labels(path, hemi)
    except BrainPainterError:
        raise
    except Exception as exc:  # nibabel raises ValueError, struct.error, OSError, ExpatError...
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise BrainPainterError(f"cannot read {path} as a label map: {reason}") from None
    if not names:
        raise BrainPainterError(f"{path} has no colour table, so it names no regions; give a label map "
                                "whose colour table names its regions")
    bad = next((n for n in names if has_control(n)), None)
    if bad is not None:
        raise BrainPainterError(f"{path}: the region name {bad[:40]!r} contains control or text-direction "
                                "characters; names may hold letters, digits, spaces and punctuation only")
    if (labels < 0).any():  # vertices outside the colour table: a non-region entry
        fill = next((i for i, n in enumerate(names) if is_non_region(n)), None)
        if fill is None:
            fill = len(names)
            names.append("unknown")
            colors = np.vstack([colors, [[25, 5, 25]]])
        labels = np.where(labels < 0, fill, labels)
    return LabelMap(hemi, path, labels, tuple(names), np.asarray(colors).clip(0, 255).astype(np.uint8))


def _swapped(path: Path, hemi: str, named: str, how: str) -> BrainPainterError:
    side = {"lh": "left", "rh": "right"}
    return BrainPainterError(
        f"label map {path} is given for the {side[hemi]} hemisphere ({hemi}=...), but {how} says "
        f"{side[named]}; swap the files (--annot {named}={path.name}), or rename the file if it is right")


def _read_gifti_labels(path: Path, hemi: str | None = None) -> tuple[np.ndarray, list[str], np.ndarray]:
    import nibabel as nib

    img = nib.load(str(path))
    if not getattr(img, "darrays", None):
        raise BrainPainterError(f"{path} holds no data array; a GIFTI label file has one label per vertex")
    meta = {**dict(img.meta or {}), **dict(img.darrays[0].meta or {})}
    structure = str(meta.get("AnatomicalStructurePrimary", "")).lower()
    side = "lh" if structure.endswith("left") else "rh" if structure.endswith("right") else None
    given = hemi_of(path) if hemi is None else hemi
    if side is not None and given is not None and side != given:
        raise _swapped(path, given, side, f"its AnatomicalStructurePrimary ({structure!r})")
    keys = np.asarray(img.darrays[0].data).astype(np.int64).ravel()
    table = list(img.labeltable.labels)
    names = [str(lab.label) for lab in table]
    colors = np.array([[round(255 * float(c if c is not None else 0)) for c in (lab.red, lab.green, lab.blue)]
                       for lab in table], dtype=np.int64).reshape(-1, 3)
    order = {int(lab.key): i for i, lab in enumerate(table)}
    lookup = np.vectorize(lambda k: order.get(int(k), -1), otypes=[np.int64])
    return (lookup(keys) if len(keys) else keys), names, colors


def source_vertex_count(template: Template, hemi: str) -> int:
    """Vertices of the full-resolution surface `hemi` of `template` was built from.

    Read from the manifest entries the builder writes (``n_source_vertices``,
    or ``n_source_faces``: a closed genus-0 triangulation has ``F / 2 + 2``
    vertices); a full-resolution template (``source_vertex`` is
    ``0..n-1``) counts its own vertices.
    """
    counts: dict[int, str] = {}
    for name in template.label_sets:
        entry = template.manifest["labels"][name].get("cortex", {}).get(hemi, {})
        if "base" in entry or not entry:
            continue
        if "n_source_vertices" in entry:
            counts.setdefault(int(entry["n_source_vertices"]), name)
        elif "n_source_faces" in entry:
            counts.setdefault(int(entry["n_source_faces"]) // 2 + 2, name)
        else:
            sv = template.base_cortex(name, hemi).source_vertex
            if np.array_equal(sv, np.arange(len(sv))):
                counts.setdefault(len(sv), name)
    if len(counts) != 1:
        raise BrainPainterError(
            f"template {template.name!r} does not record one source-surface size for {hemi} "
            f"(found {sorted(counts) or 'none'}); rebuild it with 'brainpainter template build'"
        )
    return next(iter(counts))


def check_vertex_count(template: Template, label_map: LabelMap) -> None:
    """One-line error unless `label_map` has one label per source-surface vertex."""
    expected = source_vertex_count(template, label_map.hemi)
    n = len(label_map.labels)
    if n != expected:
        subject = template.manifest.get("source", {}).get("subject", template.name)
        raise BrainPainterError(
            f"{label_map.source} labels {n} vertices, but template {template.name!r} needs a "
            f"{label_map.hemi} label map with {expected} (one per vertex of {subject}'s {label_map.hemi} "
            f"surface); give the file made for {subject}, or a template built from your surface "
            "(--template)"
        )


def labels_at_vertices(source_label: np.ndarray, base: CortexMesh) -> np.ndarray:
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


def split_faces(faces: np.ndarray, vertex_label: np.ndarray,
                crossing: np.ndarray | None = None) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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


def crossing_edges(faces: np.ndarray, vertex_label: np.ndarray) -> np.ndarray:
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


def smooth_crossings(faces: np.ndarray, vertex_label: np.ndarray,
                     steps: int = CROSSING_SMOOTHING) -> np.ndarray:
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

    def diff(r):
        return (np.asarray(smooth[r, la]).ravel() - np.asarray(smooth[r, lb]).ravel())

    du, dv = diff(row[:, 0]), diff(row[:, 1])  # A - B at u (expected > 0) and at v (< 0)
    ok = (du > 0) & (dv < 0)
    t = np.where(ok, du / np.where(ok, du - dv, 1.0), 0.5)
    # Both ends look like B after smoothing: u is a lone spike of A, so the border hugs u
    # (and hugs v in the mirror case); the spike shrinks instead of showing as a tooth.
    t = np.where(~ok & (du <= 0) & (dv < 0), 0.0, np.where(~ok & (du > 0) & (dv >= 0), 1.0, t))
    return t.clip(CROSSING_CLAMP, 1.0 - CROSSING_CLAMP)


def split_mesh(base: CortexMesh, vertex_label: np.ndarray, labels: str,
               names: tuple[str, ...], crossing: np.ndarray | None = None) -> CortexMesh:
    """`base` with faces labelled (and split where needed) by `vertex_label`, all surfaces.

    Boundary crossings are `crossing` (stored ``boundary_t``, one per edge of
    :func:`crossing_edges`, as :func:`smooth_crossings` computed them when
    the file was written) or, when not given or not matching, computed now
    with :func:`smooth_crossings`. Per-vertex arrays (positions of every
    surface, `sulc`) are interpolated at the new vertices.
    """
    n_edges = len(crossing_edges(base.faces, vertex_label)) if crossing is not None else -1
    if crossing is not None and np.shape(crossing) == (n_edges,):
        t = np.asarray(crossing, dtype=np.float64)
    else:
        t = smooth_crossings(base.faces, vertex_label)
    faces, face_label, parents, weights = split_faces(base.faces, vertex_label, t)

    def extend(values: np.ndarray) -> np.ndarray:
        v = np.asarray(values)
        added = np.einsum("kj,kj...->k...", weights, v[parents].astype(np.float64))
        return np.concatenate([v, added]).astype(np.float32)

    source = np.concatenate([base.source_vertex, np.full(len(parents), -1, dtype=np.int32)]).astype(np.int32)
    return CortexMesh(hemi=base.hemi, labels=labels, faces=faces.astype(np.int32),
                      face_label=face_label.astype(np.int16), label_names=names,
                      vertices={s: extend(v) for s, v in base.vertices.items()},
                      source_vertex=source, sulc=None if base.sulc is None else extend(base.sulc))


def _straddle_area(template: Template, base: str, maps: dict[str, LabelMap]) -> float:
    """Pial area of `base` faces whose three vertices do not share one label."""
    total = 0.0
    for hemi, m in maps.items():
        cm = template.base_cortex(base, hemi)
        lab = m.labels[cm.source_vertex][cm.faces]
        mixed = ~((lab[:, 0] == lab[:, 1]) & (lab[:, 1] == lab[:, 2]))
        v = cm.vertices.get("pial", next(iter(cm.vertices.values()))).astype(np.float64)
        f = cm.faces[mixed]
        total += 0.5 * float(np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                                            axis=1).sum())
    return total


def base_label_sets(template: Template) -> list[str]:
    """Label sets of `template` with their own meshes (not overlays)."""
    return [n for n in template.label_sets
            if all("base" not in e for e in template.manifest["labels"][n].get("cortex", {}).values())]


def choose_base(template: Template, maps: dict[str, LabelMap]) -> str:
    """The template label set whose mesh straddles the boundaries of `maps` least."""
    candidates = base_label_sets(template)
    if not candidates:
        raise BrainPainterError(f"template {template.name!r} has no cortex label set to label")
    return min(candidates, key=lambda b: (_straddle_area(template, b, maps), b))


@dataclass(frozen=True)
class HemiLabels:
    """A new label set on one hemisphere: names, a label per base-mesh vertex, the faces it makes."""

    hemi: str
    vertex_label: np.ndarray  # int16, shape (n_base_vertices,)
    face_label: np.ndarray  # int16, shape (n_faces after splitting,)
    names: tuple[str, ...]
    colors: np.ndarray  # uint8, shape (n_names, 3)
    source: str
    source_label: np.ndarray | None = None  # int16, shape (n_source_vertices,): the whole label map

    def region_faces(self) -> dict[str, int]:
        counts = np.bincount(self.face_label.astype(np.int64), minlength=len(self.names))
        return {n: int(counts[i]) for i, n in enumerate(self.names) if counts[i]}

    def regions(self) -> list[tuple[int, str, tuple[int, int, int]]]:
        """(colour-table index, name, colour) of the regions with faces, in colour-table order."""
        used = set(np.unique(self.face_label).tolist())
        return [(i, n, tuple(int(c) for c in self.colors[i])) for i, n in enumerate(self.names)
                if i in used and not is_non_region(n)]


@dataclass(frozen=True)
class LabelSet:
    """A label set made for a template from label maps.

    Attributes
    ----------
    name : str
    template : str
    base : str
        Template label set whose meshes the labels are for.
    hemis : dict of str to HemiLabels
    too_small : dict of str to list of str
        Per hemisphere, regions of the label map with vertices but no whole
        face on the template mesh (left out).
    """

    name: str
    template: str
    base: str
    hemis: dict[str, HemiLabels]
    too_small: dict[str, list[str]] = field(default_factory=dict)


def build_label_set(name: str, template: Template, maps: dict[str, LabelMap],
                    base: str | None = None) -> LabelSet:
    """Label the faces of a template mesh by per-vertex label maps (one per hemisphere).

    Parameters
    ----------
    name : str
        Name of the new label set.
    template : Template
    maps : dict of {"lh", "rh"} to LabelMap
        Both hemispheres.
    base : str, optional
        Template label set to label (default: :func:`choose_base`).
    """
    missing = [h for h in HEMIS if h not in maps]
    if missing:
        raise BrainPainterError(f"a label map for each hemisphere is needed; {missing} is missing "
                                "(give --annot lh=FILE --annot rh=FILE)")
    for m in maps.values():
        check_vertex_count(template, m)
    base = base or choose_base(template, maps)
    hemis: dict[str, HemiLabels] = {}
    too_small: dict[str, list[str]] = {}
    for hemi in HEMIS:
        m = maps[hemi]
        cm = template.base_cortex(base, hemi)
        if len(m.names) > np.iinfo(np.int16).max:
            raise BrainPainterError(f"{m.source} has {len(m.names)} colour-table entries; at most 32767")
        vertex_label = m.labels[cm.source_vertex].astype(np.int16)
        face_label = split_faces(cm.faces, vertex_label)[1]
        hl = HemiLabels(hemi, vertex_label, face_label.astype(np.int16), m.names, m.colors, m.source.name,
                        m.labels.astype(np.int16))
        hemis[hemi] = hl
        with_vertices = {m.names[i] for i in np.unique(m.labels).tolist() if not is_non_region(m.names[i])}
        too_small[hemi] = sorted(with_vertices - {n for _, n, _ in hl.regions()})
    if not any(h.regions() for h in hemis.values()):
        raise BrainPainterError(
            f"the label maps {[m.source.name for m in maps.values()]} name no region on template "
            f"{template.name!r} (only entries such as unknown or medial wall); give a label map with regions"
        )
    return LabelSet(name, template.name, base, hemis, too_small)


def _hex(rgb) -> str:
    return "#{:02x}{:02x}{:02x}".format(*(int(c) for c in rgb[:3]))


def write_label_set(folder: Path, label_set: LabelSet, template: Template, *,
                    per_source_vertex: bool = False) -> dict:
    """Write ``labels.json`` and ``cortex-{hemi}-{name}.npz`` into `folder`; returns the JSON.

    With `per_source_vertex` the files hold the whole label map (``source_label``,
    one per full-resolution vertex) instead of the labels of the base mesh's
    vertices: a little larger, but it fits the template after a rebuild.
    """
    from brainpainter.atlas.writer import save_npz

    where = "full-resolution vertices (mapped to" if per_source_vertex else "vertices of"
    entry: dict = {"source": ", ".join(label_set.hemis[h].source for h in HEMIS),
                   "method": f"label map at the {where} the template's {label_set.base!r} meshes"
                             f"{')' if per_source_vertex else ''}; faces with several labels split "
                             "through edge midpoints",
                   "regions": [], "cortex": {}}
    for hemi in HEMIS:
        hl = label_set.hemis[hemi]
        for _, n, _ in hl.regions():
            if n not in entry["regions"]:
                entry["regions"].append(n)
        file = f"cortex-{hemi}-{label_set.name}.npz"
        base = template.base_cortex(label_set.base, hemi)
        if per_source_vertex and hl.source_label is not None:
            save_npz(folder / file, {"source_label": hl.source_label})
            guard = {}
        else:
            crossing = smooth_crossings(base.faces, hl.vertex_label).astype(np.float32)
            save_npz(folder / file, {"vertex_label": hl.vertex_label, "boundary_t": crossing})
            guard = {"base_faces_sha256": faces_digest(base.faces)}
        entry["cortex"][hemi] = {
            "file": file, "base": label_set.base, **guard,
            "names": list(hl.names), "colors": [_hex(c) for c in hl.colors],
            "n_base_vertices": len(base.source_vertex), "n_faces": len(hl.face_label),
            "n_source_vertices": source_vertex_count(template, hemi),
            "region_faces": hl.region_faces(),
        }
    meta = {"format": LABELS_FORMAT, "format_version": FORMAT_VERSION, "template": template.name,
            "labels": {label_set.name: entry}}
    (folder / LABELS_FILE).write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return meta


def atlas_regions(label_set: LabelSet, region_aliases: dict[str, tuple[str, ...]] | None = None,
                  subcortical: tuple[Region, ...] = ()) -> list[Region]:
    """Regions of an atlas drawn with `label_set`: cortical per hemisphere, then `subcortical`.

    Indices follow FreeSurfer's ``ctx-lh-*`` look-up-table convention: 1000
    (left) or 2000 (right) plus the colour-table index.
    """
    region_aliases = region_aliases or {}
    out: list[Region] = []
    for hemi, offset in (("lh", 1000), ("rh", 2000)):
        for i, n, color in label_set.hemis[hemi].regions():
            aliases = (f"ctx-{hemi}-{n}", *region_aliases.get(n, ()))
            out.append(Region(offset + i, n, hemi, "cortical", color, aliases))
    keys = {r.key for r in out}
    out.extend(r for r in subcortical if r.key not in keys)
    return out


def template_subcortical(template: Template) -> tuple[Region, ...]:
    """Subcortical regions of the built-in look-up table that `template` has meshes for."""
    from brainpainter.atlas import registry
    names = {s["name"] for s in template.manifest.get("subcortical", {}).get("structures", [])}
    try:
        rows = registry.atlases.get("dk").subcortical()
    except BrainPainterError:
        return ()
    return tuple(r for r in rows if r.key in names)


_PART_B = re.compile(r"^PART B", re.MULTILINE)


def write_license(folder: Path, template: Template, sources: list[str]) -> bool:
    """Write ``LICENSE.FreeSurfer.txt`` for data derived from a FreeSurfer template (if it has one)."""
    lic = template.path / "LICENSE.FreeSurfer.txt"
    if not lic.is_file():
        return False
    text = lic.read_text(encoding="utf-8")
    head = text.split("\n\n", 1)[0]
    match = _PART_B.search(text)
    body = text[match.start():] if match else ""
    notice = "\n".join([
        "The label files in this directory (cortex-*.npz, labels.json, regions.tsv) are data",
        "derived (modified) from the label maps",
        *(f"  {s}" for s in sources),
        f"and from the brainpainter template {template.name!r}, itself data derived (modified) from",
        "FreeSurfer: " + str(template.manifest.get("attribution", "")).strip(),
        "They are not endorsed by MGH. Research use; see the licence below.",
        "",
    ])
    (folder / "LICENSE.FreeSurfer.txt").write_text(f"{head}\n\n{notice}\n{body}", encoding="utf-8")
    return True


def write_atlas_folder(folder: Path, label_set: LabelSet, template: Template, *, title: str = "",
                       description: str = "", citation: str = "", aliases: tuple[str, ...] = (),
                       region_aliases: dict[str, tuple[str, ...]] | None = None,
                       subcortical: bool = True, extra: dict | None = None,
                       per_source_vertex: bool = False) -> None:
    """Write a complete atlas folder (``atlas.json``, ``regions.tsv``, overlay, licence) into `folder`.

    The folder loads with :func:`brainpainter.atlas.model.load_atlas_dir`; it is what
    ``brainpainter atlas add`` stores and what an atlas plugin ships.
    """
    folder.mkdir(parents=True, exist_ok=True)
    write_label_set(folder, label_set, template, per_source_vertex=per_source_vertex)
    sub = template_subcortical(template) if subcortical else ()
    regions = atlas_regions(label_set, region_aliases, sub)
    write_regions_tsv(regions, folder / "regions.tsv")
    sources = [label_set.hemis[h].source for h in HEMIS]
    n = {h: sum(1 for r in regions if r.hemi == h and r.kind == "cortical") for h in HEMIS}
    meta = {
        "name": label_set.name,
        "title": title or label_set.name,
        "template_labels": label_set.name,
        "template": template.name,
        "description": description or (
            f"Label map {' + '.join(sources)} on template {template.name!r}: {n['lh']} left and "
            f"{n['rh']} right cortical regions{', plus aseg subcortical structures' if sub else ''}."),
        "citation": citation,
        "aliases": list(aliases),
        "source": {"label_maps": sources, "base_label_set": label_set.base,
                   "too_small": {h: v for h, v in label_set.too_small.items() if v}, **(extra or {})},
    }
    (folder / "atlas.json").write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    write_license(folder, template, sources)


def region_keys(label_set: LabelSet) -> list[str]:
    """Cortical region keys (``Left-7Networks_1``...) of a label set."""
    return [HEMI_PREFIX[h] + n for h in HEMIS for _, n, _ in label_set.hemis[h].regions()]
