"""Build ``brainpainter/data/fslr-fsaverage.npz``: weights bringing fsLR onto fsaverage (run once; committed).

The fsLR meshes (32k and 164k per hemisphere) are brought onto fsaverage
through HCP's fsLR spheres deformed to fsaverage
(``resample_fsaverage/fs_LR-deformed_to-fsaverage.{L,R}.sphere.{32,164}k_fs_LR.surf.gii``)
and fsaverage's own sphere (FreeSurfer's ``surf/?h.sphere``), as
``wb_command -metric-resample ... ADAP_BARY_AREA -area-metrics`` does, in numpy/scipy:

1. *forward*: each target vertex takes barycentric weights in the source
   triangle its direction from the centre passes through (the ray meets the
   triangle's plane: ``p = t (w0 a + w1 b + w2 c)``);
2. *reverse*: each source vertex takes barycentric weights in a target
   triangle; gathered per target vertex, these are the source vertices whose
   triangle holds it;
3. *adaptive*: a target vertex uses the reverse set where it holds more source
   vertices than the forward one (the source is denser there, so every source
   vertex counts), else the forward weights;
4. *area*: weights are multiplied by the source vertices' mean midthickness
   area (HCP's ``*midthickness_va_avg*``; fsaverage's for the fsaverage -> fsLR
   direction) and normalised to sum to 1 per target vertex.

What it holds (``H`` = lh/rh, ``R`` = 32k/164k):

``H_R_indptr`` int32 (163843,), ``H_R_indices`` int32, ``H_R_weights`` uint16
    fsLR ``R`` -> fsaverage: CSR rows of a (163842 x n_R) matrix, weights in
    units of 1/65535 (renormalised when used).
``H_R_roi`` uint8, packed bits of n_R
    HCP's ``?.atlasroi.R_fs_LR.shape.gii`` (cortex without the medial wall).

:func:`adaptive` also gives the other direction (fsaverage -> fsLR, with
fsaverage's ``midthickness_va_avg`` areas); it is not shipped (3.9 MB a
hemisphere at 32k).

There is no deformed 59k sphere in HCP's ``resample_fsaverage`` folder, so 59k
is not built (and is refused by :mod:`brainpainter.maps.fslr`).

It also builds ``brainpainter/data/fslr-flat.npz``, the flat maps (views
``flat-left``, ``flat-right``, ``flat``: :mod:`brainpainter.maps.flat`): HCP's
Colin flat fsLR 32k surfaces (``colin.cerebral.{L,R}.flat.32k_fs_LR.surf.gii``)
and where each of their vertices lies on fsaverage:

``H_xy`` int16 (32492, 2), ``xy_scale`` float64 ()
    The flat positions in units of ``xy_scale`` mm, each hemisphere centred,
    lh then shifted left and rh right by half its width plus half of
    :data:`FLAT_GAP` (the two sit side by side, left on the left).
``H_faces`` uint16 (n_faces, 3)
    The flat sheet's triangles (the cuts are absent), counter-clockwise seen
    from +z (the few folded-over ones turned).
``H_fsaverage`` int32 (32492, 3), ``H_fsaverage_weights`` uint16 (32492, 3)
    The fsaverage triangle each fsLR 32k vertex lies in on the fsLR sphere
    deformed to fsaverage, and its barycentric weights in units of 1/65535
    (values: the weighted mean; labels: the vertex of largest weight).

Usage: ``python tools/build_fslr_resampling.py ../shared/data/fslr ../shared/data/freesurfer/subjects``
(``--flat-only``: the flat maps alone)
"""

from __future__ import annotations

import sys
from pathlib import Path

import nibabel as nib
import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

OUT = Path(__file__).resolve().parents[1] / "brainpainter" / "data" / "fslr-fsaverage.npz"
FLAT_OUT = OUT.with_name("fslr-flat.npz")
RESOLUTIONS = ("32k", "164k")
#: Millimetres between the two hemispheres' flat maps, and the flat positions' quantum.
FLAT_GAP, FLAT_QUANTUM = 20.0, 0.02


def unit(xyz: np.ndarray) -> np.ndarray:
    xyz = np.asarray(xyz, np.float64)
    return xyz / np.linalg.norm(xyz, axis=1, keepdims=True)


