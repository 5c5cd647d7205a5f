"""The fsaverage family: which surface a vertex count is, and coarse values brought onto fsaverage.

fsaverage is an icosahedron subdivided 7 times (163842 vertices per
hemisphere); fsaverageK (K = 3..6) stops after K subdivisions and vertex ``i``
of fsaverageK *is* vertex ``i`` of fsaverage for ``i < n_K``. Every vertex
added at level ``L+1`` is the midpoint of an edge of level ``L`` (its two
*parents*, shipped in ``brainpainter/data/fsaverage_family.npz``, built by
``tools/build_fsaverage_family.py``). Coarse data is brought up one level at a
time, each new vertex taking the mean of its two parents: this is linear
interpolation along the edges of the coarse icosahedron, i.e. piecewise-linear
(barycentric) interpolation inside each coarse triangle; the shared vertices
keep their values exactly. Label maps take the first parent's label instead.
"""

from __future__ import annotations

import itertools
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError

#: Vertices per hemisphere of each member of the fsaverage family.
FAMILY = {642: "fsaverage3", 2562: "fsaverage4", 10242: "fsaverage5", 40962: "fsaverage6",
          163842: "fsaverage"}
N_FSAVERAGE = 163842
#: Vertices per hemisphere of each fsLR mesh (HCP's; brought to fsaverage by :mod:`brainpainter.maps.fslr`).
FSLR = {32492: "fsLR 32k", 59292: "fsLR 59k", 163842: "fsLR 164k"}
#: Vertex counts of the icosahedron at each subdivision level 0..7.
LEVELS = tuple(10 * 4**k + 2 for k in range(8))


@cache
def _family() -> dict[str, NDArray[Any]]:
    with resources.files("brainpainter").joinpath("data/fsaverage_family.npz").open("rb") as fh:
        with np.load(fh) as z:
            return {k: z[k] for k in z.files}


def surface_of(n: int, what: str = "map") -> str:
    """The fsaverage family member with `n` vertices per hemisphere.

    Raises
    ------
    BrainPainterError
        When `n` fits none (a subject's own surface).
    """
    if n in FAMILY:
        return FAMILY[n]
    raise BrainPainterError(
        f"{what} has {n} values per hemisphere, which fits no fsaverage surface "
        f"({', '.join(f'{v} {k}' for k, v in sorted(FAMILY.items()))}); resample it to fsaverage with "
        "FreeSurfer's mri_surf2surf (--trgsubject fsaverage).")


def known_count(n: int, what: str = "map") -> None:
    """Check that `n` vertices per hemisphere is a mesh brainpainter knows: the fsaverage family or fsLR.

    Raises
    ------
    BrainPainterError
        Listing the known meshes.
    """
    if n in FAMILY or n in FSLR:
        return
    known = {**{k: v for k, v in FAMILY.items() if k != N_FSAVERAGE}, **FSLR}
    meshes = ", ".join(f"{k} {v}" + (" or fsaverage" if k == N_FSAVERAGE else "")
                       for k, v in sorted(known.items()))
    raise BrainPainterError(
        f"{what} has {n} values per hemisphere, which fits no known mesh ({meshes}); resample it to "
        "fsaverage (FreeSurfer's mri_surf2surf --trgsubject fsaverage) or to fsLR 32k "
        "(wb_command -metric-resample).")


def native(values: NDArray[Any], what: str = "map", n: int | None = None) -> NDArray[Any]:
    """`values` as float32 (k images, n vertices), `n` a count of :data:`FAMILY` or :data:`FSLR`.

    Maps are kept at their own resolution (a series of fsaverage5 images stays
    small) and brought to fsaverage one image at a time, when drawn. Given `n`
    (the vertices of the user's own surface, ``--lh-surface``), the map must
    have exactly that many values instead.
    """
    v = np.asarray(values, dtype=np.float32)
    v = v[None] if v.ndim == 1 else v
    if n is None:
        known_count(v.shape[1], what)
    elif v.shape[1] != n:
        raise BrainPainterError(
            f"{what} has {v.shape[1]} values per hemisphere, but the surface it is drawn on has {n} "
            "vertices; give the map made on that surface (the same subject and mesh), or draw fsaverage "
            "data on fsaverage (no --lh-surface/--rh-surface, the default --template).")
    return v


def to_fsaverage(values: NDArray[Any], categorical: bool = False, what: str = "map") -> NDArray[Any]:
    """Values of any fsaverage-family surface on fsaverage.

    Parameters
    ----------
    values : ndarray, shape (n,) or (k, n)
        One value per vertex (``k`` images); ``n`` a count of :data:`FAMILY`.
    categorical : bool
        Labels: a new vertex takes its first parent's label (no averaging).

    Returns
    -------
    ndarray of float32, shape (k, 163842)
        NaN where a new vertex has no finite parent.
    """
    v = np.asarray(values, dtype=np.float32)
    v = v[None] if v.ndim == 1 else v
    n = v.shape[1]
    surface_of(n, what)
    if n == N_FSAVERAGE:
        return v
    parents = _family()["parents"].astype(np.int64)
    out = np.full((v.shape[0], N_FSAVERAGE), np.nan, np.float32)
    out[:, :n] = v
    level = LEVELS.index(n)
    for lo, hi in zip(LEVELS[level:-1], LEVELS[level + 1:], strict=True):
        p = parents[lo - LEVELS[0]:hi - LEVELS[0]]
        a, b = out[:, p[:, 0]], out[:, p[:, 1]]
        if categorical:
            out[:, lo:hi] = np.where(np.isnan(a), b, a)
        else:
            with np.errstate(invalid="ignore"):
                out[:, lo:hi] = np.where(np.isnan(a), b, np.where(np.isnan(b), a, (a + b) / 2))
    return out