def barycentric(src: np.ndarray, faces: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each point on the unit sphere: the 3 vertices of the source triangle it lies in and their weights.

    Returns (vertices int64 (m, 3), weights float64 (m, 3), each row summing to 1).
    """
    corners = src[faces]  # (f, 3 corners, 3 xyz)
    inverse = np.linalg.inv(np.transpose(corners, (0, 2, 1)))  # solves M w = p, M's columns the corners
    tree = cKDTree(unit(corners.mean(axis=1)))
    best_face = np.full(len(points), -1)
    best_w = np.zeros((len(points), 3))
    todo = np.arange(len(points))
    for k in (8, 32, 128):
        _, cand = tree.query(points[todo], k=k)
        w = np.einsum("mkij,mj->mki", inverse[cand], points[todo])  # (m, k, 3), unnormalised
        score = w.min(axis=2) / np.abs(w).sum(axis=2)
        pick = score.argmax(axis=1)
        rows = np.arange(len(todo))
        best_face[todo] = cand[rows, pick]
        best_w[todo] = w[rows, pick]
        inside = score[rows, pick] >= -1e-9
        todo = todo[~inside]
        if not len(todo):
            break
    if len(todo):
        raise SystemExit(f"{len(todo)} points in no triangle")
    best_w = np.clip(best_w, 0.0, None)
    return faces[best_face], best_w / best_w.sum(axis=1, keepdims=True)


def adaptive(src: tuple[np.ndarray, np.ndarray], tgt: tuple[np.ndarray, np.ndarray],
             src_area: np.ndarray) -> sparse.csr_matrix:
    """ADAP_BARY_AREA weights from the source mesh to the target mesh, (n_target x n_source) CSR."""
    (s_xyz, s_faces), (t_xyz, t_faces) = src, tgt
    ns, nt = len(s_xyz), len(t_xyz)
    fv, fw = barycentric(s_xyz, s_faces, t_xyz)  # forward: target vertex in a source triangle
    forward = sparse.csr_matrix((fw.ravel(), (np.repeat(np.arange(nt), 3), fv.ravel())), shape=(nt, ns))
    rv, rw = barycentric(t_xyz, t_faces, s_xyz)  # reverse: source vertex in a target triangle
    gather = sparse.csr_matrix((rw.ravel(), (rv.ravel(), np.repeat(np.arange(ns), 3))), shape=(nt, ns))
    forward.eliminate_zeros()
    gather.eliminate_zeros()
    use_gather = np.diff(gather.indptr) > np.diff(forward.indptr)
    chosen = (sparse.diags(use_gather.astype(float)) @ gather
              + sparse.diags((~use_gather).astype(float)) @ forward)
    chosen = (chosen @ sparse.diags(np.asarray(src_area, float))).tocsr()
    chosen.eliminate_zeros()
    sums = np.asarray(chosen.sum(axis=1)).ravel()
    chosen = (sparse.diags(1.0 / sums) @ chosen).tocsr()
    chosen.sort_indices()
    print(f"  {nt} targets from {ns} sources: {use_gather.mean():.1%} adaptive rows, "
          f"{chosen.nnz / nt:.2f} weights a row")
    return chosen


def signed_area2(corners: np.ndarray) -> np.ndarray:
    """Twice the signed areas of 2-D triangles (positive: counter-clockwise), corners (n, 3, 2) -> (n,)."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]  # np.cross of 2-D vectors is deprecated (numpy 2)


def gifti(path: Path) -> list[np.ndarray]:
    return [np.asarray(d.data) for d in nib.load(str(path)).darrays]


def flat(fslr: Path, fsavg: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    """Write :data:`FLAT_OUT` (the flat sheets and their fsaverage weights; see the module docstring)."""
    arrays: dict[str, np.ndarray] = {"xy_scale": np.float64(FLAT_QUANTUM)}
    for hemi, side in (("lh", "L"), ("rh", "R")):
        xyz, faces = gifti(fslr / f"colin.cerebral.{side}.flat.32k_fs_LR.surf.gii")
        xy = np.asarray(xyz, np.float64)[:, :2]
        faces = np.asarray(faces, np.int64)
        used = np.unique(faces)
        centre = (xy[used].min(axis=0) + xy[used].max(axis=0)) / 2
        half_width = np.ptp(xy[used, 0]) / 2
        shift = (half_width + FLAT_GAP / 2) * (-1 if hemi == "lh" else 1)
        q = np.round((xy - centre + [shift, 0.0]) / FLAT_QUANTUM)
        corner = q[faces]
        area = signed_area2(corner)
        faces[area < 0] = faces[area < 0][:, ::-1]  # folded-over triangles face the camera too
        xy = q * FLAT_QUANTUM
        arrays[f"{hemi}_xy"] = q.astype(np.int16)
        arrays[f"{hemi}_faces"] = faces.astype(np.uint16)
        deformed = f"fs_LR-deformed_to-fsaverage.{side}.sphere.32k_fs_LR.surf.gii"
        sphere, _ = gifti(fslr / "resample_fsaverage" / deformed)
        vertices, weights = barycentric(*fsavg[hemi], unit(sphere))
        arrays[f"{hemi}_fsaverage"] = vertices.astype(np.int32)
        arrays[f"{hemi}_fsaverage_weights"] = np.round(weights * 65535).astype(np.uint16)
        print(f"  {hemi} flat: {len(used)} of {len(xy)} vertices, {len(faces)} triangles "
              f"({int((area < 0).sum())} turned), {np.ptp(xy[used], axis=0).round(1)} mm")
    validate_flat(arrays)
    np.savez_compressed(FLAT_OUT, **arrays)
    print(f"wrote {FLAT_OUT} ({FLAT_OUT.stat().st_size // 1024} KiB)")


def validate_flat(arrays: dict[str, np.ndarray]) -> None:
    """Every triangle faces +z, lh lies left of rh, the weights sum to 1 (to a quantum each)."""
    scale = float(arrays["xy_scale"])
    for hemi in ("lh", "rh"):
        xy, faces = arrays[f"{hemi}_xy"].astype(np.float64) * scale, arrays[f"{hemi}_faces"].astype(np.int64)
        corner = xy[faces]
        area = signed_area2(corner)
        assert (area >= 0).all(), f"{hemi}: {(area < 0).sum()} triangles face away"
        sums = arrays[f"{hemi}_fsaverage_weights"].astype(np.int64).sum(axis=1)
        assert np.abs(sums - 65535).max() <= 2, f"{hemi}: weights do not sum to 1"
        assert arrays[f"{hemi}_fsaverage"].max() < 163842
    lh_right = arrays["lh_xy"][np.unique(arrays["lh_faces"]), 0].max()
    rh_left = arrays["rh_xy"][np.unique(arrays["rh_faces"]), 0].min()
    assert lh_right < 0 < rh_left, "the left flat map must lie left of the right one"


def main(fslr: Path, subjects: Path) -> None:
    resample = fslr / "resample_fsaverage"
    arrays: dict[str, np.ndarray] = {}
    spheres: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for hemi, side in (("lh", "L"), ("rh", "R")):
        sphere = subjects / "fsaverage" / "surf" / f"{hemi}.sphere"
        fs_xyz, fs_faces = nib.freesurfer.read_geometry(str(sphere))
        fsavg = spheres[hemi] = (unit(fs_xyz), fs_faces.astype(np.int64))
        if "--flat-only" in sys.argv:
            continue
        for res in RESOLUTIONS:
            print(f"{hemi} {res}")
            xyz, faces = gifti(resample / f"fs_LR-deformed_to-fsaverage.{side}.sphere.{res}_fs_LR.surf.gii")
            lr = (unit(xyz), faces.astype(np.int64))
            (area,) = gifti(resample / f"fs_LR.{side}.midthickness_va_avg.{res}_fs_LR.shape.gii")
            (roi,) = gifti(fslr / f"{side}.atlasroi.{res}_fs_LR.shape.gii")
            w = adaptive(lr, fsavg, area)
            arrays[f"{hemi}_{res}_indptr"] = w.indptr.astype(np.int32)
            arrays[f"{hemi}_{res}_indices"] = w.indices.astype(np.int32)
            arrays[f"{hemi}_{res}_weights"] = np.round(w.data * 65535).astype(np.uint16)
            arrays[f"{hemi}_{res}_roi"] = np.packbits(roi > 0)
    if arrays:
        np.savez_compressed(OUT, **arrays)
        print(f"wrote {OUT} ({OUT.stat().st_size // 1024} KiB)")
    flat(fslr, spheres)


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--flat-only"]
    main(Path(args[0]) if args else Path("../shared/data/fslr"),
         Path(args[1]) if len(args) > 1 else Path("../shared/data/freesurfer/subjects"))