@cache
def fsaverage_faces(level: int = 7) -> NDArray[np.int64]:
    """fsaverage's triangles (or those of the family member of `level` 3-7, e.g. 6: fsaverage6),
    rebuilt from the shipped parents (no surface file needed).

    The 30 edges of the icosahedron are the parents of level 1; its 20 faces are the
    triangles of those edges, oriented alike; each level splits every face in four through
    the midpoints of its edges (the children that the parents name). Read-only, cached.

    Returns
    -------
    ndarray of int64, shape (20 * 4**level, 3)
        Every face (327680 for fsaverage; both hemispheres share them), all wound the same way
        (:func:`brainpainter.maps.sheet.normals` turns them outwards for given positions).
    """
    parents = _family()["parents"].astype(np.int64)
    edges = np.sort(parents[:LEVELS[1] - LEVELS[0]], axis=1)
    pairs = {(int(a), int(b)) for a, b in edges}
    faces = [(a, b, c) for a, b in sorted(pairs) for c in range(b + 1, LEVELS[0])
             if (a, c) in pairs and (b, c) in pairs]
    tri = _oriented(np.asarray(faces, np.int64))
    for lo, hi in itertools.pairwise(LEVELS[:level + 1]):
        child = np.sort(parents[lo - LEVELS[0]:hi - LEVELS[0]], axis=1)
        keys = child[:, 0] * N_FSAVERAGE + child[:, 1]
        order = np.argsort(keys)
        a, b, c = tri.T
        ab, bc, ca = (lo + order[np.searchsorted(keys, np.minimum(u, v) * N_FSAVERAGE + np.maximum(u, v),
                                                 sorter=order)] for u, v in ((a, b), (b, c), (c, a)))
        quarters = ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))
        tri = np.concatenate([np.column_stack(t) for t in quarters])
    tri.flags.writeable = False
    return tri


def _oriented(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """The icosahedron's faces wound alike: a shared edge runs one way in one face, the other way in
    the other."""
    out = faces.copy()
    done = {0}
    todo = [0]
    while todo:
        i = todo.pop()
        directed = {(int(out[i, k]), int(out[i, (k + 1) % 3])) for k in range(3)}
        for j in range(len(out)):
            if j in done:
                continue
            mine = {(int(out[j, k]), int(out[j, (k + 1) % 3])) for k in range(3)}
            if mine & directed:                    # the same edge the same way: flip it
                out[j] = out[j, ::-1]
            elif not {(b, a) for a, b in mine} & directed:
                continue                           # no shared edge
            done.add(j)
            todo.append(j)
    return out


def masks(hemi: str) -> dict[str, NDArray[Any]]:
    """fsaverage's ``cortex`` (not medial wall), ``sulc`` (> 0) and ``curv`` (> 0) masks, bool (163842,)."""
    z = _family()
    return {name: np.unpackbits(z[f"{hemi}_{name}"])[:N_FSAVERAGE].astype(bool)
            for name in ("cortex", "sulc", "curv")}


def own_vertex_count(template: Any, hemi: str) -> int | None:
    """The vertex count of the maps a template made from a surface other than fsaverage's family takes.

    The builder records the size of the surface a template was made from
    (``n_source_vertices``, or ``n_source_faces``: ``F / 2 + 2`` vertices); a
    template of the user's own surfaces (:mod:`brainpainter.atlas.surfaces`)
    records its vertices (and ``own_vertices``: whatever their count). None for
    the fsaverage family (maps of any family member are brought to fsaverage) and
    for a template that records no size.
    """
    counts = {int(e["n_source_vertices"]) if "n_source_vertices" in e else int(e["n_source_faces"]) // 2 + 2
              for label_set in template.manifest["labels"].values()
              for e in [label_set.get("cortex", {}).get(hemi) or {}]
              if "base" not in e and ("n_source_vertices" in e or "n_source_faces" in e)}
    count = counts.pop() if len(counts) == 1 else None
    return None if count is None or (count in FAMILY and not template.manifest.get("own_vertices")) else count


def map_mesh(template: Any, labels: str, hemi: str) -> Any:
    """The template's cortex mesh that maps are drawn on: one vertex per fsaverage vertex it keeps.

    The stored (not region-split) mesh of label set `labels` (or of the mesh
    an overlay label set labels); its ``source_vertex`` indexes fsaverage, or the
    surface the template was made from where that is no fsaverage (:func:`own_vertex_count`).

    Returns
    -------
    brainpainter.atlas.mesh.CortexMesh

    Raises
    ------
    BrainPainterError
        When the template is not made from fsaverage.
    """
    entry = template.manifest["labels"][labels]["cortex"].get(hemi)
    if entry is None:
        return template.cortex(labels, hemi)  # no cortex: an empty mesh
    mesh = template.base_cortex(entry.get("base", labels), hemi)
    sv = np.asarray(mesh.source_vertex)
    if own_vertex_count(template, hemi) is not None:  # a subject's or the user's surface: maps of its own
        return mesh
    if len(sv) and (sv.min() < 0 or sv.max() >= N_FSAVERAGE):
        raise BrainPainterError(
            f"template {template.name!r} is not made from fsaverage, so per-vertex maps cannot be drawn on "
            "it; use the default template (--template fsaverage).")
    return mesh
